// Tidy CSV text, built in memory and written whole (see atomic_file.hpp). Numbers print
// in their shortest form that reads back exactly; text cells are quoted when needed.
//
// Example:
//   lmcal::CsvText csv({"time_s", "tc1_C"});
//   csv.cell(0.0).cell(26.1).end_row();
//
// Trap: end_row() checks the cell count against the header and aborts on a mismatch.
#pragma once

#include "lmcal/export.hpp"

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace LMCAL_API lmcal {

// Whether text written to a CSV cell gets a leading apostrophe: it starts with = + - @, a tab or
// a CR (a spreadsheet would take it for a formula), or with an apostrophe before one of those
// or another apostrophe (so that reading removes exactly the one added; docs/formats.md).
bool csv_formula_escape_needed(std::string_view text);

class CsvText {
 public:
  explicit CsvText(const std::vector<std::string>& header, const std::vector<std::string>& comments = {});
  CsvText& cell(double value);
  CsvText& cell(std::string_view text);
  CsvText& cell(const char* text) { return cell(std::string_view(text)); }
  CsvText& end_row();
  // About how many rows will follow (the text is then allocated once, after the first row).
  CsvText& expect_rows(std::size_t rows) {
    rows_expected_ = rows;
    return *this;
  }
  const std::string& str() const { return text_; }
  // The text, moved out: the comments and the header (its first header_bytes()), then the rows.
  std::string take() && { return std::move(text_); }
  std::size_t header_bytes() const { return header_bytes_; }

 private:
  std::size_t columns_, in_row_ = 0, header_bytes_ = 0, rows_expected_ = 0, rows_written_ = 0;
  std::string text_;
  struct LastCell {
    double value = 0;
    std::string text;  // empty: none yet
  };
  std::vector<LastCell> last_;  // per column: the last number written, and its text
};

// The text of a CSV of `rows` rows, `row(csv, i)` writing row i: the rows are written in slices
// on free threads (a 10⁵-row file's numbers take tens of milliseconds to print) and joined in
// order, the same text as writing them in turn.
std::string csv_text(const std::vector<std::string>& header, std::size_t rows,
                     const std::function<void(CsvText& csv, std::size_t row)>& row);

}  // namespace lmcal
