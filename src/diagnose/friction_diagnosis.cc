#include "lmcal/diagnose/friction_diagnosis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <tuple>

#include "lmcal/error.hpp"
#include "lmcal/fit/statistics.hpp"
#include "fit/fit_json.hpp"
#include "selection.hpp"

namespace lmcal {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A fit of the law plus `effects`, started at `start` (one start: the diagnosis refits many times).
FrictionFitResult fit_with(const FrictionLog& log, const FrictionDiagnosisOptions& o, const std::vector<std::string>& effects,
                           const FrictionConstants<double>& start, const std::vector<double>& effect_start = {}) {
  FrictionFitOptions f = o.fit;
  f.effects = effects;
  f.effect_start = effect_start;
  f.start = start;
  for (std::size_t j = 0; j < 7; ++j)
    fittable_constant(f.start, j) = std::clamp(fittable_constant(f.start, j), f.bounds[j].first, f.bounds[j].second);
  f.per_run_fits = false;
  f.cross_validate = true;
  f.run_offsets = RunOffsets::random;
  f.fit.starts = 0;  // warm-started from the previous model's estimate: no multi-start
  f.fit.profile = ProfileMode::none;
  return fit_friction(log, f);
}

// `fit` profiled one zero offset per run: its predictions include them, and the offsets
// themselves are tested for a trend over the runs.
ResidualDiagnostics diagnose_residuals(const FrictionLog& log, const FrictionFitResult& fit, double structure_p) {
  const std::vector<double>& predicted = fit.predicted_N;
  const double sigma = std::sqrt(fit.fit.residual_variance);
  ResidualDiagnostics d;
  d.sigma = sigma;
  const std::size_t n = log.size();
  std::vector<double> e(n);
  double ss = 0;
  for (std::size_t i = 0; i < n; ++i) {
    e[i] = log.friction_N[i] - predicted[i];
    ss += e[i] * e[i];
  }
  d.rmse_N = std::sqrt(ss / static_cast<double>(n));

  // Within runs in file (time) order: Durbin-Watson. Per run: the zero offset.
  double dw_num = 0, dw_den = 0;
  for (std::size_t i = 0; i < n; ++i) {
    dw_den += e[i] * e[i];
    if (i > 0 && log.run[i] == log.run[i - 1]) dw_num += (e[i] - e[i - 1]) * (e[i] - e[i - 1]);
  }
  d.durbin_watson = dw_den > 0 ? dw_num / dw_den : kNaN;
  const std::vector<double>& run_bias = fit.run_offset_N;
  for (std::size_t r = 0; r < run_bias.size(); ++r) d.run_bias_N.emplace_back(log.run_names[r], run_bias[r]);

  // Condition means: one residual per (guide, preload, load, temperature to 1 K, speed, direction).
  // Covariates take their nominal (condition) values: grouping by the logged temperature
  // itself would find the thermocouple's noise (errors in variables), not a missing term.
  using Key = std::tuple<std::uint32_t, double, double, double, double, double>;
  std::map<Key, std::array<double, 9>> groups;  // sums: e, V, P, pc, Lb, T, dir, time, count
  for (std::size_t i = 0; i < n; ++i) {
    auto& g = groups[{log.guide[i], log.preload_um[i], log.load_N[i], std::round(log.temperature_C[i]), log.velocity_m_s[i],
                      double(log.direction[i])}];
    const double values[] = {e[i], log.velocity_m_s[i], log.load_N[i], log.preload_um[i], log.block_length_mm[i],
                             std::round(log.temperature_C[i]), double(log.direction[i]),
                             std::isnan(log.time_s[i]) ? 0.0 : log.time_s[i], 1.0};
    for (std::size_t k = 0; k < 9; ++k) g[k] += values[k];
  }
  std::array<std::vector<double>, 8> columns;
  for (const auto& [key, g] : groups)
    for (std::size_t k = 0; k < 8; ++k) columns[k].push_back(g[k] / g[8]);
  const char* names[] = {"velocity_m_s", "load_N", "preload_um", "block_length_mm", "temperature_C", "direction", "time_s"};
  for (std::size_t k = 0; k < 7; ++k) {
    if (k == 6 && std::all_of(log.time_s.begin(), log.time_s.end(), [](double t) { return std::isnan(t); })) continue;
    d.covariates.push_back(detail::anova(names[k], columns[k + 1], columns[0]));
  }
  // Run order: a trend of the runs' zero offsets (random offsets per run are not a trend).
  if (run_bias.size() >= 4) {
    std::vector<double> index(run_bias.size());
    std::iota(index.begin(), index.end(), 0.0);
    const double mi = (index.size() - 1) / 2.0;
    const double mb = std::accumulate(run_bias.begin(), run_bias.end(), 0.0) / static_cast<double>(run_bias.size());
    double sxy = 0, sxx = 0, syy = 0;
    for (std::size_t r = 0; r < run_bias.size(); ++r) {
      sxy += (index[r] - mi) * (run_bias[r] - mb);
      sxx += (index[r] - mi) * (index[r] - mi);
      syy += (run_bias[r] - mb) * (run_bias[r] - mb);
    }
    const double rho = syy > 0 ? sxy / std::sqrt(sxx * syy) : 0.0;
    const double dof = static_cast<double>(run_bias.size() - 2);
    const double t = rho * std::sqrt(dof / std::max(1 - rho * rho, 1e-12));
    d.covariates.push_back({.covariate = "run order",
                            .correlation = rho,
                            .p_value = student_t_two_sided_p(t, dof),
                            .size = std::abs(rho) * std::sqrt(syy / static_cast<double>(run_bias.size())),
                            .n = run_bias.size()});
  }
  std::sort(d.covariates.begin(), d.covariates.end(), [](auto& a, auto& b) { return a.p_value < b.p_value; });
  for (auto& c : d.covariates) c.structured = c.p_value < structure_p;
  d.structured = !d.covariates.empty() && d.covariates.front().structured;
  return d;
}

double sum_of_squares(const FrictionLog& log, const std::vector<double>& predicted) {
  double ss = 0;
  for (std::size_t i = 0; i < log.size(); ++i) ss += std::pow(log.friction_N[i] - predicted[i], 2);
  return ss;
}

}  // namespace

FrictionDiagnosis diagnose_friction(const FrictionLog& log, const FrictionDiagnosisOptions& o) {
  if (log.run_names.size() < kMinDiagnosisRuns)
    throw InvalidParameter("runs", fmt::format("a diagnosis needs at least {} runs (it holds one out at a time)",
                                               kMinDiagnosisRuns));
  FrictionDiagnosis d;
  const std::size_t n = log.size();

  // 1. The baseline and its residuals.
  FrictionFitOptions base_options = o.fit;
  base_options.per_run_fits = false;
  base_options.cross_validate = true;
  base_options.run_offsets = RunOffsets::random;
  base_options.fit.profile = ProfileMode::none;
  const FrictionFitResult baseline = fit_friction(log, base_options);
  d.baseline = diagnose_residuals(log, baseline, o.structure_p);

  // 2-3. Candidates, forward.
  auto fit_candidate = [&](const std::vector<std::string>& effects, const FrictionFitResult& current) {
    std::vector<double> effect_start;
    for (std::size_t j = 7; j < current.fit.parameters.size(); ++j) effect_start.push_back(current.fit.parameters[j].value);
    // From the given start (not the current estimate: a misspecified fit may sit on a bound).
    return fit_with(log, o, effects, o.fit.start, effect_start);
  };
  auto summarise = [&](const FrictionFitResult& fit, const std::string& effect) {
    // The likelihood of the random run offsets' fit (their variance included), and the
    // law's own predictions (without the offsets) to tell ties.
    detail::ModelFit m{.ss = fit.deviance_ss,
                       .n = static_cast<double>(n),
                       .n_eff = static_cast<double>(n),
                       .k = fit.fit.free_parameters + 1,
                       .cv_rmse = fit.cv_rmse_N,
                       .cv_shape_rmse = fit.cv_shape_rmse_N};
    m.fitted = fit.predicted_N;
    for (std::size_t i = 0; i < n; ++i) m.fitted[i] -= fit.run_offset_N[log.run[i]];
    CandidateScore c;
    if (!effect.empty()) {
      const auto& p = fit.fit.parameter(effect);
      detail::set_estimate(c, p);
      if (p.held_unidentifiable) m.problem = "not identifiable from these data";
    }
    return std::make_pair(m, c);
  };
  const detail::SelectionRules rules{.lrt_p = o.lrt_p,
                                     .min_cv_gain_percent = o.min_cv_gain_percent,
                                     .max_effects = o.max_effects,
                                     .progress = o.progress};
  auto selection = detail::forward_select(friction_effect_names(), baseline, fit_candidate, summarise, rules);
  const FrictionFitResult& current = selection.current;
  d.rounds = std::move(selection.rounds);

  // 4. Verdict.
  d.final = diagnose_residuals(log, current, o.structure_p);
  d.cv_rmse_before_N = baseline.cv_rmse_N;
  d.cv_rmse_after_N = current.cv_rmse_N;
  d.accepted = detail::accepted_scores(d.rounds, selection.accepted,
                                       [&](const std::string& name) { return &current.fit.parameter(name); });
  for (std::size_t j = 0; j < 7; ++j)
    d.shifts.push_back(parameter_shift(baseline.fit.parameters[j], current.fit.parameters[j]));

  detail::conclude(d, "The published law", "N", d.cv_rmse_before_N, d.cv_rmse_after_N, d.baseline.rmse_N);
  d.final_fit = current;
  d.baseline_fit = baseline;
  return d;
}

std::string friction_diagnosis_json(const FrictionDiagnosis& d) {
  using detail::number;
  auto diagnostics = [&](const ResidualDiagnostics& r) {
    nlohmann::json runs = nlohmann::json::object();
    for (const auto& [run, bias] : r.run_bias_N) runs[run] = number(bias);
    return nlohmann::json{{"rmse_N", number(r.rmse_N)},         {"sigma", number(r.sigma)},
                          {"durbin_watson", number(r.durbin_watson)}, {"run_bias_N", runs},
                          {"covariates", detail::covariates_json(r.covariates)}, {"structured", r.structured},
                          {"lack_of_fit", detail::lack_of_fit_json(r.lack_of_fit)}};
  };
  nlohmann::json j = detail::verdict_json(d, d.cv_rmse_before_N, d.cv_rmse_after_N, "N");
  j["kind"] = "friction diagnosis";
  j["lmcal_version"] = LMCAL_VERSION;
  j["baseline_residuals"] = diagnostics(d.baseline);
  j["final_residuals"] = diagnostics(d.final);
  return j.dump(2) +
         "\n";
}

}  // namespace lmcal
