// Private CSV machinery shared by the friction-log and thermal-trace loaders: a streaming
// reader and the header/row rules both formats follow.
//
// The reader walks the file in large chunks; a row is a set of views into the chunk
// (valid until the next call to next()), so no string is built per line or per cell.
// Lines starting with '#' and blank lines are skipped; "\r\n" ends a line like "\n", and so does
// '\r' alone in a file without '\n'. The limits of lmcal/io/limits.hpp are checked as the file is read.
// Text cells may be quoted ("a ""b""", no line breaks inside). Numbers are parsed with
// fast_float, after an exact shortcut for plain decimals like "24.013" (most cells; see
// plain_decimal in the .cc); "nan"/"NaN" and an empty cell both read as missing (NaN).
//
// A loader describes its columns with ColumnSpec, binds the header with bind_header
// (units, duplicates, missing and ignored columns) and reads values with Reader::number,
// which converts to internal units and enforces the column's Rule. Every error is an
// InputError at the file, line and character column of the offending cell.
//
// Trap: cells and texts of a row are views into the reader's buffer, valid only until
// the next call to Reader::next().
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "process_heap.hpp"
#include "lmcal/io/load_report.hpp"
#include "lmcal/io/units.hpp"

namespace lmcal::csv {

// The range a numeric column's values must lie in (checked in internal units).
enum class Rule { any, non_negative, positive, above_absolute_zero, plus_or_minus_one };

// What a loader knows about one of its columns.
struct ColumnSpec {
  std::string_view name;             // "load"; for a family the prefix ("tc" for tc1_C, tc2_K, ...)
  std::optional<Quantity> quantity;  // nullopt: no unit suffix ("run", "direction")
  bool text = false;                 // kept as text (run and guide names)
  bool required = false;             // for a family: at least one column
  bool family = false;               // any number of columns `<name><digits>_<unit>`
  Rule rule = Rule::any;
  std::string_view hint = {};  // appended to range errors, e.g. why a speed is >= 0
  // Without a quantity: the values a rig gives (with one: the quantity's physical_range).
  std::optional<PhysicalRange> range = {};
};

// A header cell bound to a ColumnSpec.
struct Column {
  std::size_t spec = 0;   // index into the loader's spec list
  std::size_t cell = 0;   // 0-based position in the row
  std::string header;     // as written, e.g. "load_kgf"
  std::string name;       // without the unit, e.g. "load", "tc1"
  Conversion conversion;  // file unit -> internal unit
  Rule rule = Rule::any;
  std::string_view hint;
  std::optional<PhysicalRange> range;  // in internal units
};

class Reader {
 public:
  // Opens the file; InputError if it cannot be read. `file` is also the name errors carry.
  // The first `skip_lines` lines (a logger's preamble: whatever they hold) are not read; line
  // numbers in errors still count them.
  explicit Reader(const std::filesystem::path& file, std::size_t skip_lines = 0);
  // A reader of the data lines in `slice`, a part of the file `whole` reads that starts at a
  // line's start, after the header (header, line ends and file name as `whole`'s). Its lines
  // are numbered from `lines_before` + 1; a line of kMaxLineBytes or more is refused as `whole`
  // would. The data row limit is not checked (a slice does not know the rows before it).
  Reader(const Reader& whole, std::string_view slice, long lines_before);
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  const std::string& file() const { return file_; }

  // Reads the first line after the skipped ones that is neither blank nor a comment. Throws for an empty file and
  // for a header that is one cell but looks ';'- or tab-separated.
  void read_header();
  const std::vector<std::string>& header() const { return header_; }
  long header_line() const { return header_line_; }

  // Instead of read_header and next: the file's line `line` (1-based, whatever it holds) as the
  // current row, for an error at one of its cells; false when the file is shorter.
  bool seek_line(long line);

  // Advances to the next data row; false at the end of the file. Throws for a row whose
  // number of cells differs from the header's.
  bool next();
  long line() const { return line_; }

  // Cell i of the current row as written (quotes included, spaces kept).
  std::string_view cell(std::size_t i) const { return cells_[i]; }
  // Cell i as text: quotes removed and "" unescaped (into `scratch` only when needed).
  std::string_view text(std::size_t i, std::string& scratch) const;
  // The number in the column's cell in internal units, checked against the column's Rule and
  // physical range.
  // An empty or NaN cell returns NaN when `allow_missing`, and throws otherwise.
  double number(const Column& column, bool allow_missing) const;

  // Throws InputError at cell i of the current row (column = its character position).
  [[noreturn]] void fail(std::size_t i, const std::string& what) const;
  // Throws InputError at the current line and a 1-based character column (0: none).
  [[noreturn]] void fail_at(long line, long column, const std::string& what) const;

  // Bytes consumed so far (the file size once next() returned false).
  std::uintmax_t bytes() const { return bytes_read_; }
  // The file's size when it was opened.
  std::uintmax_t file_size() const { return file_size_; }

  // The rest of the file after the current line, read whole (the pieces read in parallel) and
  // cut at line ends into `count` slices in file order, for Reader(whole, slice, lines_before);
  // nullopt when the file no longer has the size it had when it was opened (it is being written:
  // read it line by line). A file reader only.
  struct Rest {
    std::unique_ptr<char[]> bytes;
    std::vector<std::string_view> slices;
  };
  std::optional<Rest> read_rest(int count) const;
  // Data rows still to come, extrapolated from the line lengths of the first chunk (for reserve()).
  std::size_t estimated_rows() const;

 private:
  void start();         // the first chunk read: byte-order mark and line ends found
  bool next_line();     // the next raw line into line_begin_/line_end_; false at the end
  bool refill();        // moves the unread tail to the front and reads more; false at the end
  void split();         // cells of the current line into cells_
  void split_quoted();  // the same, for a line with quotes
  long column_of(const char* where) const;
  double parse_other(const Column& column, bool allow_missing) const;  // all but plain decimals
  static bool satisfies(Rule rule, double value);
  [[noreturn]] void fail_rule(const Column& column) const;
  [[noreturn]] void fail_number(const Column& column, std::string_view found, const char* expected) const;
  bool looks_like_decimal_commas() const;  // the row's cells, as split

  struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };

  std::string file_;
  std::unique_ptr<std::FILE, FileCloser> stream_;
  std::uintmax_t file_size_ = 0;
  std::uintmax_t bytes_read_ = 0;
  std::vector<char> buffer_;
  const char* data_ = nullptr;     // buffer_, or a slice's bytes
  std::size_t pos_ = 0, end_ = 0;  // unread part of data_
  bool at_eof_ = false;
  char eol_ = '\n';       // '\r' for a file whose lines end in a bare CR
  long line_ = 0;
  std::size_t rows_ = 0;  // data rows so far
  const char* line_begin_ = nullptr;
  const char* line_end_ = nullptr;  // without the line break
  std::vector<std::string_view> cells_;
  std::vector<std::string> header_;
  long header_line_ = 0;
  std::size_t skip_lines_ = 0;
  bool slice_ = false;  // reads a slice of the file in memory
};

// conversion.apply(value), except that canonical units leave the value untouched: x * 1 + 0
// would turn -0 into +0 and break exact round trips.
inline double to_internal(const Conversion& conversion, double value) {
  return conversion.scale == 1 && conversion.offset == 0 ? value : conversion.apply(value);
}

// How a name (a header cell, a manifest key) relates to a known base name with a unit suffix:
// "load_kgf" matches "load"; "load" has no unit; "load_lb" has an unknown unit; "loads_N" and
// "load_cell_N" (a force, but named "load_cell") are something else.
struct UnitMatch {
  enum Kind { other, match, no_unit, unknown_unit } kind = other;
  SplitName split;   // kind == match
  std::string unit;  // kind == unknown_unit: the suffix as written
};
UnitMatch match_unit(std::string_view name, std::string_view base, Quantity quantity);

// "load_N, load_kN, load_kgf, load_lbf": the names `base` may take, for messages.
std::string accepted_names(std::string_view base, Quantity quantity);
// `base` with the quantity's internal unit: "load_N".
std::string canonical_name(std::string_view base, Quantity quantity);

// column.reserve(rows), the new storage preferring huge pages and mapped at once.
template <typename T>
void reserve_rows(std::vector<T>& column, std::size_t rows) {
  const T* before = column.data();
  column.reserve(rows);
  if (column.data() == before) return;  // the storage it had
  detail::prefer_huge_pages(column.data(), column.capacity() * sizeof(T));
  detail::populate_pages(column.data(), column.capacity() * sizeof(T));
}

// Binds the header cells to `specs` (in header order). Call it before the first next(): errors
// point into the header line. Unknown columns are listed in
// report.ignored_columns (with a warning in report.warnings when one looks like a known
// column — another case, a short alias such as `dir` or `temp`, one letter off — or like a
// timestamp) and unit conversions in report.conversions. Throws for a known
// column with no or an unknown unit, for a column given twice (even in different units)
// and for a required column that is missing.
std::vector<Column> bind_header(const Reader& reader, std::span<const ColumnSpec> specs, LoadReport& report);

// Throws InputError at cell `cell` of data line `line` of `file`, reading the file again to
// find the cell's character position (for errors found after the whole file was read).
[[noreturn]] void fail_at_cell(const std::filesystem::path& file, long line, std::size_t cell, const std::string& what);

// "missing column 'load_N' (accepted units: …)": what bind_header says of a required column.
std::string missing_column(const ColumnSpec& spec);

// The first column bound to spec `spec`, or nullptr.
const Column* find_column(const std::vector<Column>& columns, std::size_t spec);

}  // namespace lmcal::csv
