// What a least-squares fit reports, for every model lmcal fits (friction, thermal):
// estimates with standard errors and intervals, the correlation matrix, what the data
// cannot determine and why, and how the solver fared. Numerical trouble (a parameter at
// a bound, a singular covariance, a solver that stopped early, starts that disagree) is
// reported here as data, never thrown.
//
// Uncertainty: the covariance comes from the method that fits the data's structure
// (`uncertainty.method`, chosen automatically unless asked; every method computed is reported
// beside it so the ratio shows):
//   iid        s²(JᵀJ)⁻¹, s² = Σr²/(n − p): independent residuals of equal variance;
//   hac        Newey-West sandwich within each run: autocorrelated residuals (thermocouple
//              traces sampled every few seconds), runs alike;
//   cluster    cluster-robust sandwich by run, t with runs − 1 dof: runs that disagree beyond
//              their own noise (chosen when a test says they do; floored at the hac SE);
//   bootstrap  runs resampled with replacement (the reference; percentile interval in
//              boot_low/boot_high).
// Intervals: `ci_low/ci_high` are value ± t(0.975, dof) · SE with the chosen covariance.
// Where the linear interval is unreliable (a bound inside it, or a weakly determined,
// strongly nonlinear parameter), `profile_low/high` hold the profile-likelihood interval
// {θ_j : S(θ_j) - S_min <= k_j s² F(0.95; 1, n - p)}, k_j >= 1 the chosen variance over the iid
// one (a profile of a sum of squares knows nothing of correlated residuals), and `interval`
// says which one to quote.
#pragma once

#include "lmcal/export.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "lmcal/enum_names.hpp"

namespace LMCAL_API lmcal {

// The loss a fit's residuals go through: none (least squares), Huber's or Cauchy's, each at
// FitOptions::loss_scale (in units of the whitened residual).
enum class RobustLoss { none, huber, cauchy };
inline constexpr RobustLoss kRobustLosses[] = {RobustLoss::none, RobustLoss::huber, RobustLoss::cauchy};
constexpr const char* to_string(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::none: return "none";
    case RobustLoss::huber: return "huber";
    case RobustLoss::cauchy: return "cauchy";
  }
  return "?";
}
// The loss named `name`; InvalidParameter naming `parameter` and the names otherwise.
inline RobustLoss parse_robust_loss(std::string_view name, const std::string& parameter = "loss") {
  return parse_enum(kRobustLosses, name, parameter, "loss");
}

// Profile-likelihood intervals: for no parameter, where the linear interval is unreliable
// (automatic, see above) or for every free one.
enum class ProfileMode { none, automatic, all };
inline constexpr ProfileMode kProfileModes[] = {ProfileMode::automatic, ProfileMode::all, ProfileMode::none};
constexpr const char* to_string(ProfileMode mode) {
  switch (mode) {
    case ProfileMode::none: return "none";
    case ProfileMode::automatic: return "auto";
    case ProfileMode::all: return "all";
  }
  return "?";
}
// The mode named `name`; InvalidParameter naming `parameter` and the names otherwise.
inline ProfileMode parse_profile_mode(std::string_view name, const std::string& parameter = "profile") {
  return parse_enum(kProfileModes, name, parameter, "profile mode");
}

// The covariance the intervals quote (see Uncertainty above; automatic: by the data's structure).
enum class CovarianceMethod { automatic, iid, hac, cluster, bootstrap };
inline constexpr CovarianceMethod kCovarianceMethods[] = {CovarianceMethod::automatic, CovarianceMethod::iid,
                                                          CovarianceMethod::hac, CovarianceMethod::cluster,
                                                          CovarianceMethod::bootstrap};
constexpr const char* to_string(CovarianceMethod method) {
  switch (method) {
    case CovarianceMethod::automatic: return "auto";
    case CovarianceMethod::iid: return "iid";
    case CovarianceMethod::hac: return "hac";
    case CovarianceMethod::cluster: return "cluster";
    case CovarianceMethod::bootstrap: return "bootstrap";
  }
  return "?";
}
// The method named `name`; InvalidParameter naming `parameter` and the names otherwise.
inline CovarianceMethod parse_covariance_method(std::string_view name, const std::string& parameter = "covariance") {
  return parse_enum(kCovarianceMethods, name, parameter, "covariance method");
}

struct FitOptions {
  RobustLoss loss = RobustLoss::none;
  double loss_scale = 1.345;     // in units of the residual σ (whitened residuals)
  int starts = 8;                // multi-start local searches on a subsample before the polish
  std::size_t subsample = 300;   // residuals the multi-start stage uses (evenly spread)
  int max_iterations = 200;      // of the Ceres polish (a diagnosis caps its many warm-started fits)
  ProfileMode profile = ProfileMode::automatic;
  double confidence = 0.95;
  // A direction in (relatively scaled) parameter space whose standard error exceeds this
  // fraction of the parameters' size is called not identifiable.
  double identifiability_threshold = 0.5;
  std::uint64_t seed = 1;
  // Which covariance the SEs and intervals quote (see Uncertainty); automatic: hac where
  // rows form time series in runs, cluster where the runs also disagree beyond their noise
  // (a Holm-adjusted test below `heterogeneity_p`), iid where the model knows no structure.
  CovarianceMethod covariance = CovarianceMethod::automatic;
  double heterogeneity_p = 0.05;
  std::size_t bootstrap = 999;  // cluster-bootstrap replicates (0: none)
  // The run is the unit of replication: something differs between runs that no record of a
  // run sees (the heat reaching the rail of a thermal run), so with three runs or more the
  // automatic choice is cluster-robust by run even when the runs do not disagree significantly
  // (a test with few runs has little power; the t quantile with runs − 1 dof pays for them).
  bool runs_replicate = false;
};

// One point of a parameter's profile: the parameter held at `value`, the others refitted;
// `excess` = (S(value) − S_min) / threshold, so the profile interval's edges are where it
// crosses 1 (and a quadratic ((value − θ̂)/(t·SE))² is what the linear interval assumes).
struct ProfilePoint {
  double value = 0;
  double excess = 0;
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
  // A nuisance parameter of one run (a thermocouple offset, a start temperature, a heat
  // scale): fitted for the others' sake, left out of the tables of the model's parameters.
  bool per_run = false;
  // Listed in the tables of the model's parameters; false for a constant held only to state the
  // others, which the data say nothing of (friction_fit_as_shown).
  bool listed = true;
  double se = 0;               // NaN when not fitted or the covariance failed
  double dof = 0;              // of the t quantile of ci_low/ci_high
  double ci_low = 0, ci_high = 0;            // linear t interval
  double profile_low = 0, profile_high = 0;  // NaN unless computed
  double boot_low = 0, boot_high = 0;        // cluster-bootstrap percentile interval; NaN unless computed
  std::string interval = "linear";           // "linear", "profile" or "none"
  std::vector<ProfilePoint> profile_curve;   // every point the profile search evaluated, by value
};

// One covariance method's standard errors, beside the others.
struct CovarianceSummary {
  std::string method;       // "iid", "hac", "cluster", "bootstrap", or with a suffix for a
                            // two-stage total ("hac + heat")
  std::string description;  // the method and what it assumes
  std::string note;
  bool ok = false;
  double dof = 0;           // of its t quantile
  std::vector<double> se;   // per parameter; NaN where held or not estimated
};

// Do the runs disagree about a parameter beyond their own errors? Q = G·V_cluster/V_hac,
// Cochran's Q for one parameter, against χ²(G − 1); Holm-adjusted over the parameters.
struct RunHeterogeneity {
  std::string parameter;
  std::size_t runs = 0;
  double q = 0, p_value = 1, p_holm = 1;
  double i_squared = 0;  // the share of the between-run spread that is real, not noise
  bool significant = false;
};

struct Uncertainty {
  std::string method;  // the covariance the reported SEs and intervals come from
  std::string reason;  // why that one, in words
  double dof = 0;      // of the intervals' t quantile
  std::vector<CovarianceSummary> methods;
  std::vector<RunHeterogeneity> heterogeneity;
  std::size_t runs = 0;                 // clusters (0: the model knows no run structure)
  double lag1_autocorrelation = 0;      // of the residuals within their series; NaN if unknown
  double effective_sample_size = 0;     // n (1 − ρ)/(1 + ρ)
  double hac_lags = 0;                  // NaN without hac
  std::vector<std::string> notes;       // fallbacks and caveats, in words
  // The parameters whose SE comes from the runs as replicates (the spread of the runs' own
  // estimates, which the joint fit's covariance understated): thermal fits with 3 runs or more.
  std::vector<std::string> from_replicates;
  // Two-stage: the input the fit took as given ("heat") and, per parameter, the share of its
  // variance that comes from that input's uncertainty (NaN where none was added).
  std::string input;
  std::vector<double> input_variance_share;
  // The quoted covariance before the input's uncertainty was added (all parameters; empty
  // without an input): the parameters' uncertainty for a given input, which a prediction that
  // draws the input itself (the friction constants behind the heat) needs.
  Eigen::MatrixXd covariance_given_input;
  Eigen::MatrixXd bootstrap_draws;      // replicates × parameters: θ* − θ̂ (NaN: held/undetermined)

  const CovarianceSummary* find(const std::string& method) const;
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
  // An estimate to use: the residuals were finite, the solver did not fail, and some degree of
  // freedom is left. Otherwise `unusable_reason` says which.
  bool usable = false;
  std::string unusable_reason;
  int iterations = 0;
  std::string termination;
  std::string brief;             // Ceres BriefReport of the polish
  double initial_cost = 0, final_cost = 0;  // ½ Σ ρ(r²)
  int starts = 0, starts_agreed = 0;        // multi-start: how many reached the best minimum
  // Where each start's local search ended, ½ Σ ρ(r²) over the `start_residuals` rows the
  // multi-start uses, in start order (empty for a linear model, which needs no starts).
  std::vector<double> start_costs;
  std::size_t start_residuals = 0;
  // The Gauss-Newton step still to go at the end, in standard errors (the largest over the free
  // parameters not pressing on a bound): ~0 at a minimum. Above 0.1, and taking it lowers the
  // cost, the polish stopped where the cost still falls: `converged` is false (whatever Ceres
  // said). `restarted`: it did, and the best start, judged on all the data, was polished again.
  double remaining_step_se = 0;
  bool restarted = false;
  bool covariance_ok = false;
  std::string covariance_message;
  double seconds = 0;
};

struct FitResult {
  std::vector<ParameterEstimate> parameters;
  Eigen::MatrixXd covariance;   // all parameters (the chosen method's), rows/columns of held ones zero
  Eigen::MatrixXd correlation;  // NaN where undefined
  std::size_t residuals = 0;
  std::size_t free_parameters = 0;
  double dof = 0;                // residuals - free parameters
  double residual_variance = 0;  // s² of the whitened residuals
  Identifiability identifiability;
  Uncertainty uncertainty;
  SolverReport solver;
  std::vector<std::string> warnings;

  const ParameterEstimate& parameter(const std::string& name) const;
  std::vector<double> values() const;
};

// A unit as the summaries' tables show it: "-" for a dimensionless "1" or none.
inline std::string shown_unit(const std::string& unit) { return unit.empty() || unit == "1" ? "-" : unit; }

}  // namespace lmcal
