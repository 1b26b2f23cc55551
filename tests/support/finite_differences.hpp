// Checks a cost function's Jacobian against central finite differences, entry by entry.
#pragma once

#include <ceres/cost_function.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace lmcal::test {

// The step is `relative_step` · |θ_j| (· 1 where θ_j = 0); entries must agree to `tolerance`
// relative to max(1, |derivative|).
inline void expect_jacobian_matches_central_differences(const ceres::CostFunction& cost, const std::vector<double>& theta,
                                                        double relative_step, double tolerance) {
  const auto n = static_cast<std::size_t>(cost.num_residuals());
  const std::size_t p = theta.size();
  std::vector<double> r(n), J(n * p), plus(n), minus(n);
  const double* at[] = {theta.data()};
  double* jacobians[] = {J.data()};
  ASSERT_TRUE(cost.Evaluate(at, r.data(), jacobians));
  for (std::size_t j = 0; j < p; ++j) {
    auto tp = theta, tm = theta;
    const double h = relative_step * (theta[j] != 0 ? std::abs(theta[j]) : 1.0);
    tp[j] += h;
    tm[j] -= h;
    const double* at_plus[] = {tp.data()};
    const double* at_minus[] = {tm.data()};
    ASSERT_TRUE(cost.Evaluate(at_plus, plus.data(), nullptr));
    ASSERT_TRUE(cost.Evaluate(at_minus, minus.data(), nullptr));
    for (std::size_t i = 0; i < n; ++i) {
      const double fd = (plus[i] - minus[i]) / (2 * h);
      EXPECT_NEAR(J[i * p + j], fd, tolerance * std::max(1.0, std::abs(fd))) << "row " << i << " parameter " << j;
    }
  }
}

}  // namespace lmcal::test
