// A calibration rendered: its output files, calibration.json and the summary for the terminal.
#include "lmcal/report/calibration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <nlohmann/json.hpp>

#include "diagnose/selection.hpp"
#include "fit/fit_json.hpp"
#include "lmcal/error.hpp"
#include "lmcal/version.hpp"
#include "lmcal/fit/model_file.hpp"
#include "lmcal/io/output_record.hpp"
#include "lmcal/report/html_report.hpp"
#include "parallel_slices.hpp"
#include "report/findings.hpp"
#include "report/sections.hpp"

namespace lmcal {

namespace {

nlohmann::json options_json(const CalibrationOptions& o);

// Every JSON output says where it came from: the command, the inputs with their SHA-256, the
// calibration's resolved options and the software's versions (what a writer already records
// stays as it wrote it).
void add_provenance(std::vector<std::pair<std::string, std::string>>& outputs, const Calibration& c) {
  for (auto& [name, text] : outputs) {
    if (!name.ends_with(".json")) continue;
    nlohmann::json j = nlohmann::json::parse(text);
    if (j.value("kind", "") != "calibration") j["calibration_options"] = options_json(c.options);  // it has them as "options"
    text = with_output_record(j.dump(2), c.command, &c.inputs);
  }
}

}  // namespace

std::vector<std::pair<std::string, std::string>> calibration_outputs(const Calibration& c) {
  using Files = std::vector<std::pair<std::string, std::string>>;
  // Each writer a task of its own; they run side by side (the report, the longest, first) and
  // their files are kept in this order.
  std::vector<std::function<Files()>> tasks;
  auto one = [&](std::string name, std::function<std::string()> text) {
    tasks.push_back([name = std::move(name), text = std::move(text)] { return Files{{name, text()}}; });
  };
  // c.inputs: the friction logs first, then the thermal files.
  const auto thermal_inputs = c.inputs.begin() + static_cast<std::ptrdiff_t>(c.set.friction_logs.size());
  const std::vector<std::pair<std::string, std::string>> friction_inputs(c.inputs.begin(), thermal_inputs),
      thermal_files(thermal_inputs, c.inputs.end());
  one("model.toml", [&] { return model_file_toml(calibrated_model_file(c)); });
  const CalibratedModel& m = c.calibrated;
  if (m.friction)
    one("calibrated_friction.json", [&] {
      return friction_fit_json(*m.friction, m.friction_options, {"calibrated_friction", friction_inputs, c.command});
    });
  if (m.thermal)
    one("calibrated_thermal.json",
        [&] { return thermal_fit_json(*m.thermal, m.thermal_options, thermal_files, c.command, "calibrated_thermal"); });
  if (c.friction)
    tasks.push_back([&] {
      return friction_fit_files(*c.friction, *c.friction_log, c.friction_options, {"friction", friction_inputs, c.command});
    });
  if (c.friction_diagnosis) one("friction_diagnosis.json", [&] { return friction_diagnosis_json(*c.friction_diagnosis); });
  if (c.thermal)
    tasks.push_back([&] { return thermal_fit_files(*c.thermal, c.thermal_options, thermal_files, c.command, "thermal"); });
  if (c.thermal_diagnosis) one("thermal_diagnosis.json", [&] { return thermal_diagnosis_json(*c.thermal_diagnosis); });
  if (c.prediction) {
    one("prediction.json", [&] { return prediction_json(*c.prediction, *c.duty, calibrated_model_file(c), c.command); });
    one("prediction_time.csv", [&] { return prediction_time_csv(*c.prediction); });
  }
  if (c.plan) {
    one("plan_friction.json", [&] { return friction_plan_json(*c.plan, c.command); });
    one("plan_friction_template.csv", [&] { return friction_plan_template_csv(*c.plan); });
  }
  if (c.thermal_plan) {
    one("plan_thermal.json", [&] { return thermal_plan_json(*c.thermal_plan, c.command); });
    one("plan_thermal_manifest.toml", [&] { return thermal_plan_manifest_toml(*c.thermal_plan, *c.thermal_data); });
  }
  one("calibration.json", [&] { return calibration_json(c); });
  one("report.html", [&] { return calibration_report_html(c); });
  std::vector<Files> made(tasks.size());
  detail::for_each_index(tasks.size(), [&](std::size_t k) {
    const std::size_t task = (k + tasks.size() - 1) % tasks.size();  // the report (last) first
    made[task] = tasks[task]();
    add_provenance(made[task], c);
  });
  Files out;
  for (Files& files : made)
    for (auto& file : files) out.push_back(std::move(file));
  for (const auto& [name, text] : out) LMCAL_ASSERT(is_calibration_output(name), "every output is in calibration_output_names()");
  return out;
}

namespace {

using detail::number;


// A diagnosis's verdict without its candidate tables (those are in its own file).
nlohmann::json brief_verdict(nlohmann::json verdict) {
  verdict.erase("rounds");
  return verdict;
}

// A fit's quoted covariance: method, why, dof, and the SEs of every method side by side.
nlohmann::json how_sure_json(const FitResult& fit) {
  nlohmann::json j = detail::uncertainty_json(fit);
  j.erase("between_run_heterogeneity");
  return j;
}

nlohmann::json friction_json(const FrictionFitResult& f) {
  nlohmann::json constants = nlohmann::json::array();
  for (const auto& p : f.fit.parameters) constants.push_back(detail::parameter_json(p));
  nlohmann::json j = {{"rmse_N", number(f.rmse_N)},
                      {"cv_rmse_N", number(f.cv_rmse_N)},
                      {"max_relative_error", number(f.max_relative_error)},
                      {"runs", f.runs.size()},
                      {"parameters", constants},
                      {"uncertainty", how_sure_json(f.fit)},
                      {"converged", f.fit.solver.converged},
                      {"identifiable", f.fit.identifiability.identifiable}};
  if (!f.cv_undetermined_runs.empty()) j["cv_caveat"] = held_out_caveat(f);
  return j;
}

nlohmann::json thermal_json(const ThermalFitResult& t, const ThermalFitOptions& o) {
  nlohmann::json parameters = nlohmann::json::array();
  for (const auto& p : t.joint.parameters)
    if (!p.per_run)
      parameters.push_back(detail::parameter_json(p));
  const Spread& s = t.alpha_spread;
  return {{"alpha", detail::parameter_json(t.joint.parameter("alpha"))},
          {"parameters", parameters},
          {"alpha_across_runs", {{"n", s.n}, {"mean", number(s.mean)}, {"sd", number(s.sd)}, {"half_width", number(s.half_width)}}},
          {"source", to_string(o.source)},
          {"heat_uncertainty", t.heat_uncertainty},
          {"uncertainty", how_sure_json(t.joint)},
          {"cv_rmse_K", number(t.cv_rmse_K)},
          {"max_error_percent", number(t.max_error_percent)},
          {"converged", t.joint.solver.converged}};
}

nlohmann::json uncertainty_options_json(const FitOptions& f) {
  return {{"covariance", to_string(f.covariance)}, {"bootstrap", f.bootstrap}, {"profile", to_string(f.profile)}, {"starts", f.starts}, {"seed", f.seed}};
}

nlohmann::json friction_options_json(const FrictionFitOptions& f) {
  FrictionConstants<double> start = f.start;
  nlohmann::json constants = nlohmann::json::object();
  for (std::size_t j = 0; j < kFrictionConstantNames.size(); ++j) {
    constants[std::string(kFrictionConstantNames[j])] = {{"free", f.free[j]},
                                                         {"start", fittable_constant(start, j)},
                                                         {"bounds", {f.bounds[j].first, f.bounds[j].second}}};
  }
  return {{"constants", constants}, {"run_offsets", to_string(f.run_offsets)}, {"temperature", to_string(f.temperature)}, {"fit", uncertainty_options_json(f.fit)}};
}

nlohmann::json thermal_options_json(const ThermalFitOptions& t) {
  return {{"heat", to_string(t.heat)},
          {"source", to_string(t.source)},
          {"scheme", to_string(t.scheme)},
          {"half_rail_segments", t.half_rail_segments},
          {"time_step_s", t.time_step_s},
          {"every", t.every},
          {"ambient", t.ambient},
          {"alpha_start", t.alpha_start},
          {"fit_h", t.fit_h},
          {"h_W_m2K", t.h_W_m2K},
          {"fit_initial_temperature", t.fit_initial_temperature},
          {"offsets", to_string(t.offsets)},
          {"fit", uncertainty_options_json(t.fit)}};
}

// Every setting the calibration ran with (`lmcal calibrate` flags or --config), so that the
// outputs say how they were made.
nlohmann::json raw_options_json(const RawFrictionOptions& r) {
  return {{"force_sign", to_string(r.force_sign)},
          {"max_acceleration_m_s2", r.max_acceleration_m_s2},
          {"settling_s", r.settling_s},
          {"min_speed_m_s", r.min_speed_m_s},
          {"velocity_tolerance", r.velocity_tolerance},
          {"min_plateau_samples", r.min_plateau_samples},
          {"velocity_window", r.velocity_window},
          {"moving_mass_kg", r.moving_mass_kg},
          {"duplicate_times", to_string(r.duplicate_times)},
          {"segmentation", to_string(r.segmentation)},
          {"trajectory_window", r.trajectory_window},
          {"presliding_m", r.presliding_m},
          {"axis_incline_deg", r.axis_incline_deg}};
}

nlohmann::json options_json(const CalibrationOptions& o) {
  nlohmann::json j{{"diagnose", o.diagnose},
          {"catalog", o.catalog_file.empty() ? "<built-in>" : o.catalog_file},
          {"raw_friction", raw_options_json(o.raw)},
          {"friction", friction_options_json(o.friction)},
          {"friction_diagnosis",
           {{"fit", friction_options_json(o.friction_diagnosis.fit)},
            {"min_cv_gain_percent", o.friction_diagnosis.min_cv_gain_percent},
            {"lrt_p", o.friction_diagnosis.lrt_p}}},
          {"thermal", thermal_options_json(o.thermal)},
          {"thermal_diagnosis",
           {{"fit", thermal_options_json(o.thermal_diagnosis.fit)},
            {"min_cv_gain_percent", o.thermal_diagnosis.min_cv_gain_percent},
            {"lrt_p", o.thermal_diagnosis.lrt_p}}}};
  // Only when given: it changes what may be read (a set refused without it), never a result.
  if (o.inputs.allow_outside) j["allow_outside_root"] = true;
  return j;
}

// How the calibrated model differs from the published one, every value with its interval.
nlohmann::json shifts_json(const FitResult& published, const FitResult& calibrated) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& p : published.parameters) {
    const auto it = std::find_if(calibrated.parameters.begin(), calibrated.parameters.end(), [&](auto& q) { return q.name == p.name; });
    if (it == calibrated.parameters.end() || p.per_run) continue;
    const ParameterShift s = parameter_shift(p, *it);
    out.push_back({{"parameter", s.name},
                   {"published", number(s.baseline)},
                   {"published_ci95", {number(s.baseline_low), number(s.baseline_high)}},
                   {"calibrated", number(s.extended)},
                   {"calibrated_ci95", {number(s.extended_low), number(s.extended_high)}}});
  }
  return out;
}

}  // namespace

std::string calibration_options_json(const CalibrationOptions& options) { return options_json(options).dump(2); }

std::string calibration_json(const Calibration& c) {
  nlohmann::json inputs = nlohmann::json::array();
  for (const auto& [file, hash] : c.inputs) inputs.push_back({{"file", file}, {"sha256", hash}});
  nlohmann::json j{{"kind", "calibration"},  {"lmcal_version", LMCAL_VERSION}, {"schema_version", kOutputSchemaVersion}, {"set", c.set.name},
                   {"command", c.command},   {"inputs", inputs},               {"notes", c.notes},
                   {"warnings", c.warnings},          {"options", options_json(c.options)}};
  const CalibratedModel& m = c.calibrated;
  nlohmann::json calibrated = {{"what", "the published models with the causes the diagnoses accepted, refitted: the result"},
                               {"file", "model.toml"}};
  if (m.friction) {
    calibrated["friction"] = friction_json(*m.friction);
    calibrated["friction"]["causes"] = m.friction_causes;
    if (c.friction) calibrated["friction"]["shifts_from_published"] = shifts_json(c.friction->fit, m.friction->fit);
  }
  if (m.thermal) {
    calibrated["thermal"] = thermal_json(*m.thermal, m.thermal_options);
    calibrated["thermal"]["causes"] = m.thermal_causes;
    if (c.thermal) calibrated["thermal"]["shifts_from_published"] = shifts_json(c.thermal->joint, m.thermal->joint);
  }
  j["calibrated_model"] = calibrated;
  nlohmann::json published = {{"what", "the published models (Cheng et al. 2017) fitted as printed, for comparison: conditional "
                                        "on a model the diagnosis rejects where it finds a cause"}};
  if (c.friction) published["friction"] = friction_json(*c.friction);
  if (c.thermal) published["thermal"] = thermal_json(*c.thermal, c.thermal_options);
  j["published_model"] = published;
  const report::Findings words = report::findings(c);
  j["findings"] = {{"what", "what the calibration found and how sure it is, in words: the summary's and the report's first sentences"},
                   {"found", words.found},
                   {"how_sure", words.how_sure},
                   {"contradictions", words.contradictions}};
  if (c.friction_diagnosis)
    j["friction_diagnosis"] = brief_verdict(detail::verdict_json(*c.friction_diagnosis, c.friction_diagnosis->cv_rmse_before_N,
                                                                 c.friction_diagnosis->cv_rmse_after_N, "N"));
  if (c.thermal_diagnosis)
    j["thermal_diagnosis"] = brief_verdict(detail::verdict_json(*c.thermal_diagnosis, c.thermal_diagnosis->cv_rmse_before_K,
                                                                c.thermal_diagnosis->cv_rmse_after_K, "K"));
  return with_output_record(j.dump(2), c.command, &c.inputs);
}

namespace {

// "[low, high]" with each end as `number` formats it ("{:.5g}"), or, where the fit gave no
// interval (a parameter the data do not determine has no standard error), says so.
std::string interval_text(double low, double high, std::string_view number) {
  if (!std::isfinite(low) || !std::isfinite(high)) return "n/a (no standard error: not determined by the data)";
  return fmt::format("[{}, {}]", fmt::format(fmt::runtime(number), low), fmt::format(fmt::runtime(number), high));
}

// "name value unit [low, high]" for the free parameters of a fit (per-run nuisance left out),
// under a header; a dimensionless parameter's unit "-", an interval the fit could not give "n/a"
// with the reason.
std::string parameter_lines(const FitResult& fit) {
  const auto shown = [](const ParameterEstimate& p) { return p.interval != "none" && !p.per_run; };
  const auto unit = [](const ParameterEstimate& p) { return p.unit.empty() || p.unit == "1" ? std::string("-") : p.unit; };
  std::size_t name_width = 9, unit_width = 4;  // "parameter", "unit"
  for (const auto& p : fit.parameters)
    if (shown(p)) name_width = std::max(name_width, p.name.size()), unit_width = std::max(unit_width, unit(p).size());
  std::string s = fmt::format("    {:<{}} {:>11}  {:<{}}  {}\n", "parameter", name_width, "value", "unit", unit_width, "95 % interval");
  for (const auto& p : fit.parameters) {
    if (!shown(p)) continue;
    const bool profile = p.interval == "profile";
    const double low = profile ? p.profile_low : p.ci_low, high = profile ? p.profile_high : p.ci_high;
    s += fmt::format("    {:<{}} {:>11.5g}  {:<{}}  {}{}{}\n", p.name, name_width, p.value, unit(p), unit_width,
                     interval_text(low, high, "{:.5g}"), profile ? " profile" : "", p.at_bound ? ", on its bound" : "");
  }
  return s;
}

// "held-out RMSE 0.229 N", or why there is none: a run is predicted from the others, so one run
// leaves none to hold out; a robust loss or a fit that is not usable is not cross-validated.
std::string held_out_text(double rmse, std::string_view unit, int decimals, std::size_t runs) {
  if (std::isfinite(rmse)) return fmt::format("held-out RMSE {:.{}f} {}", rmse, decimals, unit);
  return runs < 2 ? "no held-out RMSE (one run: none to hold out)"
                  : "no held-out RMSE (not cross-validated: a robust loss, or a fit that is not usable)";
}

}  // namespace


std::string calibration_summary(const Calibration& c) {
  std::string s;
  const CalibratedModel& m = c.calibrated;
  const report::Findings words = report::findings(c);
  if (!words.found.empty()) {
    s += "WHAT WE FOUND\n";
    for (const auto& sentence : words.found) s += "  " + sentence + "\n";
    for (const auto& sentence : words.contradictions) s += "  Note: " + sentence + "\n";
    s += "HOW SURE (report.html: the methods and the terms they use)\n";
    for (const auto& sentence : words.how_sure) s += "  " + sentence + "\n";
  }
  s += "THE CALIBRATED MODEL (model.toml): the published models with the causes the diagnoses accepted\n";
  if (m.friction) {
    s += fmt::format("  friction law{}: RMSE {:.3f} N, {}\n",
                     m.friction_causes.empty() ? "" : fmt::format(" + {}", fmt::join(m.friction_causes, " + ")), m.friction->rmse_N,
                     held_out_text(m.friction->cv_rmse_N, "N", 3, m.friction->runs.size()));
    if (const std::string caveat = held_out_caveat(*m.friction); !caveat.empty()) s += "    held-out: " + caveat + "\n";
    s += parameter_lines(friction_fit_as_shown(*m.friction));
  }
  if (m.thermal) {
    s += fmt::format("  rail model{} ({} source): {}\n",
                     m.thermal_causes.empty() ? "" : fmt::format(" + {}", fmt::join(m.thermal_causes, " + ")),
                     to_string(m.thermal_options.source), held_out_text(m.thermal->cv_rmse_K, "K", 4, m.thermal->runs.size()));
    s += parameter_lines(m.thermal->joint);
    if (c.thermal_diagnosis)
      if (const auto [low, high] = candidate_alpha_range(c.thermal_diagnosis->rounds); std::isfinite(low))
        s += fmt::format("    alpha is conditional on this model: the models the diagnosis tried put it between {:.3f} and {:.3f}\n",
                         low, high);
  }
  s += "the published models, for comparison (conditional on a model the diagnosis rejects where it names a cause):\n";
  if (c.friction)
    s += fmt::format("  friction: {}, {}; the law alone, residual RMSE {:.3f} N\n", report::plural(c.friction_log->size(), "sample"),
                     report::plural(c.friction->runs.size(), "run"), c.friction->rmse_N);
  if (c.friction_diagnosis)
    s += fmt::format("  diagnosis: {}: {}\n", c.friction_diagnosis->verdict, report::without_verdict(c.friction_diagnosis->summary));
  if (c.thermal) {
    const auto& a = c.thermal->joint.parameter("alpha");
    s += fmt::format("  thermal: {}; alpha {:.3f} {} ({} source), {}\n", report::plural(c.thermal_data->runs.size(), "run"),
                     a.value, interval_text(a.ci_low, a.ci_high, "{:.3f}"), to_string(c.thermal_options.source),
                     across_runs(c.thermal->alpha_spread));
  }
  if (c.thermal_diagnosis)
    s += fmt::format("  diagnosis: {}: {}\n", c.thermal_diagnosis->verdict, report::without_verdict(c.thermal_diagnosis->summary));
  for (const auto& note : c.notes) s += "note: " + note + "\n";
  for (const auto& warning : c.warnings) s += "warning: " + warning + "\n";
  return s;
}

}  // namespace lmcal
