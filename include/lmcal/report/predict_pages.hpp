// The HTML pages of `lmcal predict` (prediction.html) and `lmcal plan` (plan.html): one
// self-contained file each (inline SVG plots and style, no external resource), built with the
// calibration report's page and plots (report::html_document).
//
//   prediction.html  the duty and the band's method; the rail's elongation, its temperature at
//                    the duty's positions, the scale's error and the block's heat over time,
//                    each with its band (data-plot "prediction-elongation",
//                    "prediction-temperature", "prediction-scale-error", "prediction-heat");
//                    the largest elongation and every segment's end with their bands (the
//                    numbers of summarize(), as prediction.json and stdout give them)
//   plan.html        the picked conditions (runs), each parameter's SE now -> after, the
//                    notes, and a plot of each SE after over now ("plan-se-ratio")
//
// Numbers to 4 significant digits. A long duty's series are drawn at up to 400 output times
// (every segment's end and the largest elongation among them; all in prediction_time.csv).
#pragma once

#include "lmcal/export.hpp"

#include <string>
#include <vector>

#include "lmcal/predict/plan.hpp"
#include "lmcal/predict/prediction.hpp"

namespace LMCAL_API lmcal {

std::string prediction_html(const Prediction& p, const DutyCycle& duty, const std::vector<std::string>& command);
std::string friction_plan_html(const FrictionPlan& plan, const std::vector<std::string>& command);
std::string thermal_plan_html(const ThermalPlan& plan, const std::vector<std::string>& command);

}  // namespace lmcal
