// lmcal calibrate: the whole story of one measurement set, in one call (the pipeline; the
// report layer renders its result: lmcal/report/calibration.hpp).
//
//   load → friction fit → friction diagnosis → thermal fit (heat from that friction fit)
//        → thermal diagnosis → the calibrated model,   with the spread across runs inside each fit
//
// The answer is the calibrated model: the published law and rail model with the causes the
// diagnoses accepted, refitted in full (every constant and mechanism with SE, interval and
// correlation; the thermal one takes its heat, and the heat's uncertainty, from the calibrated
// friction model). The fits of the published models stay, for comparison: they are
// conditional on a model the diagnosis rejects.
//
// A measurement set is a folder: its friction logs are the `friction*.csv` files in it, or the
// files a `friction*.toml` manifest lists (at most one; it gives the runs' conditions and how
// raw load-cell logs are segmented), its thermal data the `thermal*.toml` manifest (at most one). Either half may be missing; the
// thermal half then takes its heat from the manifest's measured mean friction (or is skipped).
// The outputs (lmcal/report/calibration.hpp) are the files `lmcal fit …` and `lmcal diagnose …`
// write, a summary (calibration.json) and the report (report.html, see html_report.hpp).
//
// Example:
//   auto c = lmcal::calibrate(lmcal::find_calibration_set("measurements/cheng2017"), {});
//   if (auto why = lmcal::unusable_headline(c)) std::cerr << *why << "\n";
//   else std::cout << c.calibrated.thermal->joint.parameter("alpha").value << "\n";
//
// Trap: a Calibration records its command as `lmcal calibrate SET` (not where its outputs are
// written), so the same set gives the same files wherever they go; timings ("seconds") are the
// only fields that differ between runs.
#pragma once

#include "lmcal/export.hpp"

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "lmcal/diagnose/friction_diagnosis.hpp"
#include "lmcal/diagnose/thermal_diagnosis.hpp"
#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/fit/model_file.hpp"
#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/io/thermal_run.hpp"
#include "lmcal/predict/plan.hpp"
#include "lmcal/predict/prediction.hpp"

namespace LMCAL_API lmcal {

struct CalibrationSet {
  std::filesystem::path dir;
  std::string name;                                   // the folder's name
  std::vector<std::filesystem::path> friction_logs;   // friction*.csv, sorted
  std::optional<std::filesystem::path> friction_manifest;  // friction*.toml: its files instead of friction_logs
  std::optional<std::filesystem::path> thermal_manifest;
  std::vector<std::filesystem::path> ignored_files;   // lmcal's own outputs (friction_samples.csv, …): never inputs
};

// The names of every file `calibration_outputs` may write; `find_calibration_set` never takes
// one of them for an input (calibrate -o SET writes its outputs beside the logs).
const std::vector<std::string>& calibration_output_names();
bool is_calibration_output(std::string_view file_name);

// Whether `file` is a set's measurement (friction*.csv other than lmcal's outputs,
// friction*.toml, thermal*.toml): a folder holding one is a measurement set.
bool is_measurement_file(const std::filesystem::path& file);

// What `dir` holds; InputError when it is not a folder or holds neither half.
CalibrationSet find_calibration_set(const std::filesystem::path& dir);

struct CalibrationOptions {
  std::string catalog_file;  // the user's guide catalog ("" = the built-in one only); wins over a manifest's `catalog`
  RawFrictionOptions raw;    // how raw load-cell logs are segmented
  std::vector<std::string> raw_given;  // those of `raw` set by the user (they win over a manifest's [raw])
  // Where the set's files may be (input_scope.hpp): inside the set's folder unless a root is
  // given (a fleet's ROOT) or --allow-outside-root. Its root is not part of the results.
  InputScope inputs;
  FrictionFitOptions friction;
  FrictionDiagnosisOptions friction_diagnosis;
  ThermalFitOptions thermal;  // the friction constants are set from the friction fit
  ThermalDiagnosisOptions thermal_diagnosis;
  bool diagnose = true;
};

// How far the calibration is: `step` (0-based) of `steps` named `name` starts; `detail`
// reports inside the long steps (the diagnoses' candidate fits).
struct CalibrationProgress {
  std::function<void(std::size_t step, std::size_t steps, const std::string& name)> step;
  Progress detail;
};

// The published models with the accepted causes, refitted: the result of a calibration.
struct CalibratedModel {
  std::vector<std::string> friction_causes, thermal_causes;  // the accepted effects/mechanisms
  FrictionFitOptions friction_options;
  std::optional<FrictionFitResult> friction;
  ThermalFitOptions thermal_options;
  std::optional<ThermalFitResult> thermal;
};

struct Calibration {
  CalibrationSet set;
  CalibrationOptions options;                               // as given (calibration.json records them)
  std::vector<std::pair<std::string, std::string>> inputs;  // file -> sha256
  std::vector<std::string> command;                         // as recorded in the outputs
  std::vector<std::string> notes;                           // steps skipped, and why
  // Likely mistakes in the data (the loaders' warnings, heat from the paper's constants, a run
  // that disagrees with the others): printed, in calibration.json and in the report.
  std::vector<std::string> warnings;
  std::optional<FrictionLog> friction_log;
  FrictionFitOptions friction_options;
  std::optional<FrictionFitResult> friction;
  std::optional<FrictionDiagnosis> friction_diagnosis;
  std::optional<ThermalDataSet> thermal_data;
  ThermalFitOptions thermal_options;
  std::optional<ThermalFitResult> thermal;
  std::optional<ThermalDiagnosis> thermal_diagnosis;
  CalibratedModel calibrated;
  // The calibrated model over the runs' own cycle (duty_of_runs), with bands: what the model
  // predicts, in the report and prediction.json (both halves calibrated; else a note says why not).
  std::optional<DutyCycle> duty;
  std::optional<Prediction> prediction;
  // The next friction conditions to log (D-optimal over the logs' own values, 5 conditions), for
  // the calibrated law: in the report, plan.json and plan_friction_template.csv.
  std::optional<FrictionPlan> plan;
  // The next 2 thermal runs for the calibrated rail model (speeds from half the slowest run's to
  // 1.5 times the fastest's): D-optimal, or Ds-optimal to separate the first tie the thermal
  // diagnosis reported; in the report, plan_thermal.json and plan_thermal_manifest.toml.
  std::optional<ThermalPlan> thermal_plan;
};

Calibration calibrate(const CalibrationSet& set, const CalibrationOptions& options,
                      const CalibrationProgress& progress = {});

// model.toml's contents: the calibrated model with the set's provenance (the command, the
// inputs and their hashes); what the prediction and the thermal plan use.
ModelFile calibrated_model_file(const Calibration& c);

// Why the calibration's headline fits (the calibrated models', else the law fits') give no
// answer to use, or nullopt: "the calibrated thermal fit is not usable: no degree of freedom
// left: 12 residuals for 12 free parameters". The CLI exits with its own status then, a fleet
// marks the set failed.
std::optional<std::string> unusable_headline(const Calibration& c);

}  // namespace lmcal
