// The report's "Data loaded" section: what the loaders read, converted, skipped and
// ignored, per file; the warnings of the data checks (data_checks.hpp); how the thermal runs
// were driven.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <map>

#include "sections.hpp"

namespace lmcal::report {

namespace {

std::string joined(const std::map<std::string, std::string>& m) {
  std::vector<std::string> parts;
  for (const auto& [k, v] : m) parts.push_back(fmt::format("{} ({})", k, v));
  return fmt::format("{}", fmt::join(parts, ", "));
}

std::string joined(const std::map<std::string, std::size_t>& m) {
  std::vector<std::string> parts;
  for (const auto& [k, v] : m) parts.push_back(fmt::format("{}: {}", k, v));
  return fmt::format("{}", fmt::join(parts, ", "));
}

std::vector<std::string> report_row(const LoadReport& r) {
  return {r.file,
          std::to_string(r.rows_read),
          std::to_string(r.rows_kept),
          joined(r.skipped),
          joined(r.conversions),
          fmt::format("{}", fmt::join(r.ignored_columns, ", ")),
          r.time_gaps ? std::to_string(r.time_gaps) : ""};
}

}  // namespace

void data_section(Page& page, const Calibration& c) {
  page.heading(2, "Data loaded", "data");
  if (c.warnings.empty()) {
    page.paragraph("No warnings: nothing in the data looks like a mistake the checks know (columns that resemble known "
                   "ones, signed forces given as magnitudes, heat from the paper's constants, runs that disagree with "
                   "the others).");
  } else {
    page << "<ul class=\"warning\">\n";
    for (const auto& w : c.warnings) page << "<li>" << escape_xml(w) << "</li>\n";
    page << "</ul>\n";
  }
  for (const auto& note : c.notes) page.paragraph("Note: " + note, "warning");
  std::vector<std::vector<std::string>> rows;
  if (c.friction_log)
    for (const auto& r : c.friction_log->reports) rows.push_back(report_row(r));
  if (c.thermal_data)
    for (const auto& run : c.thermal_data->runs) rows.push_back(report_row(run.trace.report));
  page.table({"file", "rows read", "kept", "skipped", "converted", "ignored columns", "time gaps"}, rows);
  if (c.thermal) {
    rows.clear();
    for (const auto& run : c.thermal->runs)
      rows.push_back({run.id, num(run.velocity_m_s), num(run.load_N), num(run.heat_rate_W), run.heat_source});
    page.table({"thermal run", "velocity (m/s)", "load (N)", "heat rate at the start (W)", "heat from"}, rows);
  }
}

}  // namespace lmcal::report
