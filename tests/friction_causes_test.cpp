// The library causes of issue 38 #2 that real axes show and the published law leaves out:
// a viscous slope that differs by direction, friction that ripples along the travel, and
// pre-sliding after reversals. Each is hidden alone in virtual-rig data (three seeds): the
// diagnosis names it and nothing else, its true value inside the interval it reports, with a
// measured held-out gain; and clean data on the same design raise at most one false alarm in
// twenty seeds.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <numbers>
#include <set>
#include <string>

#include "lmcal/diagnose/friction_diagnosis.hpp"
#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/rig/axis_rig.hpp"
#include "lmcal/rig/virtual_rig.hpp"
#include "support/temp_folder.hpp"

namespace lmcal {
namespace {

// A load-cell rig's campaign, smaller than friction_diagnosis_test.cpp's (one guide, two
// preloads, two loads): both senses at eight speeds, four runs.
FrictionRigConfig plateau_campaign(std::uint64_t seed) {
  FrictionRigConfig c;
  c.guides = {"SRN 35C"};
  c.preload_um = {1.5, 4.0};
  c.load_N = {1000, 3000};
  c.velocity_m_s = {0.002, 0.005, 0.01, 0.02, 0.04, 0.066, 0.11, 0.15};
  c.temperature_C = {22, 32};
  c.runs = 4;
  c.seed = seed;
  return c;
}

// A machine axis's own log (axis_rig.hpp): one SRN 35C, a run at each of three loads, trapezoidal
// moves at four top speeds (reversals between moves), the drive's current at 500 Hz.
class FrictionCauses : public test::TempFolderTest {
 protected:
  static FrictionRigConfig axis_setup(std::uint64_t seed) {
    FrictionRigConfig setup;
    setup.guides = {"SRN 35C"};
    setup.preload_um = {2.5};
    setup.load_N = {1000, 2000, 3000};
    setup.temperature_C = {26};
    setup.velocity_m_s = {0.01, 0.05, 0.1, 0.15};
    setup.runs = 1;
    setup.seed = seed;
    return setup;
  }
  static AxisRigConfig axis() {
    AxisRigConfig a;
    a.log_rate_Hz = 500;
    a.cycles = 1;
    return a;
  }
  FrictionLog axis_log(std::uint64_t seed, const RigEffects& effects) const {
    const AxisRigOutput made = generate_axis_logs(axis_setup(seed), axis(), effects);
    for (const auto& [file, text] : made.run_files) write(file, text);
    return load_friction_dataset(write("friction.toml", made.manifest_toml)).log;
  }
};

// The diagnosis names `effect` alone, with `truth` inside its interval and a held-out gain.
void expect_named_alone(const FrictionDiagnosis& d, const std::string& effect, double truth) {
  ASSERT_EQ(d.accepted.size(), 1u) << d.summary;
  const CandidateScore& c = d.accepted.front();
  std::cout << fmt::format("{}: {:.5g} [{:.5g}, {:.5g}] (truth {:g}), held-out gain {:.1f} % ({:.4g} -> {:.4g} N)\n",
                           c.effect, c.value, c.ci_low, c.ci_high, truth, c.cv_gain_percent, d.cv_rmse_before_N,
                           d.cv_rmse_after_N);
  EXPECT_EQ(c.effect, effect) << d.summary;
  EXPECT_LE(c.ci_low, truth) << effect << " " << c.value << " [" << c.ci_low << ", " << c.ci_high << "]";
  EXPECT_GE(c.ci_high, truth) << effect << " " << c.value << " [" << c.ci_low << ", " << c.ci_high << "]";
  EXPECT_GT(c.cv_gain_percent, 0) << d.summary;
  EXPECT_LT(d.cv_rmse_after_N, d.cv_rmse_before_N) << d.summary;
}

// Seal drag on one side: the slope forward is 1.04 times the law's, backward 0.96 times.
TEST(FrictionCausesPlateaus, ADirectionDependentViscousSlopeIsNamedAlone) {
  constexpr double truth = 0.04;
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    RigEffects effects;
    set_rig_effect(effects, "viscous_direction", truth);
    const FrictionDiagnosis d = diagnose_friction(generate_friction_log(plateau_campaign(seed), effects).log, {});
    expect_named_alone(d, "viscous_direction", truth);
  }
}

// A mass taken off 2 kg short, on a load-cell log whose speed wobbles (a = ±0.4 m/s² at every
// speed): the rig's log gets the accelerations and the force they carry through the library's
// own correction, and reaches the diagnosis as a user's would, a tidy CSV with an
// acceleration column.
TEST_F(FrictionCauses, AMovingMassErrorIsNamedAloneWhereTheAccelerationVaries) {
  constexpr double error_kg = 2;
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    FrictionLog log = generate_friction_log(plateau_campaign(seed), {}).log;
    FrictionEffects<double> e;
    e.of<MovingMassError>() = error_kg;
    const FrictionConstants<double> k = paper_friction_constants();
    for (std::size_t i = 0; i < log.size(); ++i) {
      log.acceleration_m_s2[i] = 0.4 * std::sin(0.7 * static_cast<double>(i));
      const FrictionConditions<double> c = log.conditions(i);
      log.friction_N[i] += friction_force_with_effects_N(k, e, c) - friction_force_N(k, c);
    }
    const FrictionLog loaded = load_friction_log(write("wobbling.csv", friction_log_csv(log, {})));
    expect_named_alone(diagnose_friction(loaded, {}), "moving_mass_error", error_kg);
  }
}

// A ripple of 1.5 N at a 7 mm pitch (a roller's) along the travel.
TEST_F(FrictionCauses, FrictionThatRipplesAlongTheTravelIsNamedAloneWithItsPeriod) {
  constexpr double amplitude_N = 1.5, period_m = 0.007, phase_rad = 1.0;
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    RigEffects effects;
    set_rig_effect(effects, "position_ripple", amplitude_N);
    set_rig_effect(effects, "position_ripple_period_m", period_m);
    set_rig_effect(effects, "position_ripple_phase_rad", phase_rad);
    const FrictionDiagnosis d = diagnose_friction(axis_log(seed, effects), {});
    expect_named_alone(d, "position_ripple", amplitude_N);
    const ParameterEstimate& period = d.final_fit.fit.parameter("position_ripple_period_m");
    EXPECT_NEAR(period.value, period_m, 3 * period.se) << period.value << " ± " << period.se;
    EXPECT_NEAR(period.value, period_m, 1e-3 * period_m);
  }
}

// Friction 3 N below its sliding level at a reversal, recovering over 2 mm (at 1 kN and 0.01 m/s
// the law gives 7 N).
TEST_F(FrictionCauses, PreslidingAfterReversalsIsNamedAloneWithItsDistance) {
  constexpr double deficit_N = 3, distance_m = 0.002;
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    RigEffects effects;
    set_rig_effect(effects, "presliding", deficit_N);
    set_rig_effect(effects, "presliding_distance_m", distance_m);
    const FrictionDiagnosis d = diagnose_friction(axis_log(seed, effects), {});
    expect_named_alone(d, "presliding", deficit_N);
    const ParameterEstimate& distance = d.final_fit.fit.parameter("presliding_distance_m");
    EXPECT_NEAR(distance.value, distance_m, 0.2 * distance_m) << distance.value << " ± " << distance.se;
  }
}

// On clean axis data every new candidate can show (both senses, a travel, reversals): tried, and
// none named. A false alarm is any cause named.
TEST_F(FrictionCauses, CleanAxisDataNameNoCauseInNineteenOfTwenty) {
  int alarms = 0;
  const auto start = std::chrono::steady_clock::now();
  for (std::uint64_t seed = 100; seed < 120; ++seed) {
    const FrictionDiagnosis d = diagnose_friction(axis_log(seed, {}), {});
    if (seed == 100) {
      std::set<std::string> tried;
      for (const CandidateScore& c : d.rounds.front()) tried.insert(c.effect);
      for (const char* cause : {"viscous_direction", "position_ripple", "presliding"})
        EXPECT_TRUE(tried.count(cause)) << cause << " not tried: " << d.summary;
      // A trajectory fits its moving mass with the law: its error is no candidate there.
      EXPECT_FALSE(tried.count("moving_mass_error"));
      bool noted = false;
      for (const std::string& note : d.design_notes)
        noted |= note.find("moving_mass_error (acceleration_m_s2 a trajectory") != std::string::npos;
      EXPECT_TRUE(noted) << d.summary;
    }
    if (!d.accepted.empty()) {
      ++alarms;
      std::cout << "seed " << seed << ": " << d.summary << "\n";
    }
  }
  EXPECT_LE(alarms, 1);
  std::cout << "20 clean diagnoses in "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() << " s\n";
}

// The residuals' tests along the travel (position, distance and time since the last reversal,
// acceleration within conditions). A wear track: friction 1.5 N higher in the middle of the
// stroke than at its ends (half a ripple period over the 0.3 m stroke), which no library cause
// has (position_ripple is a pitch of rollers or balls, millimetres). The published law's
// residuals follow the position most of all (distance and time since a reversal, on back-and-
// forth moves, follow it too); nothing is named in its place, and the verdict says what remains
// along the position. On clean data of the same design none of these tests calls structure.
const CovariateTest* along(const ResidualDiagnostics& r, std::string_view prefix) {
  for (const CovariateTest& t : r.covariates)
    if (t.covariate.starts_with(prefix)) return &t;
  return nullptr;
}

TEST_F(FrictionCauses, AWearTrackIsLeftUnexplainedAlongThePositionAndCleanDataShowNothingThere) {
  const std::vector<std::string> columns = {"position_m", "distance_since_reversal_m", "time_since_reversal_s",
                                            "acceleration_m_s2"};
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    RigEffects effects;
    set_rig_effect(effects, "position_ripple", 1.5);
    set_rig_effect(effects, "position_ripple_period_m", 0.6);
    set_rig_effect(effects, "position_ripple_phase_rad", 0.0);
    const FrictionDiagnosis worn = diagnose_friction(axis_log(seed, effects), {});
    const FrictionDiagnosis clean = diagnose_friction(axis_log(seed, {}), {});
    EXPECT_TRUE(worn.accepted.empty()) << worn.summary;
    EXPECT_TRUE(clean.accepted.empty()) << clean.summary;
    for (const std::string& column : columns) {
      for (const auto* r : {&worn.baseline, &worn.final, &clean.baseline, &clean.final}) {
        const CovariateTest* t = along(*r, column);
        ASSERT_NE(t, nullptr) << column << " not tested";
        std::cout << fmt::format("{} {:<40} p {:.3g} Holm {:.3g} size {:.3g} N structured {}\n",
                                 r == &worn.baseline || r == &worn.final ? "worn " : "clean", t->covariate,
                                 t->p_value, t->p_adjusted, t->size, t->structured);
        if (r == &clean.baseline || r == &clean.final) {
          EXPECT_FALSE(t->structured) << clean.summary;
        }
      }
    }
    const CovariateTest* position = along(worn.final, "position_m");
    ASSERT_TRUE(position->structured) << worn.summary;
    for (const std::string& column : columns) EXPECT_LE(along(worn.final, column)->size, position->size) << column;
    EXPECT_NE(worn.summary.find("Unexplained"), std::string::npos) << worn.summary;
    EXPECT_NE(worn.summary.find("position_m"), std::string::npos) << worn.summary;
  }
}

// A sinusoidal move repeats to a fraction of the encoder's 1 µm step, so the quantization repeats
// too: through the filter's second derivative and the mass it is a force pattern locked to the
// phase of the move (M σ_a, 0.2 N here), which the tests along the travel find with p far below
// 1e-3 and which a position ripple of the right period fits for a few % of held-out gain. Clean
// data: nothing named, nothing called structure; every such test in a note with the floor.
TEST_F(FrictionCauses, ARepeatingMovesEncoderQuantizationIsNoCauseAndNoDiscrepancy) {
  AxisRigConfig sine = axis();
  sine.reference = AxisReference::sinusoid;
  sine.log_rate_Hz = 1000;
  sine.duration_s = 30;
  sine.current_noise_A = 0.0005;  // the quantization alone: its pattern stands clear of the current's noise
  FrictionRigConfig setup = axis_setup(1);
  int locked = 0;
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    setup.seed = seed;
    const AxisRigOutput made = generate_axis_logs(setup, sine, {});
    for (const auto& [file, text] : made.run_files) write(file, text);
    const FrictionLog log = load_friction_dataset(write("friction.toml", made.manifest_toml)).log;
    const FrictionDiagnosis d = diagnose_friction(log, {});
    EXPECT_TRUE(d.accepted.empty()) << d.summary;
    EXPECT_EQ(d.verdict, "no significant discrepancy") << d.summary;
    // The floor is the mass times the filter's acceleration noise, the rig's 40 kg within its SE.
    double sigma_a = 0;
    for (const RunSegmentation& r : log.segmentation) sigma_a = std::max(sigma_a, r.acceleration_noise_m_s2);
    EXPECT_GT(d.baseline.resolution_floor_N, 0.8 * sine.moving_mass_kg * log.segmentation.front().acceleration_noise_m_s2);
    EXPECT_LE(d.baseline.resolution_floor_N, 1.01 * sine.moving_mass_kg * sigma_a);
    for (const CovariateTest& t : d.final.covariates) {
      if (t.p_adjusted >= 1e-3) continue;
      ++locked;
      EXPECT_LT(t.size, d.final.resolution_floor_N) << t.covariate;
      EXPECT_TRUE(std::any_of(d.design_notes.begin(), d.design_notes.end(), [&](const std::string& n) {
        return n.find(t.covariate + " (p ") != std::string::npos && n.find("resolution") != std::string::npos;
      })) << t.covariate << ": " << d.summary;
    }
  }
  EXPECT_GT(locked, 0) << "the quantization's pattern is significant: the floor, not the noise, keeps it from being named";
}

}  // namespace
}  // namespace lmcal
