// Private: what a file looks like, from its first lines, for the message when it is given where
// another kind was expected ("this looks like a CSV file; expected a TOML manifest").
#pragma once

#include <algorithm>
#include <string>
#include <string_view>

namespace lmcal::io {

// "a CSV file (comma-separated columns)", "a TOML file (key = value lines)", "a JSON document",
// or "" when the first line that is not blank or a comment says nothing clear.
inline std::string looks_like(std::string_view text) {
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    std::string_view line = text.substr(at, end - at);
    at = end + 1;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string_view::npos || line[first] == '#') continue;
    line = line.substr(first);
    if (line[0] == '{' || (line[0] == '[' && line.size() > 1 && (line[1] == '{' || line[1] == '"'))) return "a JSON document";
    if (line[0] == '[' || line.find('=') != std::string_view::npos) return "a TOML file (key = value lines)";
    if (std::count(line.begin(), line.end(), ',') >= 1) return "a CSV file (comma-separated columns)";
    return "";
  }
  return "";
}

}  // namespace lmcal::io
