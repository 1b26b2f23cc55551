// What the friction law gets wrong on measured data, the named physical cause, and what
// modelling it gains on data it was not fitted to.
//
//   Each run's load-cell zero is a nuisance offset, profiled out of every fit (the residuals
//   are centred within runs); a trend of those offsets over the runs is tested separately.
//
//   1. baseline: the published law fitted to the log; the zero offset of every run,
//      Durbin-Watson within runs, and the correlation of the residuals with every covariate
//      (speed, load, preload, block length, temperature, direction, run order, time), tested
//      on condition means (one value per condition, so repeated samples of a condition do
//      not count as independent evidence);
//   2. candidates: each named effect of friction_effects.hpp added on its own and fitted;
//      scored by leave-one-run-out prediction RMSE (each run predicted from the others by one
//      Gauss-Newton step from the full fit, no refits), AICc, BIC and a likelihood-ratio test;
//   3. forward selection: the best candidate is accepted only if it is significant (LRT
//      p < 0.001 and a lower BIC), its 95 % interval excludes its neutral value, and it
//      lowers the held-out RMSE of the runs' level or shape by at least 2 % without raising
//      the other by more; then the rest are tried on top of it, until nothing more passes;
//   4. verdict: the accepted causes with magnitude and interval, held-out RMSE before and
//      after, how the constants shift once the cause is modelled, and what remains. If the
//      residuals stay structured and no candidate passes: "unexplained", with the covariate
//      they follow. Otherwise "no significant discrepancy".
#pragma once

#include "lmcal/export.hpp"

#include <limits>
#include <string>
#include <vector>

#include "lmcal/diagnose/diagnosis.hpp"
#include "lmcal/fit/friction_fit.hpp"

namespace LMCAL_API lmcal {

struct ResidualDiagnostics {
  double rmse_N = 0;
  double sigma = 0;                         // residual σ of the whitened fit
  double durbin_watson = 2;                 // within runs, in time order
  std::vector<std::pair<std::string, double>> run_bias_N;
  std::vector<CovariateTest> covariates;    // strongest first
  bool structured = false;                  // a covariate significant (Holm p < 0.001) and large enough
  LackOfFit lack_of_fit;
  // A trajectory's: the force its position resolution makes through the moving mass, M σ_a (σ_a
  // the acceleration noise the filter leaves, RunSegmentation). A move that repeats repeats the
  // encoder's quantization too, so that force does not average out over the cycles: structure of
  // the position, speed and acceleration up to this RMS can be the encoder's, and is not called a
  // discrepancy or a cause. 0 without a fitted mass.
  double resolution_floor_N = 0;
};

struct FrictionDiagnosisOptions {
  // The baseline fit: what it holds, starts from and bounds; the zero offsets random by
  // default (fixed ones would hide all that changes only between runs).
  FrictionFitOptions fit = [] {
    FrictionFitOptions f;
    f.run_offsets = RunOffsets::random;
    return f;
  }();
  double lrt_p = 1e-3;
  double min_cv_gain_percent = 2.0;
  double structure_p = 1e-3;
  // Structure smaller than this share of the residual RMSE is reported but not called a
  // discrepancy: over thousands of run means, 0.02 N beside 0.2 N of noise is significant
  // without mattering.
  double min_structure_fraction = 0.2;
  // Speeds, loads and preloads that agree within this share of their value are one condition in
  // the lack-of-fit test and one value in the between-run tests: their resolution (a raw log's
  // plateau speeds differ in the fifth digit, run means of one block length in the last bit; a
  // design spaces its set values by 20 % or more). Temperature is matched to 1 K.
  double condition_tolerance = 0.01;
  // Where the design repeats too few conditions across runs for a pure error, the residuals are
  // judged against the noise of their high-frequency differences: structure remains when the
  // residual RMS exceeds this multiple of that noise (and F rejects at structure_p). Trap:
  // differences see noise correlated beyond neighbouring samples only in part (an AR(1) φ of 0.5
  // at one sample: 0.65 σ), which this margin covers up to φ ≈ 0.68.
  double noise_margin = 2.0;
  std::size_t max_effects = 3;
  // When the residuals stay structured after the named causes: learn an empirical term
  // (friction_terms.hpp) and keep it if it passes the rules a cause must pass.
  bool learn_term = true;
  Progress progress;  // the candidate fits, round by round
};

// Whether the runs' friction differs by a factor beyond their zeros, on the final model
// (src/diagnose/run_scale.hpp says how): what a new run's level cannot be predicted better than.
struct RunScaleTest {
  bool tested = false;
  bool differ = false;  // Cochran's Q significant at the selection's LRT level
  std::size_t runs = 0;
  double q = std::numeric_limits<double>::quiet_NaN(), dof = std::numeric_limits<double>::quiet_NaN();
  double p = std::numeric_limits<double>::quiet_NaN();
  double tau_percent = std::numeric_limits<double>::quiet_NaN();  // spread of the factors beyond their SEs, % of the friction
  double floor_percent = 0;  // the runs' zeros' spread as a share of the mean force: τ must exceed it
  std::vector<std::string> run;                                  // per run tested
  std::vector<double> factor_percent, se_percent;                // its factor − 1 and SE, %
  std::string reason;
};

struct FrictionDiagnosis {
  std::string verdict;          // "no significant discrepancy", "explained", "unexplained"
  std::string summary;          // the verdict in plain words
  ResidualDiagnostics baseline;
  ResidualDiagnostics final;
  std::vector<std::vector<CandidateScore>> rounds;  // the candidates of every forward step
  std::vector<CandidateScore> accepted;
  // Causes accepted before the empirical term that no longer pass on top of it (they stood in
  // for what it models), and why: left out of `accepted` and the final fit.
  std::vector<std::string> dropped;
  // From the baseline to the final model (the causes, each cause dropped, then the empirical
  // term when found): each step's before is the previous step's after; cv_rmse_after_N is the
  // last step's after.
  std::vector<DiagnosisStep> steps;
  double cv_rmse_before_N = 0, cv_rmse_after_N = 0, cv_gain_percent = 0;
  std::vector<ParameterShift> shifts;
  std::string unexplained_covariate;  // when the verdict is "unexplained"
  // What the design confounds and what it costs: covariates seen only between runs, or at
  // one value only; no repeated conditions (no lack-of-fit test).
  std::vector<std::string> design_notes;
  FrictionFitResult baseline_fit, final_fit;  // the law, and the law with the accepted causes
  // When the residuals stay structured after the causes: the empirical term learned, and the
  // fit of the law with the causes and that term (empty unless found).
  EmpiricalFinding empirical;
  FrictionFitResult empirical_fit;
  // On the final model (with the term when found): do the runs differ by a factor?
  RunScaleTest run_scale;
};

FrictionDiagnosis diagnose_friction(const FrictionLog& log, const FrictionDiagnosisOptions& options);

// Step 1 alone on a fit the caller made (`fit friction`): the residuals' tests against the
// covariates and the lack of fit, as the diagnosis's baseline gets them.
ResidualDiagnostics diagnose_friction_residuals(const FrictionLog& log, const FrictionFitResult& fit,
                                                const FrictionDiagnosisOptions& options = {});

// What those tests say remains, in one sentence ("the residuals follow velocity_m_s (p = 1e-20,
// size 0.31 N of an RMSE of 0.84 N)…"), or "" when the law fits to the noise.
std::string friction_structure_remains(const ResidualDiagnostics& r);

// What `fit friction` and Python's fit_friction add to a usable fit of two runs or more without a
// robust loss: where those tests find structure, a warning that names the commands that look
// further (a fit cannot say what its law misses).
void warn_of_missed_structure(const FrictionLog& log, const FrictionFitOptions& options, FrictionFitResult& fit);
std::string friction_diagnosis_json(const FrictionDiagnosis& d);

}  // namespace lmcal
