#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>

#include "lmcal/models/friction_effects.hpp"
#include "lmcal/models/thermal_effects.hpp"
#include "support/srn35c.hpp"

namespace lmcal {
namespace {

TEST(FrictionEffects, NeutralEffectsGiveThePublishedLaw) {
  const auto k = paper_friction_constants();
  for (double v : {0.0, 0.004, 0.05, 0.11}) {
    const auto c = test::srn35c_conditions(v);
    EXPECT_NEAR(friction_force_with_effects_N(k, FrictionEffects<double>{}, c), friction_force_N(k, c), 1e-12);
  }
}

TEST(FrictionEffects, EachEffectAddsWhatItsEquationSays) {
  const auto k = paper_friction_constants();
  auto c = test::srn35c_conditions(0.11);
  const double base = friction_force_N(k, c);
  const auto b = friction_breakdown(k, c);
  FrictionEffects<double> e;
  e.seal_drag_N_s2_m2 = 100;
  EXPECT_NEAR(friction_force_with_effects_N(k, e, c) - base, 100 * 0.11 * 0.11, 1e-12);
  e = {};
  e.viscous_load_per_kN = 0.1;  // μv up 30 % at 3 kN
  EXPECT_NEAR(friction_force_with_effects_N(k, e, c) - base, 0.3 * (b.viscous_N - 120.2 * 0.029), 1e-9);
  e = {};
  e.direction_asymmetry = 0.05;
  c.direction = -1;
  EXPECT_NEAR(friction_force_with_effects_N(k, e, c), 0.95 * base, 1e-9);
  c.direction = 1;
  EXPECT_NEAR(friction_force_with_effects_N(k, e, c), 1.05 * base, 1e-9);
  e = {};
  e.coulomb_temperature_per_K = 0.01;  // 26 °C is 14 K below T_i
  EXPECT_NEAR(friction_force_with_effects_N(k, e, c) - base, b.coulomb_N * 0.01 * -14.0, 1e-12);
  // Stribeck exponent: at V = V_St the correction vanishes (r = r^δ = 1); below it δ > 1 raises F.
  e = {};
  e.stribeck_exponent = 2;
  auto slow = test::srn35c_conditions(0.015);
  EXPECT_NEAR(friction_force_with_effects_N(k, e, slow), friction_force_N(k, slow), 1e-12);
  slow.velocity_m_s = 0.0075;
  const auto bs = friction_breakdown(k, slow);
  EXPECT_NEAR(friction_force_with_effects_N(k, e, slow) - friction_force_N(k, slow),
              bs.stribeck_N * (std::exp(0.5 - 0.25) - 1), 1e-12);
}

TEST(FrictionEffects, JetDerivativesOfTheEffectParametersEqualFiniteDifferences) {
  using Jet = ceres::Jet<double, 5>;
  const auto k = paper_friction_constants();
  const FrictionEffects<double> e{1.3, 0.05, 0.03, 40.0, 0.004};
  for (double v : {0.0, 0.01, 0.11}) {
    auto c = test::srn35c_conditions(v);
    c.direction = -1;
    FrictionEffects<Jet> ej{Jet(e.stribeck_exponent, 0), Jet(e.viscous_load_per_kN, 1), Jet(e.direction_asymmetry, 2),
                            Jet(e.seal_drag_N_s2_m2, 3), Jet(e.coulomb_temperature_per_K, 4)};
    const Jet F = friction_force_with_effects_N(k, ej, c);
    EXPECT_TRUE(std::isfinite(F.v[0])) << "V = " << v;
    for (int i = 0; i < 5; ++i) {
      auto plus = e, minus = e;
      const double step = 1e-6 * std::max(1.0, std::abs(*(&e.stribeck_exponent + i)));
      *(&plus.stribeck_exponent + i) += step;
      *(&minus.stribeck_exponent + i) -= step;
      const double fd = (friction_force_with_effects_N(k, plus, c) - friction_force_with_effects_N(k, minus, c)) / (2 * step);
      EXPECT_NEAR(F.v[i], fd, 1e-6 * std::max(1.0, std::abs(fd))) << "effect " << i << " V = " << v;
    }
  }
}

TEST(ThermalEffects, LagOfARampIsTheExactFirstOrderResponse) {
  const double tau = 40, rate = 0.01;
  std::vector<double> t, x;
  for (int i = 0; i <= 200; ++i) {
    t.push_back(5.0 * i);
    x.push_back(rate * t.back());
  }
  const auto y = first_order_lag(t, x, tau);
  for (std::size_t i = 0; i < t.size(); ++i)
    EXPECT_NEAR(y[i], rate * (t[i] - tau * (1 - std::exp(-t[i] / tau))), 1e-12);
  EXPECT_EQ(first_order_lag(t, x, 0.0), x);
}

TEST(ThermalEffects, ConvectionGrowsWithTheSquareRootOfSpeedAndAlphaLinearly) {
  EXPECT_DOUBLE_EQ(convection_with_velocity(5.3, 6.0, 0.09), 5.3 + 6.0 * 0.3);
  EXPECT_DOUBLE_EQ(alpha_with_velocity(0.6, -1.0, 0.1), 0.6);
  EXPECT_DOUBLE_EQ(alpha_with_velocity(0.6, -1.0, 0.05), 0.65);
}

}  // namespace
}  // namespace lmcal
