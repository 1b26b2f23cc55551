// How sure the calibrated model is, fit by fit: the standard error of every global parameter
// by covariance method side by side (and the quoted one over the iid one), what the
// residuals' autocorrelation leaves of the sample, whether the runs disagree beyond their own
// errors, and each run's own estimate against the pooled estimate's quoted 95 % interval.
#include <algorithm>
#include <cmath>
#include <optional>
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

// The multi-start waterfall: where each local search ended, best first, relative to the best.
// Starts on the flat line at 1 found the same minimum; a staircase means the cost surface has
// several, and the best is only as sure as the count of starts that reached it.
std::optional<Plot> waterfall_plot(const std::string& id, const SolverReport& s) {
  std::vector<double> costs = s.start_costs;
  if (costs.size() < 2) return std::nullopt;
  std::sort(costs.begin(), costs.end());
  const double best = costs.front();
  if (!(best > 0)) return std::nullopt;
  Plot plot{.id = id,
            .title = fmt::format("Multi-start: {} of {} searches reached the best minimum", s.starts_agreed, s.starts),
            .x_label = "start, ranked by where it ended",
            .y_label = fmt::format("cost / best cost ({} residuals)", s.start_residuals),
            .log_y = true};
  Series ends{.label = "each start", .mark = Mark::points, .color = colour(0)};
  for (std::size_t k = 0; k < costs.size(); ++k) {
    ends.x.push_back(static_cast<double>(k + 1));
    ends.y.push_back(costs[k] / best);
  }
  plot.series.push_back(std::move(ends));
  plot.references.push_back({.horizontal = true, .at = 1 + 1e-3, .label = "agrees (within 0.1 %)"});
  plot.width_px = 640;
  return plot;
}

// A parameter's profile: held at each value, the rest refitted; the quoted interval is where
// the curve crosses 1, and the dashed parabola is what the linear interval assumes.
Plot profile_plot(const std::string& id, const ParameterEstimate& p) {
  Plot plot{.id = id,
            .title = fmt::format("Profile of {}: {}", p.name, interval(p)),
            .x_label = p.unit.empty() || p.unit == "1" ? p.name : fmt::format("{} ({})", p.name, p.unit),
            .y_label = "cost rise / 95 % threshold"};
  Series profile{.label = "profile (others refitted)", .mark = Mark::line_points, .color = colour(0)};
  Series linear{.label = "linear interval's parabola", .color = colour(1), .dashed = true};
  const double half = 0.5 * (p.ci_high - p.ci_low);
  for (const ProfilePoint& point : p.profile_curve) {
    profile.x.push_back(point.value);
    profile.y.push_back(point.excess);
    if (half > 0) {
      linear.x.push_back(point.value);
      linear.y.push_back(std::pow((point.value - p.value) / half, 2));
    }
  }
  plot.y_min = 0;
  plot.y_max = 2.5;
  plot.series.push_back(std::move(profile));
  if (!linear.x.empty()) plot.series.push_back(std::move(linear));
  plot.references.push_back({.horizontal = true, .at = 1, .label = "95 %"});
  plot.width_px = 640;
  return plot;
}

// Everything a fit's uncertainty says, except the per-run plots; figure ids start `id`. The
// waterfall is `searched`'s: the fit whose multi-start found the minimum this one started from.
void fit_panel(Page& page, const FitResult& fit, const std::string& id, const FitResult& searched) {
  const std::vector<std::size_t> shown = estimated(fit);
  page.paragraph(intervals_statement(fit.uncertainty));
  method_table(page, fit, shown);
  structure_paragraph(page, fit);
  heterogeneity_table(page, fit.uncertainty);
  correlation_table(page, fit, shown);
  std::vector<Plot> figures;
  for (std::size_t j : shown)
    if (fit.parameters[j].interval == "profile" && fit.parameters[j].profile_curve.size() > 2)
      figures.push_back(profile_plot(fmt::format("{}profile-{}", id, j), fit.parameters[j]));
  if (!figures.empty())
    page.paragraph("Profile likelihood, where the quoted interval is the profile one: the parameter held at each value and "
                   "the others refitted. The interval is where the curve crosses 1 (the cost rise that a 95 % F test "
                   "allows, widened as the quoted covariance is); where the curve leaves the dashed parabola the linear "
                   "interval would have been wrong.");
  if (auto waterfall = waterfall_plot(id + "starts", searched.solver)) {
    if (&searched != &fit)
      page.paragraph("The multi-start below is the law's fit, whose minimum this fit started from.");
    figures.push_back(std::move(*waterfall));
  }
  if (!figures.empty()) page.figures(figures);
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
  plot.series.push_back({.tooltip = "independent (−1.96/√n)", .x = {0.5, kLags + 0.5}, .y = {-band, -band}, .color = "#999999", .dashed = true});
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
    const FitResult shown = friction_fit_as_shown(*m.friction);
    const bool started_from_the_law = m.friction->fit.solver.start_costs.size() < 2 && c.friction;
    fit_panel(page, shown, "calibrated-friction-", started_from_the_law ? c.friction->fit : shown);
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
    fit_panel(page, t.joint, "calibrated-thermal-", t.joint);
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
  Series points{.label = legend ? "each run alone" : "", .tooltip = "run alone (±t·SE)", .mark = Mark::points, .color = colour(0)};
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
  const std::string pooled_name = legend ? pooled_label : "pooled";
  plot.series.push_back({.label = pooled_label, .tooltip = pooled_name, .x = across, .y = {pooled.value, pooled.value}, .color = colour(1)});
  plot.series.push_back({.label = legend ? "its 95 % interval" : "", .tooltip = pooled_name + ", 95 % interval low", .x = across,
                         .y = {low, low}, .color = colour(1), .dashed = true});
  plot.series.push_back({.tooltip = pooled_name + ", 95 % interval high", .x = across, .y = {high, high}, .color = colour(1), .dashed = true});
  return plot;
}

}  // namespace lmcal::report
