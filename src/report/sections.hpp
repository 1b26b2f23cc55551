// The report's sections (private to the report layer); html_report.cc puts them together.
#pragma once

#include "lmcal/report/calibration.hpp"
#include "page.hpp"

namespace lmcal::report {

void friction_section(Page& page, const Calibration& c);
void thermal_section(Page& page, const Calibration& c);

// The fit's parameters (those `show` accepts) with intervals, and their correlation matrix.
template <class Show>
void parameter_tables(Page& page, const FitResult& fit, const Show& show) {
  std::vector<std::vector<std::string>> rows;
  std::vector<std::size_t> shown;
  for (std::size_t j = 0; j < fit.parameters.size(); ++j) {
    const auto& p = fit.parameters[j];
    if (!show(p)) continue;
    shown.push_back(j);
    rows.push_back({p.name, p.unit, num(p.value, 5), num(p.se, 3), interval(p), flags(p)});
  }
  page.table({"parameter", "unit", "estimate", "standard error", "95 % interval", ""}, rows);
  for (const auto& issue : fit.identifiability.issues)
    page.paragraph("Not identifiable: " + issue.why + ". To separate them: " + issue.measure + ".", "warning");
  for (const auto& w : fit.warnings) page.paragraph("Warning: " + w, "warning");
  if (shown.size() < 2 || fit.correlation.rows() == 0) return;
  std::vector<std::string> header{"correlation"};
  for (std::size_t j : shown) header.push_back(fit.parameters[j].name);
  rows.clear();
  for (std::size_t i : shown) {
    rows.push_back({fit.parameters[i].name});
    for (std::size_t j : shown)
      rows.back().push_back(correlation_cell(fit.correlation(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j))));
  }
  page.table(header, rows);
}

// The candidates of every forward step, and the accepted causes.
void candidate_tables(Page& page, const std::vector<std::vector<CandidateScore>>& rounds, const char* unit);

}  // namespace lmcal::report
