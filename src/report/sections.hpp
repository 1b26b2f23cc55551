// The report's sections (private to the report layer); html_report.cc puts them together.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "lmcal/calibrate/calibration.hpp"
#include "page.hpp"

namespace lmcal::report {

// The first screen: the calibrated model, every parameter with its interval and where it comes from.
void calibrated_section(Page& page, const Calibration& c);
// How sure the calibrated model is: the standard errors of every covariance method, the
// residuals' autocorrelation, the between-run tests, the per-run estimates against the pooled band.
void how_sure_section(Page& page, const Calibration& c);
void friction_section(Page& page, const Calibration& c);
// Fig. 6: the measured force over velocity by load, preload and temperature, with the published
// law and (when the diagnosis accepted causes) the law with them, each curve carrying its fit's
// mean zero offset of the runs drawn, so that it passes through the points it was fitted to.
std::vector<Plot> friction_velocity_panels(const Calibration& c);
void thermal_section(Page& page, const Calibration& c);
// What was loaded, converted, skipped and ignored; the data checks' warnings.
void data_section(Page& page, const Calibration& c);

// Did the diagnosis accept causes, i.e. reject the published model?
template <class Diagnosis>
bool rejects(const std::optional<Diagnosis>& d) {
  return d && !d->accepted.empty();
}

// How a fit of the published model is named wherever it appears.
inline std::string published_label(bool rejected) {
  return rejected ? "published model (for comparison; conditional on a model the diagnosis rejects)" : "published model";
}

// "95 % intervals: <method> — <reason>".
inline std::string intervals_statement(const Uncertainty& u) { return fmt::format("95 % intervals: {} — {}", u.method, u.reason); }

// What the data cannot determine, and the fit's warnings.
void fit_caveats(Page& page, const FitResult& fit);

// The correlation matrix of the parameters `shown` (indices into fit.parameters).
void correlation_table(Page& page, const FitResult& fit, const std::vector<std::size_t>& shown);

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
  fit_caveats(page, fit);
  correlation_table(page, fit, shown);
}

// The CSS classes of a verdict: its words as lower-case letters, digits and single '-', each
// part of "unexplained — empirical term found" a class of its own
// ("unexplained empirical-term-found"), so that the base verdict keeps its style.
inline std::string verdict_class(std::string_view verdict) {
  std::string classes;
  bool gap = false;  // a '-' is due before the next letter or digit
  for (std::size_t i = 0; i < verdict.size(); ++i) {
    if (verdict.substr(i).starts_with("—")) {
      if (!classes.empty() && classes.back() != ' ') classes += ' ';
      gap = false;
      i += std::string_view("—").size() - 1;
    } else if (const char ch = verdict[i]; std::isalnum(static_cast<unsigned char>(ch))) {
      if (gap && !classes.empty() && classes.back() != ' ') classes += '-';
      classes += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      gap = false;
    } else {
      gap = true;
    }
  }
  while (!classes.empty() && classes.back() == ' ') classes.pop_back();
  return classes;
}

// The verdict, styled by its class, and the summary.
// A summary without the verdict it starts with ("Unexplained: the residuals …" -> "the
// residuals …"), for a line that prints the verdict before it: said once, not twice.
inline std::string without_verdict(const std::string& summary) {
  for (std::string_view word : {"No significant discrepancy: ", "Partly explained: ", "Unexplained: ", "Explained: "})
    if (summary.starts_with(word)) return summary.substr(word.size());
  return summary;
}

inline void verdict_paragraph(Page& page, const std::string& verdict, const std::string& summary) {
  page << fmt::format("<p class=\"verdict {}\"><b>{}</b>: {}</p>\n", verdict_class(verdict), escape_xml(verdict),
                      escape_xml(without_verdict(summary)));
}

// What the diagnosis learned beyond its library of named causes (nothing unless it searched):
// the empirical term, labelled as not a named cause, its components with their intervals, the
// held-out gain, what it resembles, the ranges it was learned on and its curve (plot ID
// `id_prefix` + "-empirical-term"); or, when none was kept, why. `unit`: the residuals'.
void empirical_section(Page& page, const EmpiricalFinding& e, const std::string& id_prefix, const std::string& unit);

// The candidates of every forward step, and the accepted causes.
void candidate_tables(Page& page, const std::vector<std::vector<CandidateScore>>& rounds, const char* unit);

// The steps from the baseline (its held-out RMSE `baseline`) to the final model: before, after, gain.
void steps_table(Page& page, const std::vector<DiagnosisStep>& steps, double baseline, const char* unit);

// The lack-of-fit test of the baseline and of the final model, and what the design hides.
void lack_of_fit_paragraph(Page& page, const LackOfFit& baseline, const LackOfFit& final, const std::string& unit,
                           const std::vector<std::string>& design_notes = {});

// The parameters that move once the causes are modelled, both values with their 95 % intervals.
void shift_table(Page& page, const std::vector<ParameterShift>& shifts, const std::string& published);

// The per-run estimates of one parameter (`half_width_95`: their own ±t·SE, empty or NaN where
// unknown), beside the pooled estimate and its quoted 95 % interval (dashed lines).
struct PerRun {
  std::vector<double> value, half_width_95;
  std::vector<std::string> names;  // the runs' names: the x axis's ticks when they fit
};
Plot per_run_plot(const std::string& id, const std::string& title, const ParameterEstimate& pooled, const PerRun& runs,
                  const std::string& pooled_label);
// One small plot per parameter of the friction fit's spread across runs (those with a per-run
// value), IDs `id_prefix` + the parameter, with a caption naming the runs.
void friction_run_figures(Page& page, const FrictionFitResult& f, const std::string& id_prefix);

// Each run's own estimate of a parameter of the rail model, with its ±t·SE.
PerRun per_run_estimates(const ThermalFitResult& f, const std::string& parameter);

}  // namespace lmcal::report
