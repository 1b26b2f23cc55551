// Fit the friction constants (k1, k2, μSt, V_St, μv, β, f0 — any subset; the others held
// at given values), and optionally named effects of friction_effects.hpp, to load-cell
// logs by weighted nonlinear least squares:
//
//   r_i = (F_measured,i - F_model(θ; conditions_i)) / σ_i
//
// with F_model the one friction law of friction.hpp (autodiff through ceres::Jet), bounds
// on every parameter, an optional robust loss, weights from the spread of repeats, a
// multi-start global stage (NLopt) and a Ceres polish (see fit_result.hpp for what is
// reported). Besides the pooled fit it fits every run alone and compares the spread of
// the run estimates with the pooled interval (Eq. 1 σ, t interval, min, max).
//
// Example:
//   auto log = lmcal::load_friction_log("measurements/cheng2017/friction.csv");
//   auto fit = lmcal::fit_friction(log, {});
//   std::cout << lmcal::friction_fit_summary(fit);
//
// Trap: with one preload class k1 and k2 appear only as (k1 - k2·pc): the fit then holds
// k2 at its start value, says so in fit.identifiability, and k1 is conditional on it.
#pragma once

#include "lmcal/export.hpp"

#include <array>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "lmcal/enum_names.hpp"
#include "lmcal/fit/fit_result.hpp"
#include "lmcal/fit/statistics.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/models/friction_effects.hpp"
#include "lmcal/models/friction_terms.hpp"

namespace LMCAL_API lmcal {

enum class FrictionWeighting {
  none,           // σ_i = 1; the covariance is scaled by the residual variance
  per_run,        // σ of each run's deviations from the condition means across runs
  per_condition,  // σ of the repeats of each condition (>= 3 repeats; floored)
};
inline constexpr FrictionWeighting kFrictionWeightings[] = {FrictionWeighting::none, FrictionWeighting::per_run,
                                                            FrictionWeighting::per_condition};
const char* to_string(FrictionWeighting weighting);  // "none", "per-run", "per-condition"
// The weighting named `name`; InvalidParameter naming `parameter` and the names otherwise.
inline FrictionWeighting parse_friction_weighting(std::string_view name, const std::string& parameter = "weights") {
  return parse_enum(kFrictionWeightings, name, parameter, "weighting");
}

// The named friction effects a fit may add, with their parameter names and units.
const std::vector<std::string>& friction_effect_names();
// Those a diagnosis may name as causes: the library without the drive's dynamics.
const std::vector<std::string>& friction_cause_names();
// The terms of the drive's dynamics a log needs besides friction (friction_effect.hpp,
// `dynamics`): moving_mass for a trajectory (FrictionLog::trajectory), axis_gravity for one on
// an inclined axis. fit_friction adds those not in its options' effects.
std::vector<std::string> drive_effects(const FrictionLog& log);

// automatic: random with two runs or more and no robust loss, none otherwise.
enum class RunOffsets { automatic, none, fixed, random };
inline constexpr RunOffsets kRunOffsets[] = {RunOffsets::automatic, RunOffsets::none, RunOffsets::fixed, RunOffsets::random};
const char* to_string(RunOffsets offsets);  // "auto", "none", "fixed", "random"
inline RunOffsets parse_run_offsets(std::string_view name, const std::string& parameter = "run_offsets") {
  return parse_enum(kRunOffsets, name, parameter, "model");
}

// The temperature the law is evaluated at, per sample:
//   logged:     as logged;
//   block_mean: the mean of the logged temperature over each block a run holds at one setting
//               (run, guide, preload, load, and a set point: logged temperatures within
//               max(1 K, 5σ) of each other, σ the thermometer's noise; cut into 1 K bins
//               where they drift over more than max(3 K, 8σ)). A thermometer's noise is a
//               classical error: taken as exact it flattens the law's temperature dependence
//               (β biased toward 0, μv up). The block's mean replaces it by an error the law
//               is not biased by (a Berkson error: a drift within the block stays unbiased),
//               and at its mean the noise is averaged down.
enum class FrictionTemperature { logged, block_mean };
inline constexpr FrictionTemperature kFrictionTemperatures[] = {FrictionTemperature::block_mean, FrictionTemperature::logged};
const char* to_string(FrictionTemperature temperature);  // "block-mean", "logged"
inline FrictionTemperature parse_friction_temperature(std::string_view name, const std::string& parameter = "temperature") {
  return parse_enum(kFrictionTemperatures, name, parameter, "choice");
}
// The log as a block_mean fit sees it: each temperature replaced by its block's mean.
FrictionLog with_block_mean_temperature(const FrictionLog& logged);

struct FrictionFitOptions {
  FitOptions fit;
  FrictionConstants<double> start = paper_friction_constants();  // start values; held constants keep them
  std::array<bool, FrictionConstants<double>::kFittable> free{true, true, true, true, true, true, true};
  // Wide enough that a misspecified law finds its optimum inside (a bound hit makes the
  // projected solve slow and the estimate hard to read).
  std::array<std::pair<double, double>, FrictionConstants<double>::kFittable> bounds{{{0, 5}, {-1, 1}, {0, 50}, {1e-4, 0.5}, {0, 0.1}, {0, 0.2}, {-1, 1}}};
  std::vector<std::string> effects;  // effects to fit on top of the law (names from friction_effect_names())
  std::vector<double> effect_start;  // their start values (default: neutral), in the order of `effects`
  // Empirical terms on top of the law and the effects (friction_terms.hpp): their coefficients
  // (and scales) are fitted, starting from the values in each term. Parameters "term1",
  // "term1_scale", "term2", … after the effects'.
  std::vector<FrictionTerm> terms;
  FrictionWeighting weighting = FrictionWeighting::none;
  bool per_run_fits = true;
  bool cross_validate = false;  // leave-one-run-out prediction RMSE (one-step, no refits)
  // The load cell's zero moves between runs (not with a robust loss):
  //   none:   no offsets;
  //   fixed:  one free offset per run, profiled out (residuals centred within each run) — all
  //           that changes only between runs (load, temperature on a one-setup-per-run rig)
  //           is then lost to the offsets;
  //   random: a random run intercept of variance τ², estimated by maximum likelihood with the
  //           constants (λ = τ²/σ² profiled within the one fit: re-estimated from per-run sums
  //           at each Gauss-Newton step; a fit whose λ still moves is refitted, at most
  //           `max_variance_passes` fits; 1 holds λ at `run_offset_ratio_start`): generalised
  //           least squares, so what changes between runs stays informative, weighed against τ²;
  //   automatic (the default): random with two runs or more and no robust loss, else none.
  // Without offsets the covariance takes a load-cell zero that moves between runs for noise:
  // the constants carried by the level between runs (f0, k1) get intervals far too narrow.
  RunOffsets run_offsets = RunOffsets::automatic;
  FrictionTemperature temperature = FrictionTemperature::block_mean;
  int max_variance_passes = 4;
  double run_offset_ratio_start = 0;  // random offsets: λ at the start (a related model's, to save steps)
};

struct ConditionResidual {
  std::string guide;
  double preload_um, load_N, temperature_C, velocity_m_s, direction;  // temperature rounded to 1 K
  std::size_t n;
  double measured_N, predicted_N;  // means
  double bias_N, rmse_N;           // of measured - predicted
  double relative_error;           // |mean measured - mean predicted| / mean measured
};

struct RunSpread {
  std::string parameter;
  std::vector<double> per_run;  // one value per run (NaN where a run's fit failed)
  std::vector<double> per_run_half_width_95;  // each run's own 95 % half-width (its fit's linear interval)
  std::vector<double> per_run_se;             // each run's own SE (its fit's quoted covariance)
  Spread spread;                // Eq. 1 σ, t interval of the mean, min, max
  // Why runs give no value (NaN in per_run), with their counts: "3 of 3 runs: one load and block
  // length in the run: …"; empty when every run gives one.
  std::string undetermined;
  double pooled_se = 0;
  // σ_runs / (SE_pooled · √runs): about 1 when the runs differ only by noise the model
  // explains (a descriptive ratio; the flag below is the test).
  double ratio = 0;
  // The pooled fit's test of heterogeneity between runs (Uncertainty::heterogeneity: each
  // run's score against the within-run covariance, χ²(runs − 1), Holm across the constants):
  // the runs differ beyond what the model explains when it is significant. Its Q and p are
  // those of the pooled model, so the run's share of the random offsets is in them (a test of
  // the runs' own estimates against their own SEs rejects too often: a run's SE, from a few
  // thousand autocorrelated samples, is about 15 % too small).
  double q = std::numeric_limits<double>::quiet_NaN();
  double p = std::numeric_limits<double>::quiet_NaN();
  double p_holm = std::numeric_limits<double>::quiet_NaN();
  bool wider_than_pooled = false;
};

// A combination law's (FrictionLawConditions::combination) constants as what the data
// determine at the log's one setup, quoted at `temperature_C`: the Coulomb level (N), the
// Stribeck amplitude (N) and speed (m/s), the viscous slope (N·s/m). Each is the fitted k1,
// mu_st, v_st_m_s or mu_v times the neutral conditions' factor (and, for a temperature away
// from T_i, ν's): intervals scaled with them where one constant carries the combination,
// by the delta method otherwise (`interval` says which).
struct LawCombination {
  ParameterEstimate estimate;  // name "coulomb_N", "stribeck_N", "stribeck_speed_m_s", "viscous_N_s_m"
  std::string meaning;         // in words, with the paper's constants it stands for
};

struct FrictionFitResult {
  FitResult fit;  // parameters: k1 … f0, then the effects
  std::vector<double> predicted_N;
  std::vector<double> sigma_N;
  double rmse_N = 0;
  // Leave-one-run-out, when asked: each run predicted from the others as a new setup (with
  // random offsets its zero unknown, at the offsets' mean), and the same with the held-out
  // run's own level taken out (its shape only; equal to the first with fixed offsets).
  double cv_rmse_N = std::numeric_limits<double>::quiet_NaN();
  double cv_shape_rmse_N = std::numeric_limits<double>::quiet_NaN();
  // Runs the others cannot stand in for: each alone varies something the law needs (the only
  // run at its load, preload or temperature), so held out, that part of the fit stays at the
  // full data's estimate, and their held-out errors are optimistic (held_out_caveat says so).
  std::vector<std::string> cv_undetermined_runs;
  // Per run: the zero offset in the predictions — the run's mean of measured - law (fixed
  // offsets), its shrunken estimate (random: mean · nλ/(1 + nλ)), or 0 (none) — and that mean.
  std::vector<double> run_offset_N;
  std::vector<double> run_mean_residual_N;
  double run_offset_sd_N = 0;     // τ of random offsets (ML; 0 otherwise)
  double run_offset_ratio = 0;    // λ = τ²/σ² of the whitened residuals
  int variance_passes = 0;        // fits the random offsets took
  RunOffsets run_offsets = RunOffsets::none;  // the model used (automatic resolved)
  // -2 log-likelihood of the fit as n log(deviance_ss / n), σ² profiled: the residual sum of
  // squares (whitened, offsets out) for none and fixed offsets, and with the random offsets'
  // determinant Σ log(1 + n_r λ) folded in for random ones. Comparable between models fitted
  // with the same offsets.
  double deviance_ss = 0;
  // max over samples of |measured − predicted| / max(|measured|, a tenth of the median |measured|)
  double max_relative_error = 0;
  std::size_t max_relative_error_sample = 0;
  std::vector<ConditionResidual> conditions;
  std::vector<std::string> runs;
  std::vector<RunSpread> spread;  // empty unless per-run fits ran (>= 2 runs)

  std::vector<FrictionTerm> terms;  // the fitted empirical terms (coefficient and scale at their estimates)

  // What the log gave (FrictionLog::law); for a combination law the combinations, quoted at
  // `law_temperature_C` (the mean logged temperature; T_i when none was logged).
  FrictionLawConditions law;
  std::vector<LawCombination> combinations;
  double law_temperature_C = 0;

  FrictionConstants<double> constants() const;
  FrictionEffects<double> effects() const;
};

// "" or, where cv_undetermined_runs is not empty, the words that go beside the held-out RMSE:
// which runs alone determine part of the law, and what that means for the number.
std::string held_out_caveat(const FrictionFitResult& fit);

FrictionFitResult fit_friction(const FrictionLog& log, const FrictionFitOptions& options);

// Provenance recorded with a fit.
struct FitProvenance {
  std::string name;
  std::vector<std::pair<std::string, std::string>> inputs;  // file -> sha256
  std::vector<std::string> command;
};

std::string friction_fit_json(const FrictionFitResult& result, const FrictionFitOptions& options,
                              const FitProvenance& provenance);
std::string friction_fit_samples_csv(const FrictionFitResult& result, const FrictionLog& log);
std::string friction_fit_conditions_csv(const FrictionFitResult& result);
// Every file a friction fit writes, file name -> contents: NAME.json, NAME_samples.csv and
// NAME_conditions.csv, with NAME = provenance.name.
std::vector<std::pair<std::string, std::string>> friction_fit_files(const FrictionFitResult& result, const FrictionLog& log,
                                                                    const FrictionFitOptions& options,
                                                                    const FitProvenance& provenance);
std::string friction_fit_summary(const FrictionFitResult& result);
// The fit as outputs show it: a combination law's combinations (FrictionFitResult::
// combinations) in place of the constants they scale, each covariance method's SE scaled as
// the quoted one; the constants that are not the log's (k2 and f0 of a combination law, β
// without a logged temperature) with interval "none".
FitResult friction_fit_as_shown(const FrictionFitResult& result);

}  // namespace lmcal
