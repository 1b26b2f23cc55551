#include "cause_starts.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lmcal/models/friction_effects.hpp"

namespace lmcal::detail {

namespace {

// The least-squares line through the origin y ≈ c g: c and the sum of squares it removes.
struct Projection {
  double coefficient = 0, explained = 0;
};
Projection project(double gy, double gg) { return gg > 0 ? Projection{gy / gg, gy * gy / gg} : Projection{}; }

std::vector<double> ripple_start(const FrictionLog& log, const std::vector<double>& residual_N) {
  const auto [low, high] = std::minmax_element(log.position_m.begin(), log.position_m.end());
  const double travel_m = *high - *low;
  const double shortest_m = PositionRipplePeriod::info.lower, longest_m = travel_m / 3;
  if (!(longest_m > shortest_m)) return {};
  // Means in bins of a quarter of the shortest period: the periodogram's cost is bins × periods,
  // not samples × periods, and a bin's mean averages the passes over it.
  const double bin_m = shortest_m / 4;
  const auto bins = static_cast<std::size_t>(travel_m / bin_m) + 1;
  std::vector<double> sum(bins, 0.0), count(bins, 0.0);
  for (std::size_t i = 0; i < log.size(); ++i) {
    const auto b = static_cast<std::size_t>((log.position_m[i] - *low) / bin_m);
    sum[b] += residual_N[i];
    count[b] += 1;
  }
  std::vector<double> x, y, w;
  for (std::size_t b = 0; b < bins; ++b)
    if (count[b] > 0) {
      x.push_back(*low + (static_cast<double>(b) + 0.5) * bin_m);
      y.push_back(sum[b] / count[b]);
      w.push_back(count[b]);
    }
  // Frequencies 4 times finer than the travel resolves: the peak is within a quarter of its width.
  const double step_1_m = 1 / (4 * travel_m);
  double best = 0, best_period = 0, best_a = 0, best_b = 0;
  for (double f = 1 / longest_m; f <= 1 / shortest_m; f += step_1_m) {
    // Weighted least squares of y on sin and cos (not orthogonal over an uneven coverage).
    double ss = 0, sc = 0, cc = 0, sy = 0, cy = 0;
    for (std::size_t k = 0; k < x.size(); ++k) {
      const double angle = 2 * std::numbers::pi * f * x[k], s = std::sin(angle), c = std::cos(angle);
      ss += w[k] * s * s, sc += w[k] * s * c, cc += w[k] * c * c, sy += w[k] * s * y[k], cy += w[k] * c * y[k];
    }
    const double det = ss * cc - sc * sc;
    if (!(det > 1e-12 * ss * cc)) continue;
    const double a = (cc * sy - sc * cy) / det, b = (ss * cy - sc * sy) / det;
    const double explained = a * sy + b * cy;
    if (explained > best) best = explained, best_period = 1 / f, best_a = a, best_b = b;
  }
  if (best_period == 0) return {};
  // A sin θ + B cos θ = R sin(θ + φ), R = √(A² + B²), φ = atan2(B, A).
  return {std::hypot(best_a, best_b), best_period, std::atan2(best_b, best_a)};
}

std::vector<double> presliding_start(const FrictionLog& log, const std::vector<double>& residual_N) {
  const double lower = PreslidingDistance::info.lower, upper = PreslidingDistance::info.upper;
  constexpr int kGrid = 25;
  double best = 0, best_share = 0, best_distance = PreslidingDistance::info.neutral;
  for (int g = 0; g < kGrid; ++g) {
    const double distance_m = lower * std::pow(upper / lower, (g + 0.5) / kGrid);
    double gy = 0, gg = 0;
    for (std::size_t i = 0; i < log.size(); ++i) {
      const double shape = -std::exp(-log.distance_since_reversal_m[i] / distance_m);
      gy += shape * residual_N[i], gg += shape * shape;
    }
    const Projection p = project(gy, gg);
    if (p.explained > best) best = p.explained, best_share = p.coefficient, best_distance = distance_m;
  }
  return {std::clamp(best_share, Presliding::info.lower, Presliding::info.upper), best_distance};
}

}  // namespace

std::vector<double> cause_start(std::string_view cause, const FrictionLog& log, const std::vector<double>& residual_N) {
  if (log.size() == 0 || log.position_m.size() != log.size()) return {};
  if (cause == PositionRipple::info.name) return ripple_start(log, residual_N);
  if (cause == Presliding::info.name) return presliding_start(log, residual_N);
  return {};
}

}  // namespace lmcal::detail
