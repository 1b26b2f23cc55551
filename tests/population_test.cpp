#include "lmcal/fit/population.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "lmcal/error.hpp"
#include "lmcal/fit/statistics.hpp"

namespace lmcal {
namespace {

// Deterministic normal deviates: std::mt19937_64 is specified bit for bit, std::normal_distribution
// is not, so the Box-Muller transform is written out here.
class Normal {
 public:
  explicit Normal(std::uint64_t seed) : rng_(seed) {}
  double uniform() { return (static_cast<double>(rng_() >> 11) + 0.5) * 0x1p-53; }  // in (0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  double operator()() {
    if (spare_) {
      spare_ = false;
      return second_;
    }
    const double r = std::sqrt(-2 * std::log(uniform())), phi = 2 * std::numbers::pi * uniform();
    second_ = r * std::sin(phi);
    spare_ = true;
    return r * std::cos(phi);
  }

 private:
  std::mt19937_64 rng_;
  bool spare_ = false;
  double second_ = 0;
};

// Written again here, independently of the library: the generalized Q and the restricted
// log-likelihood of τ² (up to a constant).
double generalized_q(const std::vector<Estimate>& e, double tau2) {
  double sw = 0, swy = 0;
  for (const Estimate& x : e) {
    sw += 1 / (x.se * x.se + tau2);
    swy += x.value / (x.se * x.se + tau2);
  }
  double q = 0;
  for (const Estimate& x : e) q += std::pow(x.value - swy / sw, 2) / (x.se * x.se + tau2);
  return q;
}

double restricted_log_likelihood(const std::vector<Estimate>& e, double tau2) {
  double sw = 0, log_v = 0;
  for (const Estimate& x : e) {
    sw += 1 / (x.se * x.se + tau2);
    log_v += std::log(x.se * x.se + tau2);
  }
  return -0.5 * (log_v + std::log(sw) + generalized_q(e, tau2));
}

// τ² maximizing the restricted likelihood on a grid of `points` over [0, top].
double grid_reml_tau2(const std::vector<Estimate>& e, double top, int points) {
  double best = 0, best_ll = -std::numeric_limits<double>::infinity();
  for (int i = 0; i <= points; ++i) {
    const double tau2 = top * i / points;
    const double ll = restricted_log_likelihood(e, tau2);
    if (ll > best_ll) {
      best_ll = ll;
      best = tau2;
    }
  }
  return best;
}

// A fleet drawn from the model: y_i = mu + u_i + e_i, se_i uniform in [se_lo, se_hi].
std::vector<Estimate> draw_fleet(Normal& normal, std::size_t k, double mu, double tau, double se_lo, double se_hi) {
  std::vector<Estimate> e(k);
  for (Estimate& x : e) {
    x.se = normal.uniform(se_lo, se_hi);
    x.value = mu + tau * normal() + x.se * normal();
  }
  return e;
}

// ---- random_effects -----------------------------------------------------------------------

// y = 0, 2, 3, 9 with se = 1, 1, 2, 2, by hand (f = 1/se² = 1, 1, 1/4, 1/4):
//   Σf = 5/2, Σf y = 5, fixed-effect mean 2
//   Q = 1·4 + 1·0 + ¼·1 + ¼·49 = 16.5 on 3 dof
//   Σf² = 2.125, Σf − Σf²/Σf = 2.5 − 0.85 = 1.65, τ²_DL = (16.5 − 3)/1.65 = 90/11
//   s̃² = 3 · 2.5 / (6.25 − 2.125) = 20/11, so I²(τ_DL) = (90/11)/(110/11) = 9/11 = (Q − 3)/Q
const std::vector<Estimate> kHand = {{0, 1}, {2, 1}, {3, 2}, {9, 2}};

TEST(RandomEffects, HandExampleMatchesTheClosedForms) {
  const RandomEffects r = random_effects(kHand);
  EXPECT_EQ(r.k, 4u);
  EXPECT_NEAR(r.q, 16.5, 1e-12);
  EXPECT_NEAR(r.q_p, chi_squared_upper_p(16.5, 3), 1e-15);
  EXPECT_LT(r.q_p, 1e-3);
  EXPECT_NEAR(r.tau_dl * r.tau_dl, 90.0 / 11, 1e-12);
  const double typical_v = 20.0 / 11;
  EXPECT_NEAR(r.i2, r.tau * r.tau / (r.tau * r.tau + typical_v), 1e-12);
  // Higgins-Thompson: with the DL τ² the same s̃² gives I² = (Q − (k − 1))/Q.
  EXPECT_NEAR(90.0 / 11 / (90.0 / 11 + typical_v), 9.0 / 11, 1e-12);
  EXPECT_TRUE(r.converged);

  // Mean and HKSJ interval at the reported τ², from the definitions.
  const double tau2 = r.tau * r.tau;
  double sw = 0, swy = 0;
  for (const Estimate& x : kHand) {
    sw += 1 / (x.se * x.se + tau2);
    swy += x.value / (x.se * x.se + tau2);
  }
  EXPECT_NEAR(r.mean, swy / sw, 1e-12);
  const double mean_se = std::sqrt(std::max(1.0, generalized_q(kHand, tau2) / 3) / sw);
  EXPECT_NEAR(r.mean_se, mean_se, 1e-12);
  EXPECT_NEAR(r.mean_high - r.mean, student_t_quantile(0.975, 3) * mean_se, 1e-12);
  EXPECT_NEAR(r.mean - r.mean_low, student_t_quantile(0.975, 3) * mean_se, 1e-12);

  // Q-profile: the generalized Q at the bounds equals the χ²(3) quantiles.
  ASSERT_GT(r.tau_low, 0);
  ASSERT_TRUE(std::isfinite(r.tau_high));
  EXPECT_NEAR(generalized_q(kHand, r.tau_low * r.tau_low), chi_squared_quantile(0.975, 3), 1e-9);
  EXPECT_NEAR(generalized_q(kHand, r.tau_high * r.tau_high), chi_squared_quantile(0.025, 3), 1e-9);
  EXPECT_LT(r.tau_low, r.tau);
  EXPECT_GT(r.tau_high, r.tau);
  EXPECT_NE(r.method.find("Hartung-Knapp-Sidik-Jonkman"), std::string::npos);
  EXPECT_NE(r.method.find("Q-profile"), std::string::npos);
}

TEST(RandomEffects, RemlMaximizesTheRestrictedLikelihood) {
  const std::vector<Estimate> five = {{1.2, 0.3}, {0.4, 0.2}, {2.1, 0.5}, {0.9, 0.1}, {1.6, 0.4}};
  for (const auto& e : {kHand, five}) {
    const RandomEffects r = random_effects(e);
    const double top = 40 * r.tau_dl * r.tau_dl + 1;
    const int points = 400000;
    const double grid = grid_reml_tau2(e, top, points);
    EXPECT_NEAR(r.tau * r.tau, grid, 2 * top / points);
    EXPECT_GE(restricted_log_likelihood(e, r.tau * r.tau), restricted_log_likelihood(e, grid) - 1e-12);
    EXPECT_GT(std::abs(r.tau - r.tau_dl), 1e-3);  // REML is not just the DL start
  }
}

TEST(RandomEffects, HomogeneousUnitsGiveTauZeroAtTheBoundary) {
  const std::vector<Estimate> e = {{1.00, 0.1}, {1.02, 0.1}, {0.99, 0.12}, {1.01, 0.08}};
  const RandomEffects r = random_effects(e);
  EXPECT_EQ(r.tau, 0.0);
  EXPECT_EQ(grid_reml_tau2(e, 0.01, 10000), 0.0);
  EXPECT_EQ(r.tau_low, 0.0);  // Q(0) is below both quantiles: both bounds are 0
  EXPECT_EQ(r.tau_high, 0.0);
  EXPECT_EQ(r.i2, 0.0);
  EXPECT_TRUE(r.converged);
}

TEST(RandomEffects, EqualSesGiveSampleVarianceMinusSeSquared) {
  const std::vector<double> y = {1.0, 1.3, 0.8, 1.6, 1.1, 0.7};
  for (double se : {0.1, 0.3, 0.5}) {
    std::vector<Estimate> e;
    for (double v : y) e.push_back({v, se});
    const double s = sample_standard_deviation(y);
    const RandomEffects r = random_effects(e);
    EXPECT_NEAR(r.tau * r.tau, std::max(0.0, s * s - se * se), 1e-12) << "se = " << se;
  }
}

TEST(RandomEffects, OneEstimateIsItself) {
  const std::vector<Estimate> e = {{3.5, 0.2}};
  const RandomEffects r = random_effects(e);
  EXPECT_EQ(r.k, 1u);
  EXPECT_EQ(r.mean, 3.5);
  EXPECT_EQ(r.mean_se, 0.2);
  EXPECT_NEAR(r.mean_high - r.mean, 1.959964 * 0.2, 1e-6);
  EXPECT_TRUE(std::isnan(r.tau));
  EXPECT_TRUE(std::isnan(r.q));
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.method.find("one estimate"), std::string::npos);
  EXPECT_EQ(random_effects(std::vector<Estimate>{}).k, 0u);
}

TEST(RandomEffects, TwoEstimatesGiveAWideButHonestTauInterval) {
  const std::vector<Estimate> e = {{1.0, 0.1}, {2.0, 0.1}};  // 7 se apart
  const RandomEffects r = random_effects(e);
  EXPECT_NEAR(r.mean, 1.5, 1e-12);
  EXPECT_TRUE(std::isfinite(r.mean_low) && std::isfinite(r.mean_high));
  EXPECT_NEAR(r.tau * r.tau, 0.5 - 0.01, 1e-12);  // equal se: sample variance − se²
  ASSERT_TRUE(std::isfinite(r.tau_high));
  EXPECT_NEAR(generalized_q(e, r.tau_high * r.tau_high), chi_squared_quantile(0.025, 1), 1e-9);
  EXPECT_GT(r.tau_high, 10 * r.tau);  // one dof knows little about a spread
  // At 99.999 % the χ²(1) quantile is ~2e-10: Q(τ²) = 0.5/(0.01 + τ²) needs τ² ~ 2.5e9, beyond
  // 1e6 × the data's variance: +inf, and the method says so.
  const RandomEffects wide = random_effects(e, 0.99999);
  EXPECT_TRUE(std::isinf(wide.tau_high));
  EXPECT_NE(wide.method.find("+inf"), std::string::npos);
}

// 40 units, τ = 0.08, se in [0.02, 0.06]: the Q-profile τ interval and the HKSJ mean interval
// each cover the truth in about 95 % of 400 fleets (binomial SD 1.1 %).
TEST(RandomEffects, IntervalsCoverTheTruth) {
  Normal normal(20240611);
  const double mu = 1.0, tau = 0.08;
  int tau_covered = 0, mean_covered = 0;
  const int replicates = 400;
  for (int rep = 0; rep < replicates; ++rep) {
    const RandomEffects r = random_effects(draw_fleet(normal, 40, mu, tau, 0.02, 0.06));
    tau_covered += r.tau_low <= tau && tau <= r.tau_high;
    mean_covered += r.mean_low <= mu && mu <= r.mean_high;
  }
  const double tau_coverage = double(tau_covered) / replicates, mean_coverage = double(mean_covered) / replicates;
  EXPECT_GE(tau_coverage, 0.90);
  EXPECT_LE(tau_coverage, 0.985);
  EXPECT_GE(mean_coverage, 0.90);
  EXPECT_LE(mean_coverage, 0.985);
  std::printf("coverage: tau %.3f, mean %.3f\n", tau_coverage, mean_coverage);
}

TEST(RandomEffects, BadInputNamesTheEstimate) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const auto parameter_of = [](const std::vector<Estimate>& e) -> std::string {
    try {
      random_effects(e);
    } catch (const InvalidParameter& error) {
      return error.parameter();
    }
    return "no throw";
  };
  EXPECT_EQ(parameter_of({{1, 0.1}, {2, 0.1}, {3, 0}}), "estimates[2].se");
  EXPECT_EQ(parameter_of({{1, -0.1}, {2, 0.1}}), "estimates[0].se");
  EXPECT_EQ(parameter_of({{1, 0.1}, {2, inf}}), "estimates[1].se");
  EXPECT_EQ(parameter_of({{1, 0.1}, {2, nan}}), "estimates[1].se");
  EXPECT_EQ(parameter_of({{nan, 0.1}, {2, 0.1}}), "estimates[0].value");
  EXPECT_THROW(random_effects(kHand, 1.0), InvalidParameter);
  EXPECT_THROW(fit_population(std::vector<Estimate>{{1, 0}}), InvalidParameter);
  EXPECT_THROW(fit_population(kHand, 0), InvalidParameter);
  EXPECT_THROW(fit_population(kHand, 1, 0.0), InvalidParameter);
}

// ---- fit_population -----------------------------------------------------------------------

TEST(FitPopulation, FindsExactlyTheTwoPlantedOutliers) {
  Normal normal(7);
  const double mu = 1.0, tau = 0.08;
  std::vector<Estimate> e = draw_fleet(normal, 40, mu, tau, 0.02, 0.06);
  // Two more units 8 σ out, σ = their total SD about the population: at indices 13 and 40.
  const auto planted = [&](double sign, double se) { return Estimate{mu + sign * 8 * std::hypot(tau, se), se}; };
  e.insert(e.begin() + 13, planted(+1, 0.03));
  e.push_back(planted(-1, 0.05));
  const PopulationFit f = fit_population(e, 3);
  EXPECT_EQ(f.outliers, (std::vector<std::size_t>{13, 41}));
  EXPECT_EQ(f.population.k, 40u);
  EXPECT_NEAR(f.population.mean, mu, 4 * f.population.mean_se);
  EXPECT_NEAR(f.population.tau, tau, 0.04);
  ASSERT_EQ(f.z.size(), 42u);
  ASSERT_EQ(f.p_adjusted.size(), 42u);
  EXPECT_GT(f.z[13], 5);
  EXPECT_LT(f.z[41], -5);
  EXPECT_LT(f.p_adjusted[13], 0.05);
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (i != 13 && i != 41) {
      EXPECT_LT(std::abs(f.z[i]), 4) << i;
    }
  }
}

// Family-wise error: on clean fleets of 40, about 5 % have any unit flagged. 500 fleets (binomial
// SD 1 %) tell 5 % from the 10 % that a normal reading of z gives here; 200 could not.
TEST(FitPopulation, CleanFleetsRarelyFlagAnyone) {
  Normal normal(11);
  int any_flag = 0;
  const int replicates = 500;
  for (int rep = 0; rep < replicates; ++rep)
    any_flag += !fit_population(draw_fleet(normal, 40, 1.0, 0.08, 0.02, 0.06)).outliers.empty();
  EXPECT_LE(double(any_flag) / replicates, 0.075);
  std::printf("clean fleets with a false flag: %d of %d\n", any_flag, replicates);
}

TEST(FitPopulation, OutwardTestUnmasksAndStopsAtHalf) {
  // Four wild units beside four tight ones: each flagged in turn, the most extreme first, until
  // half the fleet is flagged.
  const std::vector<Estimate> e = {{0, 0.01}, {10, 0.01}, {0.01, 0.01}, {-100, 0.01},
                                   {-0.01, 0.01}, {1000, 0.01}, {0.005, 0.01}, {-10000, 0.01}};
  const PopulationFit f = fit_population(e);
  EXPECT_EQ(f.outliers, (std::vector<std::size_t>{1, 3, 5, 7}));
  EXPECT_NE(f.note.find("half"), std::string::npos);
  EXPECT_EQ(f.population.k, 4u);
}

TEST(FitPopulation, TooFewUnitsAreNotTested) {
  const std::vector<Estimate> e = {{0, 0.01}, {0.01, 0.01}, {5, 0.01}};
  const PopulationFit f = fit_population(e);
  EXPECT_TRUE(f.outliers.empty());
  EXPECT_NE(f.note.find("no unit tested"), std::string::npos);
  EXPECT_EQ(f.population.k, 3u);
  EXPECT_TRUE(std::isfinite(f.z[2]));  // still reported, against the other two
}

// ---- drift_test ---------------------------------------------------------------------------

// Eight monthly dates; value and se relative to the first value.
std::vector<DatedEstimate> series(const std::vector<double>& values, double se) {
  std::vector<DatedEstimate> s;
  for (std::size_t i = 0; i < values.size(); ++i) s.push_back({30.0 * double(i), values[i], se});
  return s;
}

TEST(Drift, LinearDriftOfTwentyFivePercentIsFound) {
  std::vector<double> exact, noisy;
  Normal normal(3);
  for (int i = 0; i < 8; ++i) {
    exact.push_back(1 + 0.25 * i / 7);
    noisy.push_back(exact.back() + 0.02 * normal());
  }
  const Drift clean = drift_test(series(exact, 0.02));
  EXPECT_NEAR(clean.trend_percent, 25, 1e-9);
  EXPECT_NEAR(clean.slope_per_day, 0.25 / 210, 1e-15);
  // se of the slope: 0.02 / sqrt(Σ(t − t̄)²), Σ(t − t̄)² = 42 · 30² (the scatter scale is 1 here)
  EXPECT_NEAR(clean.slope_se, 0.02 / std::sqrt(42 * 900.0), 1e-15);

  const Drift d = drift_test(series(noisy, 0.02));
  EXPECT_LT(d.trend_p, 1e-3);
  EXPECT_LT(d.p, 1e-3);
  // The change in fitted value over 210 days has se 0.02·210/sqrt(42·900) = 2.2 %: 3 se.
  EXPECT_NEAR(d.trend_percent, 25, 6.5);
}

TEST(Drift, StepChangeIsLocated) {
  Normal normal(5);
  std::vector<double> v;
  for (int i = 0; i < 10; ++i) v.push_back((i >= 4 ? 1.10 : 1.00) + 0.02 * normal());  // a step at the fifth date
  const Drift d = drift_test(series(v, 0.02));
  ASSERT_TRUE(d.change_index.has_value());
  EXPECT_EQ(*d.change_index, 4u);
  EXPECT_NEAR(d.shift, 0.10, 3 * 0.02 * std::sqrt(1.0 / 4 + 1.0 / 6));
  EXPECT_NEAR(d.shift_percent, 10, 4.5);
  EXPECT_LT(d.change_p, 1e-3);
  EXPECT_LT(d.change_p, d.trend_p);  // a step is told from a line
  EXPECT_NEAR(d.p, std::min(1.0, 2 * d.change_p), 1e-15);
}

// Scatter beyond equal SEs: the widened slope SE and its t test are ordinary least squares'.
TEST(Drift, ExtraScatterIsOrdinaryLeastSquares) {
  const std::vector<double> y = {1.00, 1.09, 0.97, 1.12, 1.01, 1.15, 1.04};  // scatter ~5x the se
  const Drift d = drift_test(series(y, 0.01));
  // OLS by hand: x = 0..6 (× 30 days), x̄ = 3, Sxx = 28 · 900.
  double ybar = 0, sxy = 0, rss = 0;
  for (double v : y) ybar += v / 7;
  for (int i = 0; i < 7; ++i) sxy += (i - 3) * 30.0 * (y[i] - ybar);
  const double slope = sxy / (28 * 900.0);
  for (int i = 0; i < 7; ++i) rss += std::pow(y[i] - ybar - slope * (i - 3) * 30.0, 2);
  const double se = std::sqrt(rss / 5 / (28 * 900.0));
  ASSERT_GT(rss / 5, 0.01 * 0.01);  // beyond the SEs
  EXPECT_NEAR(d.slope_per_day, slope, 1e-15);
  EXPECT_NEAR(d.slope_se, se, 1e-15);
  EXPECT_NEAR(d.trend_p, student_t_two_sided_p(slope / se, 5), 1e-12);
}

// No drift: over 300 series of 8 dates, P(p < 0.05) is near (at most) 5 %.
TEST(Drift, CleanSeriesRarelyDrift) {
  Normal normal(17);
  int rejected = 0;
  const int replicates = 300;
  for (int rep = 0; rep < replicates; ++rep) {
    std::vector<DatedEstimate> s;
    for (int i = 0; i < 8; ++i) {
      const double se = normal.uniform(0.01, 0.03);
      s.push_back({10.0 * i + normal.uniform(0, 5), 1 + se * normal(), se});
    }
    rejected += drift_test(s).p < 0.05;
  }
  const double rate = double(rejected) / replicates;
  EXPECT_GE(rate, 0.01);
  EXPECT_LE(rate, 0.09);
  std::printf("clean series with p < 0.05: %.3f\n", rate);
}

TEST(Drift, DaysMustIncreaseStrictly) {
  std::vector<DatedEstimate> s = series({1, 1, 1, 1}, 0.01);
  s[2].day = s[1].day;
  try {
    drift_test(s);
    FAIL() << "no throw";
  } catch (const InvalidParameter& error) {
    EXPECT_EQ(error.parameter(), "series[2].day");
  }
  s[2].day = s[1].day - 1;
  EXPECT_THROW(drift_test(s), InvalidParameter);
  s = series({1, 1, 1, 1}, 0.01);
  s[3].se = 0;
  EXPECT_THROW(drift_test(s), InvalidParameter);
}

TEST(Drift, ShortSeriesTestWhatTheyCan) {
  const Drift three = drift_test(series({1.0, 1.1, 1.2}, 0.01));
  EXPECT_TRUE(std::isfinite(three.trend_p));
  EXPECT_FALSE(three.change_index.has_value());
  EXPECT_EQ(three.p, three.trend_p);
  EXPECT_FALSE(three.note.empty());
  const Drift two = drift_test(series({1.0, 1.1}, 0.01));
  EXPECT_TRUE(std::isnan(two.p));
  EXPECT_FALSE(two.note.empty());
}


}  // namespace
}  // namespace lmcal
