// The steps of `calibrate` after the fits of the published models and their diagnoses
// (private to the calibrate layer): each reads what the steps before it left in the
// Calibration and adds its own result, or a note saying why there is none.
#pragma once

#include "lmcal/calibrate/calibration.hpp"

namespace lmcal::detail {

// The law refitted with the causes the friction diagnosis accepted (calibrated_model.cc).
void calibrate_friction_model(Calibration& c);
// The rail model refitted with the mechanisms the thermal diagnosis accepted, its heat from the
// calibrated friction model (calibrated_model.cc).
void calibrate_thermal_model(Calibration& c, const CalibrationOptions& options);

// The next friction conditions to log, the next thermal runs, the runs' cycle predicted
// (plan_and_predict.cc).
void plan_next_friction(Calibration& c);
void plan_next_thermal(Calibration& c);
void predict_runs_cycle(Calibration& c);

}  // namespace lmcal::detail
