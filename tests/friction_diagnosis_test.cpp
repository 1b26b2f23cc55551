#include "lmcal/diagnose/friction_diagnosis.hpp"

#include <gtest/gtest.h>

#include <fmt/format.h>
#include <fmt/ranges.h>

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
                           {"coulomb_temperature", 0.03}, {"coulomb_temperature", 0.08},
                           {"seal_drag_block", 15},       {"seal_drag_block", 60},
                           {"signed_zero_offset", 0.1},   {"signed_zero_offset", 0.3},
                           {"viscous_direction", 0.02},   {"viscous_direction", 0.05}};
  // A newly registered effect must come with its own cases here; the drive's dynamics (the
  // moving mass and an incline's weight) are no cause to name: trajectory_friction_test.cpp.
  // Causes a tidy log cannot show (a raw log's travel, a mass error's accelerations) and shape
  // parameters: friction_causes_test.cpp.
  const auto tidy_log_shows = [](const FrictionEffectInfo& info) {
    for (const char* column : {"position_m", "distance_since_reversal_m", "acceleration_m_s2"})
      if (std::string_view(info.varies) == column) return false;
    return !is_friction_effect_part(info);
  };
  for (const auto& info : FrictionEffectLibrary::infos) {
    if (!info.dynamics && tidy_log_shows(info)) {
      EXPECT_TRUE(std::any_of(std::begin(hidden), std::end(hidden), [&](const Hidden& h) { return h.effect == std::string(info.name); }))
          << info.name << " is registered but never hidden in the test data";
    }
  }
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
  // The true law and effect at the conditions the fits see (each block's mean logged
  // temperature): its error is the rig's noise (load cell, and what is left of the logged
  // temperature's).
  double ss = 0;
  FrictionEffects<double> truth_effects;
  truth_effects.of<SealDrag>() = 80;
  const FrictionLog seen = with_block_mean_temperature(made.log);
  for (std::size_t i = 0; i < seen.size(); ++i)
    ss += std::pow(seen.friction_N[i] - friction_force_with_effects_N(paper_friction_constants(), truth_effects, seen.conditions(i)),
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

namespace lmcal {
namespace {

// A rig that logs one setup per run (one load, one temperature), swept over speed and
// direction: what most rigs do. Load and temperature change only between runs.
FrictionRigConfig one_setup_per_run(std::uint64_t seed) {
  FrictionRigConfig c;
  c.guides = {"SRG 25C", "SRN 35C"};
  c.preload_um = {2.5};
  c.load_N = {1000, 2000, 3000};
  c.temperature_C = {22, 30, 40};
  c.one_setup_per_run = true;
  c.runs = 1;
  c.seed = seed;
  return c;
}

// Per-run zero offsets used to erase everything that changes only between runs: a
// temperature-dependent Coulomb term in one-setup runs is named, with its interval. Two
// sweeps of the 18 setups: with one, only the 18 runs' levels see the term (the fit sees each
// run's mean logged temperature), and its direction beside k1 is at the edge of what they
// determine (relative SE 0.53 against the 0.5 that counts as identified). A cause is named only
// where its interval excludes 0 (issue 38 #5): on seed 1 the estimate, 0.089, lies near its
// bound 0.1, and its interval on the logit scale reaches below 0 ([-0.003, 0.099]): not named,
// and the round says why.
TEST(FrictionDiagnosis, OneSetupPerRunStillShowsWhatChangesBetweenRuns) {
  for (std::uint64_t seed : {1, 2, 3}) {
    RigEffects effects;
    set_rig_effect(effects, "coulomb_temperature", 0.08);
    FrictionRigConfig rig = one_setup_per_run(seed);
    rig.runs = 2;
    const auto d = diagnose(generate_friction_log(rig, effects).log);
    if (seed == 1) {
      ASSERT_TRUE(d.accepted.empty()) << d.summary;
      const auto& round = d.rounds.front();
      const auto c = std::find_if(round.begin(), round.end(), [](auto& c) { return c.effect == "coulomb_temperature"; });
      ASSERT_NE(c, round.end());
      EXPECT_LE(c->ci_low, 0) << c->reason;
      EXPECT_NE(c->reason.find("contains its neutral value 0"), std::string::npos) << c->reason;
      continue;
    }
    ASSERT_FALSE(d.accepted.empty()) << "seed " << seed << ": " << d.summary;
    EXPECT_GT(d.accepted.front().ci_low, 0) << d.summary;
    EXPECT_EQ(d.accepted.front().effect, "coulomb_temperature") << "seed " << seed << ": " << d.summary;
    EXPECT_LE(d.accepted.front().ci_low, 0.08) << d.summary;
    EXPECT_GE(d.accepted.front().ci_high, 0.08) << d.summary;
    // The design is named: load and temperature are seen only between runs.
    EXPECT_TRUE(std::any_of(d.design_notes.begin(), d.design_notes.end(),
                            [](const std::string& note) { return note.find("temperature_C") != std::string::npos; }))
        << "seed " << seed;
  }
}

TEST(FrictionDiagnosis, OneSetupPerRunCleanDataRaiseNoFalseAlarmInNineteenOfTwenty) {
  int alarms = 0;
  for (std::uint64_t seed = 200; seed < 220; ++seed) {
    const auto d = diagnose(generate_friction_log(one_setup_per_run(seed), {}).log);
    if (d.verdict != "no significant discrepancy") {
      ++alarms;
      ADD_FAILURE() << "seed " << seed << ": " << d.summary;  // reported; the count decides
    }
  }
  EXPECT_LE(alarms, 1);
}

// Structure in a product of covariates that no candidate models: the friction changes with
// speed differently at each temperature, changing sign within the speed range. Named as the
// pair, "unexplained".
TEST(FrictionDiagnosis, StructureInAPairOfCovariatesIsUnexplainedNamingThePair) {
  for (std::uint64_t seed : {51, 52}) {
    auto log = generate_friction_log(campaign(seed), {}).log;
    for (std::size_t i = 0; i < log.size(); ++i)
      log.friction_N[i] += 0.12 * (std::round(log.temperature_C[i]) - 30.67) / 9.0 * std::log(log.velocity_m_s[i] / 0.02);
    const auto d = diagnose(log);
    EXPECT_TRUE(d.verdict.starts_with("unexplained") || d.verdict.starts_with("partly explained"))
        << "seed " << seed << ": " << d.summary;
    EXPECT_NE(d.unexplained_covariate.find("temperature_C"), std::string::npos) << d.summary;
    // Beyond the library, the term learned uses the pair (not a named cause).
    if (d.empirical.found) {
      EXPECT_NE(d.empirical.formula.find("V·(T - 40)"), std::string::npos) << d.empirical.formula;
    }
    EXPECT_NE(d.unexplained_covariate.find("velocity_m_s"), std::string::npos) << d.summary;
  }
}

// A load cell whose zero sits in the signed force reads F + direction·o: the diagnosis names
// the sensor offset, and invents no direction asymmetry (f0 free).
TEST(FrictionDiagnosis, ASignedSensorOffsetIsNotADirectionAsymmetry) {
  for (std::uint64_t seed : {61, 62, 63}) {
    RigEffects effects;
    set_rig_effect(effects, "signed_zero_offset", 0.25);
    const auto d = diagnose(generate_friction_log(one_setup_per_run(seed), effects).log);
    ASSERT_FALSE(d.accepted.empty()) << d.summary;
    EXPECT_EQ(d.accepted.front().effect, "signed_zero_offset") << d.summary;
    EXPECT_EQ(shown_name(d.accepted.front()), "signed_zero_offset") << "the rig states its load cell and mounting";
    for (const auto& c : d.accepted) EXPECT_NE(c.effect, "direction_asymmetry") << d.summary;
  }
}

// Lack of fit against pure error: repeated conditions give the noise; a law that misses by
// more is rejected even when no one covariate carries the miss.
TEST(FrictionDiagnosis, LackOfFitIsTestedAgainstTheSpreadOfRepeats) {
  auto clean = generate_friction_log(campaign(71), {}).log;
  const auto ok = diagnose(clean);
  ASSERT_TRUE(ok.baseline.lack_of_fit.tested) << ok.baseline.lack_of_fit.basis;
  EXPECT_TRUE(ok.baseline.lack_of_fit.fits) << ok.summary;
  EXPECT_NEAR(ok.baseline.lack_of_fit.pure_error_rms, 0.15, 0.03);  // the rig's load-cell noise
  // A fixed pseudo-random miss per condition (the same in every run): no covariate follows it.
  auto wrong = clean;
  for (std::size_t i = 0; i < wrong.size(); ++i) {
    const double key = wrong.velocity_m_s[i] * 1e3 + wrong.load_N[i] + wrong.preload_um[i] * 7 +
                       std::round(wrong.temperature_C[i]) * 13 + wrong.direction[i] * 17 + wrong.block_length_mm[i];
    wrong.friction_N[i] += 0.15 * std::sin(key * 12.9898);
  }
  const auto bad = diagnose(wrong);
  EXPECT_FALSE(bad.baseline.lack_of_fit.fits) << bad.summary;
  EXPECT_NE(bad.verdict, "no significant discrepancy") << bad.summary;
  EXPECT_NE(bad.verdict, "explained") << bad.summary;
}

// A parameter held in the baseline is never reported as moving.
TEST(FrictionDiagnosis, HeldParametersAreNotReportedAsShifts) {
  RigEffects effects;
  set_rig_effect(effects, "seal_drag", 60);
  FrictionDiagnosisOptions o;
  o.fit.free[6] = false;  // f0 held at the paper's value
  const auto d = diagnose_friction(generate_friction_log(campaign(81), effects).log, o);
  const auto f0 = std::find_if(d.shifts.begin(), d.shifts.end(), [](const auto& s) { return s.name == "f0"; });
  ASSERT_NE(f0, d.shifts.end());
  EXPECT_FALSE(f0->free);
  EXPECT_EQ(d.summary.find("f0 "), std::string::npos) << d.summary;
}

}  // namespace
}  // namespace lmcal

namespace lmcal {
namespace {

// With one block length, seal drag and a block-size seal drag change the fit identically: a
// tie, named together with the plainer one as representative, not one cause picked at random.
TEST(FrictionDiagnosis, CausesTheDataCannotTellApartAreReportedAsATie) {
  auto rig = campaign(91);
  rig.guides = {"SRG 25C"};
  RigEffects effects;
  set_rig_effect(effects, "seal_drag", 60);
  const auto d = diagnose(generate_friction_log(rig, effects).log);
  ASSERT_FALSE(d.accepted.empty()) << d.summary;
  EXPECT_EQ(d.accepted.front().effect, "seal_drag") << d.summary;
  EXPECT_EQ(d.accepted.front().tied_with, std::vector<std::string>{"seal_drag_block"}) << d.summary;
  EXPECT_NE(d.summary.find("seal_drag or seal_drag_block: these data cannot tell them apart"), std::string::npos) << d.summary;
  EXPECT_NE(d.summary.find("To separate them, log guides with different block lengths"), std::string::npos) << d.summary;
  // Two block lengths separate them: no tie.
  const auto two = diagnose(generate_friction_log(campaign(91), effects).log);
  ASSERT_FALSE(two.accepted.empty()) << two.summary;
  EXPECT_EQ(two.accepted.front().effect, "seal_drag") << two.summary;
  EXPECT_TRUE(two.accepted.front().tied_with.empty()) << two.summary;
}

}  // namespace
}  // namespace lmcal

namespace lmcal {
namespace {

// A cause whose signature cannot show in the log is not tried (issue 38: named only where its
// precondition holds): at one temperature a Coulomb temperature coefficient is k1, at one load
// a load-dependent viscous slope is mu_v. The design notes say which were left out, and why.
TEST(FrictionDiagnosis, ACauseWhosePreconditionIsAbsentIsNotTried) {
  FrictionRigConfig c = campaign(5);
  c.temperature_C = {26};
  c.load_N = {3000};
  const FrictionDiagnosis d = diagnose(generate_friction_log(c, {}).log);
  for (const auto& round : d.rounds)
    for (const auto& candidate : round) {
      EXPECT_NE(candidate.effect, "coulomb_temperature");
      EXPECT_NE(candidate.effect, "viscous_load");
    }
  std::string noted;
  for (const auto& note : d.design_notes)
    if (note.starts_with("not tried, their precondition absent: ")) noted = note;
  EXPECT_NE(noted.find("coulomb_temperature (temperature_C constant or not logged)"), std::string::npos)
      << fmt::format("{}", fmt::join(d.design_notes, "\n"));
  EXPECT_NE(noted.find("viscous_load (load_N constant or not logged)"), std::string::npos) << noted;
  // Where they can show, they are tried.
  const FrictionDiagnosis full = diagnose(generate_friction_log(campaign(5), {}).log);
  bool tried = false;
  for (const auto& candidate : full.rounds.front()) tried |= candidate.effect == "coulomb_temperature";
  EXPECT_TRUE(tried);
}

}  // namespace
}  // namespace lmcal
