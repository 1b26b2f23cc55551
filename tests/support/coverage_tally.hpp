// Coverage of quoted intervals, counted over replicates with a known truth: hits, errors and
// quoted SEs of one parameter (tests/coverage_test.cpp and the trajectory tests use it).
#pragma once

#include <cmath>
#include <cstddef>
#include <string>

#include "lmcal/fit/fit_result.hpp"

namespace lmcal::test {

struct Tally {
  std::string name;
  double truth = 0;
  std::size_t n = 0, hits = 0;
  double squared_error = 0, se = 0;

  void add(const ParameterEstimate& p) {
    const double low = p.interval == "profile" ? p.profile_low : p.ci_low;
    const double high = p.interval == "profile" ? p.profile_high : p.ci_high;
    ++n;
    hits += truth >= low && truth <= high ? 1 : 0;
    squared_error += (p.value - truth) * (p.value - truth);
    se += p.se;
  }
  double coverage() const { return static_cast<double>(hits) / static_cast<double>(n); }
  // The quoted SE over the actual error (RMS about the truth, bias included): about 1 when the
  // intervals are as wide as they need to be, far above 1 when they widen needlessly.
  double se_ratio() const { return (se / static_cast<double>(n)) / std::sqrt(squared_error / static_cast<double>(n)); }
};

// The fewest hits in n replicates that 95 % intervals reach with probability at least
// 1 - alpha: the binomial(n, 0.95) lower quantile. Fewer says the coverage is below 95 %.
inline std::size_t fewest_hits(std::size_t n, double alpha) {
  double below = 0;  // P(X < k)
  for (std::size_t k = 0; k <= n; ++k) {
    const double p_k = std::exp(std::lgamma(n + 1.0) - std::lgamma(k + 1.0) - std::lgamma(n - k + 1.0) +
                                static_cast<double>(k) * std::log(0.95) + static_cast<double>(n - k) * std::log(0.05));
    if (below + p_k > alpha) return k;
    below += p_k;
  }
  return n;
}

}  // namespace lmcal::test
