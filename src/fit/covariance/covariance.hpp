// The covariance of a least-squares estimate θ̂, by several methods behind one interface
// (private to the fit layer; one file per method). Everything is computed from the whitened
// residuals r and their Jacobian J = ∂r/∂θ at θ̂ (free parameters only), the bread
// B = (JᵀJ)⁻¹, and how the rows hang together (RowStructure: the run of each row and its
// time step within the run). With H = JᵀJ and g_i = row i of J:
//
//   iid        s² B,  s² = Σr²/(n − m)            independent, equal-variance residuals
//   hac        B M B, M = Σ_runs [Γ₀ + Σ_l w_l (Γ_l + Γ_lᵀ)]   (newey_west.cc)
//              Newey-West with Bartlett weights w_l = 1 − l/(L+1) over each run's score
//              series s_t = Σ_{i at t} r_i g_i (sensors sharing a time step summed), bandwidth
//              L from Andrews' AR(1) plug-in; autocorrelation within runs, runs independent
//   cluster    B (Σ_c S_c S_cᵀ) B · G/(G−1)·(n−1)/(n−m), S_c the run's whole score,
//              t quantiles with G − 1 dof (cluster_robust.cc); any dependence within a run,
//              and runs that disagree beyond their own noise
//   bootstrap  runs resampled with replacement, θ* one Newton step from θ̂ on the resampled
//              runs (exact for models linear in θ; bootstrap.cc)
//
// Trap: every method here treats the model as right in its mean; none of them repairs a
// biased estimate. They differ in what they assume about the noise.
#pragma once

#include <Eigen/Core>

#include <cmath>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace lmcal::detail {

// How residual rows hang together: each row belongs to one run (a cluster) and one time
// step within it; rows of one run sharing a time step (several sensors read at once) have
// their scores summed before lags are taken. `series` numbers the rows' own time series (one
// sensor of one run) for the residual autocorrelation. Empty: no structure known (iid only).
struct RowStructure {
  std::vector<std::size_t> cluster;  // per row: its run, 0 .. clusters-1
  std::vector<std::size_t> time;     // per row: time step within its run, non-decreasing per run
  std::vector<std::size_t> series;   // per row: its time series (optional; empty = the run)
  // Per row (optional): for a prior's pseudo-observation (not data), its variance, known by
  // construction: the within-run sandwich counts the row at that variance (or at its squared
  // residual, if larger) rather than from one residual, and keeps it out of the time series.
  // NaN for data rows.
  std::vector<double> prior_variance;
  std::size_t clusters = 0;
  bool is_prior(std::size_t row) const { return !prior_variance.empty() && !std::isnan(prior_variance[row]); }
  bool empty() const { return cluster.empty(); }
};

// What every method reads.
struct ScoreInputs {
  const Eigen::MatrixXd& jacobian;   // n × m, free parameters only
  const Eigen::VectorXd& residuals;  // n
  const Eigen::MatrixXd& bread;      // (JᵀJ)⁻¹, m × m
  const RowStructure& rows;
};

struct CovarianceEstimate {
  std::string method;        // "iid", "hac", "cluster", "bootstrap"
  std::string description;   // the method and what it assumes, in words
  Eigen::MatrixXd covariance;  // m × m
  double dof = std::numeric_limits<double>::infinity();  // for t quantiles
  bool ok = false;
  std::string note;          // why it is not ok, or what to keep in mind
  double bandwidth = std::numeric_limits<double>::quiet_NaN();  // hac: lags L
};

// Each run's score series, made when asked for (a 10⁶-row fit's series together are as large as
// its Jacobian): row t = Σ_{rows of the run at time step t} r_i g_i (time steps without rows are
// zero rows); prior rows join their run's first step unless left out.
class RunScoreSeries {
 public:
  RunScoreSeries(const ScoreInputs& in, bool with_priors);
  std::size_t runs() const { return steps_.size(); }
  Eigen::Index components() const { return in_.jacobian.cols(); }  // the free parameters
  // The run's time steps: its series' rows.
  Eigen::Index length(std::size_t run) const { return static_cast<Eigen::Index>(steps_[run]); }
  Eigen::MatrixXd operator()(std::size_t run) const;

 private:
  const ScoreInputs& in_;
  std::vector<std::size_t> steps_;
  // Rows in series order (each run's rows together, time 0, 1, 2, …; no priors): each run's
  // first row, its series a block of J scaled by its residuals. Otherwise empty, and each
  // run's rows in order.
  std::vector<std::size_t> first_;
  std::vector<std::vector<std::size_t>> rows_of_;
};

CovarianceEstimate iid_covariance(const ScoreInputs& in);
// Newey-West over every run's score series; `max_bandwidth_fraction` caps L at that share of
// the shortest run's length.
CovarianceEstimate hac_covariance(const ScoreInputs& in, double max_bandwidth_fraction = 0.5);
// The HAC meat of one run's score series with `lags` Bartlett lags (O(T m²) by moving sums).
Eigen::MatrixXd bartlett_meat(const Eigen::MatrixXd& series, std::size_t lags);
// Andrews' (1991) AR(1) plug-in bandwidth for a Bartlett kernel over the runs' score series.
double andrews_bandwidth(const RunScoreSeries& series);
CovarianceEstimate cluster_covariance(const ScoreInputs& in);

// Between-run heterogeneity of each parameter the runs share: Q_j = G·V^cl_jj / V^hac_jj
// (raw cluster variance over the within-run one), which for one parameter is Cochran's
// Q = Σ_c (θ_c − θ̄)²/SE_c², against χ²(G_j − 1).
struct HeterogeneityTest {
  std::size_t parameter = 0;  // free index
  std::size_t runs = 0;       // runs whose rows depend on it
  double q = 0, p_value = 1;
  double i_squared = 0;       // (Q − (G−1))/Q, floored at 0: the share of the spread that is real
};
std::vector<HeterogeneityTest> between_run_heterogeneity(const ScoreInputs& in, const CovarianceEstimate& hac);

// Cluster bootstrap (runs resampled with replacement), one Newton step from θ̂ per replicate.
// An external input the fit took as given (the heat from a friction fit) can be resampled
// with it: `external_jacobian` (n × q) is ∂r/∂u and `external_draws[b]` the replicate's
// deviation u* − û. Deterministic for a seed, with any number of threads.
struct BootstrapResult {
  CovarianceEstimate estimate;
  Eigen::MatrixXd draws;  // replicates × m: θ* − θ̂ (NaN where a replicate could not determine it)
};
BootstrapResult cluster_bootstrap(const ScoreInputs& in, std::size_t replicates, std::uint64_t seed,
                                  const Eigen::MatrixXd* external_jacobian = nullptr,
                                  const std::vector<Eigen::VectorXd>* external_draws = nullptr);

// `count` vectors of `size` independent standard normal numbers, the same for a seed on any
// machine (splitmix64 and Box-Muller, not std::normal_distribution).
std::vector<Eigen::VectorXd> standard_normal_draws(std::size_t count, Eigen::Index size, std::uint64_t seed);

// Lag-1 autocorrelation of the residuals within their series, pooled, and the effective
// number of independent residuals n (1 − ρ)/(1 + ρ).
double residual_lag1_autocorrelation(const Eigen::VectorXd& residuals, const RowStructure& rows);
double effective_sample_size(double n, double rho);

}  // namespace lmcal::detail
