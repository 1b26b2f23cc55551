// The options of a calibration (`lmcal calibrate` and `lmcal fleet`): the fits' constants,
// uncertainty and multi-start, the raw logs' segmentation, the rail model, the diagnoses'
// thresholds; one setting for every step that has it.
#pragma once

#include <CLI/CLI.hpp>

#include "cli_common.hpp"
#include "lmcal/calibrate/calibration.hpp"

namespace lmcal::cli {

struct CalibrationCliOptions {
  CalibrationOptions calibration;
  FitOptions uncertainty;  // --covariance, --bootstrap: for every fit; --profile: the quoted fits
  FrictionConstantOptions constants;
  ThermalModelOptions thermal_model;
  FrictionInputOptions input;  // --catalog and the raw logs' segmentation
  const CLI::Option* lrt_p = nullptr;
  const CLI::Option* starts = nullptr;
  const CLI::Option* seed = nullptr;

  void add_to(CLI::App& app);
  // The options as every step takes them: the published fits, the diagnoses' baselines and
  // the calibrated model's fits.
  CalibrationOptions resolve();
};

}  // namespace lmcal::cli
