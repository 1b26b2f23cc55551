// The friction fit written out: its JSON, the samples' and the conditions' CSV, the terminal
// summary, and the names of its options' values they use.
#include "lmcal/version.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "fit_json.hpp"
#include "friction_steps.hpp"
#include "lmcal/fit/statistics.hpp"
#include "lmcal/io/csv_writer.hpp"

namespace lmcal {

using detail::combination_of;
using detail::fit_json;
using detail::number;

const char* to_string(RunOffsets offsets) {
  switch (offsets) {
    case RunOffsets::automatic: return "auto";
    case RunOffsets::none: return "none";
    case RunOffsets::fixed: return "fixed";
    case RunOffsets::random: return "random";
  }
  return "?";
}

const char* to_string(FrictionTemperature temperature) {
  return temperature == FrictionTemperature::block_mean ? "block-mean" : "logged";
}

const char* to_string(FrictionWeighting w) {
  switch (w) {
    case FrictionWeighting::none: return "none";
    case FrictionWeighting::per_run: return "per-run";
    case FrictionWeighting::per_condition: return "per-condition";
  }
  return "?";
}

std::string held_out_caveat(const FrictionFitResult& fit) {
  if (fit.cv_undetermined_runs.empty()) return {};
  return fmt::format("{} {} alone what the law needs (the only {} at a load, preload or temperature): held out, that "
                     "part of the law stays at the full data's estimate, so {} held-out error is optimistic",
                     fmt::join(fit.cv_undetermined_runs, ", "), fit.cv_undetermined_runs.size() == 1 ? "varies" : "each vary",
                     fit.cv_undetermined_runs.size() == 1 ? "run" : "runs",
                     fit.cv_undetermined_runs.size() == 1 ? "its" : "their");
}

namespace {

nlohmann::json run_offsets_json(const FrictionFitResult& r, const FrictionFitOptions& o) {
  const std::string model = fmt::format("{}{}",
                                        r.run_offsets == RunOffsets::random  ? "random (a run intercept of variance tau^2, ML, GLS)"
                                        : r.run_offsets == RunOffsets::fixed ? "fixed (one free offset per run, profiled)"
                                                                             : "none",
                                        o.run_offsets == RunOffsets::automatic ? "; chosen automatically" : "");
  nlohmann::json per_run = nlohmann::json::object();
  for (std::size_t k = 0; k < r.runs.size() && k < r.run_offset_N.size(); ++k)
    per_run[r.runs[k]] = {{"offset_N", number(r.run_offset_N[k])}, {"mean_residual_N", number(r.run_mean_residual_N[k])}};
  return {{"model", model}, {"sd_N", number(r.run_offset_sd_N)}, {"ratio_to_noise_variance", number(r.run_offset_ratio)},
          {"fits", r.variance_passes}, {"per_run", per_run}};
}

}  // namespace

namespace {

// Whether the summary's table shows parameter j: not the constants a combination law held at
// 0, nor β without a logged temperature (its value would be the paper's, not this log's).
bool shown(const FrictionFitResult& r, std::size_t j) {
  constexpr std::size_t kK2 = 1, kBeta = 5, kF0 = 6;
  return (r.combinations.empty() || (j != kK2 && j != kF0)) && (r.law.temperature || j != kBeta);
}

// What the log gave and what the fit could therefore determine.
std::string law_summary(const FrictionFitResult& r) {
  if (!r.law.combination() && r.law.temperature) return "";
  if (!r.law.combination())
    return "law: no temperature logged: evaluated at the oil's ν40 (T_i = 40 °C), beta_per_K held; log the "
           "temperature to fit it\n";
  std::string s = fmt::format("law: not given: {} ({}); fitted in the combinations one setup determines, at {}\n",
                              fmt::join(r.law.not_logged(), ", "), r.law.stated(),
                              r.law.temperature ? fmt::format("the mean logged temperature, {:g} °C", r.law_temperature_C)
                                                : std::string("the log's own (unlogged) temperature"));
  for (const LawCombination& c : r.combinations) s += fmt::format("  {:<20} {}\n", c.estimate.name, c.meaning);
  s += "  to separate the paper's constants: give load_N, preload_um (or preload_class) and block_length_mm, with runs "
       "at two loads or more (k1 from f0), two preloads (k2) and temperatures over 10 K or more (beta)\n";
  return s;
}

nlohmann::json law_json(const FrictionFitResult& r) {
  nlohmann::json j = {{"form", r.law.combination() ? "combinations" : "constants"},
                      {"not_given", r.law.not_logged()}};
  if (!r.law.combination()) return j;
  nlohmann::json combinations = nlohmann::json::array();
  for (const LawCombination& c : r.combinations) {
    const ParameterEstimate& e = c.estimate;
    combinations.push_back({{"name", e.name}, {"unit", e.unit}, {"meaning", c.meaning}, {"value", number(e.value)},
                            {"se", number(e.se)}, {"interval", e.interval},
                            {"ci95", {number(e.interval == "profile" ? e.profile_low : e.ci_low),
                                      number(e.interval == "profile" ? e.profile_high : e.ci_high)}}});
  }
  j["stated"] = r.law.stated();
  j["temperature_C"] = r.law_temperature_C;
  j["combinations"] = combinations;
  return j;
}

}  // namespace

FitResult friction_fit_as_shown(const FrictionFitResult& r) {
  FitResult f = r.fit;
  for (std::size_t j = 0; j < f.parameters.size(); ++j) {
    if (!shown(r, j)) f.parameters[j].interval = "none", f.parameters[j].listed = false;
    const LawCombination* c = combination_of(r, j);
    if (!c) continue;
    const double ratio = r.fit.parameters[j].se > 0 ? c->estimate.se / r.fit.parameters[j].se : 0;
    for (CovarianceSummary& m : f.uncertainty.methods)
      if (j < m.se.size()) m.se[j] *= ratio;
    for (RunHeterogeneity& h : f.uncertainty.heterogeneity)
      if (h.parameter == f.parameters[j].name) h.parameter = c->estimate.name;
    f.parameters[j] = c->estimate;
  }
  return f;
}

std::string friction_fit_json(const FrictionFitResult& r, const FrictionFitOptions& o, const FitProvenance& prov) {
  nlohmann::json spread = nlohmann::json::array();
  for (const auto& s : r.spread) {
    nlohmann::json per_run = nlohmann::json::array();
    nlohmann::json per_run_se = nlohmann::json::array();
    for (double v : s.per_run) per_run.push_back(number(v));
    for (double v : s.per_run_se) per_run_se.push_back(number(v));
    nlohmann::json row = {{"parameter", s.parameter},
                          {"per_run", per_run},
                          {"per_run_se", per_run_se},
                          {"n", s.spread.n},
                          {"mean", number(s.spread.mean)},
                          {"sd_eq1", number(s.spread.sd)},
                          {"ci95", {number(s.spread.low), number(s.spread.high)}},
                          {"min", number(s.spread.min)},
                          {"max", number(s.spread.max)},
                          {"pooled_se", number(s.pooled_se)},
                          {"ratio_to_pooled", number(s.ratio)},
                          {"cochran_q", number(s.q)},
                          {"p", number(s.p)},
                          {"p_holm", number(s.p_holm)},
                          {"wider_than_pooled", s.wider_than_pooled}};
    if (!s.undetermined.empty()) row["undetermined"] = s.undetermined;  // why per_run has NaN
    spread.push_back(std::move(row));
  }
  nlohmann::json inputs = nlohmann::json::array();
  for (const auto& [file, hash] : prov.inputs) inputs.push_back({{"file", file}, {"sha256", hash}});
  nlohmann::json j = {
      {"kind", "friction fit"},
      {"name", prov.name},
      {"lmcal_version", LMCAL_VERSION}, {"schema_version", kOutputSchemaVersion},
      {"command", prov.command},
      {"inputs", inputs},
      {"seed", o.fit.seed},
      {"options",
       {{"weighting", to_string(o.weighting)},
        {"loss", to_string(o.fit.loss)},
        {"loss_scale", o.fit.loss_scale},
        {"starts", o.fit.starts},
        {"effects", o.effects},
        {"temperature", to_string(o.temperature)},
        {"reference_temperature_C", o.start.T_ref_C}}},
      {"runs", r.runs},
      {"run_offsets", run_offsets_json(r, o)},
      {"goodness",
       {{"rmse_N", r.rmse_N},
        {"max_relative_error", r.max_relative_error},
        {"max_relative_error_sample", r.max_relative_error_sample},
        {"conditions", r.conditions.size()}}},
      {"spread_across_runs", spread},
      {"law", law_json(r)}};
  j.update(fit_json(r.fit));
  if (!r.terms.empty()) {
    nlohmann::json terms = nlohmann::json::array();
    for (std::size_t t = 0; t < r.terms.size(); ++t)
      terms.push_back({{"symbol", r.terms[t].symbol(t + 1)},
                       {"covariates", r.terms[t].covariates()},
                       {"coefficient", r.terms[t].coefficient},
                       {"coefficient_unit", r.terms[t].coefficient_unit()},
                       {"scale", r.terms[t].has_scale() ? nlohmann::json(r.terms[t].scale) : nlohmann::json()},
                       {"scale_unit", r.terms[t].scale_unit()}});
    j["empirical_terms"] = terms;
  }
  return j.dump(2) + "\n";
}

std::string friction_fit_samples_csv(const FrictionFitResult& r, const FrictionLog& log) {
  // Only the conditions the log gave: a combination law's neutral values are not data.
  const bool setup = !log.law.combination(), temperature = log.law.temperature;
  std::vector<std::string> header{"run", "line", "time_s", "guide", "velocity_m_s"};
  if (setup) header.insert(header.end(), {"load_N", "preload_um", "block_length_mm"});
  if (temperature) header.push_back("temperature_C");
  header.insert(header.end(), {"direction", "measured_N", "predicted_N", "residual_N", "sigma_N"});
  return csv_text(header, log.size(), [&](CsvText& csv, std::size_t i) {
    csv.cell(log.run_names[log.run[i]]).cell(i < log.line.size() && log.line[i] > 0 ? std::to_string(log.line[i]) : "");
    csv.cell(i < log.time_s.size() ? log.time_s[i] : NAN);  // nan: the log has no time
    csv.cell(log.guide_names.empty() ? "" : log.guide_names[log.guide[i]]);
    csv.cell(log.velocity_m_s[i]);
    if (setup) csv.cell(log.load_N[i]).cell(log.preload_um[i]).cell(log.block_length_mm[i]);
    if (temperature) csv.cell(log.temperature_C[i]);
    csv.cell(double(log.direction[i])).cell(log.friction_N[i]).cell(r.predicted_N[i]);
    csv.cell(log.friction_N[i] - r.predicted_N[i]).cell(r.sigma_N[i]).end_row();
  });
}

std::vector<std::pair<std::string, std::string>> friction_fit_files(const FrictionFitResult& result, const FrictionLog& log,
                                                                    const FrictionFitOptions& options,
                                                                    const FitProvenance& provenance) {
  return {{provenance.name + ".json", friction_fit_json(result, options, provenance)},
          {provenance.name + "_samples.csv", friction_fit_samples_csv(result, log)},
          {provenance.name + "_conditions.csv", friction_fit_conditions_csv(result)}};
}

std::string friction_fit_conditions_csv(const FrictionFitResult& r) {
  const bool setup = !r.law.combination(), temperature = r.law.temperature;
  std::vector<std::string> header{"guide"};
  if (setup) header.insert(header.end(), {"preload_um", "load_N"});
  if (temperature) header.push_back("temperature_C");
  header.insert(header.end(), {"velocity_m_s", "direction", "n", "measured_N", "predicted_N", "bias_N", "rmse_N",
                               "relative_error"});
  CsvText csv(header);
  for (const auto& c : r.conditions) {
    csv.cell(c.guide);
    if (setup) csv.cell(c.preload_um).cell(c.load_N);
    if (temperature) csv.cell(c.temperature_C);
    csv.cell(c.velocity_m_s).cell(c.direction);
    csv.cell(double(c.n)).cell(c.measured_N).cell(c.predicted_N).cell(c.bias_N).cell(c.rmse_N).cell(c.relative_error);
    csv.end_row();
  }
  return csv.str();
}

std::string friction_fit_summary(const FrictionFitResult& r) {
  const FitResult f = friction_fit_as_shown(r);
  std::string s;
  std::size_t free = 0;
  for (const auto& p : f.parameters) free += p.free ? 1 : 0;
  s += fmt::format("{} samples, {} runs, {} of {} parameters asked free\n", f.residuals, r.runs.size(), free,
                   f.parameters.size());
  s += law_summary(r);
  s += fmt::format("  {:<20} {:>12} {:>11}  {:<19} {:<27} {}\n", "parameter", "value", "SE", "unit", "95% interval", "note");
  for (std::size_t j = 0; j < f.parameters.size(); ++j) {
    if (!shown(r, j)) continue;
    const ParameterEstimate& p = f.parameters[j];
    std::string note;
    if (!p.free) note = "held (given)";
    else if (p.held_unidentifiable) note = "held: not identifiable";
    else if (p.at_bound) note = "at a bound";
    std::string interval = "";
    if (p.interval == "profile") interval = fmt::format("[{:.5g}, {:.5g}] profile", p.profile_low, p.profile_high);
    else if (p.interval == "linear") interval = fmt::format("[{:.5g}, {:.5g}]", p.ci_low, p.ci_high);
    // No SE (a held or undetermined constant) is "n/a", its reason in the note: never "nan".
    const std::string se = std::isfinite(p.se) ? fmt::format("{:.3g}", p.se) : "n/a";
    s += fmt::format("  {:<20} {:>12.6g} {:>11}  {:<19} {:<27} {}\n", p.name, p.value, se, shown_unit(p.unit), interval, note);
  }
  s += detail::uncertainty_summary(f);
  if (f.identifiability.identifiable) {
    s += fmt::format("identifiability: all requested parameters determined (condition number {:.3g})\n",
                     f.identifiability.condition_number);
  } else {
    for (const auto& issue : f.identifiability.issues)
      s += fmt::format("NOT IDENTIFIABLE: {}\n  -> held {}; to separate them: {}\n", issue.why,
                       fmt::join(issue.held, ", "), issue.measure);
  }
  // The strongest correlations among fitted parameters.
  std::vector<std::tuple<double, double, std::string, std::string>> pairs;
  for (std::size_t i = 0; i < f.parameters.size(); ++i)
    for (std::size_t j = i + 1; j < f.parameters.size(); ++j) {
      const double c = f.correlation(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
      if (std::isfinite(c)) pairs.emplace_back(std::abs(c), c, f.parameters[i].name, f.parameters[j].name);
    }
  std::sort(pairs.rbegin(), pairs.rend());
  if (!pairs.empty()) {
    s += "strongest correlations:";
    for (std::size_t k = 0; k < std::min<std::size_t>(3, pairs.size()); ++k)
      s += fmt::format(" {}/{} {:+.3f};", std::get<2>(pairs[k]), std::get<3>(pairs[k]), std::get<1>(pairs[k]));
    s += "\n";
  }
  s += fmt::format("solver: {} after {} iterations{}; {} of {} starts reached the best minimum of a {}-residual subsample{}; "
                   "covariance {}\n",
                   f.solver.termination, f.solver.iterations, f.solver.converged ? "" : " (not converged)", f.solver.starts_agreed,
                   f.solver.starts, f.solver.start_residuals, f.solver.restarted ? " (polished again from the best on all data)" : "",
                   f.solver.covariance_ok ? "ok" : "FAILED");
  s += fmt::format("goodness: RMSE {:.3f} N, max error {:.1f} % of the measured force's range (sample {}), residual sigma {:.3g}\n", r.rmse_N,
                   100 * r.max_relative_error, r.max_relative_error_sample, std::sqrt(f.residual_variance));
  if (r.variance_passes > 0 && r.run_offset_ratio > 0)
    s += fmt::format("run offsets: random, tau = {:.3g} N (variance {:.3g} x the noise's, ML with the constants{})\n",
                     r.run_offset_sd_N, r.run_offset_ratio,
                     r.variance_passes > 1 ? fmt::format(", {} fits", r.variance_passes) : std::string());
  if (!r.spread.empty()) {
    s += fmt::format("spread across {} runs (Eq. 1 sigma; ratio = sigma / (pooled SE * sqrt(runs)), ~1 if only noise; "
                     "p: the pooled fit's test of heterogeneity between runs, Holm across the constants):\n",
                     r.runs.size());
    // Each constant's unit beside its name, as in every other table ("-": dimensionless).
    const auto unit = [&](const std::string& name) {
      for (const auto& p : f.parameters)
        if (p.name == name) return p.unit.empty() || p.unit == "1" ? std::string("-") : p.unit;
      return std::string("-");
    };
    std::size_t unit_width = 4;
    for (const auto& sp : r.spread) unit_width = std::max(unit_width, unit(sp.parameter).size());
    for (const auto& sp : r.spread) {
      if (sp.spread.n < 2) {  // fewer than two runs' own values (the report's rule too)
        s += fmt::format("  {:<20} {:<{}}  no spread: not determined run by run ({})\n", sp.parameter, unit(sp.parameter),
                         unit_width, sp.undetermined.empty() ? "fewer than two runs' own fits gave it" : sp.undetermined);
        continue;
      }
      s += fmt::format("  {:<20} {:<{}}  mean {:>11.5g}  sigma {:>9.3g}  [{:.5g}, {:.5g}]  min {:.5g} max {:.5g}  ratio {:.2f}  p {}{}{}\n",
                       sp.parameter, unit(sp.parameter), unit_width, sp.spread.mean, sp.spread.sd, sp.spread.low, sp.spread.high,
                       sp.spread.min, sp.spread.max, sp.ratio, p_value_text(sp.p_holm),
                       sp.wider_than_pooled ? "  WIDER: the runs differ beyond what the model explains" : "",
                       sp.undetermined.empty() ? "" : "  (without " + sp.undetermined + ")");
    }
  }
  for (const auto& w : f.warnings) s += "warning: " + w + "\n";
  return s;
}

}  // namespace lmcal
