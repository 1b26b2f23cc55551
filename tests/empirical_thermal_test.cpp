// The thermal diagnosis learns what no mechanism of its library explains: a daily swing of
// the air that the rail sees in full but the ambient sensors only in part, and a slow drift
// of the thermocouples (virtual-rig effects outside the library) end in an empirical term in
// time and the ambient's periodic components, with the held-out gain of the true model and
// the truth's drift rate and period; clean data grow no term; an in-library mechanism is
// still named as itself. Also the pieces: the dominant period of an ambient, and a sensor
// term fitted jointly with the rail model recovers its coefficient and scale.
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "diagnose/empirical_thermal.hpp"
#include "lmcal/diagnose/thermal_diagnosis.hpp"
#include "lmcal/rig/virtual_rig.hpp"

namespace lmcal {
namespace {

// Three runs at three speeds, 40 h each (a daily period shows), a record every 120 s, in a
// room whose air drifts 0.02 K/h besides the rig's 2 h wave.
ThermalDataSet long_runs(std::uint64_t seed, const RigEffects& effects = {}) {
  ThermalRigConfig rig;
  rig.velocity_m_s = {0.066, 0.09, 0.11};
  rig.duration_s = 40 * 3600;
  rig.record_every_s = 120;
  rig.ambient_drift_K_per_h = 0.02;
  rig.seed = seed;
  return generate_thermal_dataset(rig, effects, "test").set;
}

// The air swings daily (1.5 K), the ambient sensors (in a sheltered spot) log 30 % of it, and
// every rail thermocouple drifts (0.03 K/h).
RigEffects daily_and_drift(double daily_K = 1.5, double drift_K_per_h = 0.03) {
  RigEffects effects;
  set_rig_effect(effects, "ambient_daily_K", daily_K);
  set_rig_effect(effects, "ambient_daily_seen", 0.3);
  set_rig_effect(effects, "tc_drift_K_per_h", drift_K_per_h);
  return effects;
}

// The diagnosis of long runs of this seed, with the rig's heat (the paper's law at the start
// temperature) and 120 s steps (Crank-Nicolson; the rail's time constant is over an hour).
ThermalDiagnosis diagnose(std::uint64_t seed, const RigEffects& effects = {}) {
  ThermalDiagnosisOptions o;
  o.fit.heat = HeatInput::friction_law;
  o.fit.time_step_s = 120;
  return diagnose_thermal(long_runs(seed, effects), o);
}

// The component whose coefficient is the sensor term `kind` ("c<j> t", "c<j> a_P", …).
const EmpiricalComponent* component(const EmpiricalFinding& f, const std::string& kind) {
  for (const auto& c : f.components) {
    const std::string& name = c.coefficient.name;
    if (name.size() > kind.size() && name.compare(name.size() - kind.size() - 1, std::string::npos, " " + kind) == 0) return &c;
  }
  return nullptr;
}

void expect_daily_swing_and_drift_learned(std::uint64_t seed, double daily_K, double drift_K_per_h) {
  const ThermalDiagnosis d = diagnose(seed, daily_and_drift(daily_K, drift_K_per_h));
  const ThermalDiagnosis clean = diagnose(seed);
  const EmpiricalFinding& f = d.empirical;
  ASSERT_NE(d.verdict.find("empirical term found"), std::string::npos) << d.summary;
  ASSERT_TRUE(f.found) << f.reason;
  EXPECT_EQ(f.where, "every thermocouple reading");
  // In time and in the ambient's periodic components.
  const EmpiricalComponent* drift = component(f, "t");
  const EmpiricalComponent* swing = component(f, "a_P");  // at the ambient's first or second period
  if (!swing) swing = component(f, "b_P");
  ASSERT_TRUE(drift) << f.formula;
  ASSERT_TRUE(swing) << f.formula;
  EXPECT_NEAR(drift->coefficient.value, drift_K_per_h, 0.3 * drift_K_per_h) << f.formula << "; " << d.summary;
  ASSERT_TRUE(swing->has_scale) << f.formula;
  EXPECT_NEAR(swing->scale.value / 3600, 24, 0.3 * 24) << d.summary;
  // The held-out gain of the true model: what the baseline loses to the hidden effects.
  const double truth_gain = 1 - clean.cv_rmse_before_K / d.cv_rmse_before_K;
  const double gain = 1 - f.cv_rmse_after / d.cv_rmse_before_K;
  EXPECT_NEAR(gain, truth_gain, 0.25 * truth_gain) << d.summary;
  // The curve over the time since the start, with a band around the term.
  ASSERT_EQ(f.curve.x.size(), 20u);
  for (std::size_t b = 0; b < f.curve.x.size(); ++b) {
    EXPECT_LE(f.curve.low[b], f.curve.value[b]);
    EXPECT_GE(f.curve.high[b], f.curve.value[b]);
  }
  EXPECT_FALSE(d.empirical_fit.samples.empty());
  std::printf("seed %llu: %s; gain %.2f %% (truth %.2f %%), drift %.4g K/h, P %.3g h\n",
              static_cast<unsigned long long>(seed), f.formula.c_str(), 100 * gain, 100 * truth_gain,
              drift->coefficient.value, swing->scale.value / 3600);
}

TEST(EmpiricalThermal, LearnsADailySwingAndAThermocoupleDriftSeed1) { expect_daily_swing_and_drift_learned(1, 1.5, 0.03); }
// A smaller swing: the ambient sensors log 0.15 K of it, less than the room's 0.3 K 2 h wave,
// so the day is the ambient's second period.
TEST(EmpiricalThermal, LearnsASmallerDailySwingAndDriftSeed2) { expect_daily_swing_and_drift_learned(2, 0.5, 0.01); }

TEST(EmpiricalThermal, CleanDataGrowNoTerm) {
  for (std::uint64_t seed : {11, 12, 13}) {
    const ThermalDiagnosis d = diagnose(seed);
    EXPECT_FALSE(d.empirical.found) << "seed " << seed << ": " << d.summary;
    EXPECT_EQ(d.verdict.find("empirical"), std::string::npos) << d.summary;
  }
}

// A mechanism of the library is named as itself (a base loss, or its tie, a larger h), and
// nothing is left for an empirical term.
TEST(EmpiricalThermal, AnInLibraryMechanismIsNamedNotLearned) {
  RigEffects effects;
  set_rig_effect(effects, "base_loss", 0.1);
  const ThermalDiagnosis d = diagnose(3, effects);
  ASSERT_FALSE(d.accepted.empty()) << d.summary;
  const auto& c = d.accepted.front();
  std::vector<std::string> named{c.effect};
  named.insert(named.end(), c.tied_with.begin(), c.tied_with.end());
  EXPECT_TRUE(std::find(named.begin(), named.end(), "base_loss") != named.end()) << d.summary;
  EXPECT_FALSE(d.empirical.found) << d.summary;
}

// The rig's hidden effects draw no noise of their own: with the same seed, the thermocouple
// drift adds exactly rate·t to every rail reading and nothing to the ambient sensors, and the
// daily swing adds `seen` of itself to the ambient sensors (its phase in the truth) and more
// to the rail, which sees all of it.
TEST(EmpiricalThermal, TheRigHidesADailySwingAndADriftWithoutNewNoiseDraws) {
  ThermalRigConfig rig;
  rig.velocity_m_s = {0.066, 0.11};
  rig.duration_s = 30 * 3600;
  rig.record_every_s = 600;
  const ThermalRigOutput clean = generate_thermal_dataset(rig, {}, "test");
  RigEffects drift;
  set_rig_effect(drift, "tc_drift_K_per_h", 0.04);
  const ThermalRigOutput drifted = generate_thermal_dataset(rig, drift, "test");
  const ThermalRigOutput swung = generate_thermal_dataset(rig, daily_and_drift(), "test");
  const auto truth = nlohmann::json::parse(swung.truth_json);
  EXPECT_TRUE(truth["effects"]["ambient_daily_K"]["active"].get<bool>());
  EXPECT_TRUE(truth["effects"]["ambient_daily_seen"]["active"].get<bool>());
  for (std::size_t r = 0; r < clean.set.runs.size(); ++r) {
    const ThermalTrace& a = clean.set.runs[r].trace;
    const ThermalTrace& b = drifted.set.runs[r].trace;
    const ThermalTrace& c = swung.set.runs[r].trace;
    const double phase = truth["runs"][r]["ambient"]["daily_phase_rad"].get<double>();
    double rail_swing = 0, ambient_swing = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double daily = 1.5 * std::sin(2 * std::numbers::pi * a.time_s[i] / 86400 + phase);
      for (std::size_t s = 0; s < a.rail.size(); ++s) {
        EXPECT_NEAR(b.rail[s].values[i] - a.rail[s].values[i], 0.04 * a.time_s[i] / 3600, 0.0101);
        rail_swing = std::max(rail_swing, std::abs(c.rail[s].values[i] - a.rail[s].values[i] - 0.03 * a.time_s[i] / 3600));
      }
      for (std::size_t k = 0; k < a.ambient.size(); ++k) {
        EXPECT_EQ(b.ambient[k].values[i], a.ambient[k].values[i]);
        EXPECT_NEAR(c.ambient[k].values[i] - a.ambient[k].values[i], 0.3 * daily, 0.0101);
        ambient_swing = std::max(ambient_swing, std::abs(c.ambient[k].values[i] - a.ambient[k].values[i]));
      }
    }
    EXPECT_GT(rail_swing, 2 * ambient_swing);  // the rail sees the whole swing (through its own lag)
  }
}

// The ambient's dominant period: a 24 h swing over a line and a 2 h wave of less amplitude.
TEST(EmpiricalThermal, DominantPeriodOfTheAmbient) {
  std::vector<AmbientTrace> ambients;
  for (double phase : {0.3, 2.0, 4.1}) {
    AmbientTrace a;
    for (double t = 0; t <= 40 * 3600; t += 120) {
      a.time_s.push_back(t);
      a.temperature_C.push_back(22 + 0.1 * t / 3600 + 0.45 * std::sin(2 * std::numbers::pi * t / 86400 + phase) +
                                0.3 * std::sin(2 * std::numbers::pi * t / 7200 + 2 * phase));
    }
    ambients.push_back(a);
  }
  EXPECT_NEAR(detail::dominant_ambient_period_s(ambients) / 3600, 24, 0.05 * 24);
}

// A sensor term fitted jointly with the rail model: a drift of every thermocouple, and the
// ambient's daily component (its period free), recovered from data that carry exactly them.
TEST(EmpiricalThermal, JointFitRecoversASensorTermsCoefficientAndPeriod) {
  // The air swings daily, and the ambient sensors log all of it (the model follows it).
  RigEffects daily;
  set_rig_effect(daily, "ambient_daily_K", 0.5);
  ThermalDataSet data = long_runs(5, daily);
  ThermalFitOptions o;
  o.heat = HeatInput::friction_law;
  o.time_step_s = 60;
  o.offsets = ThermalOffsets::fitted;
  o.per_run_fits = o.compare_sources = false;
  o.curve_points = 0;
  o.fit.profile = ProfileMode::none;
  // Add 0.02 K/h and 0.8 × the run's own ambient component at 24 h to every rail reading.
  ThermalFitOptions truth = o;
  truth.sensor_terms = {{.kind = ThermalTermKind::time, .coefficient = 0.02},
                        {.kind = ThermalTermKind::ambient_in_phase, .coefficient = 0.8, .scale_s = 86400, .fit_scale = false}};
  const ThermalFitResult plain = fit_thermal(data, o);
  const std::vector<std::vector<double>> phi = thermal_sensor_term_values(data, o, plain, truth.sensor_terms);
  std::vector<double> added(plain.samples.size(), 0.0);
  for (std::size_t k = 0; k < added.size(); ++k) added[k] = 0.02 * phi[0][k] + 0.8 * phi[1][k];
  for (std::size_t k = 0; k < plain.samples.size(); ++k) {
    const auto& s = plain.samples[k];
    auto& run = data.runs[s.run];
    const auto at = std::find(run.trace.time_s.begin(), run.trace.time_s.end(), s.time_s) - run.trace.time_s.begin();
    run.trace.rail[s.sensor].values[static_cast<std::size_t>(at)] += added[k];
  }
  ThermalFitOptions joint = o;
  joint.sensor_terms = {{.kind = ThermalTermKind::time},
                        {.kind = ThermalTermKind::ambient_in_phase, .scale_s = 20 * 3600, .scale_lower_s = 10 * 3600,
                         .scale_upper_s = 40 * 3600}};
  const ThermalFitResult fit = fit_thermal(data, joint);
  EXPECT_NEAR(fit.joint.parameter("c1 t").value, 0.02, 0.002);
  EXPECT_NEAR(fit.joint.parameter("c2 a_P").value, 0.8, 0.08);
  EXPECT_NEAR(fit.joint.parameter("P_s").value / 3600, 24, 1.0);
  EXPECT_NEAR(fit.joint.parameter("alpha").value, plain.joint.parameter("alpha").value, 0.01);
  // The sum the fit adds is the one put in.
  const std::vector<double> sum = thermal_sensor_term_sum(data, joint, fit);
  double worst = 0;
  for (std::size_t k = 0; k < sum.size(); ++k) worst = std::max(worst, std::abs(sum[k] - added[k]));
  EXPECT_LT(worst, 0.05);
}

// Monte Carlo: clean data grow no term in at least 19 of 20 seeds (slow: run by hand).
TEST(EmpiricalThermal, DISABLED_CleanDataGrowNoTermInNineteenOfTwenty) {
  int grown = 0;
  for (std::uint64_t seed = 200; seed < 220; ++seed) {
    const ThermalDiagnosis d = diagnose(seed);
    if (d.empirical.found) {
      ++grown;
      ADD_FAILURE_AT(__FILE__, __LINE__) << "seed " << seed << ": " << d.summary;  // reported; the count decides
    }
    std::printf("seed %llu: %s; searched %d\n", static_cast<unsigned long long>(seed), d.verdict.c_str(), d.empirical.searched);
  }
  EXPECT_LE(grown, 1);
}

}  // namespace
}  // namespace lmcal
