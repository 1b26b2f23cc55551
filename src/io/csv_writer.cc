#include "lmcal/io/csv_writer.hpp"

#include <fmt/format.h>

#include "lmcal/error.hpp"

namespace lmcal {

CsvText::CsvText(const std::vector<std::string>& header, const std::vector<std::string>& comments)
    : columns_(header.size()) {
  for (const auto& line : comments) text_ += "# " + line + "\n";
  for (std::size_t i = 0; i < header.size(); ++i) text_ += (i ? "," : "") + header[i];
  text_ += '\n';
}

CsvText& CsvText::cell(double value) {
  text_ += in_row_++ ? "," : "";
  fmt::format_to(std::back_inserter(text_), "{}", value);
  return *this;
}

CsvText& CsvText::cell(std::string_view text) {
  text_ += in_row_++ ? "," : "";
  if (text.find_first_of(",\"\n") == std::string_view::npos) {
    text_ += text;
    return *this;
  }
  text_ += '"';
  for (char c : text) text_ += c == '"' ? std::string("\"\"") : std::string(1, c);
  text_ += '"';
  return *this;
}

CsvText& CsvText::end_row() {
  LMCAL_ASSERT(in_row_ == columns_, "CSV row with the wrong number of cells");
  text_ += '\n';
  in_row_ = 0;
  return *this;
}

}  // namespace lmcal
