#include "diagnose/sparse_regression.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace lmcal::detail {
namespace {

// Rows in `groups` groups of `per_group`, each group with its own level (a run's zero), a
// fixed column the model already has, and a dictionary: eight noise-like columns, and the
// family exp(-t/l) over a grid of l.
struct Synthetic {
  SparseProblem problem;
  std::vector<double> t, x;
};

Synthetic make(unsigned seed, double decay_amplitude, double decay_scale, double x_coefficient) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Synthetic s;
  const std::size_t groups = 8, per_group = 200;
  const std::vector<double> scales{25, 50, 100, 200, 400, 800};
  auto& p = s.problem;
  p.fixed.resize(1);
  p.candidates.resize(8 + scales.size());
  double time = 0;
  for (std::size_t g = 0; g < groups; ++g) {
    const double level = normal(rng);
    for (std::size_t i = 0; i < per_group; ++i, time += 1) {
      const double f = std::sin(0.1 * static_cast<double>(i));
      const double x = normal(rng);
      double y = level + 0.7 * f + 0.2 * normal(rng) + x_coefficient * x + decay_amplitude * std::exp(-time / decay_scale);
      p.y.push_back(y);
      p.group.push_back(g);
      p.level.push_back(g);
      p.fixed[0].push_back(f);
      p.candidates[0].push_back(x);
      for (std::size_t c = 1; c < 8; ++c) p.candidates[c].push_back(normal(rng));
      for (std::size_t k = 0; k < scales.size(); ++k) p.candidates[8 + k].push_back(std::exp(-time / scales[k]));
    }
  }
  p.family.assign(p.candidates.size(), 0);
  for (std::size_t c = 0; c < 8; ++c) p.family[c] = c;
  for (std::size_t k = 0; k < scales.size(); ++k) p.family[8 + k] = 8;
  return s;
}

TEST(SparseRegression, FindsTheTermsThatPredictHeldOutGroups) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Synthetic s = make(seed, 1.5, 200, 0.3);
    const SparseSelection r = select_sparse(s.problem, {});
    ASSERT_EQ(r.selected.size(), 2u) << "seed " << seed;
    EXPECT_EQ(r.selected[0], 0u);               // x
    EXPECT_EQ(r.selected[1], 8u + 3u);          // the decay at the true scale, 200
    EXPECT_NEAR(r.coefficient[0], 0.3, 0.05);
    EXPECT_NEAR(r.coefficient[1], 1.5, 0.3);
    EXPECT_LT(r.cv_rmse, 0.7 * r.cv_rmse_fixed);
  }
}

TEST(SparseRegression, NoiseGrowsNoTerm) {
  int grown = 0;
  for (unsigned seed = 10; seed < 30; ++seed) {
    const Synthetic s = make(seed, 0, 200, 0);
    const SparseSelection r = select_sparse(s.problem, {});
    if (!r.selected.empty()) ++grown;
    EXPECT_DOUBLE_EQ(r.cv_rmse, r.selected.empty() ? r.cv_rmse_fixed : r.cv_rmse);
  }
  EXPECT_LE(grown, 1);
}

TEST(SparseRegression, ATermTheFixedColumnsAlreadyHoldIsNotChosen) {
  Synthetic s = make(4, 0, 200, 0);
  // A candidate equal to the fixed column (plus a level): nothing beyond F.
  s.problem.candidates.push_back(s.problem.fixed[0]);
  s.problem.family.push_back(99);
  const SparseSelection r = select_sparse(s.problem, {});
  EXPECT_TRUE(std::find(r.selected.begin(), r.selected.end(), s.problem.candidates.size() - 1) == r.selected.end());
}

}  // namespace
}  // namespace lmcal::detail
