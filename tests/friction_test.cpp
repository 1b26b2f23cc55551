#include "lmcal/models/friction.hpp"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>

#include "lmcal/error.hpp"
#include "support/srn35c.hpp"

namespace lmcal {
namespace {

using test::srn35c_conditions;

// PHYSICS.md §2 sanity figures: SRN 35C, pc = 4 µm, P = 3000 N, T = 26 °C.
TEST(Friction, ReproducesThePapersSanityFigures) {
  const auto k = paper_friction_constants();
  const double velocity[] = {0.066, 0.083, 0.11};
  const double force_N[] = {28.2, 34.4, 44.2};
  const double heat_W[] = {1.86, 2.85, 4.86};
  for (int i = 0; i < 3; ++i) {
    const auto c = srn35c_conditions(velocity[i]);
    EXPECT_NEAR(friction_force_N(k, c), force_N[i], 0.05) << "V = " << velocity[i];
    EXPECT_NEAR(heat_rate_W(k, c), heat_W[i], 0.005) << "V = " << velocity[i];
  }
}

TEST(Friction, ViscousDominatesAtTheThermalSpeedsAndStribeckOnlyAtLowSpeed) {
  const auto k = paper_friction_constants();
  const auto fast = friction_breakdown(k, srn35c_conditions(0.11));
  EXPECT_GT(fast.viscous_N, 0.9 * fast.total_N());
  EXPECT_LT(fast.stribeck_N, 0.01);
  const auto slow = friction_breakdown(k, srn35c_conditions(0.005));
  EXPECT_GT(slow.stribeck_N, slow.coulomb_N);
  // Coulomb term is (k1 - k2 pc) P / 1000 = (0.315 - 0.12) * 3 N.
  EXPECT_NEAR(fast.coulomb_N, 0.585, 1e-12);
}

TEST(Friction, ViscosityHalvesForALn2OverBetaRise) {
  const auto k = paper_friction_constants();
  EXPECT_DOUBLE_EQ(viscosity_mm2_s(k, 40.0), 99.0);
  EXPECT_NEAR(viscosity_mm2_s(k, 40.0 + std::log(2.0) / k.beta_per_K), 49.5, 1e-9);
}

TEST(Friction, HeatRateIsForceTimesSpeed) {
  const auto k = paper_friction_constants();
  for (double v : {0.001, 0.02, 0.3}) {
    const auto c = srn35c_conditions(v);
    EXPECT_DOUBLE_EQ(heat_rate_W(k, c), friction_force_N(k, c) * v);
  }
}

// Jet derivatives of F with respect to the seven constants and the temperature equal
// central finite differences.
TEST(Friction, JetDerivativesEqualFiniteDifferences) {
  using Jet = ceres::Jet<double, 8>;
  const auto k = paper_friction_constants();
  for (double v : {0.005, 0.03, 0.11}) {
    const auto c = srn35c_conditions(v);
    FrictionConstants<Jet> kj = k.cast<Jet>();
    for (std::size_t i = 0; i < 7; ++i) fittable_constant(kj, i).v[i] = 1.0;
    FrictionConditions<Jet> cj = c.cast<Jet>();
    cj.temperature_C.v[7] = 1.0;
    const Jet F = friction_force_N(kj, cj);
    EXPECT_DOUBLE_EQ(F.a, friction_force_N(k, c));

    auto perturbed = [&](int i, double step) {
      auto kp = k;
      auto cp = c;
      (i < 7 ? fittable_constant(kp, static_cast<std::size_t>(i)) : cp.temperature_C) += step;
      return friction_force_N(kp, cp);
    };
    for (int i = 0; i < 8; ++i) {
      const double base = i < 7 ? fittable_constant(k, static_cast<std::size_t>(i)) : c.temperature_C;
      const double step = 1e-6 * std::max(1.0, std::abs(base));
      const double fd = (perturbed(i, step) - perturbed(i, -step)) / (2 * step);
      EXPECT_NEAR(F.v[i], fd, 1e-6 * std::max(1.0, std::abs(fd))) << "parameter " << i << " at V = " << v;
    }
  }
}

TEST(Friction, RefusesNonPhysicalConditionsNamingTheParameter) {
  auto c = srn35c_conditions();
  c.load_N = -5;
  try {
    validate(c);
    FAIL() << "negative load accepted";
  } catch (const InvalidParameter& e) {
    EXPECT_EQ(e.parameter(), "load_N");
    EXPECT_NE(std::string(e.what()).find("-5"), std::string::npos) << e.what();
  }
  c = srn35c_conditions();
  c.temperature_C = std::nan("");
  EXPECT_THROW(validate(c), InvalidParameter);
  c = srn35c_conditions();
  c.block_length_mm = 0;
  EXPECT_THROW(validate(c), InvalidParameter);
  auto k = paper_friction_constants();
  k.v_st_m_s = 0;
  EXPECT_THROW(validate(k), InvalidParameter);
  EXPECT_NO_THROW(validate(paper_friction_constants()));
  EXPECT_NO_THROW(validate(srn35c_conditions()));
}

}  // namespace
}  // namespace lmcal
