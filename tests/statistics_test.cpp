#include "lmcal/fit/statistics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "lmcal/error.hpp"

namespace lmcal {
namespace {

// PHYSICS.md §5: the paper's four α values, reported as 0.601 ± 0.019.
TEST(Statistics, ThePapersAlphaValuesGive0600PlusMinus0019) {
  const std::vector<double> alpha = {0.593, 0.61, 0.61, 0.586};
  const Spread s = spread(alpha);
  EXPECT_EQ(s.n, 4u);
  EXPECT_NEAR(s.mean, 0.59975, 1e-12);
  EXPECT_NEAR(s.sd, 0.0121758, 1e-6);  // Eq. 1; PHYSICS.md: s = 0.0122
  EXPECT_NEAR(s.half_width, 0.019, 0.0005);
  EXPECT_NEAR(s.half_width, student_t_quantile(0.975, 3) * s.sd / 2, 1e-15);
  EXPECT_DOUBLE_EQ(s.min, 0.586);
  EXPECT_DOUBLE_EQ(s.max, 0.61);
}

// The spread across runs in words: the paper's figure, and for one run what is missing rather
// than "0.000 ± 0.000".
TEST(Statistics, AcrossRunsSaysWhenThereIsOnlyOneRun) {
  const std::vector<double> alpha = {0.593, 0.61, 0.61, 0.586};
  EXPECT_EQ(across_runs(spread(alpha)), "across runs 0.6 ± 0.0194");
  EXPECT_EQ(across_runs(spread(std::vector<double>{0.6})), "one run: no spread across runs");
}

TEST(Statistics, EquationOneIsTheNMinusOneStandardDeviation) {
  const std::vector<double> x = {2, 4, 4, 4, 5, 5, 7, 9};  // Σ(x - 5)² = 32
  EXPECT_NEAR(sample_standard_deviation(x), std::sqrt(32.0 / 7.0), 1e-15);
  EXPECT_TRUE(std::isnan(sample_standard_deviation(std::vector<double>{1.0})));
}

TEST(Statistics, EquationTwoIsThePercentDifferenceToTheMean) {
  EXPECT_NEAR(percent_difference(1.1, 0.9), 20.0, 1e-12);
  EXPECT_NEAR(percent_difference(0.9, 1.1), 20.0, 1e-12);
  // The paper's largest ambient disagreement, 19 %: e.g. a rise of 2.19 K against 1.81 K.
  EXPECT_NEAR(percent_difference(2.19, 1.81), 19.0, 1e-9);
  EXPECT_TRUE(std::isnan(percent_difference(1, -1)));
}

TEST(Statistics, QuantilesMatchTables) {
  EXPECT_NEAR(student_t_quantile(0.975, 3), 3.182446, 1e-6);
  EXPECT_NEAR(student_t_quantile(0.975, 1e6), 1.959966, 1e-5);
  EXPECT_NEAR(fisher_f_quantile(0.95, 1, 10), 4.964603, 1e-6);
  EXPECT_NEAR(chi_squared_quantile(0.95, 1), 3.841459, 1e-6);
}

TEST(Statistics, SpreadLeavesOutNaN) {
  const std::vector<double> x = {1.0, std::nan(""), 3.0};
  const Spread s = spread(x);
  EXPECT_EQ(s.n, 2u);
  EXPECT_DOUBLE_EQ(s.mean, 2.0);
}

// ---- holm_adjust --------------------------------------------------------------------------

TEST(Holm, TextbookExample) {
  const std::vector<double> p = {0.01, 0.04, 0.03, 0.005};
  const std::vector<double> adjusted = holm_adjust(p);
  const std::vector<double> expected = {0.03, 0.06, 0.06, 0.02};
  ASSERT_EQ(adjusted.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR(adjusted[i], expected[i], 1e-15) << i;
}

TEST(Holm, NaNStaysOutOfTheFamilyAndLargePCapAtOne) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> adjusted = holm_adjust(std::vector<double>{0.01, nan, 0.6, 0.02});
  EXPECT_NEAR(adjusted[0], 0.03, 1e-15);  // three in the family, not four
  EXPECT_TRUE(std::isnan(adjusted[1]));
  EXPECT_NEAR(adjusted[3], 0.04, 1e-15);
  EXPECT_EQ(adjusted[2], 0.6);
  EXPECT_EQ(holm_adjust(std::vector<double>{0.5, 0.9})[0], 1.0);
  EXPECT_THROW(holm_adjust(std::vector<double>{1.5}), InvalidParameter);
}

}  // namespace
}  // namespace lmcal
