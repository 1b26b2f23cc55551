// Heteroscedasticity-and-autocorrelation-consistent covariance (Newey & West 1987) over each
// run's score series, Bartlett weights, bandwidth by Andrews' (1991) AR(1) plug-in.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <vector>
#include <fmt/format.h>

#include "covariance.hpp"
#include "parallel_slices.hpp"

namespace lmcal::detail {

// Bartlett weights are the autocorrelation of a box of L + 1 ones, divided by L + 1, so
//   Σ_{t,s} (1 − |t−s|/(L+1))₊ s_t s_sᵀ = Σ_j W_j W_jᵀ / (L + 1),
// W_j the sum of s_t over the window [j, j + L] (j = −L … T−1, clipped to the series):
// O(T m²) whatever L, where the lag sum is O(T L m²).
Eigen::MatrixXd bartlett_meat(const Eigen::MatrixXd& series, std::size_t lags) {
  const auto T = series.rows(), m = series.cols();
  const auto L = static_cast<Eigen::Index>(lags);
  std::vector<double> prefix(static_cast<std::size_t>(T) + 1);
  Eigen::MatrixXd windows(T + L, m);
  for (Eigen::Index a = 0; a < m; ++a) {  // column by column, as both are stored
    const double* s = series.col(a).data();
    for (Eigen::Index t = 0; t < T; ++t) prefix[static_cast<std::size_t>(t) + 1] = prefix[static_cast<std::size_t>(t)] + s[t];
    double* w = windows.col(a).data();
    for (Eigen::Index j = -L; j < T; ++j)
      w[j + L] = prefix[static_cast<std::size_t>(std::min(T, j + L + 1))] - prefix[static_cast<std::size_t>(std::max<Eigen::Index>(0, j))];
  }
  Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(m, m);
  meat.selfadjointView<Eigen::Lower>().rankUpdate(windows.transpose(), 1.0 / static_cast<double>(L + 1));
  return meat.selfadjointView<Eigen::Lower>();
}

// α̂(1) = Σ_a 4ρ_a²/((1−ρ_a)⁶(1+ρ_a)²) / Σ_a 1/(1−ρ_a)⁴ over the score components a (each
// standardised: the bandwidth should not depend on the parameters' units), and
// L = 1.1447 (α̂(1) T)^{1/3}, T the mean length of a run's series. Each ρ_a is the AR(1)
// coefficient the slowest-decaying of the lags 1, 2, 4 and 8 implies (c_k^{1/k}): for an AR(1)
// they agree, but where rows are not evenly spaced in time (a log that skips conditions) or
// mix fast and slow noise, lag 1 alone understates the memory, and the bandwidth with it.
double andrews_bandwidth(const RunScoreSeries& series) {
  const std::size_t runs = series.runs();
  if (runs == 0) return 0;
  double num = 0, den = 0, length = 0;
  for (std::size_t c = 0; c < runs; ++c) length += static_cast<double>(series.length(c));
  length /= static_cast<double>(runs);
  constexpr Eigen::Index kLags[] = {0, 1, 2, 4, 8};
  constexpr std::size_t kNumLags = std::size(kLags);
  // Each run's series made on a free thread, and its components' five autocovariances (a dot
  // product of the component with itself shifted) kept; then each component's sums over the
  // runs in their order: the same bits on any number of threads.
  const auto m = static_cast<std::size_t>(series.components());
  const auto dot = [m](std::size_t run, std::size_t component, std::size_t lag) { return (run * m + component) * kNumLags + lag; };
  std::vector<double> dots(runs * m * kNumLags, 0.0);
  for_each_index(runs, [&](std::size_t c) {
    const Eigen::MatrixXd s = series(c);
    for (std::size_t a = 0; a < m; ++a) {
      const auto x = s.col(static_cast<Eigen::Index>(a));
      for (std::size_t k = 0; k < kNumLags; ++k) {
        const Eigen::Index shifted = s.rows() - kLags[k];
        if (shifted > 0) dots[dot(c, a, k)] = x.tail(shifted).dot(x.head(shifted));
      }
    }
  });
  std::vector<double> num_of(m, 0.0), den_of(m, 0.0);
  for (std::size_t component = 0; component < m; ++component) {
    double sums[kNumLags] = {};
    for (std::size_t c = 0; c < runs; ++c)
      for (std::size_t k = 0; k < kNumLags; ++k)
        if (series.length(c) - kLags[k] > 0) sums[k] += dots[dot(c, component, k)];
    auto autocovariance = [&](Eigen::Index lag) {
      return sums[std::find(std::begin(kLags), std::end(kLags), lag) - std::begin(kLags)];
    };
    const double c0 = autocovariance(0);
    if (!(c0 > 0)) continue;
    // Longer lags count only where lag 1 and they themselves stand out of the noise (3/√N):
    // the k-th root of a chance 0.02 would be 0.6 at lag 8.
    const double noise = 3 / std::sqrt(length * static_cast<double>(runs));
    double rho = autocovariance(1) / c0;
    for (const Eigen::Index lag : {2, 4, 8}) {
      const double c = autocovariance(lag) / c0;
      if (rho > noise && c > noise) rho = std::max(rho, std::pow(c, 1.0 / static_cast<double>(lag)));
    }
    rho = std::clamp(rho, -0.97, 0.97);
    num_of[component] = 4 * rho * rho / (std::pow(1 - rho, 6) * std::pow(1 + rho, 2));
    den_of[component] = 1 / std::pow(1 - rho, 4);
  }
  // (A component without variance left its terms at +0, which add nothing.)
  for (std::size_t a = 0; a < num_of.size(); ++a) num += num_of[a], den += den_of[a];
  if (!(den > 0)) return 0;
  return 1.1447 * std::cbrt(num / den * length);
}

// Andrews' bandwidth minimises the mean squared error of the variance estimate; an interval
// needs less bias than that (Sun, Phillips & Jin 2008: the bandwidth that serves a test grows
// faster with T): six times it, up to half a run, with the fixed-b correction below for the bias that remains.
// Checked by coverage on AR(1) noise with φ = 0.9 (tests/coverage_test.cpp).
constexpr double kBandwidthFactor = 6.0;

CovarianceEstimate hac_covariance(const ScoreInputs& in, double max_bandwidth_fraction) {
  CovarianceEstimate e;
  e.method = "hac";
  const RunScoreSeries series(in, false);
  std::size_t shortest = series.runs() == 0 ? 0 : static_cast<std::size_t>(series.length(0));
  for (std::size_t c = 0; c < series.runs(); ++c) shortest = std::min(shortest, static_cast<std::size_t>(series.length(c)));
  const double cap = max_bandwidth_fraction * static_cast<double>(shortest);
  double chosen = kBandwidthFactor * andrews_bandwidth(series);
  if (!(chosen >= 0)) chosen = 0;  // non-finite scores (a fit that failed): no lags, not a NaN cast to a count
  const auto lags = static_cast<std::size_t>(std::floor(std::min(chosen, cap)));
  e.bandwidth = static_cast<double>(lags);
  // Fixed-b correction (Kiefer & Vogelsang 2005): with a bandwidth M = L + 1 that is a
  // share b = M/T of the series, the Bartlett estimate of a long-run variance is biased down by
  // E[Ω̂]/Ω = 1 − b + b²/3 (the fitted parameters take up part of the slow noise), and it is
  // itself uncertain: the interval's t quantile takes ν = G/b̄ degrees of freedom over G runs
  // (for one run, t(1/b) is within a few per cent of Kiefer & Vogelsang's fixed-b critical
  // values up to b = 0.5; independent runs average out).
  Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(in.jacobian.cols(), in.jacobian.cols());
  double b_sum = 0;
  // Each run's meat on a free thread, added in run order.
  std::vector<Eigen::MatrixXd> run_meat(series.runs());
  for_each_index(series.runs(), [&](std::size_t c) { run_meat[c] = bartlett_meat(series(c), lags); });
  for (std::size_t c = 0; c < series.runs(); ++c) {
    const double b = std::min(1.0, static_cast<double>(lags + 1) / std::max<double>(1.0, static_cast<double>(series.length(c))));
    meat += run_meat[c] / (1 - b + b * b / 3);
    b_sum += b;
  }
  const double G = static_cast<double>(std::max<std::size_t>(series.runs(), 1));
  const double n = static_cast<double>(in.residuals.size()), m = static_cast<double>(in.jacobian.cols());
  // Priors at their known variance, or their squared residual if larger.
  for (std::size_t i = 0; i < in.rows.cluster.size(); ++i)
    if (in.rows.is_prior(i)) {
      const auto row = static_cast<Eigen::Index>(i);
      const double variance = std::max(in.residuals[row] * in.residuals[row], in.rows.prior_variance[i]);
      meat += variance * in.jacobian.row(row).transpose() * in.jacobian.row(row);
    }
  e.dof = std::min(n - m, b_sum > 0 ? G * G / b_sum : n - m);
  e.ok = n - m > 0 && meat.allFinite();
  e.covariance = in.bread * meat * in.bread * (n / std::max(n - m, 1.0));
  e.description = fmt::format(
      "Newey-West sandwich within each run (Bartlett, {} lags by Andrews' AR(1) plug-in, fixed-b bias correction, "
      "t with {:.0f} dof): residuals may be autocorrelated and of unequal variance within a run; runs independent "
      "and alike",
      lags, e.dof);
  if (chosen > cap) e.note = fmt::format("bandwidth capped at {:.0f} lags ({:.0f} % of the shortest run)", cap, 100 * max_bandwidth_fraction);
  return e;
}

}  // namespace lmcal::detail
