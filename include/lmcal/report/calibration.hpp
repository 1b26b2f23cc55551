// A calibration rendered: every output file of `lmcal calibrate` (calibration_outputs),
// calibration.json and the summary for the terminal. The pipeline that makes a Calibration is
// lmcal/calibrate/calibration.hpp; the report (report.html) is html_report.hpp.
//
// Example:
//   auto c = lmcal::calibrate(lmcal::find_calibration_set("measurements/cheng2017"), {});
//   lmcal::OutputSet out;
//   for (auto& [name, text] : lmcal::calibration_outputs(c)) out.add(std::filesystem::path("fits/cheng2017") / name, text);
//   out.commit();
//
// Trap: the outputs record the command as `lmcal calibrate SET` (not where they were written),
// so the same set gives the same files wherever they go; timings ("seconds") are the only
// fields that differ between runs.
#pragma once

#include "lmcal/export.hpp"

#include <string>
#include <utility>
#include <vector>

#include "lmcal/calibrate/calibration.hpp"

namespace LMCAL_API lmcal {

// Every output file, name -> contents, in a fixed order: model.toml (the calibrated model),
// calibrated_friction.json, calibrated_thermal.json (its fits in full), friction.json,
// friction_samples.csv, friction_conditions.csv, friction_diagnosis.json, thermal.json,
// thermal_samples.csv, thermal_alpha_curve.csv, thermal_diagnosis.json (the published models
// and the diagnoses; those of the steps that ran), prediction.json and prediction_time.csv (the
// runs' cycle predicted), plan_friction.json and plan_friction_template.csv (the next friction
// conditions to log), plan_thermal.json and plan_thermal_manifest.toml (the next thermal runs),
// calibration.json and report.html.
std::vector<std::pair<std::string, std::string>> calibration_outputs(const Calibration& c);

// Every setting a calibration runs with, as calibration.json records them ("options").
std::string calibration_options_json(const CalibrationOptions& options);

// calibration.json: the set, its inputs and their hashes, the steps, the headline numbers and
// the verdicts.
std::string calibration_json(const Calibration& c);

// The headline numbers and verdicts in a few lines, for the terminal.
std::string calibration_summary(const Calibration& c);

}  // namespace lmcal
