#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>

#include "lmcal/error.hpp"
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
  e.of<SealDrag>() = 100;
  EXPECT_NEAR(friction_force_with_effects_N(k, e, c) - base, 100 * 0.11 * 0.11, 1e-12);
  e = {};
  e.of<ViscousLoad>() = 0.1;  // μv up 30 % at 3 kN
  EXPECT_NEAR(friction_force_with_effects_N(k, e, c) - base, 0.3 * (b.viscous_N - 120.2 * 0.029), 1e-9);
  e = {};
  e.of<DirectionAsymmetry>() = 0.05;
  c.direction = -1;
  EXPECT_NEAR(friction_force_with_effects_N(k, e, c), 0.95 * base, 1e-9);
  c.direction = 1;
  EXPECT_NEAR(friction_force_with_effects_N(k, e, c), 1.05 * base, 1e-9);
  e = {};
  e.of<CoulombTemperature>() = 0.01;  // 26 °C is 14 K below T_i
  EXPECT_NEAR(friction_force_with_effects_N(k, e, c) - base, b.coulomb_N * 0.01 * -14.0, 1e-12);
  // Stribeck exponent: at V = V_St the correction vanishes (r = r^δ = 1); below it δ > 1 raises F.
  e = {};
  e.of<StribeckExponent>() = 2;
  auto slow = test::srn35c_conditions(0.015);
  EXPECT_NEAR(friction_force_with_effects_N(k, e, slow), friction_force_N(k, slow), 1e-12);
  slow.velocity_m_s = 0.0075;
  const auto bs = friction_breakdown(k, slow);
  EXPECT_NEAR(friction_force_with_effects_N(k, e, slow) - friction_force_N(k, slow),
              bs.stribeck_N * (std::exp(0.5 - 0.25) - 1), 1e-12);
}

// Every registered effect, all switched on at once, against central differences.
TEST(FrictionEffects, JetDerivativesOfTheEffectParametersEqualFiniteDifferences) {
  using Jet = ceres::Jet<double, kFrictionEffectCount>;
  const auto k = paper_friction_constants();
  FrictionEffects<double> e;
  for (std::size_t i = 0; i < kFrictionEffectCount; ++i) {
    const auto& info = FrictionEffectLibrary::infos[i];
    e[i] = info.neutral + 0.3 * info.scale;  // away from neutral, inside the fit bounds
    ASSERT_LT(e[i], info.upper) << info.name;
  }
  for (double v : {0.0, 0.01, 0.11}) {
    auto c = test::srn35c_conditions(v);
    c.direction = -1;
    c.acceleration_m_s2 = 0.4;            // a trajectory's sample: every effect acts
    c.position_m = 0.0123;
    c.distance_since_reversal_m = 6e-4;
    FrictionEffects<Jet> ej;
    for (std::size_t i = 0; i < kFrictionEffectCount; ++i) ej[i] = Jet(e[i], static_cast<int>(i));
    const Jet F = friction_force_with_effects_N(k, ej, c);
    EXPECT_TRUE(std::isfinite(F.a)) << "V = " << v;
    for (std::size_t i = 0; i < kFrictionEffectCount; ++i) {
      auto plus = e, minus = e;
      const double step = 1e-6 * std::max(1.0, std::abs(e[i]));
      plus[i] += step;
      minus[i] -= step;
      const double fd = (friction_force_with_effects_N(k, plus, c) - friction_force_with_effects_N(k, minus, c)) / (2 * step);
      EXPECT_NEAR(F.v[i], fd, 1e-6 * std::max(1.0, std::abs(fd)))
          << FrictionEffectLibrary::infos[i].name << " V = " << v;
    }
  }
}

// The registry's contract: names are unique and findable, the bounds hold the neutral value
// (a physical one-sided bound may sit on it: a drag is >= 0),
// and every correction vanishes at its neutral value, at every condition.
TEST(FrictionEffects, EveryRegisteredEffectVanishesAtItsNeutralValueAndIsFindableByName) {
  const auto k = paper_friction_constants();
  std::size_t checked = 0;
  FrictionEffectLibrary::for_each([&]<class Effect, std::size_t slot>() {
    const FrictionEffectInfo& info = Effect::info;
    EXPECT_EQ(friction_effect_slot(info.name), slot);
    EXPECT_LE(info.lower, info.neutral) << info.name;
    EXPECT_LT(info.lower, info.upper) << info.name;
    EXPECT_GT(info.upper, info.neutral) << info.name;
    EXPECT_GT(info.scale, 0) << info.name;
    EXPECT_FALSE(std::string_view(info.measure).empty()) << info.name << ": what to log to see it (a tie quotes it)";
    if constexpr (is_friction_effect_part(Effect::info)) {
      // A shape parameter: no correction of its own; it acts through its effect (the Jet test).
      EXPECT_EQ(friction_effect_slot(info.part_of) + 1 <= slot, true) << info.name << " registered before its effect";
      ++checked;
      return;
    } else {
    bool acts = false;
    for (double v : {0.0, 0.004, 0.05, 0.11})
      for (double temperature_C : {22.0, 40.0})
        for (int direction : {-1, 1}) {
          auto c = test::srn35c_conditions(v);
          c.temperature_C = temperature_C;
          c.direction = direction;
          c.acceleration_m_s2 = v > 0.1 ? 0.5 : 0.0;  // a trajectory's sample (the moving mass acts there)
          c.position_m = v > 0.1 ? 0.0123 : 0.0;      // along a raw log's travel (a ripple acts there)
          c.distance_since_reversal_m = v > 0.1 ? 6e-4 : 0.0;  // 0.6 mm after a reversal (pre-sliding)
          const auto b = friction_breakdown(k, c);
          EXPECT_NEAR(Effect::correction_N(k, c, b, b.total_N(), info.neutral), 0.0, 1e-12 * b.total_N())
              << info.name << " V = " << v;
          acts = acts || Effect::correction_N(k, c, b, b.total_N(), info.neutral + info.scale) != 0.0;
        }
    EXPECT_TRUE(acts) << info.name << " changes nothing at any test condition";
    ++checked;
    }
  });
  EXPECT_EQ(checked, kFrictionEffectCount);
  EXPECT_THROW(friction_effect_slot("no_such_effect"), InvalidParameter);
}

// The direction factor acts on the force with the other effects already applied.
TEST(FrictionEffects, DirectionAsymmetryScalesTheTotalWithTheOtherEffects) {
  const auto k = paper_friction_constants();
  auto c = test::srn35c_conditions(0.11);
  c.direction = -1;
  FrictionEffects<double> drag;
  drag.of<SealDrag>() = 100;
  FrictionEffects<double> both = drag;
  both.of<DirectionAsymmetry>() = 0.05;
  EXPECT_NEAR(friction_force_with_effects_N(k, both, c), 0.95 * friction_force_with_effects_N(k, drag, c), 1e-12);
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
