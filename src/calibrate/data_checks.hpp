// Checks of the loaded data and of the fits' per-run results that catch a user's mistakes
// (private to the calibrate layer): what `lmcal calibrate` prints as warnings, writes to
// calibration.json ("warnings") and lists in the report's "data loaded" section.
//
//   - every loader warning (LoadReport::warnings: a column that resembles a known one but is
//     not read, a magnitude where a signed force was expected, …), with its file;
//   - a thermal run whose heat came from the paper's friction constants because nothing else
//     was given (no friction log, no measured friction, no heater power);
//   - a run that disagrees with the others: a friction run whose residual RMS is over
//     kRunRmsRatio times the median run's, a thermal run whose own α lies more than
//     kRunOutlierZ robust σ from the median of the runs' (σ = max(1.4826·MAD, the median of
//     the runs' standard errors), so that runs that agree within their errors are never
//     flagged). Needs at least three runs.
#pragma once

#include <string>
#include <vector>

#include "lmcal/calibrate/calibration.hpp"

namespace lmcal::detail {

inline constexpr double kRunRmsRatio = 3.0;
inline constexpr double kRunOutlierZ = 5.0;

std::vector<std::string> calibration_warnings(const Calibration& c);

}  // namespace lmcal::detail
