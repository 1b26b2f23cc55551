// Friction from a drive's own trajectory (RawSegmentation::trajectory): a carriage of known
// mass on an inclined axis moving along two superposed sinusoids (reversals, speeds from rest
// to 0.2 m/s, accelerations that vary independently of the speed), its drive force logged with
// noise and its position quantised to the encoder's count. The moving mass and the incline's
// weight are recovered to a fraction of a per cent, the determined friction constants within
// their 95 % intervals; the log that never rests is read whole; a trajectory that never
// accelerates is refused.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "lmcal/error.hpp"
#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/models/friction.hpp"
#include "lmcal/rig/axis_rig.hpp"
#include "parallel_slices.hpp"
#include "lmcal/rig/virtual_rig.hpp"
#include "support/coverage_tally.hpp"
#include "support/temp_folder.hpp"

namespace lmcal {
namespace {

namespace fs = std::filesystem;

struct Axis {
  double mass_kg = 40;
  double incline_deg = 20;
  double noise_N = 2;
  double count_m = 1e-6;  // the encoder's resolution
  double weight_N() const { return axis_weight_N(mass_kg, incline_deg); }
};

struct RunSpec {
  std::string id;
  double load_N, temperature_C;
  double amplitude_m, frequency_Hz;  // the slow sweep; a fast ripple rides on it
};

class TrajectoryFriction : public test::TempFolderTest {
 protected:
  // write(name, text) into the test's folder, for code outside the fixture.
  auto writer() const {
    return [this](const fs::path& name, const std::string& text) { return write(name, text); };
  }
  // Writes one run as a drive logs it (1 kHz, 20 s): time, quantised position, drive force.
  void write_run(const RunSpec& r, const Axis& axis, unsigned seed, bool accelerate = true) const {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0, axis.noise_N);
    const FrictionConstants<double> k = paper_friction_constants();
    std::string csv = "time_s,position_mm,force_N\n";
    const double w1 = 2 * std::numbers::pi * r.frequency_Hz, w2 = 2 * std::numbers::pi * 2.7;
    const double a2 = accelerate ? 0.004 : 0;
    for (int i = 0; i < 20000; ++i) {
      const double t = i * 1e-3;
      double x = r.amplitude_m * std::sin(w1 * t) + a2 * std::sin(w2 * t + 0.3);
      double v = r.amplitude_m * w1 * std::cos(w1 * t) + a2 * w2 * std::cos(w2 * t + 0.3);
      double a = -r.amplitude_m * w1 * w1 * std::sin(w1 * t) - a2 * w2 * w2 * std::sin(w2 * t + 0.3);
      if (!accelerate) {  // a constant speed, back and forth once
        v = t < 10 ? 0.1 : -0.1;
        x = t < 10 ? 0.1 * t : 1.0 - 0.1 * (t - 10);
        a = 0;
      }
      const FrictionConditions<double> c{.load_N = r.load_N, .preload_um = 4, .block_length_mm = 120.2,
                                         .velocity_m_s = std::abs(v), .temperature_C = r.temperature_C};
      const double sense = v < 0 ? -1.0 : 1.0;
      const double force = axis.mass_kg * a + sense * friction_force_N(k, c) + axis.weight_N() + noise(rng);
      const double counted = std::round(x / axis.count_m) * axis.count_m;
      csv += fmt::format("{:.3f},{:.6f},{:.3f}\n", t, counted * 1e3, force);
    }
    write(r.id + ".csv", csv);
  }

  fs::path write_manifest(const std::vector<RunSpec>& runs, const Axis& axis) const {
    std::string toml = fmt::format("[raw]\nsegmentation = \"trajectory\"\naxis_incline_deg = {}\n", axis.incline_deg);
    for (const RunSpec& r : runs)
      toml += fmt::format("[[run]]\nid = \"{}\"\nfile = \"{}.csv\"\nguide = \"SRN 35C\"\nload_N = {}\npreload_um = 4\n"
                          "temperature_C = {}\n",
                          r.id, r.id, r.load_N, r.temperature_C);
    return write("friction.toml", toml);
  }
};

double quoted_low(const ParameterEstimate& p) { return p.interval == "profile" ? p.profile_low : p.ci_low; }
double quoted_high(const ParameterEstimate& p) { return p.interval == "profile" ? p.profile_high : p.ci_high; }

TEST_F(TrajectoryFriction, TheMassTheWeightAndTheLawAreRecovered) {
  const Axis axis;
  const std::vector<RunSpec> runs{{"a", 1000, 24, 0.05, 0.45}, {"b", 3000, 24, 0.06, 0.35},
                                  {"c", 1000, 34, 0.05, 0.40}, {"d", 3000, 34, 0.06, 0.50}};
  for (int seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    for (std::size_t r = 0; r < runs.size(); ++r) write_run(runs[r], axis, static_cast<unsigned>(10 * seed + r));
    const FrictionDataSet set = load_friction_dataset(write_manifest(runs, axis));
    const FrictionLog& log = set.log;
    ASSERT_TRUE(log.trajectory);
    ASSERT_EQ(log.segmentation.size(), runs.size());
    for (const RunSegmentation& s : log.segmentation) {
      EXPECT_GT(s.kept, s.samples * 8 / 10) << "a log that never rests is read whole, but for its reversals";
      EXPECT_GE(s.filter_window, 5u);
      EXPECT_GT(s.acceleration_noise_m_s2, 0);
    }
    FrictionFitOptions o;
    o.free = {true, false, true, true, true, true, true};  // one preload: k2 held (k1 - k2 pc is what is seen)
    o.fit.starts = 1;
    o.per_run_fits = false;
    const FrictionFitResult fit = fit_friction(log, o);
    ASSERT_TRUE(fit.fit.solver.usable) << fit.fit.solver.termination;
    // The mass and the weight to 0.2 % and 0.05 %; their intervals (±0.05 %, ±0.01 %) are not
    // asserted to cover: a bias of that size remains (the filter's residual autocorrelation
    // against the HAC bandwidth is the first suspect; open in issue 37).
    const ParameterEstimate& mass = fit.fit.parameter("moving_mass");
    EXPECT_NEAR(mass.value, axis.mass_kg, 0.002 * axis.mass_kg) << "the mass within 0.2 %";
    const ParameterEstimate& weight = fit.fit.parameter("axis_gravity");
    EXPECT_NEAR(weight.value, axis.weight_N(), 5e-4 * axis.weight_N()) << "the weight within 0.05 %";
    const FrictionConstants<double> truth = paper_friction_constants();
    for (const char* name : {"k1", "mu_v", "beta_per_K"}) {
      const ParameterEstimate& p = fit.fit.parameter(name);
      const double want = fittable_constant(truth, *find_friction_constant(name));
      EXPECT_LE(quoted_low(p), want) << name << " " << p.value;
      EXPECT_GE(quoted_high(p), want) << name << " " << p.value;
    }
    for (const auto& p : fit.fit.parameters) EXPECT_NE(p.name, "signed_zero_offset") << "never a load-cell zero";
  }
}

// The virtual rig's closed-loop axis (a P-PI controller on trapezoidal moves at ten speeds, a
// 1 µm encoder, current noise), 20° incline, loads of 1 and 3 kN.
struct ClosedLoopAxis {
  FrictionRigConfig setup;
  AxisRigConfig axis;
  ClosedLoopAxis() {
    setup.guides = {"SRN 35C"};
    setup.preload_um = {2.5};
    setup.load_N = {1000, 3000};
    setup.temperature_C = {26};
    setup.runs = 1;
    axis.incline_deg = 20;
  }
  double weight_N() const { return axis_weight_N(axis.moving_mass_kg, axis.incline_deg); }
  // The log as the reader gives it, and its fit as a user's defaults give it but lean (one
  // start, no per-run fits). `write(name, text)` writes a file and returns its path.
  template <class Write>
  FrictionFitResult fit(const Write& write, unsigned seed, FrictionLog* loaded = nullptr) {
    setup.seed = seed;
    const AxisRigOutput made = generate_axis_logs(setup, axis, {});
    for (const auto& [file, text] : made.run_files) write(file, text);
    FrictionLog log = load_friction_dataset(write("friction.toml", made.manifest_toml)).log;
    FrictionFitOptions o;
    o.fit.starts = 1;
    o.per_run_fits = false;
    FrictionFitResult result = fit_friction(log, o);
    if (loaded) *loaded = std::move(log);
    return result;
  }
  // The truth of a determined parameter of the fit (nullopt: not one with a truth).
  std::optional<double> truth(const ParameterEstimate& p) const {
    if (!p.free || p.held_unidentifiable || p.per_run) return std::nullopt;
    if (p.name == "moving_mass") return axis.moving_mass_kg;
    if (p.name == "axis_gravity") return weight_N();
    if (const auto constant = find_friction_constant(p.name)) return fittable_constant(setup.constants, *constant);
    return std::nullopt;
  }
};

// Seeds 1-3: the mass within 2 %, the weight within 0.5 %, five constants determined, never a
// load-cell zero. The drive force steps at every corner of the moves (the feedforward M·a_ref):
// before the reader dropped the samples within the filter's reach of such a step (raw_friction.cc,
// drop_force_steps), mu_st came out 4-8 % low and mu_v 0.4 % low at 3-8 SE on every seed. The
// speed varies sample by sample: the per-condition table groups it in 2 % bins.
TEST_F(TrajectoryFriction, TheClosedLoopRigsMassAndWeightAreRecovered) {
  ClosedLoopAxis rig;
  for (unsigned seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    FrictionLog log;
    const FrictionFitResult fit = rig.fit(writer(), seed, &log);
    for (const RunSegmentation& s : log.segmentation) {
      EXPECT_GT(s.dropped_acceleration, 0u) << "the samples next to the force's steps (the moves' corners) dropped";
      EXPECT_GT(s.kept, s.samples * 7 / 10);
    }
    ASSERT_TRUE(fit.fit.solver.usable) << fit.fit.solver.termination;
    EXPECT_NEAR(fit.fit.parameter("moving_mass").value, rig.axis.moving_mass_kg, 0.02 * rig.axis.moving_mass_kg);
    EXPECT_NEAR(fit.fit.parameter("axis_gravity").value, rig.weight_N(), 0.005 * rig.weight_N());
    std::size_t constants = 0;
    for (const ParameterEstimate& p : fit.fit.parameters) {
      EXPECT_NE(p.name, "signed_zero_offset");
      constants += rig.truth(p) && find_friction_constant(p.name) ? 1 : 0;
    }
    EXPECT_EQ(constants, 5u) << "k1, mu_st, v_st, mu_v, f0 (one preload: k2 held; one temperature: beta held)";
    std::size_t grouped = 0;
    for (const ConditionResidual& c : fit.conditions) grouped += c.n;
    EXPECT_EQ(grouped, log.size());
    EXPECT_LT(fit.conditions.size(), log.size() / 100) << "speed bins, not a condition per sample";
  }
}

// A drive whose current carries a constant offset (0.05 A x 80 N/A = 4 N) on the 20° axis: the
// offset has the weight's shape and goes into axis_gravity (4 N above M g sin θ, 3 %), and with
// the mass fitted and the incline stated the fit says so; the same axis without the offset, and
// seeds 1-3 of the test above, raise no such warning.
bool warns_of_the_weight(const FrictionFitResult& fit) {
  return std::any_of(fit.fit.warnings.begin(), fit.fit.warnings.end(),
                     [](const std::string& w) { return w.starts_with("axis_gravity") && w.find("current offset") != std::string::npos; });
}

TEST_F(TrajectoryFriction, AWeightThatTheMassAndInclineDoNotGiveIsReportedWithItsTwoReadings) {
  for (unsigned seed : {1u, 2u}) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    ClosedLoopAxis rig;
    EXPECT_FALSE(warns_of_the_weight(rig.fit(writer(), seed)));
    rig.axis.current_offset_A = 0.05;
    const FrictionFitResult fit = rig.fit(writer(), seed);
    const ParameterEstimate& G = fit.fit.parameter("axis_gravity");
    EXPECT_NEAR(G.value - rig.weight_N(), 0.05 * rig.axis.force_constant_N_A, 0.5);
    EXPECT_TRUE(warns_of_the_weight(fit)) << fmt::format("{}", fmt::join(fit.fit.warnings, "; "));
  }
}

// A sinusoidal log starts and ends at rest (x_ref = A(1 − cos 2πft)): the filter's window is cut
// short at the log's first and last samples, and their v, a and F are biased. Those samples were
// kept (1-2 mm/s, 2.2-2.8 N off the law, on runs of 0.47 N RMSE) and made a clean log's residuals
// "follow velocity_m_s". Within the filter's reach of either end nothing is kept now, and at the
// lowest kept speeds the law misses by no more than elsewhere.
TEST_F(TrajectoryFriction, TheSamplesAtTheLogsEndsWhereTheFilterIsCutShortAreDropped) {
  ClosedLoopAxis rig;
  rig.axis.reference = AxisReference::sinusoid;
  rig.axis.incline_deg = 0;
  rig.axis.duration_s = 20;
  FrictionLog log;
  const FrictionFitResult fit = rig.fit(writer(), 5, &log);
  ASSERT_TRUE(fit.fit.solver.usable) << fit.fit.solver.termination;
  const double window_s = log.segmentation.at(0).filter_window_s;
  double slow_worst = 0, rms = 0;
  for (std::size_t i = 0; i < log.size(); ++i) {
    EXPECT_GT(log.time_s[i], window_s / 2) << "sample " << i << " within the filter's reach of the start";
    EXPECT_LT(log.time_s[i], rig.axis.duration_s - window_s / 2) << "sample " << i << " within reach of the end";
    const double r = log.friction_N[i] - fit.predicted_N[i];
    rms += r * r;
    if (log.velocity_m_s[i] < 0.002) slow_worst = std::max(slow_worst, std::abs(r));
  }
  rms = std::sqrt(rms / static_cast<double>(log.size()));
  EXPECT_LT(slow_worst, 4 * rms) << "the slowest samples' worst miss against the RMSE " << rms;
}

// The intervals' coverage over 30 seeds: for the mass, the weight and each determined constant,
// at least the hits that 95 % intervals reach in 30 replicates with probability 99 % (25), 192
// of the 210 together (the same bound for the pooled count), and intervals not wider than the
// errors need. (Every interval of three seeds at once covers only 0.95^21 = 34 % of the time:
// a test of three seeds would be a test of the seeds chosen.)
TEST_F(TrajectoryFriction, TheClosedLoopRigsIntervalsCoverTheTruthAtTheirRate) {
  ClosedLoopAxis rig;
  constexpr std::size_t kSeeds = 30;
  std::vector<test::Tally> tallies;
  for (unsigned seed = 101; seed < 101 + kSeeds; ++seed) {
    const FrictionFitResult fit = rig.fit(writer(), seed);
    ASSERT_TRUE(fit.fit.solver.usable) << "seed " << seed << ": " << fit.fit.solver.termination;
    std::size_t t = 0;
    for (const ParameterEstimate& p : fit.fit.parameters) {
      const std::optional<double> truth = rig.truth(p);
      if (!truth) continue;
      if (t == tallies.size()) tallies.push_back({p.name, *truth});
      ASSERT_EQ(tallies[t].name, p.name) << "seed " << seed << ": the same parameters determined on every seed";
      tallies[t++].add(p);
    }
  }
  ASSERT_EQ(tallies.size(), 7u);
  std::size_t hits = 0, intervals = 0;
  for (const test::Tally& t : tallies) {
    std::cout << fmt::format("  {:<14} coverage {}/{}; mean SE / RMS error {:.2f}\n", t.name, t.hits, t.n, t.se_ratio());
    EXPECT_GE(t.hits, test::fewest_hits(t.n, 0.01)) << t.name;
    EXPECT_LT(t.se_ratio(), 1.6) << t.name << ": intervals wider than the errors need";
    hits += t.hits, intervals += t.n;
  }
  EXPECT_GE(hits, test::fewest_hits(intervals, 0.01));
}

TEST_F(TrajectoryFriction, AHorizontalAxisFitsTheMassAndNoWeight) {
  Axis axis;
  axis.incline_deg = 0;
  const std::vector<RunSpec> runs{{"a", 1000, 24, 0.05, 0.45}, {"b", 3000, 30, 0.06, 0.35}};
  for (std::size_t r = 0; r < runs.size(); ++r) write_run(runs[r], axis, static_cast<unsigned>(r + 1));
  const FrictionLog log = load_friction_dataset(write_manifest(runs, axis)).log;
  EXPECT_EQ(drive_effects(log), std::vector<std::string>{"moving_mass"});
}

TEST_F(TrajectoryFriction, ATrajectoryThatNeverAcceleratesIsRefusedNamingWhatToDo) {
  const Axis axis;
  const std::vector<RunSpec> runs{{"a", 1000, 24, 0.05, 0.45}};
  write_run(runs[0], axis, 1, false);
  try {
    load_friction_dataset(write_manifest(runs, axis));
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the trajectory never accelerates"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("segmentation = \"plateaus\""), std::string::npos) << e.what();
  }
}

TEST_F(TrajectoryFriction, ThePlateauReaderSaysWhenItDropsMostOfATrajectory) {
  Axis axis;
  axis.incline_deg = 0;
  const std::vector<RunSpec> runs{{"a", 1000, 24, 0.05, 0.45}};
  write_run(runs[0], axis, 1);
  write("plateaus.toml", "[[run]]\nid = \"a\"\nfile = \"a.csv\"\nguide = \"SRN 35C\"\nload_N = 1000\npreload_um = 4\n"
                         "temperature_C = 24\n");
  try {
    const FrictionLog log = load_friction_dataset(dir_ / "plateaus.toml").log;
    bool warned = false;
    for (const auto& report : log.reports)
      for (const auto& w : report.warnings) warned |= w.find("--segmentation trajectory") != std::string::npos;
    EXPECT_TRUE(warned) << "the plateau reader keeps little of a trajectory and says what would keep it";
  } catch (const InputError& e) {
    // No plateau at all in a pure sweep: the refusal is the plateau reader's, and says how to read it.
    EXPECT_NE(std::string(e.what()).find("--segmentation trajectory"), std::string::npos) << e.what();
  }
}


// ---- conditions nobody logged (FrictionLawConditions) ---------------------------------------

// The combinations a log of one setup determines, from the paper's constants at that setup.
struct TrueCombinations {
  double coulomb_N, stribeck_N, stribeck_speed_m_s, viscous_N_s_m;
};
TrueCombinations true_combinations(double load_N, double preload_um, double block_length_mm, double temperature_C) {
  const FrictionConstants<double> k = paper_friction_constants();
  const double nu = k.nu_ref_mm2_s * std::exp(-k.beta_per_K * (temperature_C - k.T_ref_C));
  return {(k.k1 - k.k2 * preload_um) * load_N * 1e-3 + block_length_mm * k.f0, k.mu_st * preload_um * block_length_mm / nu,
          k.v_st_m_s, block_length_mm * k.mu_v * preload_um * nu};
}

void expect_covers(const FrictionFitResult& fit, const TrueCombinations& truth) {
  ASSERT_EQ(fit.combinations.size(), 4u);
  const double values[] = {truth.coulomb_N, truth.stribeck_N, truth.stribeck_speed_m_s, truth.viscous_N_s_m};
  for (std::size_t c = 0; c < 4; ++c) {
    const ParameterEstimate& e = fit.combinations[c].estimate;
    EXPECT_LE(quoted_low(e), values[c]) << e.name << " " << e.value;
    EXPECT_GE(quoted_high(e), values[c]) << e.name << " " << e.value;
  }
}

// A drive's log with nothing but time, position and force (no manifest, no run column): the
// mass, the weight and the four combinations are recovered, and no output states a load,
// preload, block length or temperature it was not given.
TEST_F(TrajectoryFriction, ALogOfTimePositionAndForceFitsTheCombinations) {
  const Axis axis;
  const RunSpec run{"drive", 2000, 26, 0.05, 0.45};
  write_run(run, axis, 7);
  RawFrictionOptions raw;
  raw.segmentation = RawSegmentation::trajectory;
  raw.axis_incline_deg = axis.incline_deg;
  const FrictionLog log = load_friction_log(dir_ / "drive.csv", raw);
  EXPECT_TRUE(log.law.combination());
  EXPECT_FALSE(log.law.temperature);
  EXPECT_EQ(log.run_names, std::vector<std::string>{"drive"});
  EXPECT_EQ(log.law.stated(), "no conditions given");
  FrictionFitOptions o;
  o.fit.starts = 2;
  const FrictionFitResult fit = fit_friction(log, o);
  ASSERT_TRUE(fit.fit.solver.usable) << fit.fit.solver.termination;
  EXPECT_NEAR(fit.fit.parameter("moving_mass").value, axis.mass_kg, 0.01 * axis.mass_kg);
  EXPECT_NEAR(fit.fit.parameter("axis_gravity").value, axis.weight_N(), 0.005 * axis.weight_N());
  expect_covers(fit, true_combinations(run.load_N, 4, 120.2, run.temperature_C));
  const std::string summary = friction_fit_summary(fit);
  for (const char* invented : {"load 1000", "preload 1 ", "block length 1 ", "\n  beta_per_K ", "\n  k1 ", "\n  mu_st "})
    EXPECT_EQ(summary.find(invented), std::string::npos) << invented << " in\n" << summary;
  EXPECT_NE(summary.find("not given: load_N, preload_um, block_length_mm, temperature_C"), std::string::npos) << summary;
  const std::string samples = friction_fit_samples_csv(fit, log);
  const std::string header = samples.substr(0, samples.find('\n'));
  for (const char* column : {"load_N", "preload_um", "block_length_mm", "temperature_C"})
    EXPECT_EQ(header.find(column), std::string::npos) << header;
  EXPECT_EQ(friction_fit_conditions_csv(fit).find("load_N"), std::string::npos);
}

// A tidy speed-and-force log with a logged temperature that varies: β is fitted with the
// combinations, which are quoted at the mean logged temperature.
TEST_F(TrajectoryFriction, ASpeedAndForceLogWithATemperatureFitsBetaToo) {
  const FrictionConstants<double> k = paper_friction_constants();
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0, 0.05);
  std::string csv = "velocity_m_s,temperature_C,friction_N\n";
  double sum_T = 0;
  int n = 0;
  for (double T : {22.0, 27.0, 32.0, 37.0})
    for (double v : {0.002, 0.005, 0.01, 0.02, 0.04, 0.066, 0.083, 0.11})
      for (int rep = 0; rep < 20; ++rep) {
        const FrictionConditions<double> c{.load_N = 1500, .preload_um = 4, .block_length_mm = 97, .velocity_m_s = v,
                                           .temperature_C = T};
        csv += fmt::format("{},{},{:.4f}\n", v, T, friction_force_N(k, c) + noise(rng));
        sum_T += T, ++n;
      }
  write("bench.csv", csv);
  const FrictionLog log = load_friction_log(dir_ / "bench.csv");
  EXPECT_TRUE(log.law.combination());
  EXPECT_TRUE(log.law.temperature);
  const FrictionFitResult fit = fit_friction(log, {});
  ASSERT_TRUE(fit.fit.solver.usable);
  EXPECT_DOUBLE_EQ(fit.law_temperature_C, std::round(10 * sum_T / n) / 10);
  const ParameterEstimate& beta = fit.fit.parameter("beta_per_K");
  EXPECT_TRUE(beta.free);
  EXPECT_LE(quoted_low(beta), k.beta_per_K);
  EXPECT_GE(quoted_high(beta), k.beta_per_K);
  expect_covers(fit, true_combinations(1500, 4, 97, fit.law_temperature_C));
}

// A preload by its catalog class is the class's µm; a preload known only as a force leaves the
// law in combinations and is stated as given; the one setup's load must stay one.
TEST_F(TrajectoryFriction, APreloadByClassOrForceAndOneSetupPerCombinationLaw) {
  write("r.csv", "velocity_m_s,friction_N\n0.01,20\n0.02,21\n0.05,22\n");
  const auto manifest = [&](const std::string& run_keys) {
    return write("f.toml", "file = \"r.csv\"\n[[run]]\nid = \"r\"\nguide = \"SRN 35C\"\nload_N = 1000\ntemperature_C = 24\n" +
                               run_keys);
  };
  EXPECT_EQ(load_friction_dataset(manifest("preload_class = \"C0\"\n")).log.preload_um.front(), 4.0);
  EXPECT_EQ(load_friction_dataset(manifest("preload_class = \"C1\"\n")).log.preload_um.front(), 2.5);
  EXPECT_FALSE(load_friction_dataset(manifest("preload_class = \"C1\"\n")).log.law.combination());
  const FrictionLog spring = load_friction_dataset(manifest("preload_N = 0.8\n")).log;
  EXPECT_TRUE(spring.law.combination());
  EXPECT_EQ(spring.law.stated(), "load 1000 N, preload 0.8 N, block length 120.2 mm");
  for (const auto& [keys, expected] : std::vector<std::pair<std::string, std::string>>{
           {"preload_class = \"C9\"\n", "unknown class 'C9'"},
           {"preload_class = \"C0\"\npreload_um = 4\n", "both give run 'r''s preload"},
           {"preload_N = -1\n", "expected a force >= 0"}}) {
    try {
      load_friction_dataset(manifest(keys));
      ADD_FAILURE() << keys << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
  write("s.csv", "velocity_m_s,friction_N\n0.01,20\n0.02,21\n");
  write("springs.toml", "[[run]]\nid = \"r\"\nfile = \"r.csv\"\npreload_N = 0.8\n[[run]]\nid = \"s\"\nfile = \"s.csv\"\n"
                        "preload_N = 1.2\n");
  try {
    load_friction_dataset(dir_ / "springs.toml");
    ADD_FAILURE() << "two spring preloads accepted as one setup";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("preload_N = 1.2 differs from the log's first value, 0.8"), std::string::npos)
        << e.what();
  }
  write("loads.csv", "run,velocity_m_s,load_N,friction_N\nr,0.01,1000,20\nr,0.02,2000,21\n");
  try {
    load_friction_log(dir_ / "loads.csv");
    ADD_FAILURE() << "two loads without a preload accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(std::string(e.what()).find("load_N = 2000 differs from the log's first value, 1000"), std::string::npos)
        << e.what();
  }
  write("with_load.csv", "run,velocity_m_s,load_N,preload_um,block_length_mm,temperature_C,friction_N\nr,0.01,1000,4,97,24,20\n");
  write("without.csv", "run,velocity_m_s,friction_N\ns,0.01,20\n");
  try {
    load_friction_logs({dir_ / "with_load.csv", dir_ / "without.csv"});
    ADD_FAILURE() << "files that disagree on the conditions accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("give the same conditions for every file of a log"), std::string::npos) << e.what();
  }
}

// A run at one load and block length: k1 P/1000 and f0 Lb are one offset within it, so no run's
// own fit gives k1. The spread across runs says so with the count, in the summary, the JSON and
// the report alike, never "mean nan sigma nan".
TEST_F(TrajectoryFriction, ASpreadNoRunDeterminesSaysWhyNotNan) {
  ClosedLoopAxis rig;
  FrictionLog log;
  rig.fit([&](const std::string& f, const std::string& t) { return write(f, t); }, 3, &log);
  FrictionFitOptions o;
  o.fit.starts = 1;
  const FrictionFitResult r = fit_friction(log, o);
  ASSERT_FALSE(r.spread.empty());
  const RunSpread* k1 = nullptr;
  for (const RunSpread& s : r.spread) {
    SCOPED_TRACE(s.parameter);
    const auto given = static_cast<std::size_t>(std::count_if(s.per_run.begin(), s.per_run.end(), [](double v) { return std::isfinite(v); }));
    EXPECT_EQ(s.undetermined.empty(), given == s.per_run.size()) << s.undetermined;
    if (s.parameter == "k1") {
      k1 = &s;
      EXPECT_EQ(given, 0u);
      EXPECT_NE(s.undetermined.find("2 of 2 runs: one load and block length in the run"), std::string::npos) << s.undetermined;
    }
  }
  ASSERT_NE(k1, nullptr);
  const std::string summary = friction_fit_summary(r);
  const std::string spread = summary.substr(summary.find("spread across"));
  EXPECT_EQ(summary.find("nan"), std::string::npos) << summary;  // k2 held: its SE n/a, the reason beside it
  // k1's row: its name, its unit ("-"), and why there is no spread.
  const std::size_t why = spread.find("no spread: not determined run by run (2 of 2 runs");
  ASSERT_NE(why, std::string::npos) << summary;
  const std::string row = spread.substr(spread.rfind('\n', why) + 1, why - spread.rfind('\n', why) - 1);
  EXPECT_TRUE(row.starts_with("  k1 ") && row.find(" - ") != std::string::npos) << row;
  const auto j = nlohmann::json::parse(friction_fit_json(r, o, {}));
  bool in_json = false;
  for (const auto& s : j.at("spread_across_runs"))
    if (s.at("parameter") == "k1") in_json = s.at("undetermined").get<std::string>() == k1->undetermined;
  EXPECT_TRUE(in_json) << j.at("spread_across_runs").dump();
}

// A trajectory's rows are evaluated on several threads (batched_autodiff.hpp): the fit with its
// defaults (starts, random run offsets, per-run fits, covariance, held-out runs) gives the same
// bits on one thread as on two.
TEST_F(TrajectoryFriction, AFitGivesTheSameBitsOnOneThreadOrTwo) {
  // scripts/sanitize.sh builds with clang, which ignores OpenMP: there one thread is two.
  if (std::getenv("LMCAL_TEST_SERIAL_BUILD") != nullptr) GTEST_SKIP() << "a serial build (LMCAL_TEST_SERIAL_BUILD)";
  ClosedLoopAxis rig;
  rig.setup.seed = 5;
  const AxisRigOutput made = generate_axis_logs(rig.setup, rig.axis, {});
  for (const auto& [file, text] : made.run_files) write(file, text);
  const FrictionLog log = load_friction_dataset(write("friction.toml", made.manifest_toml)).log;
  const auto fit_on = [&](int threads) {
    const int before = detail::limit_slice_threads(threads);
    EXPECT_EQ(detail::slice_threads(log.size(), 4096), std::min<std::size_t>(threads, log.size() / 4096))
        << "the rows are split over the threads asked for";
    FrictionFitResult result = fit_friction(log, {});
    detail::limit_slice_threads(before);
    return result;
  };
  ASSERT_GT(log.size(), 2u * 4096) << "enough rows for two threads";
  const FrictionFitResult one = fit_on(1), two = fit_on(2);
  const auto bits = [](const std::vector<double>& v) {  // NaN (a held parameter's SE) equals NaN
    std::vector<std::uint64_t> out;
    for (double x : v) out.push_back(std::bit_cast<std::uint64_t>(x));
    return out;
  };
  ASSERT_EQ(one.fit.parameters.size(), two.fit.parameters.size());
  for (std::size_t j = 0; j < one.fit.parameters.size(); ++j) {
    const ParameterEstimate &a = one.fit.parameters[j], &b = two.fit.parameters[j];
    SCOPED_TRACE(a.name);
    EXPECT_EQ(bits({a.value, a.se, a.ci_low, a.ci_high}), bits({b.value, b.se, b.ci_low, b.ci_high}));
  }
  EXPECT_EQ(one.fit.solver.iterations, two.fit.solver.iterations);
  EXPECT_EQ(bits({one.rmse_N, one.cv_rmse_N, one.run_offset_ratio}), bits({two.rmse_N, two.cv_rmse_N, two.run_offset_ratio}));
  EXPECT_EQ(bits(one.predicted_N), bits(two.predicted_N));
  ASSERT_EQ(one.spread.size(), two.spread.size());
  for (std::size_t j = 0; j < one.spread.size(); ++j) EXPECT_EQ(bits(one.spread[j].per_run), bits(two.spread[j].per_run));
}

}  // namespace
}  // namespace lmcal
