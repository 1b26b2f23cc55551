// Tidy CSV text, built in memory and written whole (see atomic_file.hpp). Numbers print
// in their shortest form that reads back exactly; text cells are quoted when needed.
//
// Example:
//   lmcal::CsvText csv({"time_s", "tc1_C"});
//   csv.cell(0.0).cell(26.1).end_row();
//
// Trap: end_row() checks the cell count against the header and aborts on a mismatch.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace lmcal {

class CsvText {
 public:
  explicit CsvText(const std::vector<std::string>& header, const std::vector<std::string>& comments = {});
  CsvText& cell(double value);
  CsvText& cell(std::string_view text);
  CsvText& cell(const char* text) { return cell(std::string_view(text)); }
  CsvText& end_row();
  const std::string& str() const { return text_; }

 private:
  std::size_t columns_, in_row_ = 0;
  std::string text_;
};

}  // namespace lmcal
