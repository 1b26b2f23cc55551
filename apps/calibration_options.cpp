#include "calibration_options.hpp"

#include <string>
#include <utility>
#include <vector>

#include "lmcal/io/limits.hpp"

namespace lmcal::cli {

void CalibrationCliOptions::add_to(CLI::App& app) {
  CalibrationOptions& c = calibration;
  app.add_flag_function("--no-diagnosis", [&c](std::int64_t) { c.diagnose = false; }, "Skip the two diagnoses (fits and report only)");
  add_uncertainty_options(app, uncertainty);
  // The friction fits: constants held, freed, started and bounded; the load cell's zero; the
  // multi-start search.
  add_friction_constant_options(app, constants);
  starts = app.add_option("--starts", c.friction.fit.starts, "Multi-start local searches of the friction fits")
               ->check(up_to_limit(1, io::kMaxStarts))
               ->capture_default_str();
  seed = app.add_option("--seed", c.friction.fit.seed, "Seed of the multi-start sequence")->capture_default_str();
  // The guides' catalog and the raw load-cell logs' segmentation.
  input.add_to(app);
  // The rail model: heat, source, numerics, h, offsets.
  thermal_model.add_to(app, c.thermal);
  ThermalModelOptions::add_offsets(app, c.thermal);
  // The diagnoses' thresholds.
  app.add_option("--friction-min-gain", c.friction_diagnosis.min_cv_gain_percent,
                 "Least held-out RMSE gain to accept a friction cause, %")
      ->check(at_least(0))
      ->capture_default_str();
  app.add_option("--thermal-min-gain", c.thermal_diagnosis.min_cv_gain_percent,
                 "Least held-out RMSE gain to accept a thermal mechanism, %")
      ->check(at_least(0))
      ->capture_default_str();
  lrt_p = app.add_option("--lrt-p", c.friction_diagnosis.lrt_p, "Significance level of the diagnoses' likelihood-ratio tests")
              ->check(inside(0, 1))
              ->capture_default_str();
}

CalibrationOptions CalibrationCliOptions::resolve() {
  CalibrationOptions options = calibration;
  options.catalog_file = input.catalog_file;
  options.raw = input.parsed();
  options.raw_given = input.raw_given();
  apply_friction_constant_options(constants, options.friction);
  apply_friction_constant_options(constants, options.friction_diagnosis.fit);
  std::vector<std::pair<std::string, std::string>> no_inputs;
  thermal_model.apply(options.thermal, no_inputs);
  thermal_model.apply(options.thermal_diagnosis.fit, no_inputs);
  thermal_model.copy_given(options.thermal, options.thermal_diagnosis.fit);
  if (lrt_p->count() > 0) options.thermal_diagnosis.lrt_p = options.friction_diagnosis.lrt_p;
  for (FitOptions* fit : {&options.friction.fit, &options.friction_diagnosis.fit.fit, &options.thermal.fit,
                          &options.thermal_diagnosis.fit.fit}) {
    fit->covariance = uncertainty.covariance;
    fit->bootstrap = uncertainty.bootstrap;
  }
  // Profiles where the model is quoted (the diagnoses' many candidate fits keep theirs automatic).
  options.friction.fit.profile = options.thermal.fit.profile = uncertainty.profile;
  if (starts->count() > 0) options.friction_diagnosis.fit.fit.starts = options.friction.fit.starts;
  if (seed->count() > 0) options.friction_diagnosis.fit.fit.seed = options.friction.fit.seed;
  return options;
}

}  // namespace lmcal::cli
