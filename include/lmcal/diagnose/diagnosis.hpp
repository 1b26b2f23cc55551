// What the friction and the thermal diagnosis share: the covariate tests of the residuals,
// the score of a candidate cause, and the shift of the baseline's parameters.
#pragma once

#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "lmcal/fit/fit_result.hpp"

namespace lmcal {

// A diagnosis holds one run out at a time and scores it from the others.
inline constexpr std::size_t kMinDiagnosisRuns = 3;

// Told what a long computation is doing and how far it has got: step `done` of `total`
// (0-based) of `what`. Called from the calling thread; may be empty.
using Progress = std::function<void(const std::string& what, std::size_t done, std::size_t total)>;

struct CovariateTest {
  std::string covariate;
  double correlation = 0;  // η, the share of the residuals' variation the covariate's groups explain
  double p_value = 1;
  double p_adjusted = 1;   // Holm-adjusted over every test of the same residuals
  double size = 0;         // RMS of the structure it explains, in the residuals' unit
  std::size_t n = 0;       // group means tested (condition or cell means, or runs for run order)
  bool structured = false; // counts as structure under the diagnosis's rule
};

struct CandidateScore {
  std::string effect;
  double value = 0, se = 0, ci_low = 0, ci_high = 0;  // its (first) parameter; NaN for a switch
  std::size_t added_parameters = 1;
  double aicc = 0, bic = 0;
  double lrt_statistic = 0, lrt_p = 1;  // NaN for a switch (not nested: BIC decides)
  double cv_rmse = 0;                   // leave-one-run-out, in the data's unit
  double cv_gain_percent = 0;           // against the current model
  double cv_shape_gain_percent = std::numeric_limits<double>::quiet_NaN();  // on the runs' shape (their level out)
  bool accepted = false;
  std::string reason;                   // why it was or was not accepted
  std::string measure;                  // what to log to see this cause directly
  // Candidates of the same round whose change to the fit cannot be told from this one's
  // (the changes they make to the fitted values correlate above 0.99): a tie, named together.
  std::vector<std::string> tied_with;
};

// Lack of fit against pure error: do the model's residuals exceed the noise? Friction: the
// condition means (after the run levels) against the spread of repeated conditions across
// runs. Thermal: the residual variance against the thermocouples' noise floor.
struct LackOfFit {
  bool tested = false;
  std::string basis;       // what the pure error is, or why it was not tested
  double statistic = 0;    // F
  double df1 = 0, df2 = 0;
  double p_value = 1;
  double lack_rms = 0;     // RMS of the lack of fit beyond the noise, in the residuals' unit
  double pure_error_rms = 0;  // the noise it is judged against
  bool fits = true;        // not rejected at the diagnosis's structure_p (or not tested)
};

// How a parameter moves once the causes are modelled, each value with its 95 % interval
// (the quoted one: linear or profile).
struct ParameterShift {
  std::string name;
  double baseline = 0, extended = 0;
  double baseline_low = 0, baseline_high = 0, extended_low = 0, extended_high = 0;
  bool free = true;  // estimated in both models (a held parameter is never reported as moving)
};
ParameterShift parameter_shift(const ParameterEstimate& baseline, const ParameterEstimate& extended);

}  // namespace lmcal
