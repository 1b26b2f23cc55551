#include "io/input_file.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <sstream>

#include "lmcal/error.hpp"
#include "lmcal/io/config_file.hpp"
#include "lmcal/io/limits.hpp"

namespace lmcal::io {

std::string byte_size(std::uintmax_t bytes) {
  if (bytes < 1024) return fmt::format("{} bytes", bytes);
  static constexpr const char* kUnits[] = {"KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  double value = static_cast<double>(bytes) / 1024;
  std::size_t unit = 0;
  while (value >= 1024 && unit + 1 < std::size(kUnits)) {
    value /= 1024;
    ++unit;
  }
  return fmt::format("{:.3g} {}", value, kUnits[unit]);
}

std::optional<std::string> not_a_file(const std::filesystem::path& file, std::uintmax_t* size) {
  struct stat info {};
  if (::stat(file.c_str(), &info) != 0) return std::string(std::strerror(errno));
  if (S_ISDIR(info.st_mode)) return "this is a folder, not a file";
  if (!S_ISREG(info.st_mode)) {
    const char* kind = S_ISCHR(info.st_mode) || S_ISBLK(info.st_mode) ? "a device"
                       : S_ISFIFO(info.st_mode)                         ? "a pipe"
                       : S_ISSOCK(info.st_mode)                         ? "a socket"
                                                                        : "not a regular file";
    return fmt::format("this is {}; expected a regular file", kind);
  }
  if (size) *size = static_cast<std::uintmax_t>(info.st_size);
  return std::nullopt;
}

std::uintmax_t check_input_file(const std::filesystem::path& file, std::uintmax_t max_bytes, std::string_view what) {
  check_path_name(file, "file name");
  const std::string name = file.string();
  std::uintmax_t size = 0;
  if (auto problem = not_a_file(file, &size)) throw InputError(name, 0, 0, fmt::format("cannot open {}: {}", what, *problem));
  if (size > max_bytes) {
    throw InputError(name, 0, 0,
                     fmt::format("{} is {} bytes; the limit is {} (docs/formats.md#limits)", what, size, byte_size(max_bytes)));
  }
  return size;
}

std::string read_text_file(const std::filesystem::path& file, std::string_view what) {
  const std::uintmax_t size = check_input_file(file, kMaxTextBytes, what);
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  const std::unique_ptr<std::FILE, Closer> in(std::fopen(file.c_str(), "rb"));
  if (!in) throw InputError(file.string(), 0, 0, fmt::format("cannot open {}: {}", what, std::strerror(errno)));
  // Read to the end, not to the size stat gave: the file may have changed since, but never
  // beyond the limit.
  std::string text(static_cast<std::size_t>(size), '\0');
  std::size_t got = 0;
  for (;;) {
    if (got == text.size()) {
      if (text.size() >= kMaxTextBytes + 1) break;
      text.resize(std::min<std::uintmax_t>(std::max<std::size_t>(2 * text.size(), 4096), kMaxTextBytes + 1));
    }
    const std::size_t n = std::fread(text.data() + got, 1, text.size() - got, in.get());
    got += n;
    if (n == 0) break;
  }
  if (std::ferror(in.get())) throw InputError(file.string(), 0, 0, fmt::format("cannot read {}: {}", what, std::strerror(errno)));
  if (got > kMaxTextBytes) {
    throw InputError(file.string(), 0, 0,
                     fmt::format("{} grew beyond the limit of {} while it was read", what, byte_size(kMaxTextBytes)));
  }
  text.resize(got);
  return text;
}


namespace {

// The first character of `text`, decoded: its code point (or nullopt when the bytes are not
// UTF-8) and its length in bytes (1 for a byte that is not UTF-8).
struct Character {
  std::optional<char32_t> code;
  std::size_t length = 1;
};

Character decode(std::string_view text) {
  const auto* p = reinterpret_cast<const unsigned char*>(text.data());
  const unsigned char lead = p[0];
  const std::size_t length = lead < 0x80 ? 1 : (lead & 0xE0) == 0xC0 ? 2 : (lead & 0xF0) == 0xE0 ? 3 : (lead & 0xF8) == 0xF0 ? 4 : 0;
  if (length == 0 || text.size() < length) return {};
  static constexpr char32_t kSmallest[] = {0, 0, 0x80, 0x800, 0x10000};  // shorter forms are overlong
  char32_t code = length == 1 ? lead : lead & (0x7F >> length);
  for (std::size_t k = 1; k < length; ++k) {
    if ((p[k] & 0xC0) != 0x80) return {};
    code = (code << 6) | (p[k] & 0x3F);
  }
  if (code < kSmallest[length] || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return {};
  return {code, length};
}

bool is_control(char32_t code) { return code < 0x20 || code == 0x7F || (code >= 0x80 && code < 0xA0); }

bool is_bidi_control(char32_t code) {
  return (code >= 0x202A && code <= 0x202E) || (code >= 0x2066 && code <= 0x2069) || code == 0x200E || code == 0x200F ||
         code == 0x061C;
}

}  // namespace

std::optional<BidiControl> bidi_control_at(std::string_view text) {
  if (text.empty()) return std::nullopt;
  const Character c = decode(text);
  if (!c.code || !is_bidi_control(*c.code)) return std::nullopt;
  return BidiControl{*c.code, c.length};
}

std::optional<std::string> name_problem(std::string_view name, bool free_text) {
  long character = 1;
  for (std::size_t at = 0; at < name.size(); ++character) {
    const Character c = decode(name.substr(at));
    if (!c.code) {
      return fmt::format("byte 0x{:02X} at character {} is not UTF-8 (names must be UTF-8: they go into JSON)",
                         static_cast<unsigned char>(name[at]), character);
    }
    if (is_control(*c.code) && !(free_text && (*c.code == '\n' || *c.code == '\t' || *c.code == '\r')))
      return fmt::format("control character U+{:04X} at character {} (names are printed to terminals and pages)",
                         static_cast<unsigned>(*c.code), character);
    if (is_bidi_control(*c.code))
      return fmt::format("bidirectional control U+{:04X} at character {} (it would reorder the text shown after it)",
                         static_cast<unsigned>(*c.code), character);
    at += c.length;
  }
  return std::nullopt;
}

std::string printable(std::string_view text) {
  std::string out;
  for (std::size_t at = 0; at < text.size();) {
    const Character c = decode(text.substr(at));
    if (!c.code) {
      out += fmt::format("\\x{:02X}", static_cast<unsigned char>(text[at]));
    } else if (is_control(*c.code) || is_bidi_control(*c.code)) {
      out += fmt::format("\\u{:04X}", static_cast<unsigned>(*c.code));
    } else {
      out += text.substr(at, c.length);
    }
    at += c.length;
  }
  return out;
}

void check_path_name(const std::filesystem::path& path, std::string_view what) {
  if (auto problem = name_problem(path.string())) throw InputError(printable(path.string()), 0, 0, fmt::format("{}: {}", what, *problem));
}

void check_config_file(const std::filesystem::path& file) {
  std::istringstream text(read_text_file(file, "config file"));
  std::map<std::string, long> tables;  // [name] → the line it opens at
  long line = 0;
  for (std::string row; std::getline(text, row);) {
    ++line;
    const auto open = row.find_first_not_of(" \t");
    if (open == std::string::npos || row[open] != '[' || row.compare(open, 2, "[[") == 0) continue;
    const auto close = row.find(']', open);
    if (close == std::string::npos) continue;  // the parser tells what is wrong
    std::string name = row.substr(open + 1, close - open - 1);
    std::erase_if(name, [](char c) { return c == ' ' || c == '\t'; });
    if (const auto [first, added] = tables.emplace(name, line); !added)
      throw InputError(printable(file.string()), line, static_cast<long>(open) + 1,
                       fmt::format("[{}] given twice (first at line {}): one table per command", printable(name), first->second));
  }
}

}  // namespace lmcal::io
