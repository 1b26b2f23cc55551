// The calibration pipeline: the measurements loaded, then the steps in order (calibrate), and
// whether its headline fits give an answer to use (unusable_headline).
#include "lmcal/calibrate/calibration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <string_view>

#include "calibrate/data_checks.hpp"
#include "calibrate/steps.hpp"
#include "io/input_file.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/hash.hpp"

namespace lmcal {

namespace fs = std::filesystem;

namespace {

// The set's files read (each with its SHA-256 in c.inputs), every one inside the input scope.
void load_measurements(Calibration& c, const CalibrationSet& set, const CalibrationOptions& options) {
  // The set's own files, too, must resolve inside the scope: a friction.csv that links to
  // /etc/shadow is refused before it is opened.
  const InputScope scope{.root = options.inputs.root_for(set.dir), .allow_outside = options.inputs.allow_outside};
  std::vector<fs::path> own_files = set.friction_logs;
  for (const auto& manifest : {set.friction_manifest, set.thermal_manifest})
    if (manifest) own_files.push_back(*manifest);
  for (const fs::path& file : own_files)
    if (auto problem = outside_scope(file, set.dir, scope)) throw InputError(io::printable(file.string()), 0, 0, *problem);
  for (const auto& file : set.ignored_files)
    c.notes.push_back(fmt::format("{} not read: it is an output of lmcal calibrate, not a measurement", file.string()));
  const std::optional<GuideCatalog> catalog =
      options.catalog_file.empty() ? std::nullopt : std::optional(load_catalog(options.catalog_file));
  if (catalog) c.inputs.emplace_back(options.catalog_file, sha256_file(options.catalog_file));
  if (set.friction_manifest) {
    FrictionDataSet data = load_friction_dataset(*set.friction_manifest, catalog ? &*catalog : nullptr, options.raw,
                                                 options.raw_given, scope);
    c.inputs.emplace_back(set.friction_manifest->string(), sha256_file(*set.friction_manifest));
    for (const auto& file : data.files) c.inputs.emplace_back(file.string(), sha256_file(file));
    for (const auto& file : set.friction_logs)
      if (std::find(data.files.begin(), data.files.end(), file) == data.files.end())
        c.notes.push_back(fmt::format("{} not read: the friction manifest {} lists the set's friction logs, and not it",
                                      file.string(), set.friction_manifest->string()));
    c.options.raw = data.raw;  // as applied: the manifest's [raw] under the user's flags
    c.friction_log = std::move(data.log);
  } else if (!set.friction_logs.empty()) {
    for (const auto& file : set.friction_logs) c.inputs.emplace_back(file.string(), sha256_file(file));
    c.friction_log = load_friction_logs(set.friction_logs, options.raw);
  }
  if (set.thermal_manifest) {
    c.thermal_data = load_thermal_dataset(*set.thermal_manifest, catalog ? &*catalog : nullptr, scope);
    c.inputs.emplace_back(set.thermal_manifest->string(), sha256_file(*set.thermal_manifest));
    for (const auto& run : c.thermal_data->runs) c.inputs.emplace_back(run.file.string(), sha256_file(run.file));
  }
}

// A diagnosis holds one run out at a time: the note when `runs` are too few.
std::string too_few_runs(std::string_view half, std::string_view holder, std::size_t runs) {
  return fmt::format("{} diagnosis skipped: it holds one run out at a time and needs at least {} runs; {} {}", half,
                     kMinDiagnosisRuns, holder, runs);
}

using StepStart = std::function<void(const char* name)>;

// The friction fit, its diagnosis, the calibrated friction model and the next conditions to log.
void friction_steps(Calibration& c, const CalibrationOptions& options, const CalibrationProgress& progress,
                    const StepStart& start) {
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
      c.notes.push_back(too_few_runs("friction", "the logs have", c.friction_log->run_names.size()));
    }
  }
  start("calibrated friction model");
  detail::calibrate_friction_model(c);
  start("plan of the next friction conditions");
  detail::plan_next_friction(c);
}

// The thermal fit (its heat from the friction fit), its diagnosis and the calibrated rail model.
void thermal_steps(Calibration& c, const CalibrationOptions& options, const CalibrationProgress& progress,
                   const StepStart& start) {
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
      c.notes.push_back(too_few_runs("thermal", "the manifest has", c.thermal_data->runs.size()));
    }
  }
  start("calibrated thermal model");
  detail::calibrate_thermal_model(c, options);
}

}  // namespace

Calibration calibrate(const CalibrationSet& set, const CalibrationOptions& options, const CalibrationProgress& progress) {
  Calibration c;
  c.set = set;
  c.options = options;
  c.command = {"lmcal", "calibrate", set.dir.string()};
  const bool friction = !set.friction_logs.empty() || set.friction_manifest, thermal = set.thermal_manifest.has_value();
  std::vector<std::string> steps = {"loading the measurements"};
  if (friction) steps.insert(steps.end(), {"friction fit", "friction diagnosis"});
  if (friction) steps.insert(steps.end(), {"calibrated friction model", "plan of the next friction conditions"});
  if (thermal) steps.insert(steps.end(), {"thermal fit", "thermal diagnosis", "calibrated thermal model"});
  if (friction && thermal) steps.insert(steps.end(), {"plan of the next thermal runs", "prediction of the runs' cycle"});
  if (!options.diagnose) std::erase_if(steps, [](const std::string& s) { return s.ends_with("diagnosis"); });
  std::size_t step = 0;
  auto start = [&](const char* name) {
    LMCAL_ASSERT(step < steps.size() && steps[step] == name, "calibration steps in order");
    if (progress.step) progress.step(step, steps.size(), name);
    ++step;
  };

  start("loading the measurements");
  load_measurements(c, set, options);

  if (friction)
    friction_steps(c, options, progress, start);
  else
    c.notes.push_back("no friction logs (friction*.csv): the friction steps were skipped");
  if (thermal)
    thermal_steps(c, options, progress, start);
  else
    c.notes.push_back("no thermal manifest (thermal*.toml): the thermal steps were skipped");
  if (friction && thermal) {
    start("plan of the next thermal runs");
    detail::plan_next_thermal(c);
    start("prediction of the runs' cycle");
    detail::predict_runs_cycle(c);
  }
  c.warnings = detail::calibration_warnings(c);
  return c;
}

std::optional<std::string> unusable_headline(const Calibration& c) {
  const CalibratedModel& m = c.calibrated;
  const auto check = [](const char* which, const char* model, const FitResult& fit) -> std::optional<std::string> {
    if (fit.solver.usable) return std::nullopt;
    return fmt::format("the {} {} fit is not usable: {}", which, model, fit.solver.unusable_reason);
  };
  if (m.friction) {
    if (auto why = check("calibrated", "friction", m.friction->fit)) return why;
  } else if (c.friction) {
    if (auto why = check("law's", "friction", c.friction->fit)) return why;
  }
  if (m.thermal) return check("calibrated", "thermal", m.thermal->joint);
  if (c.thermal) return check("paper model's", "thermal", c.thermal->joint);
  return std::nullopt;
}

}  // namespace lmcal
