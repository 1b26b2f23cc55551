// How sure the calibrated model is, fit by fit: the standard error of every global parameter
// by covariance method side by side (and the quoted one over the iid one), what the
// residuals' autocorrelation leaves of the sample, whether the runs disagree beyond their own
// errors, and each run's own estimate against the pooled estimate's quoted 95 % interval.
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "lmcal/fit/statistics.hpp"
#include "sections.hpp"

namespace lmcal::report {

namespace {

constexpr double kConfidence = 0.95;

// The global parameters the fit estimated (held and per-run nuisance ones left out).
std::vector<std::size_t> estimated(const FitResult& fit) {
  std::vector<std::size_t> shown;
  for (std::size_t j = 0; j < fit.parameters.size(); ++j) {
    const auto& p = fit.parameters[j];
    if (!nuisance(p) && p.free && !p.held_unidentifiable) shown.push_back(j);
  }
  return shown;
}

double se_of(const CovarianceSummary* m, std::size_t j) {
  return m && m->ok && j < m->se.size() ? m->se[j] : std::nan("");
}

// The SE of every parameter by method, the quoted one, its ratio to the iid one and (two-stage)
// the share of its variance that comes from the input's uncertainty; a last row with each
// method's t degrees of freedom.
void method_table(Page& page, const FitResult& fit, const std::vector<std::size_t>& shown) {
  const Uncertainty& u = fit.uncertainty;
  const CovarianceSummary* iid = u.find("iid");
  const bool input = !u.input.empty();
  std::vector<std::string> header{"standard error", "unit"};
  for (const auto& m : u.methods) header.push_back(m.ok ? m.method : m.method + " (failed)");
  header.insert(header.end(), {"quoted: " + u.method, "quoted / iid"});
  if (input) header.push_back("share of the variance from the " + u.input);
  std::vector<std::vector<std::string>> rows;
  for (std::size_t j : shown) {
    const ParameterEstimate& p = fit.parameters[j];
    rows.push_back({p.name, p.unit});
    for (const auto& m : u.methods) rows.back().push_back(num(se_of(&m, j), 3));
    rows.back().insert(rows.back().end(), {num(p.se, 3), num(p.se / se_of(iid, j), 3)});
    if (input) rows.back().push_back(j < u.input_variance_share.size() ? num(100 * u.input_variance_share[j], 3) + " %" : "–");
  }
  rows.push_back({"t degrees of freedom", ""});
  for (const auto& m : u.methods) rows.back().push_back(num(m.dof));
  rows.back().insert(rows.back().end(), {num(u.dof), ""});
  if (input) rows.back().push_back("");
  page.table(header, rows);
  rows.clear();
  for (const auto& m : u.methods) rows.push_back({m.method, m.description, m.note});
  page << "<details><summary>What each method assumes</summary>\n";
  page.table({"method", "what it assumes", "note"}, rows);
  page << "</details>\n";
}

// Residuals, runs, autocorrelation, effective sample size, Newey-West lags.
void structure_paragraph(Page& page, const FitResult& fit) {
  const Uncertainty& u = fit.uncertainty;
  std::string text = fmt::format("{} residuals", fit.residuals);
  if (u.runs > 0) text += fmt::format(" in {} runs", u.runs);
  text += fmt::format(". Lag-1 autocorrelation of the residuals within their series ρ = {}: effective sample size "
                      "n_eff = n (1 − ρ)/(1 + ρ) = {} of {}.",
                      num(u.lag1_autocorrelation, 3), num(u.effective_sample_size, 3), fit.residuals);
  if (std::isfinite(u.hac_lags)) text += fmt::format(" Newey-West (hac) lags: {}.", num(u.hac_lags, 3));
  page.paragraph(text);
}

// Cochran's Q per parameter: do the runs disagree beyond their own errors?
void heterogeneity_table(Page& page, const Uncertainty& u) {
  if (u.heterogeneity.empty()) return;
  std::vector<std::vector<std::string>> rows;
  for (const auto& h : u.heterogeneity)
    rows.push_back({h.parameter, std::to_string(h.runs), num(h.q, 3), p_value(h.p_value), p_value(h.p_holm),
                    num(100 * h.i_squared, 3) + " %", h.significant ? "yes" : "no"});
  page.paragraph("Between runs: Cochran's Q of each parameter against χ²(runs − 1), Holm-adjusted over the parameters; I² is "
                 "the share of the between-run spread that is real rather than noise.");
  page.table({"parameter", "runs", "Q", "p", "Holm p", "I²", "runs disagree"}, rows);
}

// Everything a fit's uncertainty says, except the per-run plots.
void fit_panel(Page& page, const FitResult& fit) {
  const std::vector<std::size_t> shown = estimated(fit);
  page.paragraph(intervals_statement(fit.uncertainty));
  method_table(page, fit, shown);
  structure_paragraph(page, fit);
  heterogeneity_table(page, fit.uncertainty);
  correlation_table(page, fit, shown);
}

// Each run's α alone: its heat, its offsets, its estimate and interval.
void thermal_run_table(Page& page, const ThermalFitResult& t) {
  std::vector<std::vector<std::string>> rows;
  for (std::size_t r = 0; r < t.runs.size(); ++r) {
    const RunInfo& info = t.runs[r];
    const ParameterEstimate* a = r < t.per_run.size() ? &t.per_run[r].parameter("alpha") : nullptr;
    rows.push_back({std::to_string(r + 1), info.id, num(info.velocity_m_s), a ? num(a->value) : "–", a ? num(a->se, 3) : "–",
                    a ? interval(*a) : "–", num(100 * info.heat_relative_se, 3) + " %",
                    info.offsets_fitted ? "fitted" : "held: " + info.offsets_note});
  }
  page.table({"", "run", "velocity (m/s)", "α alone", "SE", "95 % interval", "heat's relative SE", "thermocouple offsets"}, rows);
}

// The residuals' autocorrelation by lag, pooled over series (a run, or a run's sensor) in time
// order, with the band ±1.96/√n that independent residuals stay inside: what the quoted
// covariance has to account for, and why s²(JᵀJ)⁻¹ does not.
Plot autocorrelation_plot(const std::string& id, const std::string& title, const std::vector<std::vector<double>>& series,
                          double effective_n) {
  constexpr std::size_t kLags = 30;
  std::vector<double> c(kLags + 1, 0.0);
  double n = 0;
  for (const auto& x : series) {
    if (x.size() < 2) continue;
    double mean = 0;
    for (double v : x) mean += v / static_cast<double>(x.size());
    for (std::size_t lag = 0; lag <= kLags && lag < x.size(); ++lag)
      for (std::size_t i = lag; i < x.size(); ++i) c[lag] += (x[i] - mean) * (x[i - lag] - mean);
    n += static_cast<double>(x.size());
  }
  Plot plot{.id = id, .x_label = "lag (samples within a series)", .y_label = "autocorrelation"};
  Series acf{.label = "residuals", .mark = Mark::line_points, .color = colour(0)};
  for (std::size_t lag = 1; lag <= kLags && c[0] > 0; ++lag) {
    acf.x.push_back(static_cast<double>(lag));
    acf.y.push_back(c[lag] / c[0]);
  }
  plot.series.push_back(std::move(acf));
  const double band = n > 0 ? 1.96 / std::sqrt(n) : 0;
  plot.title = fmt::format("{} (n {:.0f}, effective {:.0f})", title, n, effective_n);
  plot.references.push_back({});  // zero
  plot.series.push_back(
      {.label = "independent (±1.96/√n)", .x = {0.5, kLags + 0.5}, .y = {band, band}, .color = "#999999", .dashed = true});
  plot.series.push_back({.x = {0.5, kLags + 0.5}, .y = {-band, -band}, .color = "#999999", .dashed = true});
  plot.width_px = 640;
  return plot;
}

}  // namespace

void how_sure_section(Page& page, const Calibration& c) {
  const CalibratedModel& m = c.calibrated;
  if (!m.friction && !m.thermal) return;
  page.heading(2, "How sure: the calibrated model's uncertainty", "how-sure");
  page.paragraph("Thermocouple traces and load-cell logs are time series in runs: neighbouring residuals are correlated and "
                 "runs differ by more than their noise, so s²(JᵀJ)⁻¹ (iid) understates the error. Each method's standard "
                 "error side by side; the quoted one is the method that fits the data's structure.");
  if (m.friction) {
    page.heading(3, "Friction law: how sure");
    fit_panel(page, m.friction->fit);
    friction_run_figures(page, *m.friction, "calibrated-friction-runs-");
    const FrictionLog& log = *c.friction_log;
    std::vector<std::vector<double>> runs(log.run_names.size());
    for (std::size_t i = 0; i < log.size() && i < m.friction->predicted_N.size(); ++i)
      runs[log.run[i]].push_back(log.friction_N[i] - m.friction->predicted_N[i]);
    page.figures({autocorrelation_plot("calibrated-friction-acf", "Friction residuals: autocorrelation within runs", runs,
                                       m.friction->fit.uncertainty.effective_sample_size)});
  }
  if (m.thermal) {
    const ThermalFitResult& t = *m.thermal;
    page.heading(3, "Rail model: how sure");
    fit_panel(page, t.joint);
    thermal_run_table(page, t);
    const ParameterEstimate& alpha = t.joint.parameter("alpha");
    Plot plot = per_run_plot("calibrated-thermal-runs-alpha", "α of each run alone (±t·SE) and the pooled 95 % interval", alpha,
                             per_run_estimates(t, "alpha"), "pooled (" + t.joint.uncertainty.method + ")");
    plot.width_px = 640;
    std::map<std::pair<std::size_t, std::size_t>, std::vector<double>> by_sensor;
    for (const auto& sample : t.samples) by_sensor[{sample.run, sample.sensor}].push_back(sample.measured_C - sample.simulated_C);
    std::vector<std::vector<double>> series;
    for (auto& [key, residuals] : by_sensor) series.push_back(std::move(residuals));
    page.figures({plot, autocorrelation_plot("calibrated-thermal-acf", "Rail-temperature residuals: autocorrelation within "
                                             "each run's sensor", series, t.joint.uncertainty.effective_sample_size)});
  }
}

PerRun per_run_estimates(const ThermalFitResult& f, const std::string& parameter) {
  PerRun out;
  for (std::size_t r = 0; r < f.per_run.size(); ++r) {
    const ParameterEstimate& p = f.per_run[r].parameter(parameter);
    out.value.push_back(p.value);
    out.half_width_95.push_back(student_t_quantile(0.5 + 0.5 * kConfidence, p.dof) * p.se);
    out.names.push_back(r < f.runs.size() ? f.runs[r].id : std::to_string(r + 1));
  }
  return out;
}

Plot per_run_plot(const std::string& id, const std::string& title, const ParameterEstimate& pooled, const PerRun& runs,
                  const std::string& pooled_label) {
  const bool legend = !pooled_label.empty();
  Plot plot{.id = id, .title = title, .x_label = "run",
            .y_label = pooled.unit.empty() || pooled.unit == "1" ? pooled.name : fmt::format("{} ({})", pooled.name, pooled.unit)};
  Series points{.label = legend ? "each run alone" : "", .mark = Mark::points, .color = colour(0)};
  for (std::size_t r = 0; r < runs.value.size(); ++r) {
    points.x.push_back(static_cast<double>(r + 1));
    points.y.push_back(runs.value[r]);
    points.y_error.push_back(r < runs.half_width_95.size() ? runs.half_width_95[r] : std::nan(""));
  }
  for (std::size_t r = 0; r < runs.names.size() && r < runs.value.size(); ++r)
    plot.x_tick_labels.emplace_back(static_cast<double>(r + 1), runs.names[r]);
  const std::vector<double> across{0.5, static_cast<double>(runs.value.size()) + 0.5};
  const auto [low, high] = quoted_bounds(pooled);
  plot.series.push_back(std::move(points));
  plot.series.push_back({.label = pooled_label, .x = across, .y = {pooled.value, pooled.value}, .color = colour(1)});
  plot.series.push_back({.label = legend ? "its 95 % interval" : "", .x = across, .y = {low, low}, .color = colour(1), .dashed = true});
  plot.series.push_back({.x = across, .y = {high, high}, .color = colour(1), .dashed = true});
  return plot;
}

}  // namespace lmcal::report
