#include "lmcal/diagnose/friction_diagnosis.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "lmcal/rig/virtual_rig.hpp"

namespace lmcal {
namespace {

// A rig with every covariate varied, four runs, load-cell noise 0.15 N and a zero offset
// per run: what a real repeat campaign looks like.
FrictionRigConfig campaign(std::uint64_t seed) {
  FrictionRigConfig c;
  c.guides = {"SRG 25C", "SRN 35C"};
  c.velocity_m_s = {0.002, 0.005, 0.01, 0.02, 0.04, 0.066, 0.11, 0.15};
  c.temperature_C = {22, 30, 40};
  c.runs = 4;
  c.seed = seed;
  return c;
}

FrictionDiagnosis diagnose(const FrictionLog& log) { return diagnose_friction(log, {}); }

struct Hidden {
  const char* effect;
  double magnitude;  // about 2-3 σ of the load-cell noise at the conditions it acts on, and larger
};

// Each library effect hidden in generated data is named, for two seeds and two magnitudes.
TEST(FrictionDiagnosis, NamesEveryLibraryEffectHiddenInTheData) {
  const Hidden hidden[] = {{"seal_drag", 15},           {"seal_drag", 60},
                           {"direction_asymmetry", 0.01}, {"direction_asymmetry", 0.03},
                           {"viscous_load", 0.01},        {"viscous_load", 0.04},
                           {"stribeck_exponent", 1.3},    {"stribeck_exponent", 1.6},
                           {"coulomb_temperature", 0.03}, {"coulomb_temperature", 0.08}};
  // A newly registered effect must come with its own cases here.
  for (const auto& info : FrictionEffectLibrary::infos)
    EXPECT_TRUE(std::any_of(std::begin(hidden), std::end(hidden), [&](const Hidden& h) { return h.effect == std::string(info.name); }))
        << info.name << " is registered but never hidden in the test data";
  for (const auto& h : hidden) {
    for (std::uint64_t seed : {21, 22}) {
      RigEffects effects;
      set_rig_effect(effects, h.effect, h.magnitude);
      const auto d = diagnose(generate_friction_log(campaign(seed), effects).log);
      ASSERT_FALSE(d.accepted.empty()) << h.effect << "=" << h.magnitude << " seed " << seed << ": " << d.summary;
      EXPECT_EQ(d.accepted.front().effect, h.effect) << h.magnitude << " seed " << seed << ": " << d.summary;
      EXPECT_EQ(d.verdict, "explained");
      const auto& c = d.accepted.front();
      // The magnitude is recovered. (Its interval assumes equal noise on every sample; the
      // rig's logged-temperature noise is not, so the interval is not asserted here.)
      const double neutral = FrictionEffectLibrary::infos[friction_effect_slot(h.effect)].neutral;
      EXPECT_NEAR(c.value - neutral, h.magnitude - neutral, 0.1 * std::abs(h.magnitude - neutral))
          << h.effect << " seed " << seed << ": " << c.value << " [" << c.ci_low << ", " << c.ci_high << "]";
    }
  }
}

TEST(FrictionDiagnosis, CleanDataRaiseNoFalseAlarmInNineteenOfTwenty) {
  int alarms = 0;
  for (std::uint64_t seed = 100; seed < 120; ++seed) {
    const auto d = diagnose(generate_friction_log(campaign(seed), {}).log);
    if (d.verdict != "no significant discrepancy") ++alarms;
  }
  EXPECT_LE(alarms, 1);
}

// An effect outside the library: the load cell's zero drifts from run to run. Nothing in the
// library explains it; the diagnosis says "unexplained" and names run order.
TEST(FrictionDiagnosis, AnEffectOutsideTheLibraryIsUnexplainedWithItsCovariate) {
  auto rig = campaign(31);
  rig.runs = 8;
  rig.run_offset_N = 0;
  auto log = generate_friction_log(rig, {}).log;
  for (std::size_t i = 0; i < log.size(); ++i) log.friction_N[i] += 0.15 * log.run[i];
  const auto d = diagnose(log);
  EXPECT_EQ(d.verdict, "unexplained") << d.summary;
  EXPECT_EQ(d.unexplained_covariate, "run order");
  EXPECT_TRUE(d.accepted.empty());
}

// The reported held-out gain is close to the gain the true model would give.
TEST(FrictionDiagnosis, ReportedGainIsCloseToTheTruthsGain) {
  RigEffects effects;
  set_rig_effect(effects, "seal_drag", 80);
  auto rig = campaign(41);
  rig.run_offset_N = 0;
  const auto made = generate_friction_log(rig, effects);
  const auto d = diagnose(made.log);
  ASSERT_EQ(d.accepted.size(), 1u);
  // The true law and effect at the logged conditions: its error is the rig's noise (load
  // cell, and the logged temperature's).
  double ss = 0;
  FrictionEffects<double> truth_effects;
  truth_effects.of<SealDrag>() = 80;
  for (std::size_t i = 0; i < made.log.size(); ++i)
    ss += std::pow(made.log.friction_N[i] -
                       friction_force_with_effects_N(paper_friction_constants(), truth_effects, made.log.conditions(i)),
                   2);
  const double truth_rmse = std::sqrt(ss / static_cast<double>(made.log.size()));
  const double truth_gain = 100 * (1 - truth_rmse / d.cv_rmse_before_N);
  EXPECT_NEAR(d.cv_gain_percent, truth_gain, 3.0);
  // The constants move back to the truth once the cause is modelled.
  const auto mu_v = std::find_if(d.shifts.begin(), d.shifts.end(), [](const auto& s) { return s.name == "mu_v"; });
  ASSERT_NE(mu_v, d.shifts.end());
  EXPECT_NEAR(mu_v->extended, 0.003, 0.0001);
}

}  // namespace
}  // namespace lmcal
