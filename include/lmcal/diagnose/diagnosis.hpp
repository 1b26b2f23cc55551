// What the friction and the thermal diagnosis share: the covariate tests of the residuals,
// the score of a candidate cause, and the shift of the baseline's parameters.
#pragma once

#include "lmcal/export.hpp"

#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "lmcal/fit/fit_result.hpp"

namespace LMCAL_API lmcal {

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

// A held-out gain in [−100, 100] %: 100 (before − after) / max(before, after). A gain is quoted
// against the RMSE before, a loss against the RMSE after (a model twice as bad is 50 % worse),
// so no number of the diagnosis reads "−1316 % better". NaN unless both are finite and > 0.
double held_out_gain_percent(double before, double after);

// What a held-out gain is counted on: the leave-one-run-out RMSE of new runs ("level": each
// predicted with an unknown zero), or the same with each held-out run's own level taken out
// ("shape"). Their words, for every text that quotes one.
std::string held_out_criterion_words(const std::string& criterion);

struct CandidateScore;
// The name a candidate is reported under: its neutral name where its precondition is absent.
const std::string& shown_name(const CandidateScore& c);

struct CandidateScore {
  std::string effect;
  double value = 0, se = 0, ci_low = 0, ci_high = 0;  // its (first) parameter; NaN for a switch
  // How ci_low/ci_high were formed: "linear" (value ± t·SE), or, where that would cross one of the
  // parameter's bounds, "log"/"logit" (on the log scale of the distance to the bound, or the
  // logit between two, mapped back) or "clipped" (the estimate on its bound).
  std::string interval = "linear";
  std::string unit;                                   // that parameter's ("N s2/m2" for seal_drag)
  std::size_t added_parameters = 1;
  double aicc = 0, bic = 0;
  double lrt_statistic = 0, lrt_p = 1;  // NaN for a switch (not nested: BIC decides)
  double cv_rmse = 0;                   // leave-one-run-out, in the data's unit
  double cv_gain_percent = 0;           // against the current model (held_out_gain_percent)
  double cv_shape_rmse = std::numeric_limits<double>::quiet_NaN();  // on the runs' shape (their level out)
  double cv_shape_gain_percent = std::numeric_limits<double>::quiet_NaN();
  bool accepted = false;
  std::string reason;                   // why it was or was not accepted
  std::string measure;                  // what to log to see this cause directly
  // The name outputs give it, where its precondition does not hold (a load cell's zero needs a
  // load cell): a neutral one ("signed_constant_force") with its look-alikes in `tied_with`
  // and `precondition` saying what is unknown; empty: `effect` (shown_name).
  std::string shown;
  std::string precondition;
  // The value at which the cause is absent (the library's neutral value): a cause is accepted
  // only where its interval excludes it. NaN: no such rule (a switch, a thermal extension).
  double neutral = std::numeric_limits<double>::quiet_NaN();
  // Candidates of the same round whose change to the fit cannot be told from this one's
  // (the changes they make to the fitted values correlate above 0.99): a tie, named together.
  std::vector<std::string> tied_with;
  // Thermal: α of the model with this candidate in (NaN for friction): α is conditional on
  // the model, and these show how far the candidates move it.
  double alpha = std::numeric_limits<double>::quiet_NaN();
  double alpha_low = std::numeric_limits<double>::quiet_NaN(), alpha_high = std::numeric_limits<double>::quiet_NaN();
};
inline const std::string& shown_name(const CandidateScore& c) { return c.shown.empty() ? c.effect : c.shown; }
// One step from the baseline to the final model: a cause added (forward selection), a cause
// dropped (it stood in for the empirical term: the model refitted without it), or the empirical
// term added. Each model's held-out RMSEs are computed once and carried: a step's before is the
// previous step's after, the first step's the baseline's, and the last step's after is the
// diagnosis's final value (cv_rmse_after_*), which every text quotes.
struct DiagnosisStep {
  std::string action;  // "add cause", "drop cause", "add empirical term"
  std::string name;    // the cause, or the term's formula
  double cv_rmse_before = std::numeric_limits<double>::quiet_NaN(), cv_rmse_after = std::numeric_limits<double>::quiet_NaN();
  double cv_shape_rmse_before = std::numeric_limits<double>::quiet_NaN();  // NaN: not scored (thermal)
  double cv_shape_rmse_after = std::numeric_limits<double>::quiet_NaN();
  std::string criterion = "level";  // what the step's gain is counted on: "level" or "shape"
  double gain_percent = std::numeric_limits<double>::quiet_NaN();  // on the criterion, held_out_gain_percent
  double before() const { return criterion == "shape" ? cv_shape_rmse_before : cv_rmse_before; }
  double after() const { return criterion == "shape" ? cv_shape_rmse_after : cv_rmse_after; }
};

// The range of α over the candidate models of every round (thermal; NaN when none has one).
std::pair<double, double> candidate_alpha_range(const std::vector<std::vector<CandidateScore>>& rounds);

// Lack of fit: do the model's residuals exceed the noise? Friction: the condition means (after
// the run levels) against the spread of conditions repeated across runs (pure error), or where
// the design repeats none, the residual variance against the noise of high-frequency
// differences of consecutive residuals. Thermal: the residual variance against the
// thermocouples' noise floor.
struct LackOfFit {
  bool tested = false;
  std::string basis;       // what the pure error is, or why it was not tested
  std::string against;     // "pure error" or "noise" ("" when not tested)
  double statistic = 0;    // F
  double df1 = 0, df2 = 0;
  double p_value = 1;
  double lack_rms = 0;     // RMS of the lack of fit beyond the noise, in the residuals' unit
  double pure_error_rms = 0;  // the noise it is judged against
  // Against the noise: structure remains when the residual RMS exceeds `margin` times the noise
  // (and F rejects). NaN: not this rule.
  double margin = std::numeric_limits<double>::quiet_NaN();
  // Friction: the relative tolerance within which speed, load and preload matched as one
  // condition (their resolution; NaN: thermal).
  double condition_tolerance = std::numeric_limits<double>::quiet_NaN();
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

// An empirical discrepancy term: what the model still misses after the named causes, learned
// from the residuals when they stay structured (a sparse regression over a dictionary of
// transforms of the covariates, selected by leave-one-run-out error) and then fitted jointly
// with the model. It is never a named cause: it says what the residuals follow and what
// modelling that buys on held-out runs, and which mechanisms it resembles.
struct EmpiricalComponent {
  std::string symbol;                   // "c1 * exp(-s/l1) * F_law"
  std::string words;                    // "decays with the sliding distance s, in proportion to the law's force"
  std::vector<std::string> covariates;  // what it uses: "sliding_distance_m", "friction_law_N"
  ParameterEstimate coefficient;        // c, with the joint fit's interval
  bool has_scale = false;
  ParameterEstimate scale;              // ℓ, τ or the period, with its interval, when the term has one
};

// The term over its main covariate, for the report: means over bins of the covariate.
struct EmpiricalCurve {
  std::string covariate, unit;
  std::vector<double> x;                       // bin centres
  std::vector<double> value, low, high;        // the term's mean contribution and its 95 % band (delta method)
  // The residuals' means in the same bins: after, the joint fit's; before, the same with the
  // term added back (partial residuals: what the term has to explain).
  std::vector<double> residual_before, residual_after;
};

struct CovariateRange {
  std::string covariate;
  double min = 0, max = 0;  // seen in the data: the term is an extrapolation beyond
};

struct EmpiricalFinding {
  bool searched = false;  // the residuals stayed structured after the named causes
  bool found = false;     // a term passed: significant, and better on held-out runs
  std::string form;       // "sparse" (a few dictionary terms) or "smooth" (B-splines in one covariate)
  std::string where;      // what it is added to: "the friction force", "every thermocouple reading"
  std::string formula;    // the whole term in symbols
  std::vector<EmpiricalComponent> components;
  std::size_t dictionary_size = 0;  // candidate terms searched
  // Held-out, the residuals' unit, on the criterion the term was kept by ("level" or "shape":
  // the RMSE of the runs' shape, each held-out run's level out), before and after the term:
  // the gain beside them is theirs.
  std::string criterion = "level";
  double cv_rmse_before = std::numeric_limits<double>::quiet_NaN();
  double cv_rmse_after = std::numeric_limits<double>::quiet_NaN();
  double cv_gain_percent = std::numeric_limits<double>::quiet_NaN();
  double lrt_p = std::numeric_limits<double>::quiet_NaN();
  double delta_bic = std::numeric_limits<double>::quiet_NaN();
  std::string resembles;  // mechanisms it resembles, in words ("" when none)
  std::string reason;     // when searched: why it was kept, or why nothing was
  std::vector<CovariateRange> ranges;
  EmpiricalCurve curve;
};

}  // namespace lmcal
