// The summaries' prose wrapped to the terminal's width at word boundaries, so that a line of
// 900 characters reads as a paragraph, not as a terminal's hard wrap through the middle of words:
//
//   lines longer than the width break at spaces; the next lines hang under the text of a list
//   item ("- ", "1. "), under a short label's text ("diagnosis: explained: The …" hangs under
//   "explained"), under the last column of a table row (columns padded with two spaces or more;
//   4 further in where that column starts past 60 % of the width), else 2 in; a word longer
//   than a line stands alone.
//
// The width is COLUMNS when it is set (in a pipe too: `COLUMNS=100 lmcal calibrate SET | less`),
// else the terminal's own (TIOCGWINSZ) when stdout is one; a pipe or a file without COLUMNS gets
// the lines as they are. The man page and the completion script are never wrapped.
#pragma once

#include <cstddef>
#include <memory>
#include <streambuf>
#include <string>
#include <string_view>

namespace lmcal::cli {

// The width to wrap stdout to, or 0: do not wrap.
std::size_t stdout_columns();

// `line` (no newline in it) broken into lines of at most `width` columns (code points) as above;
// unchanged when it fits or `width` is below 20.
std::string wrap_line(std::string_view line, std::size_t width);

// Passes what is written through it on to `out`, each line wrapped (wrap_line) once its newline
// comes; a last line without one when it is destroyed.
class WrappingBuffer : public std::streambuf {
 public:
  WrappingBuffer(std::streambuf* out, std::size_t width) : out_(out), width_(width) {}
  ~WrappingBuffer() override;

 protected:
  int_type overflow(int_type c) override;
  std::streamsize xsputn(const char* s, std::streamsize n) override;
  int sync() override;

 private:
  void emit();
  std::streambuf* out_;
  std::size_t width_;
  std::string line_;
};

}  // namespace lmcal::cli
