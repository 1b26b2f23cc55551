#include "terminal.hpp"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdlib>

namespace lmcal::cli {

namespace {

constexpr std::size_t kNarrowest = 20;  // below this, wrapping would leave a word a line

// Columns of UTF-8 text: its code points.
std::size_t columns(std::string_view text) {
  return static_cast<std::size_t>(
      std::count_if(text.begin(), text.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

// How a line breaks: where the lines after the first start (columns from the left), and the byte
// from which the rest stays on one line (a table row's last column, where it fits one), if any.
struct Breaks {
  std::size_t hang;
  std::size_t whole_from = std::string_view::npos;
};

Breaks breaks_of(std::string_view line, std::size_t lead, std::size_t width) {
  std::string_view body = line.substr(lead);
  body = body.substr(0, body.find_last_not_of(' ') + 1);
  // A list item: under the item's text.
  for (const std::string_view marker : {"- ", "* ", "• "})
    if (body.starts_with(marker)) return {lead + columns(marker)};
  const std::size_t digits = body.find_first_not_of("0123456789");
  if (digits != std::string_view::npos && digits > 0 && digits + 2 <= body.size() &&
      (body.substr(digits, 2) == ". " || body.substr(digits, 2) == ") "))
    return {lead + digits + 2};
  // A table row (columns padded): under its last column where that starts early enough (kept
  // whole there, "[0.027983, 0.031145]", where it fits), else 4 in (whole where it fits).
  if (const std::size_t gap = body.rfind("  "); gap != std::string_view::npos) {
    const std::size_t from = body.find_first_not_of(' ', gap), last = lead + columns(body.substr(0, from));
    const std::size_t hang = 10 * last <= 6 * width ? last : lead + 4;
    return {hang, hang + columns(body.substr(from)) <= width ? lead + from : std::string_view::npos};
  }
  // "label: text", the label short: under the text.
  if (const std::size_t colon = body.find(": "); colon != std::string_view::npos) {
    const std::size_t text = lead + columns(body.substr(0, colon + 2));
    if (text <= std::min<std::size_t>(width / 3, 32)) return {text};
  }
  return {lead + 2};
}

}  // namespace

std::size_t stdout_columns() {
  if (const char* given = std::getenv("COLUMNS"); given && *given) {
    std::size_t width = 0;
    const std::string_view text = given;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), width);
    return error == std::errc() && end == text.data() + text.size() ? width : 0;
  }
  if (!isatty(STDOUT_FILENO)) return 0;
  winsize size{};
  return ioctl(STDOUT_FILENO, TIOCGWINSZ, &size) == 0 ? size.ws_col : 0;
}

std::string wrap_line(std::string_view line, std::size_t width) {
  if (width < kNarrowest || columns(line) <= width) return std::string(line);
  const std::size_t lead = std::min(line.find_first_not_of(' '), line.size());
  const Breaks breaks = breaks_of(line, lead, width);
  const std::string hang(std::min(breaks.hang, 6 * width / 10), ' ');
  std::string out(line.substr(0, lead));
  std::size_t used = lead;  // columns on the line being filled
  bool first = true;        // no word on it yet
  for (std::size_t at = lead; at < line.size();) {
    const std::size_t start = line.find_first_not_of(' ', at);
    if (start == std::string_view::npos) break;  // trailing spaces
    const std::size_t end = start == breaks.whole_from ? line.find_last_not_of(' ') + 1 : std::min(line.find(' ', start), line.size());
    const std::string_view gap = line.substr(at, start - at), word = line.substr(start, end - start);
    if (!first && used + gap.size() + columns(word) > width) {  // the word starts the next line
      out += '\n';
      out += hang;
      used = hang.size();
    } else {
      out += gap;
      used += gap.size();
    }
    out += word;
    used += columns(word);
    first = false;
    at = end;
  }
  return out;
}

WrappingBuffer::~WrappingBuffer() {
  if (!line_.empty()) emit();
  out_->pubsync();
}

WrappingBuffer::int_type WrappingBuffer::overflow(int_type c) {
  if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
  line_ += traits_type::to_char_type(c);
  if (traits_type::to_char_type(c) == '\n') emit();
  return c;
}

std::streamsize WrappingBuffer::xsputn(const char* s, std::streamsize n) {
  for (std::streamsize i = 0; i < n; ++i) overflow(traits_type::to_int_type(s[i]));
  return n;
}

// A line waits for its newline (it can only be wrapped whole); what is complete is passed on.
int WrappingBuffer::sync() { return out_->pubsync(); }

void WrappingBuffer::emit() {
  const bool newline = !line_.empty() && line_.back() == '\n';
  if (newline) line_.pop_back();
  const std::string wrapped = wrap_line(line_, width_) + (newline ? "\n" : "");
  out_->sputn(wrapped.data(), static_cast<std::streamsize>(wrapped.size()));
  line_.clear();
}

}  // namespace lmcal::cli
