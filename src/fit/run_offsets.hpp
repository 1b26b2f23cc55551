// Random run intercepts (a load cell's zero that moves between runs), private to the fit layer.
//
// A run's offset u_g ~ N(0, τ²) on residuals of variance σ² is whitened by taking out the share
// c_g = 1 − 1/√(1 + n_g λ) of the run's mean residual (λ = τ²/σ², n_g the run's residuals):
// generalised least squares with only per-run sums (BatchedAutoDiffCostFunction's groups).
// λ by maximum likelihood from the raw residuals' per-run count n_g, sum S_g and the total
// within-run sum of squares W:
//   −2 log L(λ) = n log(Q(λ)/n) + Σ_g log(1 + n_g λ),   Q(λ) = W + Σ_g S_g²/n_g / (1 + n_g λ),
// σ² = Q/n profiled. Q(λ) is also the whitened residuals' sum of squares at λ, so a polish
// that re-estimates λ at every Gauss-Newton step (ProfiledRunOffsets) ends at the joint
// maximum likelihood that alternating whole fits only approach.
// Trap: with few runs the ML τ² is biased low by about the between-run share of the constants;
// the intervals do not rest on it (see assess_uncertainty).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace lmcal::detail {

struct RunOffsetVariance {
  double ratio = 0, sigma2 = 1, deviance_ss = 0;
  std::vector<double> count;  // residuals per run
};

// λ from per-run sums (count[g] = 0: a run without residuals). A grid over log λ, then
// golden-section refinement; λ = 0 when no offset variance is seen.
inline RunOffsetVariance run_offset_variance(std::vector<double> count, const std::vector<double>& sum, double within) {
  RunOffsetVariance v;
  v.count = std::move(count);
  const std::size_t runs = v.count.size();
  double n = 0;
  for (double c : v.count) n += c;
  auto q = [&](double lambda) {
    double Q = within;
    for (std::size_t g = 0; g < runs; ++g)
      if (v.count[g] > 0) Q += sum[g] * sum[g] / v.count[g] / (1 + v.count[g] * lambda);
    return Q;
  };
  auto deviance = [&](double lambda) {
    double logdet = 0;
    for (double c : v.count) logdet += std::log1p(c * lambda);
    return n * std::log(std::max(q(lambda), 1e-300) / n) + logdet;
  };
  double best = 0, best_d = deviance(0);
  for (double e = -8; e <= 6; e += 0.25)
    if (const double d = deviance(std::pow(10.0, e)); d < best_d) best = std::pow(10.0, e), best_d = d;
  if (best > 0) {
    double a = std::log10(best) - 0.25, b = std::log10(best) + 0.25;
    const double g = (std::sqrt(5.0) - 1) / 2;
    for (int it = 0; it < 40; ++it) {
      const double x1 = b - g * (b - a), x2 = a + g * (b - a);
      if (deviance(std::pow(10.0, x1)) < deviance(std::pow(10.0, x2))) b = x2;
      else a = x1;
    }
    const double refined = std::pow(10.0, (a + b) / 2);
    if (deviance(refined) < best_d) best = refined;
  }
  v.ratio = best;
  v.sigma2 = q(best) / n;
  v.deviance_ss = n * std::exp(deviance(best) / n);
  return v;
}

// λ from the raw residuals (whitened by σ, offsets not taken out), `run` their run indices.
inline RunOffsetVariance run_offset_variance(const std::vector<double>& raw, const std::vector<std::size_t>& run,
                                             std::size_t runs) {
  std::vector<double> count(runs, 0.0), sum(runs, 0.0), sq(runs, 0.0);
  for (std::size_t i = 0; i < raw.size(); ++i) {
    count[run[i]] += 1;
    sum[run[i]] += raw[i];
    sq[run[i]] += raw[i] * raw[i];
  }
  double within = 0;
  for (std::size_t g = 0; g < runs; ++g)
    if (count[g] > 0) within += sq[g] - sum[g] * sum[g] / count[g];
  return run_offset_variance(std::move(count), sum, within);
}

// The share c_g of a run's mean residual taken out for an offset of variance ratio λ.
inline double run_offset_shrink(double count, double ratio) { return 1 - 1 / std::sqrt(1 + count * ratio); }

// λ profiled during a polish: while `profiling`, each evaluation of the normal equations over
// all rows re-estimates λ from the raw residuals' per-run sums at θ and re-whitens (`*shrink`,
// the model's c_g, updated in place; the step of that iteration solves the GLS at that λ).
// The engine ends profiling once the estimate is settled (LeastSquaresModel::estimate_settled),
// so that its covariance, bootstrap and profiles see one objective.
struct ProfiledRunOffsets {
  std::vector<double>* shrink = nullptr;
  bool profiling = false;
  int updates = 0;  // re-estimates of λ
  double ratio = 0;

  void update(const std::vector<double>& count, const std::vector<double>& sum, double within) {
    const RunOffsetVariance v = run_offset_variance(count, sum, within);
    ratio = v.ratio;
    ++updates;
    shrink->resize(count.size());
    for (std::size_t g = 0; g < count.size(); ++g) (*shrink)[g] = run_offset_shrink(count[g], ratio);
  }
};

}  // namespace lmcal::detail
