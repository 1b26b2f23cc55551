// What a least-squares fit reports, for every model lmcal fits (friction, thermal):
// estimates with standard errors and intervals, the correlation matrix, what the data
// cannot determine and why, and how the solver fared. Numerical trouble (a parameter at
// a bound, a singular covariance, a solver that stopped early, starts that disagree) is
// reported here as data, never thrown.
//
// Intervals: `ci_low/ci_high` are linear, value ± t(0.975, n - p) · SE with
// SE² = s² · [(JᵀJ)⁻¹]_jj and s² = Σr² / (n - p) (the covariance ceres::Covariance would
// give, from the autodiff Jacobian at the solution, scaled by the residual variance). Where the linear interval is unreliable (a bound inside it, or a
// weakly determined, strongly nonlinear parameter), `profile_low/high` hold the
// profile-likelihood interval {θ_j : S(θ_j) - S_min <= s² · F(0.95; 1, n - p)}, and
// `interval` says which one to quote.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace lmcal {

enum class RobustLoss { none, huber, cauchy };
enum class ProfileMode { none, automatic, all };

struct FitOptions {
  RobustLoss loss = RobustLoss::none;
  double loss_scale = 1.345;     // in units of the residual σ (whitened residuals)
  int starts = 8;                // multi-start local searches (NLopt) before the Ceres polish
  std::size_t subsample = 300;   // residuals the multi-start stage uses (evenly spread)
  ProfileMode profile = ProfileMode::automatic;
  double confidence = 0.95;
  // A direction in (relatively scaled) parameter space whose standard error exceeds this
  // fraction of the parameters' size is called not identifiable.
  double identifiability_threshold = 0.5;
  std::uint64_t seed = 1;
};

struct ParameterEstimate {
  std::string name;
  std::string unit;
  double value = 0;
  double start = 0;
  double lower = 0, upper = 0;
  bool free = true;            // asked to be fitted
  bool held_unidentifiable = false;  // asked to be fitted, but held at `start`: see identifiability
  bool at_bound = false;       // the estimate sits on a bound
  double se = 0;               // NaN when not fitted or the covariance failed
  double ci_low = 0, ci_high = 0;            // linear t interval
  double profile_low = 0, profile_high = 0;  // NaN unless computed
  std::string interval = "linear";           // "linear", "profile" or "none"
};

struct IdentifiabilityIssue {
  std::vector<std::pair<std::string, double>> combination;  // parameter -> weight (unit vector, relative scale)
  double relative_se = 0;  // standard error along that combination, relative to the parameters' size
  std::string why;
  std::string measure;     // which conditions would separate them
  std::vector<std::string> held;  // parameters held at their start value to fit the rest
};

struct Identifiability {
  bool identifiable = true;
  double condition_number = 0;  // of the relatively scaled Jacobian of the requested free parameters
  std::vector<IdentifiabilityIssue> issues;
};

struct SolverReport {
  bool converged = false;
  bool usable = false;
  int iterations = 0;
  std::string termination;
  std::string brief;             // Ceres BriefReport of the polish
  double initial_cost = 0, final_cost = 0;  // ½ Σ ρ(r²)
  int starts = 0, starts_agreed = 0;        // multi-start: how many reached the best minimum
  bool covariance_ok = false;
  std::string covariance_message;
  double seconds = 0;
};

struct FitResult {
  std::vector<ParameterEstimate> parameters;
  Eigen::MatrixXd covariance;   // all parameters, rows/columns of held ones zero
  Eigen::MatrixXd correlation;  // NaN where undefined
  std::size_t residuals = 0;
  std::size_t free_parameters = 0;
  double dof = 0;                // residuals - free parameters
  double residual_variance = 0;  // s² of the whitened residuals
  Identifiability identifiability;
  SolverReport solver;
  std::vector<std::string> warnings;

  const ParameterEstimate& parameter(const std::string& name) const;
  std::vector<double> values() const;
};

// Name -> version of the numerical libraries the fits were built with (Ceres, Eigen, NLopt).
std::vector<std::pair<std::string, std::string>> numerical_library_versions();

}  // namespace lmcal
