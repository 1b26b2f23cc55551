#include "lmcal/report/calibration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "diagnose/selection.hpp"
#include "fit/fit_json.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/hash.hpp"
#include "lmcal/report/html_report.hpp"

namespace lmcal {

namespace fs = std::filesystem;

CalibrationSet find_calibration_set(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir.string(), 0, 0, "expected a measurement folder (friction*.csv, thermal*.toml)");
  CalibrationSet set;
  set.dir = dir;
  set.name = fs::weakly_canonical(dir).filename().string();
  std::vector<fs::path> manifests;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const std::string file = entry.path().filename().string();
    if (file.starts_with("friction") && entry.path().extension() == ".csv") set.friction_logs.push_back(entry.path());
    if (file.starts_with("thermal") && entry.path().extension() == ".toml") manifests.push_back(entry.path());
  }
  std::sort(set.friction_logs.begin(), set.friction_logs.end());
  std::sort(manifests.begin(), manifests.end());
  if (manifests.size() > 1)
    throw InputError(manifests[1].string(), 0, 0,
                     fmt::format("expected one thermal manifest in {}, found {} (thermal*.toml)", dir.string(), manifests.size()));
  if (!manifests.empty()) set.thermal_manifest = manifests.front();
  if (set.friction_logs.empty() && !set.thermal_manifest)
    throw InputError(dir.string(), 0, 0, "expected friction logs (friction*.csv) or a thermal manifest (thermal*.toml) in the folder");
  return set;
}

Calibration calibrate(const CalibrationSet& set, const CalibrationOptions& options, const CalibrationProgress& progress) {
  Calibration c;
  c.set = set;
  c.command = {"lmcal", "calibrate", set.dir.string()};
  const bool friction = !set.friction_logs.empty(), thermal = set.thermal_manifest.has_value();
  std::vector<std::string> steps = {"loading the measurements"};
  if (friction) steps.insert(steps.end(), {"friction fit", "friction diagnosis"});
  if (thermal) steps.insert(steps.end(), {"thermal fit", "thermal diagnosis"});
  if (!options.diagnose) std::erase_if(steps, [](const std::string& s) { return s.ends_with("diagnosis"); });
  std::size_t step = 0;
  auto start = [&](const char* name) {
    LMCAL_ASSERT(step < steps.size() && steps[step] == name, "calibration steps in order");
    if (progress.step) progress.step(step, steps.size(), name);
    ++step;
  };

  start("loading the measurements");
  for (const auto& file : set.friction_logs) c.inputs.emplace_back(file.string(), sha256_file(file));
  if (friction) c.friction_log = load_friction_logs(set.friction_logs);
  if (thermal) {
    c.thermal_data = load_thermal_dataset(*set.thermal_manifest);
    c.inputs.emplace_back(set.thermal_manifest->string(), sha256_file(*set.thermal_manifest));
    for (const auto& run : c.thermal_data->runs) c.inputs.emplace_back(run.file.string(), sha256_file(run.file));
  }

  if (friction) {
    start("friction fit");
    c.friction_options = options.friction;
    c.friction = fit_friction(*c.friction_log, c.friction_options);
    if (options.diagnose) {
      start("friction diagnosis");
      if (c.friction_log->run_names.size() >= kMinDiagnosisRuns) {
        FrictionDiagnosisOptions o = options.friction_diagnosis;
        o.progress = progress.detail;
        c.friction_diagnosis = diagnose_friction(*c.friction_log, o);
      } else {
        c.notes.push_back(fmt::format("friction diagnosis skipped: it holds one run out at a time and needs at least "
                                      "{} runs; the logs have {}",
                                      kMinDiagnosisRuns, c.friction_log->run_names.size()));
      }
    }
  } else {
    c.notes.push_back("no friction logs (friction*.csv): the friction steps were skipped");
  }

  if (thermal) {
    start("thermal fit");
    c.thermal_options = options.thermal;
    ThermalDiagnosisOptions diagnosis = options.thermal_diagnosis;
    if (c.friction) {
      c.thermal_options.friction = diagnosis.fit.friction = c.friction->constants();
      c.thermal_options.friction_effects = diagnosis.fit.friction_effects = c.friction->effects();
    } else {
      c.notes.push_back("no friction fit: the thermal model takes its heat from the manifest's mean friction");
    }
    c.thermal = fit_thermal(*c.thermal_data, c.thermal_options);
    if (options.diagnose) {
      start("thermal diagnosis");
      if (c.thermal_data->runs.size() >= kMinDiagnosisRuns) {
        diagnosis.progress = progress.detail;
        c.thermal_diagnosis = diagnose_thermal(*c.thermal_data, diagnosis);
      } else {
        c.notes.push_back(fmt::format("thermal diagnosis skipped: it holds one run out at a time and needs at least {} "
                                      "runs; the manifest has {}",
                                      kMinDiagnosisRuns, c.thermal_data->runs.size()));
      }
    }
  } else {
    c.notes.push_back("no thermal manifest (thermal*.toml): the thermal steps were skipped");
  }
  return c;
}

std::vector<std::pair<std::string, std::string>> calibration_outputs(const Calibration& c) {
  std::vector<std::pair<std::string, std::string>> out;
  auto append = [&](std::vector<std::pair<std::string, std::string>> files) {
    for (auto& file : files) out.push_back(std::move(file));
  };
  // c.inputs: the friction logs first, then the thermal files.
  const auto thermal_inputs = c.inputs.begin() + static_cast<std::ptrdiff_t>(c.set.friction_logs.size());
  if (c.friction)
    append(friction_fit_files(*c.friction, *c.friction_log, c.friction_options,
                              {"friction", {c.inputs.begin(), thermal_inputs}, c.command}));
  if (c.friction_diagnosis) out.emplace_back("friction_diagnosis.json", friction_diagnosis_json(*c.friction_diagnosis));
  if (c.thermal) append(thermal_fit_files(*c.thermal, c.thermal_options, {thermal_inputs, c.inputs.end()}, c.command, "thermal"));
  if (c.thermal_diagnosis) out.emplace_back("thermal_diagnosis.json", thermal_diagnosis_json(*c.thermal_diagnosis));
  out.emplace_back("calibration.json", calibration_json(c));
  out.emplace_back("report.html", calibration_report_html(c));
  return out;
}

namespace {

using detail::number;

nlohmann::json estimate_json(const ParameterEstimate& p) {
  return {{"name", p.name},         {"unit", p.unit},         {"value", number(p.value)}, {"se", number(p.se)},
          {"ci_low", number(p.interval == "profile" ? p.profile_low : p.ci_low)},
          {"ci_high", number(p.interval == "profile" ? p.profile_high : p.ci_high)},
          {"at_bound", p.at_bound}, {"held", !p.free || p.held_unidentifiable}};
}

// A diagnosis's verdict without its candidate tables (those are in its own file).
nlohmann::json brief_verdict(nlohmann::json verdict) {
  verdict.erase("rounds");
  return verdict;
}

}  // namespace

std::string calibration_json(const Calibration& c) {
  nlohmann::json inputs = nlohmann::json::array();
  for (const auto& [file, hash] : c.inputs) inputs.push_back({{"file", file}, {"sha256", hash}});
  nlohmann::json j{{"kind", "calibration"},  {"lmcal_version", LMCAL_VERSION}, {"set", c.set.name},
                   {"command", c.command},   {"inputs", inputs},               {"notes", c.notes}};
  if (c.friction) {
    nlohmann::json constants = nlohmann::json::array();
    for (const auto& p : c.friction->fit.parameters) constants.push_back(estimate_json(p));
    j["friction"] = {{"rmse_N", number(c.friction->rmse_N)},
                     {"max_relative_error", number(c.friction->max_relative_error)},
                     {"runs", c.friction->runs.size()},
                     {"parameters", constants},
                     {"converged", c.friction->fit.solver.converged},
                     {"identifiable", c.friction->fit.identifiability.identifiable}};
  }
  if (c.friction_diagnosis)
    j["friction_diagnosis"] = brief_verdict(detail::verdict_json(*c.friction_diagnosis, c.friction_diagnosis->cv_rmse_before_N,
                                                                 c.friction_diagnosis->cv_rmse_after_N, "N"));
  if (c.thermal) {
    const Spread& s = c.thermal->alpha_spread;
    j["thermal"] = {{"alpha", estimate_json(c.thermal->joint.parameter("alpha"))},
                    {"alpha_across_runs", {{"n", s.n}, {"mean", number(s.mean)}, {"sd", number(s.sd)},
                                           {"half_width", number(s.half_width)}}},
                    {"source", to_string(c.thermal_options.source)},
                    {"max_error_percent", number(c.thermal->max_error_percent)},
                    {"converged", c.thermal->joint.solver.converged}};
  }
  if (c.thermal_diagnosis)
    j["thermal_diagnosis"] = brief_verdict(detail::verdict_json(*c.thermal_diagnosis, c.thermal_diagnosis->cv_rmse_before_K,
                                                                c.thermal_diagnosis->cv_rmse_after_K, "K"));
  return j.dump(2) + "\n";
}

std::string calibration_summary(const Calibration& c) {
  std::string s;
  if (c.friction) {
    s += fmt::format("friction: {} samples, {} runs; law fitted with residual RMSE {:.3f} N\n", c.friction_log->size(),
                     c.friction->runs.size(), c.friction->rmse_N);
  }
  if (c.friction_diagnosis) s += fmt::format("  diagnosis: {}\n  {}\n", c.friction_diagnosis->verdict, c.friction_diagnosis->summary);
  if (c.thermal) {
    const auto& a = c.thermal->joint.parameter("alpha");
    s += fmt::format("thermal: {} runs; alpha {:.3f} [{:.3f}, {:.3f}] ({} source), across runs {:.3f} ± {:.3f}\n",
                     c.thermal_data->runs.size(), a.value, a.ci_low, a.ci_high, to_string(c.thermal_options.source),
                     c.thermal->alpha_spread.mean, c.thermal->alpha_spread.half_width);
  }
  if (c.thermal_diagnosis) s += fmt::format("  diagnosis: {}\n  {}\n", c.thermal_diagnosis->verdict, c.thermal_diagnosis->summary);
  for (const auto& note : c.notes) s += "note: " + note + "\n";
  return s;
}

}  // namespace lmcal
