// The thermal fit written out: its JSON, the samples' and the α curve's CSV, the terminal
// summary, and the names of its options' values they use.
#include "lmcal/version.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "fit_json.hpp"
#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/io/csv_writer.hpp"

namespace lmcal {

using detail::number;

const char* to_string(ThermalOffsets offsets) {
  switch (offsets) {
    case ThermalOffsets::automatic: return "auto";
    case ThermalOffsets::fitted: return "fit";
    case ThermalOffsets::held: return "hold";
  }
  return "?";
}

const char* to_string(ThermalTermKind kind) {
  switch (kind) {
    case ThermalTermKind::time: return "t";
    case ThermalTermKind::time_squared: return "t^2";
    case ThermalTermKind::ambient_in_phase: return "a_P";
    case ThermalTermKind::ambient_quadrature: return "b_P";
    case ThermalTermKind::ambient_lag: return "lag_tau(Tamb)-Tamb";
    case ThermalTermKind::ambient_change: return "Tamb-Tamb0";
    case ThermalTermKind::rise_time: return "rise*t";
    case ThermalTermKind::velocity_time: return "V*t";
  }
  return "?";
}

bool term_has_scale(ThermalTermKind kind) {
  return kind == ThermalTermKind::ambient_in_phase || kind == ThermalTermKind::ambient_quadrature ||
         kind == ThermalTermKind::ambient_lag;
}

const char* term_coefficient_unit(ThermalTermKind kind) {
  switch (kind) {
    case ThermalTermKind::time: return "K/h";
    case ThermalTermKind::time_squared: return "K/h2";
    case ThermalTermKind::rise_time: return "1/h";
    case ThermalTermKind::velocity_time: return "K/(h m/s)";
    default: return "1";  // K per K of the ambient
  }
}

std::string thermal_fit_json(const ThermalFitResult& r, const ThermalFitOptions& o,
                             const std::vector<std::pair<std::string, std::string>>& inputs,
                             const std::vector<std::string>& command, const std::string& name) {
  nlohmann::json runs = nlohmann::json::array();
  for (std::size_t i = 0; i < r.runs.size(); ++i) {
    const auto& info = r.runs[i];
    nlohmann::json run = {{"id", info.id},
                          {"velocity_m_s", info.velocity_m_s},
                          {"load_N", info.load_N},
                          {"heat_rate_W", info.heat_rate_W},
                          {"heat_source", info.heat_source},
                          {"initial_temperature_C", info.initial_temperature_C},
                          {"ambient_sensors_percent_difference_eq2", number(info.ambient_difference_percent)}};
    if (i < r.per_run.size()) run["fit"] = detail::fit_json(r.per_run[i]);
    runs.push_back(run);
  }
  nlohmann::json goodness = nlohmann::json::array();
  for (const auto& g : r.goodness)
    goodness.push_back({{"run", g.run},
                        {"sensor", g.sensor},
                        {"position_m", g.position_m},
                        {"n", g.n},
                        {"rmse_K", number(g.rmse_K)},
                        {"max_error_K", number(g.max_error_K)},
                        {"max_error_percent", number(g.max_error_percent)}});
  nlohmann::json repeats = nlohmann::json::array();
  for (const auto& d : r.repeat_differences)
    repeats.push_back({{"runs", d.runs},
                       {"alpha_percent_difference_eq2", number(d.percent)},
                       {"z", number(d.z)},
                       {"z_within_run_se_only", number(d.z_within)}});
  const RandomEffects& re = r.alpha_runs;
  const nlohmann::json random_effects_json = {{"runs", re.k},
                                              {"mean", number(re.mean)},
                                              {"se", number(re.mean_se)},
                                              {"ci95", {number(re.mean_low), number(re.mean_high)}},
                                              {"tau", number(re.tau)},
                                              {"tau_ci95", {number(re.tau_low), number(re.tau_high)}},
                                              {"cochran_q", number(re.q)},
                                              {"q_p", number(re.q_p)},
                                              {"i_squared", number(re.i2)},
                                              {"method", re.method}};
  nlohmann::json in = nlohmann::json::array();
  for (const auto& [file, hash] : inputs) in.push_back({{"file", file}, {"sha256", hash}});
  const auto& s = r.alpha_spread;
  nlohmann::json j = {{"kind", "thermal fit"},
                      {"name", name},
                      {"lmcal_version", LMCAL_VERSION}, {"schema_version", kOutputSchemaVersion},
                      {"command", command},
                      {"inputs", in},
                      {"options",
                       {{"source", to_string(o.source)},
                        {"scheme", to_string(o.scheme)},
                        {"half_rail_segments", o.half_rail_segments},
                        {"time_step_s", o.time_step_s},
                        {"every", o.every},
                        {"ambient", o.ambient},
                        {"fit_h", o.fit_h},
                        {"offsets", to_string(o.offsets)},
                        {"fit_initial_temperature", o.fit_initial_temperature},
                        {"extensions", o.extensions}}},
                      {"cv_rmse_K", number(r.cv_rmse_K)},
                      {"joint", detail::fit_json(r.joint)},
                      {"alpha_across_runs",
                       {{"n", s.n},
                        {"mean", number(s.mean)},
                        {"sd_eq1", number(s.sd)},
                        {"ci95", {number(s.low), number(s.high)}},
                        {"half_width", number(s.half_width)},
                        {"min", number(s.min)},
                        {"max", number(s.max)},
                        {"random_effects", random_effects_json}}},
                      {"repeats", repeats},
                      {"source_comparison",
                       {{"other_source", r.other_source},
                        {"other_source_alpha", number(r.other_source_alpha)},
                        {"alpha_paper_over_averaged", number(r.alpha_ratio_paper_over_averaged)},
                        {"contact_over_stroke", number(r.contact_over_stroke)}}},
                      {"runs", runs},
                      {"goodness", goodness},
                      {"max_error_percent", number(r.max_error_percent)}};
  if (!o.sensor_terms.empty()) {  // empirical terms (a diagnosis's); absent otherwise, so plain fits keep their bytes
    nlohmann::json terms = nlohmann::json::array();
    for (const auto& t : o.sensor_terms) {
      terms.push_back({{"kind", to_string(t.kind)}, {"coefficient_unit", term_coefficient_unit(t.kind)}});
      if (term_has_scale(t.kind)) terms.back()["scale_s"] = t.scale_s;
    }
    j["options"]["sensor_terms"] = terms;
  }
  return j.dump(2) + "\n";
}

std::string thermal_fit_samples_csv(const ThermalFitResult& r) {
  return csv_text({"run", "line", "sensor", "time_s", "measured_C", "simulated_C", "residual_K"}, r.samples.size(),
                  [&](CsvText& csv, std::size_t i) {
                    const auto& s = r.samples[i];
                    csv.cell(r.runs[s.run].id).cell(s.line > 0 ? std::to_string(s.line) : "");
                    csv.cell(r.sensor_names[s.run][s.sensor]).cell(s.time_s).cell(s.measured_C);
                    csv.cell(s.simulated_C).cell(s.measured_C - s.simulated_C).end_row();
                  });
}

std::vector<std::pair<std::string, std::string>> thermal_fit_files(const ThermalFitResult& result,
                                                                   const ThermalFitOptions& options,
                                                                   const std::vector<std::pair<std::string, std::string>>& inputs,
                                                                   const std::vector<std::string>& command,
                                                                   const std::string& name) {
  return {{name + ".json", thermal_fit_json(result, options, inputs, command, name)},
          {name + "_samples.csv", thermal_fit_samples_csv(result)},
          {name + "_alpha_curve.csv", thermal_fit_curve_csv(result)}};
}

std::string thermal_fit_curve_csv(const ThermalFitResult& r) {
  CsvText csv({"run", "alpha", "rmse_K", "max_error_K"});
  for (const auto& p : r.alpha_curve) csv.cell(p.run).cell(p.alpha).cell(p.rmse_K).cell(p.max_error_K).end_row();
  return csv.str();
}

std::string thermal_fit_summary(const ThermalFitResult& r) {
  std::string s;
  s += fmt::format("{} runs, {} records; joint fit over all runs:\n", r.runs.size(), r.joint.residuals);
  for (const auto& p : r.joint.parameters) {
    const std::string interval = p.interval == "profile" ? fmt::format("[{:.4g}, {:.4g}] profile", p.profile_low, p.profile_high)
                                 : p.interval == "linear" ? fmt::format("[{:.4g}, {:.4g}]", p.ci_low, p.ci_high)
                                 : p.interval != "none" ? fmt::format("[{:.4g}, {:.4g}] {} scale", p.ci_low, p.ci_high, p.interval)
                                                          : std::string("held");
    s += fmt::format("  {:<24} {:>10.5g} ± {:<9.3g} {:<9} {}{}\n", p.name, p.value, p.se, shown_unit(p.unit), interval,
                     p.at_bound ? "  at a bound" : "");
  }
  s += fmt::format("  residual sigma {:.3f} K; {}\n", std::sqrt(r.joint.residual_variance), r.joint.solver.termination);
  s += detail::uncertainty_summary(r.joint);
  if (!r.heat_uncertainty.empty()) s += "  the heat's uncertainty: " + r.heat_uncertainty + "\n";
  for (const auto& run : r.runs)
    if (!run.offsets_note.empty()) s += fmt::format("  {}: {}\n", run.id, run.offsets_note);
  if (std::isfinite(r.cv_rmse_K)) s += fmt::format("  leave-one-run-out prediction RMSE {:.4f} K\n", r.cv_rmse_K);
  for (const auto& issue : r.joint.identifiability.issues)
    s += fmt::format("  NOT IDENTIFIABLE: {} -> held {}; {}\n", issue.why, fmt::join(issue.held, ", "), issue.measure);
  if (!r.per_run.empty()) {
    s += "per run:\n";
    for (std::size_t i = 0; i < r.per_run.size(); ++i) {
      const auto& p = r.per_run[i].parameter("alpha");
      const double ambient = r.runs[i].ambient_difference_percent;
      s += fmt::format("  {:<10} V {:.3f} m/s  Q {:.2f} W  alpha {:.4f} ± {:.4f}{}\n", r.runs[i].id, r.runs[i].velocity_m_s,
                       r.runs[i].heat_rate_W, p.value, p.se,
                       std::isfinite(ambient) ? fmt::format("  ambient sensors differ {:.1f} % (Eq. 2)", ambient)
                                              : "  one ambient sensor (no comparison)");
    }
    const auto& sp = r.alpha_spread;
    if (sp.n < 2)
      s += fmt::format("alpha {}\n", across_runs(sp));
    else
      s += fmt::format("alpha across runs: {:.3f} ± {:.3f} (mean ± 95 % t half-width; spread of runs (Eq. 1 sigma) {:.4f}, n {}, min {:.3f}, max {:.3f})\n",
                       sp.mean, sp.half_width, sp.sd, sp.n, sp.min, sp.max);
    const RandomEffects& re = r.alpha_runs;
    if (re.k >= 2 && re.tau > 0)
      s += fmt::format("  the runs' alpha differ beyond their own SEs by tau = {:.3g} (REML; Cochran's Q = {:.3g} on {} runs, p = "
                       "{:.2g}, I2 = {:.0f} %): a run's alpha is known to sqrt(SE^2 + tau^2), not to its own SE; random-effects "
                       "mean {:.4f}, 95 % [{:.4f}, {:.4f}] (Hartung-Knapp)\n",
                       re.tau, re.q, re.k, re.q_p, 100 * re.i2, re.mean, re.mean_low, re.mean_high);
    for (const auto& d : r.repeat_differences)
      s += fmt::format("  repeats {}: alpha differs {:.1f} % (Eq. 2); z = {:.2f} against sqrt(SE1^2 + SE2^2 + 2 tau^2) ({:.2f} "
                       "against their own SEs alone)\n",
                       d.runs, d.percent, d.z, d.z_within);
  }
  s += "goodness per sensor (joint fit):\n";
  for (const auto& g : r.goodness)
    s += fmt::format("  {:<10} {:<8} x {:.3f} m  RMSE {:.3f} K  max error {:.3f} K ({:.1f} % of the span)\n", g.run, g.sensor,
                     g.position_m, g.rmse_K, g.max_error_K, g.max_error_percent);
  s += fmt::format("max error {:.1f} % of the measured span (each sensor's highest minus lowest 10-record mean, at least a "
                   "tenth of the widest sensor's; the paper reports 12 % of the rise)\n",
                   r.max_error_percent);
  if (!r.other_source.empty())
    s += fmt::format(
        "source model: alpha with `{}` is {:.4f}; alpha(paper) / alpha(averaged) = {:.3f} (Lb1/L1 = {:.3f}: the paper's "
        "source puts L1/Lb1 times the block's power into the rail, so its alpha is smaller by about that factor)\n",
        r.other_source, r.other_source_alpha, r.alpha_ratio_paper_over_averaged, r.contact_over_stroke);
  for (const auto& w : r.joint.warnings) s += "warning: " + w + "\n";
  return s;
}

}  // namespace lmcal
