#include "lmcal/io/csv_writer.hpp"

#include <fmt/compile.h>
#include <fmt/format.h>

#include <cstring>

#include "lmcal/error.hpp"
#include "parallel_slices.hpp"

namespace lmcal {

CsvText::CsvText(const std::vector<std::string>& header, const std::vector<std::string>& comments)
    : columns_(header.size()), last_(header.size()) {
  for (const auto& line : comments) text_ += "# " + line + "\n";
  for (std::size_t i = 0; i < header.size(); ++i) text_ += (i ? "," : "") + header[i];
  text_ += '\n';
  header_bytes_ = text_.size();
}

CsvText& CsvText::cell(double value) {
  LMCAL_ASSERT(in_row_ < columns_, "CSV row with too many cells");
  if (in_row_ > 0) text_ += ',';
  // A column that repeats its value (a condition held for a stretch of samples) reuses the
  // text: the shortest round-trip conversion is most of a 10⁵-row file's time.
  LastCell& last = last_[in_row_++];
  if (!last.text.empty() && std::memcmp(&last.value, &value, sizeof value) == 0) {
    text_ += last.text;
    return *this;
  }
  char buffer[40];
  // The shortest text that reads back the same (fmt's "{}", compiled: no format parsing).
  char* end = fmt::format_to(buffer, FMT_COMPILE("{}"), value);
  last.value = value;
  last.text.assign(buffer, end);
  text_ += last.text;
  return *this;
}

namespace {
bool formula_start(char c) { return c == '=' || c == '+' || c == '-' || c == '@' || c == '\t' || c == '\r'; }
}  // namespace

bool csv_formula_escape_needed(std::string_view text) {
  return !text.empty() && (formula_start(text[0]) || (text[0] == '\'' && text.size() > 1 && (formula_start(text[1]) || text[1] == '\'')));
}

CsvText& CsvText::cell(std::string_view text) {
  LMCAL_ASSERT(in_row_ < columns_, "CSV row with too many cells");
  if (in_row_++) text_ += ',';
  // A spreadsheet would run a cell starting with = + - @ (or a tab, a CR) as a formula: such
  // text gets a leading apostrophe, which spreadsheets show as text and lmcal's reader removes
  // (csv::formula_escaped). So does text that starts with an apostrophe before one of those.
  std::string escaped;
  if (csv_formula_escape_needed(text)) {
    escaped.reserve(text.size() + 1);
    escaped.push_back('\'');
    escaped.append(text.data(), text.size());
    text = escaped;
  }
  // Quoted where it would not read back as written: separators, quotes and line ends inside, a
  // leading '#' (a comment line), spaces at either end (trimmed when unquoted).
  const bool plain = text.find_first_of(",\"\n\r") == std::string_view::npos && !text.starts_with('#') &&
                     !text.starts_with(' ') && !text.ends_with(' ') && !text.starts_with('\t') && !text.ends_with('\t');
  if (plain) {
    text_ += text;
    return *this;
  }
  text_ += '"';
  for (char c : text) {
    text_ += c;
    if (c == '"') text_ += '"';  // a quote inside is doubled
  }
  text_ += '"';
  return *this;
}

CsvText& CsvText::end_row() {
  LMCAL_ASSERT(in_row_ == columns_, "CSV row with the wrong number of cells");
  text_ += '\n';
  in_row_ = 0;
  // The first row tells the size of the rest: one allocation instead of a doubling series.
  if (rows_expected_ > 0 && rows_written_++ == 0)
    text_.reserve(text_.size() + (text_.size() - header_bytes_) * (rows_expected_ + rows_expected_ / 8));
  return *this;
}

std::string csv_text(const std::vector<std::string>& header, std::size_t rows,
                     const std::function<void(CsvText& csv, std::size_t row)>& row) {
  constexpr std::size_t kRowsPerThread = 16384;
  const int threads = detail::slice_threads(rows, kRowsPerThread);
  std::vector<std::string> texts(static_cast<std::size_t>(threads));
  std::size_t header_bytes = 0;
  detail::for_each_slice(rows, threads, [&](int slice, std::size_t begin, std::size_t end) {
    // On this thread's stack: slices side by side in one array would share cache lines, which
    // every cell writes (a 100 k-row file took longer on 2 threads than on 1).
    CsvText csv(header);
    csv.expect_rows(end - begin);
    for (std::size_t i = begin; i < end; ++i) row(csv, i);
    if (slice == 0) header_bytes = csv.header_bytes();
    texts[static_cast<std::size_t>(slice)] = std::move(csv).take();
  });
  // The first slice's text, then the others' rows (each slice wrote the header too).
  std::size_t bytes = texts.front().size();
  for (std::size_t s = 1; s < texts.size(); ++s) bytes += texts[s].size() - header_bytes;
  std::string text = std::move(texts.front());
  text.reserve(bytes);
  for (std::size_t s = 1; s < texts.size(); ++s) text.append(texts[s], header_bytes);
  return text;
}

}  // namespace lmcal
