// The SVG plots' text: measured, cut, wrapped, escaped and written (svg_parts.hpp).

#include "lmcal/report/svg_plot.hpp"
#include "report/svg_parts.hpp"

#include "io/input_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace lmcal::report {

namespace svg {

std::string px(double v) {
  std::string s = fmt::format("{:.2f}", v);
  s.erase(s.find_last_not_of('0') + 1);
  if (s.back() == '.') s.pop_back();
  if (s == "-0") s = "0";
  return s;
}

std::string tick_label(double v, double step) {
  if (!(step > 0)) return fmt::format("{:g}", v);
  if (std::abs(v) < 1e-9 * step) return "0";
  const int digits = static_cast<int>(std::floor(std::log10(std::abs(v)))) -
                     static_cast<int>(std::floor(std::log10(step))) + 1;
  return fmt::format("{:.{}g}", v, std::clamp(digits, 6, 15));
}

double text_px(std::string_view text) {
  const auto n = std::count_if(text.begin(), text.end(),
                               [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; });
  return kCharPx * static_cast<double>(n);
}

std::string shortened(const std::string& text, double max_px) {
  if (text_px(text) <= max_px) return text;
  std::string out;
  double used = kCharPx;  // the ellipsis
  for (std::size_t i = 0; i < text.size();) {
    std::size_t next = i + 1;
    while (next < text.size() && (static_cast<unsigned char>(text[next]) & 0xC0) == 0x80) ++next;
    if (used + kCharPx > max_px) break;
    out.append(text, i, next - i);
    used += kCharPx;
    i = next;
  }
  return out + "…";
}

std::vector<std::string> wrap(const std::string& text, double max_px) {
  std::vector<std::string> lines;
  std::string line;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t end = std::min(text.find(' ', at), text.size());
    const std::string word = text.substr(at, end - at);
    if (!line.empty() && text_px(line + " " + word) > max_px) {
      lines.push_back(line);
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
    at = end + 1;
  }
  if (!line.empty() || lines.empty()) lines.push_back(line);
  return lines;
}

std::vector<std::string> wrap_lines(const std::string& text, double max_px, std::size_t most) {
  std::vector<std::string> lines = wrap(text, max_px);
  if (lines.size() > most) {
    for (std::size_t k = most; k < lines.size(); ++k) lines[most - 1] += " " + lines[k];
    lines.resize(most);
  }
  for (std::string& line : lines) line = shortened(line, max_px);
  return lines;
}

namespace {

// Whether every line is at most `max_px` wide.
bool all_fit(const std::vector<std::string>& lines, double max_px) {
  return std::all_of(lines.begin(), lines.end(), [&](const std::string& line) { return text_px(line) <= max_px; });
}

}  // namespace

TitleLayout title_layout(const std::string& title, double width) {
  if (title.empty()) return {};
  // Bold glyphs of s px are about s/11 · 1.1 as wide as the 11 px ones kCharPx measures.
  const auto room = [&](double size) { return (width - 12) / (size / 11.0 * 1.1); };
  if (std::vector<std::string> lines = wrap(title, room(13)); lines.size() <= 2 && all_fit(lines, room(13)))
    return {std::move(lines), 13, 16};
  return {wrap_lines(title, room(11), 3), 11, 14};
}

void write_text(Out out, double x, double y, std::string_view anchor, std::string_view text, std::string_view extra) {
  fmt::format_to(out, "<text x=\"{}\" y=\"{}\" text-anchor=\"{}\"{}>{}</text>\n", px(x), px(y), anchor, extra,
                 escape_xml(text));
}

void write_line(Out out, double x1, double y1, double x2, double y2, std::string_view extra) {
  fmt::format_to(out, "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"{}/>\n", px(x1), px(y1), px(x2), px(y2), extra);
}

}  // namespace svg

std::string escape_xml(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    // A bidirectional control would reorder everything after it on the page: shown as its name.
    if (const auto control = io::bidi_control_at(text.substr(i))) {
      out += fmt::format("[U+{:04X}]", static_cast<unsigned>(control->code));
      i += control->length - 1;
      continue;
    }
    const char c = text[i];
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default:
        if (static_cast<unsigned char>(c) >= 0x20 || c == '\t' || c == '\n' || c == '\r') out += c;
    }
  }
  return out;
}

}  // namespace lmcal::report
