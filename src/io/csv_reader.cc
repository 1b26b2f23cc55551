// The streaming CSV reader: chunks, lines, cells (quoted or not), numbers and their rules,
// and the errors at a cell (the header's binding: csv_header.cc).
#include "io/csv_reader.hpp"

#include <fast_float/fast_float.h>
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>

#include <unistd.h>

#include "io/input_file.hpp"
#include "parallel_slices.hpp"
#include "lmcal/io/csv_writer.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"

namespace lmcal::csv {

namespace {

namespace fs = std::filesystem;

// Large enough that fread and the tail move are noise, and the longest line allowed: a
// longer one is refused when it fills the buffer.
constexpr std::size_t kChunkBytes = io::kMaxLineBytes;
constexpr double kAbsoluteZero_C = -273.15;

bool is_space(char c) { return c == ' ' || c == '\t'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

// Comments and blank lines carry no data, wherever they are.
bool is_skipped(const char* begin, const char* end) {
  if (begin != end && *begin == '#') return true;
  while (begin != end && is_space(*begin)) ++begin;
  return begin == end;
}

// Exact mask of the bytes of `word` equal to `c`: the high bit of each such byte.
std::uint64_t bytes_equal(std::uint64_t word, char c) {
  constexpr std::uint64_t kLow7 = 0x7F7F7F7F7F7F7F7FULL;
  const std::uint64_t x = word ^ (0x0101010101010101ULL * static_cast<unsigned char>(c));
  return ~(((x & kLow7) + kLow7) | x | kLow7);  // high bit set where x's byte is zero
}

// Plain decimals ("-12.345", at most 15 digits) are nearly every cell of a log. Such a number
// is m / 10^k with m < 2^53 and 10^k exact, so one IEEE division rounds it correctly: the
// fast path fast_float itself takes (Clinger), without its generality. Anything else
// (exponents, nan, inf, more digits) returns false and goes to fast_float.
bool plain_decimal(const char* p, const char* end, double& out) {
  static constexpr double kPow10[] = {1e0, 1e1, 1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                      1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15};
  const bool negative = p != end && *p == '-';
  p += negative;
  std::uint64_t mantissa = 0;
  // The digits from p on (how many): the whole part, then the decimals after a point.
  const auto digits = [&] {
    const char* const first = p;
    for (unsigned d; p != end && (d = static_cast<unsigned>(*p - '0')) < 10; ++p) mantissa = 10 * mantissa + d;
    return p - first;
  };
  const auto whole = digits();
  const auto decimals = p != end && *p == '.' ? (++p, digits()) : 0;
  if (p != end || whole + decimals == 0 || whole + decimals > 15) return false;
  double value = static_cast<double>(mantissa);
  if (decimals > 0) value /= kPow10[decimals];
  out = negative ? -value : value;
  return true;
}

}  // namespace

// ---- Reader -------------------------------------------------------------------------------

Reader::Reader(const fs::path& file, std::size_t skip_lines) : file_(file.string()), skip_lines_(skip_lines) {
  file_size_ = io::check_input_file(file, io::kMaxCsvBytes, "file");
  stream_.reset(std::fopen(file.c_str(), "rb"));
  if (!stream_) throw InputError(file_, 0, 0, fmt::format("cannot open file: {}", std::strerror(errno)));
  buffer_.resize(kChunkBytes);
  data_ = buffer_.data();
}

Reader::Reader(const Reader& whole, std::string_view slice, long lines_before)
    : file_(whole.file_), file_size_(whole.file_size_), data_(slice.data()), end_(slice.size()), at_eof_(true),
      eol_(whole.eol_), line_(lines_before), header_(whole.header_), header_line_(whole.header_line_),
      skip_lines_(whole.skip_lines_), slice_(true) {}

std::optional<Reader::Rest> Reader::read_rest(int count) const {
  const std::uintmax_t offset = bytes_read_ - (end_ - pos_);
  const std::size_t size = static_cast<std::size_t>(file_size_ - std::min(offset, file_size_));
  Rest rest{.bytes = std::unique_ptr<char[]>(new char[std::max<std::size_t>(size, 1)]), .slices = {}};
  char* const bytes = rest.bytes.get();
  detail::prefer_huge_pages(bytes, size);
  const int fd = fileno(stream_.get());
  std::atomic<bool> whole = true;
  // Pieces of at least 4 MiB: each thread's pages are first written by that thread.
  detail::for_each_slice(size, detail::slice_threads(size, std::size_t{4} << 20), [&](int, std::size_t begin, std::size_t end) {
    while (begin < end) {
      const ssize_t got = ::pread(fd, bytes + begin, end - begin, static_cast<off_t>(offset + begin));
      if (got <= 0) {
        if (got < 0 && errno == EINTR) continue;
        whole = false;  // shorter than it was (or unreadable: the line-by-line reader says why)
        return;
      }
      begin += static_cast<std::size_t>(got);
    }
  });
  char probe;
  if (!whole || ::pread(fd, &probe, 1, static_cast<off_t>(offset + size)) != 0) return std::nullopt;  // it grew
  // Each slice ends after a line end at or past its share of the bytes.
  const char* start = bytes;
  const char* const end = bytes + size;
  for (int k = 1; k <= count; ++k) {
    const char* stop = end;
    if (k < count) {
      const char* share = std::max<const char*>(start, bytes + size * static_cast<std::size_t>(k) / static_cast<std::size_t>(count));
      const void* eol = share == end ? nullptr : std::memchr(share, eol_, static_cast<std::size_t>(end - share));
      stop = eol ? static_cast<const char*>(eol) + 1 : end;
    }
    rest.slices.emplace_back(start, static_cast<std::size_t>(stop - start));
    start = stop;
  }
  return rest;
}

bool Reader::refill() {
  if (at_eof_) return false;
  // (A slice is at its end from the start: it never refills.)
  // The unread tail is a partial line: keep it, at the front.
  const std::size_t tail = end_ - pos_;
  if (tail != 0 && pos_ != 0) std::memmove(buffer_.data(), data_ + pos_, tail);
  pos_ = 0;
  end_ = tail;
  if (end_ == buffer_.size()) {
    // One line fills the buffer: memory stays bounded by refusing it rather than growing.
    fail_at(line_ + 1, 1,
            fmt::format("line longer than {} (the limit, docs/formats.md#limits): expected the lines of a CSV file",
                        io::byte_size(io::kMaxLineBytes)));
  }
  const std::size_t wanted = buffer_.size() - end_;
  const std::size_t got = std::fread(buffer_.data() + end_, 1, wanted, stream_.get());
  if (got < wanted) {
    if (std::ferror(stream_.get())) throw InputError(file_, 0, 0, fmt::format("read error: {}", std::strerror(errno)));
    at_eof_ = true;
  }
  end_ += got;
  bytes_read_ += got;
  if (bytes_read_ > io::kMaxCsvBytes) {
    fail_at(line_ + 1, 1, fmt::format("the file grew beyond the limit of {} while it was read", io::byte_size(io::kMaxCsvBytes)));
  }
  return got != 0;
}

bool Reader::next_line() {
  for (;;) {
    const char* begin = data_ + pos_;
    if (const void* nl = std::memchr(begin, eol_, end_ - pos_)) {
      line_begin_ = begin;
      line_end_ = static_cast<const char*>(nl);
      pos_ = static_cast<std::size_t>(line_end_ - data_) + 1;
      break;
    }
    if (!refill()) {
      if (pos_ == end_) return false;
      // The last line, without a line break.
      line_begin_ = data_ + pos_;
      line_end_ = data_ + end_;
      pos_ = end_;
      break;
    }
  }
  // The file reader refuses a line that fills its buffer; a slice, which holds whole lines, any
  // line that could have (the exact limit is the file reader's to say).
  if (slice_ && static_cast<std::size_t>(line_end_ - line_begin_) + 2 >= kChunkBytes)
    fail_at(line_ + 1, 1, "line too long for a slice");
  if (line_end_ != line_begin_ && line_end_[-1] == '\r') --line_end_;
  ++line_;
  return true;
}

void Reader::split() {
  cells_.clear();
  const char* p = line_begin_;
  const char* const end = line_end_;
  const char* start = p;
  // Fast path, eight bytes at a time: commas found with bit tricks, one cell per comma.
  // A quote anywhere sends the line to the general loop below, from its start.
  for (; end - p >= 8; p += 8) {
    std::uint64_t word;
    std::memcpy(&word, p, 8);
    if (bytes_equal(word, '"') != 0) {
      cells_.clear();
      split_quoted();
      return;
    }
    for (std::uint64_t commas = bytes_equal(word, ','); commas != 0; commas &= commas - 1) {
      // Byte order: the lowest set bit is the first comma (little-endian load).
      const char* comma = p + std::countr_zero(commas) / 8;
      cells_.emplace_back(start, static_cast<std::size_t>(comma - start));
      start = comma + 1;
    }
  }
  for (; p != end; ++p) {
    if (*p == '"') {
      cells_.clear();
      split_quoted();
      return;
    }
    if (*p == ',') {
      cells_.emplace_back(start, static_cast<std::size_t>(p - start));
      start = p + 1;
    }
  }
  cells_.emplace_back(start, static_cast<std::size_t>(end - start));
}

void Reader::split_quoted() {
  const char* p = line_begin_;
  const char* const end = line_end_;
  for (;;) {
    const char* const start = p;
    if (p != end && *p == '"') {
      // Quoted: up to the closing quote; "" inside is an escaped quote.
      ++p;
      for (;;) {
        p = static_cast<const char*>(std::memchr(p, '"', static_cast<std::size_t>(end - p)));
        if (!p) fail_at(line_, column_of(start), "unterminated quote (a quoted cell cannot span lines)");
        ++p;
        if (p == end || *p != '"') break;
        ++p;
      }
      if (p != end && *p != ',') fail_at(line_, column_of(p), "expected ',' after the closing quote");
    } else {
      while (p != end && *p != ',') ++p;
    }
    cells_.emplace_back(start, static_cast<std::size_t>(p - start));
    if (p == end) break;
    ++p;  // the ','
  }
}

void Reader::start() {
  refill();
  // A UTF-8 byte-order mark (spreadsheet exports) is not part of the first header cell.
  if (end_ >= 3 && std::memcmp(data_, "\xEF\xBB\xBF", 3) == 0) pos_ = 3;
  // Lines end in "\n" or "\r\n"; a file with '\r' but no '\n' in its first chunk ends them
  // in '\r' alone (old Mac and some instrument exports).
  const std::string_view first(data_, end_);
  if (first.find('\n') == std::string_view::npos && first.find('\r') != std::string_view::npos) eol_ = '\r';
}

bool Reader::seek_line(long line) {
  start();
  while (next_line()) {
    if (line_ == line) {
      split();
      return true;
    }
  }
  return false;
}

void Reader::read_header() {
  start();
  while (next_line()) {
    if (static_cast<std::size_t>(line_) <= skip_lines_) continue;  // a logger's preamble, whatever it holds
    if (is_skipped(line_begin_, line_end_)) continue;
    header_line_ = line_;
    split();
    if (cells_.size() > io::kMaxColumns) {
      fail(io::kMaxColumns, fmt::format("{} columns; at most {} are read (the limit, docs/formats.md#limits)", cells_.size(),
                                        io::kMaxColumns));
    }
    if (cells_.size() == 1) {
      const std::string_view line(line_begin_, static_cast<std::size_t>(line_end_ - line_begin_));
      const auto semicolons = std::count(line.begin(), line.end(), ';');
      const auto tabs = std::count(line.begin(), line.end(), '\t');
      if (semicolons + tabs > 0) {
        fail_at(line_, 1,
                fmt::format("expected comma-separated columns; this header looks {}-separated",
                            semicolons >= tabs ? "';'" : "tab"));
      }
    }
    std::string scratch;
    for (std::size_t i = 0; i < cells_.size(); ++i) {
      header_.emplace_back(text(i, scratch));
      if (auto problem = io::name_problem(header_.back())) fail(i, "column name: " + *problem);
    }
    return;
  }
  if (skip_lines_ != 0 && line_ != 0) {
    fail_at(0, 0, fmt::format("no header line after the {} skipped line{} (skip_lines = {}; the file has {})", skip_lines_,
                              skip_lines_ == 1 ? "" : "s", skip_lines_, line_));
  }
  fail_at(0, 0, "empty file; expected a header line");
}

bool Reader::next() {
  while (next_line()) {
    if (is_skipped(line_begin_, line_end_)) continue;
    if (++rows_ > io::kMaxRows && !slice_) {
      fail_at(line_, 1, fmt::format("more than {} data rows in one file (the limit, docs/formats.md#limits): split the "
                                    "log into several files listed in a manifest",
                                    io::kMaxRows));
    }
    split();
    if (cells_.size() > header_.size()) {
      fail(header_.size(), fmt::format("expected {} cells as in the header, found {}{}", header_.size(), cells_.size(),
                                       looks_like_decimal_commas() ? " (decimal commas? numbers take a point: 26.5, not 26,5)" : ""));
    }
    if (cells_.size() < header_.size()) {
      fail_at(line_, column_of(line_end_),
              fmt::format("expected {} cells as in the header, found {}", header_.size(), cells_.size()));
    }
    return true;
  }
  return false;
}

std::string_view Reader::text(std::size_t i, std::string& scratch) const {
  std::string_view cell = trim(cells_[i]);
  if (cell.size() >= 2 && cell.front() == '"') {
    cell = cell.substr(1, cell.size() - 2);
    if (cell.find('"') != std::string_view::npos) {
      scratch.clear();
      for (std::size_t k = 0; k < cell.size(); ++k) {
        scratch += cell[k];
        if (cell[k] == '"') ++k;  // "" -> "
      }
      cell = scratch;
    }
  }
  // The apostrophe a writer puts before formula-like text ('=r1 reads as =r1).
  if (cell.size() >= 2 && cell.front() == '\'' && csv_formula_escape_needed(cell.substr(1))) cell.remove_prefix(1);
  return cell;
}

double Reader::number(const Column& column, bool allow_missing) const {
  // The hot path: a plain decimal with nothing around it. Everything else, and every
  // message, is out of line so that this stays small.
  const std::string_view cell = cells_[column.cell];
  double value = 0;
  if (!plain_decimal(cell.data(), cell.data() + cell.size(), value)) {
    value = parse_other(column, allow_missing);
    if (std::isnan(value)) return value;  // missing, and allowed
  }
  value = to_internal(column.conversion, value);
  // Finite as written is not enough: 1e306 kN is infinite in newtons.
  if (!std::isfinite(value)) fail_number(column, trim(cell), "a number that stays finite in the column's internal unit");
  if (!satisfies(column.rule, value)) fail_rule(column);
  if (column.range && !column.range->contains(value)) fail(column.cell, out_of_range_message(column.header, trim(cell), *column.range));
  return value;
}

double Reader::parse_other(const Column& column, bool allow_missing) const {
  const std::string_view found = trim(cells_[column.cell]);
  if (found.empty()) {
    if (allow_missing) return std::numeric_limits<double>::quiet_NaN();
    fail(column.cell, fmt::format("column '{}': expected a number, found an empty cell", column.header));
  }
  const char* first = found.data();
  const char* last = first + found.size();
  // fast_float 3.9 does not take a leading '+' ("+1" in a direction column).
  if (*first == '+' && last - first > 1 && (first[1] == '.' || (first[1] >= '0' && first[1] <= '9'))) ++first;
  double value = 0;
  const auto [end, ec] = fast_float::from_chars(first, last, value);
  if (ec != std::errc() || end != last) fail_number(column, found, "a number");
  if (std::isnan(value)) {
    if (allow_missing) return value;
    fail_number(column, found, "a number");
  }
  if (std::isinf(value)) fail_number(column, found, "a finite number");
  return value;
}

bool Reader::satisfies(Rule rule, double value) {
  switch (rule) {
    case Rule::any: return true;
    case Rule::non_negative: return value >= 0;
    case Rule::positive: return value > 0;
    case Rule::above_absolute_zero: return value > kAbsoluteZero_C;
    case Rule::plus_or_minus_one: return value == 1 || value == -1;
  }
  return true;
}

void Reader::fail_rule(const Column& column) const {
  // Messages quote the cell as written; the rule was checked in internal units.
  const std::string_view found = trim(cells_[column.cell]);
  const std::string_view h = column.header;
  switch (column.rule) {
    case Rule::any: break;
    case Rule::non_negative:
      fail(column.cell, fmt::format("{} = {} is negative; expected >= 0{}", h, found, column.hint));
    case Rule::positive:
      fail(column.cell, fmt::format("{} = {} is not positive; expected > 0{}", h, found, column.hint));
    case Rule::above_absolute_zero:
      fail(column.cell, fmt::format("{} = {} is not above absolute zero (-273.15 °C){}", h, found, column.hint));
    case Rule::plus_or_minus_one: fail(column.cell, fmt::format("{} = {}: expected +1 or -1{}", h, found, column.hint));
  }
  fail(column.cell, fmt::format("{} = {} is out of range", h, found));
}

void Reader::fail_number(const Column& column, std::string_view found, const char* expected) const {
  const bool comma = found.find(',') != std::string_view::npos;
  fail(column.cell, fmt::format("column '{}': expected {}, found '{}'{}", column.header, expected, found,
                                comma ? " (a decimal comma? numbers take a point: 26.5, not 26,5)" : ""));
}

bool Reader::looks_like_decimal_commas() const {
  // "26,5" split into "26" and "5": no decimal point anywhere in the row, and a cell of digits
  // right after a cell that ends in a digit for every cell too many.
  const auto digits = [](std::string_view cell) {
    cell = trim(cell);
    return !cell.empty() && std::all_of(cell.begin(), cell.end(), [](char c) { return c >= '0' && c <= '9'; });
  };
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < cells_.size(); ++i) {
    if (cells_[i].find('.') != std::string_view::npos) return false;
    const std::string_view before = i == 0 ? std::string_view() : trim(cells_[i - 1]);
    pairs += !before.empty() && before.back() >= '0' && before.back() <= '9' && digits(cells_[i]);
  }
  return pairs >= cells_.size() - header_.size();
}

long Reader::column_of(const char* where) const {
  // Characters, not bytes: UTF-8 continuation bytes (10xxxxxx) do not start a character.
  long column = 1;
  for (const char* p = line_begin_; p < where; ++p) column += (static_cast<unsigned char>(*p) & 0xC0) != 0x80;
  return column;
}

void Reader::fail(std::size_t i, const std::string& what) const { fail_at(line_, column_of(cells_[i].data()), what); }

void Reader::fail_at(long line, long column, const std::string& what) const {
  throw InputError(file_, line, column, what);
}

std::size_t Reader::estimated_rows() const {
  // Data lines only: a file of blank lines around one row must not reserve for millions.
  const char* p = data_ + pos_;
  const char* const end = data_ + end_;
  std::size_t lines = 0;
  while (p != end) {
    const char* nl = static_cast<const char*>(std::memchr(p, eol_, static_cast<std::size_t>(end - p)));
    const char* line_end = nl ? nl : end;
    const char* content_end = line_end != p && line_end[-1] == '\r' ? line_end - 1 : line_end;
    lines += !is_skipped(p, content_end);
    p = nl ? nl + 1 : end;
  }
  const std::size_t rest_bytes = end_ - pos_;
  if (at_eof_) return lines;
  const std::uintmax_t consumed = bytes_read_ - rest_bytes;
  if (lines == 0 || file_size_ <= consumed) return lines;
  // A little above the extrapolation, so that one reserve() usually suffices.
  const double rows =
      static_cast<double>(file_size_ - consumed) * static_cast<double>(lines) / static_cast<double>(rest_bytes);
  return std::min(static_cast<std::size_t>(rows * 1.03) + 16, io::kMaxRows);
}

}  // namespace lmcal::csv
