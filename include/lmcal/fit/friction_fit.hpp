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

#include <array>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "lmcal/fit/fit_result.hpp"
#include "lmcal/fit/statistics.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/models/friction_effects.hpp"

namespace lmcal {

enum class FrictionWeighting {
  none,           // σ_i = 1; the covariance is scaled by the residual variance
  per_run,        // σ of each run's deviations from the condition means across runs
  per_condition,  // σ of the repeats of each condition (>= 3 repeats; floored)
};

// The named friction effects a fit may add, with their parameter names and units.
const std::vector<std::string>& friction_effect_names();

struct FrictionFitOptions {
  FitOptions fit;
  FrictionConstants<double> start = paper_friction_constants();  // start values; held constants keep them
  std::array<bool, 7> free{true, true, true, true, true, true, true};
  // Wide enough that a misspecified law finds its optimum inside (a bound hit makes the
  // projected solve slow and the estimate hard to read).
  std::array<std::pair<double, double>, 7> bounds{{{0, 5}, {-1, 1}, {0, 50}, {1e-4, 0.5}, {0, 0.1}, {0, 0.2}, {-1, 1}}};
  std::vector<std::string> effects;  // effects to fit on top of the law (names from friction_effect_names())
  std::vector<double> effect_start;  // their start values (default: neutral), in the order of `effects`
  FrictionWeighting weighting = FrictionWeighting::none;
  bool per_run_fits = true;
  bool cross_validate = false;  // leave-one-run-out prediction RMSE (one-step, no refits)
  // Profile out one zero offset per run (the load cell's zero moves between runs): residuals
  // are centred within each run. Not with a robust loss.
  bool zero_offset_per_run = false;
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
  Spread spread;                // Eq. 1 σ, t interval of the mean, min, max
  double pooled_se = 0;
  // σ_runs / (SE_pooled · √runs): about 1 when the runs differ only by noise the model
  // explains; far above 1 (> 3) means the model misses something that differs by run.
  double ratio = 0;
  bool wider_than_pooled = false;
};

struct FrictionFitResult {
  FitResult fit;  // parameters: k1 … f0, then the effects
  std::vector<double> predicted_N;
  std::vector<double> sigma_N;
  double rmse_N = 0;
  double cv_rmse_N = std::numeric_limits<double>::quiet_NaN();  // leave-one-run-out, when asked
  std::vector<double> run_offset_N;  // per run: mean of measured - predicted (the profiled offset)
  double max_relative_error = 0;  // max over samples of |measured - predicted| / |measured|
  std::size_t max_relative_error_sample = 0;
  std::vector<ConditionResidual> conditions;
  std::vector<std::string> runs;
  std::vector<RunSpread> spread;  // empty unless per-run fits ran (>= 2 runs)

  FrictionConstants<double> constants() const;
  FrictionEffects<double> effects() const;
};

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

}  // namespace lmcal
