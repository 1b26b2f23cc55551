// Raw load-cell time series (segmentation into plateaus, sign conventions, inertia, duplicate
// times) and friction manifests (conditions as keys instead of columns), end to end from the
// virtual rig's raw logs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>

#include "io/raw_friction.hpp"
#include "lmcal/error.hpp"
#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/io/limits.hpp"
#include "lmcal/models/friction_effects.hpp"
#include "lmcal/rig/virtual_rig.hpp"
#include "support/refusal.hpp"
#include "support/temp_folder.hpp"

namespace lmcal {
namespace {

class RawFriction : public test::TempFolderTest {
 protected:
  // Writes a raw rig's data set into the test folder; returns the manifest's path.
  std::filesystem::path write_set(const RawFrictionRigOutput& made) const {
    for (const auto& [file, text] : made.run_files) write(file, text);
    return write("friction.toml", made.manifest_toml);
  }
};

// One guide, one setup, a few speeds: a run a rig logs in a few minutes.
FrictionRigConfig one_setup(std::vector<double> speeds = {0.01, 0.05, 0.11}) {
  FrictionRigConfig c;
  c.guides = {"SRN 35C"};
  c.preload_um = {2.5};
  c.load_N = {2000};
  c.temperature_C = {26};
  c.velocity_m_s = std::move(speeds);
  c.runs = 1;
  c.noise_N = 0.05;
  c.run_offset_N = 0;
  c.seed = 5;
  return c;
}

RawFrictionRigConfig quiet_rig() {
  RawFrictionRigConfig r;
  r.sample_rate_Hz = 200;
  r.cycles = 2;
  r.drift_N_per_h = 0;
  return r;
}

// Every kept plateau lies inside one of the generator's cruises, at its speed, and every
// cruise long enough to outlast the filter and the settling time gives exactly one plateau,
// starting within the settling time plus one filter window of the cruise's start and ending
// within one window of its end.
TEST_F(RawFriction, PlateausMatchTheRigsConstantVelocitySegments) {
  const RawFrictionRigConfig rig = quiet_rig();
  const RawFrictionRigOutput made = generate_raw_friction_logs(one_setup(), rig, {});
  const FrictionDataSet set = load_friction_dataset(write_set(made));
  ASSERT_EQ(set.log.segmentation.size(), 1u);
  const RunSegmentation& seg = set.log.segmentation[0];
  const std::vector<CruiseSegment>& cruises = made.cruises[0];
  const RawFrictionOptions& o = set.raw;
  const double dt = 1 / rig.sample_rate_Hz;
  const double window_s = static_cast<double>(o.velocity_window) * dt;
  ASSERT_EQ(cruises.size(), 3u * 2u * 2u);  // speeds × cycles × directions
  ASSERT_EQ(seg.plateaus.size(), cruises.size());
  for (std::size_t i = 0; i < cruises.size(); ++i) {
    const CruiseSegment& c = cruises[i];
    const Plateau& p = seg.plateaus[i];
    EXPECT_GE(p.start_s, c.start_s) << i;
    EXPECT_LE(p.end_s, c.end_s) << i;
    EXPECT_LE(p.start_s - c.start_s, o.settling_s + window_s) << i;
    EXPECT_LE(c.end_s - p.end_s, window_s) << i;
    EXPECT_NEAR(p.velocity_m_s, c.velocity_m_s, 1e-3 * std::abs(c.velocity_m_s)) << i;  // encoder steps of 1 µm
    EXPECT_EQ(p.samples, static_cast<std::size_t>(std::llround((p.end_s - p.start_s) / dt)) + 1) << i;
  }
  EXPECT_EQ(seg.kept + seg.dropped_acceleration + seg.dropped_settling + seg.dropped_stationary + seg.dropped_short,
            seg.samples);
  EXPECT_GT(seg.dropped_acceleration, 0u);
  EXPECT_GT(seg.dropped_stationary, 0u);  // the dwells
  EXPECT_EQ(set.log.size(), seg.kept);
  EXPECT_TRUE(set.log.reports.at(0).warnings.empty());
  // Each kept sample names its raw row: the line of the file that holds its time.
  std::ifstream file(set.log.reports.at(0).file);
  std::vector<std::string> lines(1);  // lines[1] is line 1
  for (std::string line; std::getline(file, line);) lines.push_back(line);
  ASSERT_EQ(set.log.line.size(), set.log.size());
  for (std::size_t i = 0; i < set.log.size(); i += 97) {
    ASSERT_LT(set.log.line[i], lines.size());
    EXPECT_DOUBLE_EQ(std::stod(lines[set.log.line[i]]), set.log.time_s[i]) << "sample " << i << ", line " << set.log.line[i];
  }
}

// A raw run's CSV text with its motion column (the second) rewritten: `cell(k, value)` gives
// the k-th data row's new cell.
template <typename Cell>
std::string with_motion(const std::string& csv, Cell cell) {
  std::string out;
  std::istringstream in(csv);
  int k = 0;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#' && line[0] != 't') {  // a data row (not a comment or the header)
      const auto a = line.find(','), b = line.find(',', a + 1);
      line = line.substr(0, a + 1) + cell(k++, std::stod(line.substr(a + 1, b - a - 1))) + line.substr(b);
    }
    out += line + "\n";
  }
  return out;
}

// An encoder that jitters by a count (seen at rest) is no position going back: the same
// plateaus as without the jitter.
TEST_F(RawFriction, EncoderJitterOfACountIsNotAStepBack) {
  RawFrictionRigConfig rig = quiet_rig();
  const RawFrictionRigOutput made = generate_raw_friction_logs(one_setup(), rig, {});
  // -1, 0, +1 µm in turn
  const std::string jittered = with_motion(made.run_files.at(0).second, [](int k, double x_mm) {
    return fmt::format("{:.3f}", x_mm + 0.001 * ((k % 3) - 1));
  });
  const FrictionDataSet clean = load_friction_dataset(write_set(made));
  write(made.run_files.at(0).first, jittered);
  const FrictionDataSet noisy = load_friction_dataset(dir_ / "friction.toml");
  ASSERT_EQ(noisy.log.segmentation.at(0).plateaus.size(), clean.log.segmentation.at(0).plateaus.size());
  EXPECT_NEAR(static_cast<double>(noisy.log.size()), static_cast<double>(clean.log.size()), 0.02 * clean.log.size());
}

// A drive's velocity feedback is noisy (±1 % here): filtered before the classification, it
// gives the generator's plateaus, at the plateau speed to 0.1 %.
TEST_F(RawFriction, ANoisyVelocityColumnGivesTheSamePlateaus) {
  RawFrictionRigConfig rig = quiet_rig();
  rig.log_velocity = true;
  const RawFrictionRigOutput made = generate_raw_friction_logs(one_setup(), rig, {});
  // up to ±1 %
  const std::string noisy_text = with_motion(made.run_files.at(0).second, [](int k, double v) {
    return fmt::format("{:.7g}", v * (1 + 0.005 * ((k % 5) - 2)));
  });
  write(made.run_files.at(0).first, noisy_text);
  write("friction.toml", made.manifest_toml);
  const FrictionDataSet noisy = load_friction_dataset(dir_ / "friction.toml");
  const std::vector<Plateau>& plateaus = noisy.log.segmentation.at(0).plateaus;
  ASSERT_EQ(plateaus.size(), made.cruises.at(0).size());
  for (std::size_t i = 0; i < plateaus.size(); ++i)
    EXPECT_NEAR(plateaus[i].velocity_m_s, made.cruises[0][i].velocity_m_s, 1e-3 * std::abs(made.cruises[0][i].velocity_m_s));
}

// The kept samples' friction, averaged per plateau, is the law at the plateau's speed in both
// directions, whatever the sign convention of the force, once the loader is told it.
TEST_F(RawFriction, FrictionIsTheLawOnEveryPlateauUnderEachSignConvention) {
  for (ForceSign sign : {ForceSign::follows_motion, ForceSign::opposes_motion, ForceSign::magnitude}) {
    RawFrictionRigConfig rig = quiet_rig();
    rig.force_sign = sign;
    const RawFrictionRigOutput made = generate_raw_friction_logs(one_setup(), rig, {});
    const FrictionDataSet set = load_friction_dataset(write_set(made));  // the manifest's [raw] names the sign
    EXPECT_EQ(set.raw.force_sign, sign);
    const FrictionLog& log = set.log;
    // (set speed, direction) -> (sum, n); a plateau's measured speed is within 0.1 % of it.
    std::map<std::pair<double, int>, std::pair<double, int>> per_plateau;
    for (std::size_t i = 0; i < log.size(); ++i) {
      double set_speed = 0;
      for (double s : {0.01, 0.05, 0.11})
        if (std::abs(log.velocity_m_s[i] - s) < 1e-3 * s) set_speed = s;
      auto& [sum, n] = per_plateau[{set_speed, log.direction[i]}];
      sum += log.friction_N[i];
      ++n;
    }
    EXPECT_EQ(per_plateau.size(), 3u * 2u);
    for (const auto& [key, value] : per_plateau) {
      FrictionConditions<double> c = log.conditions(0);
      c.velocity_m_s = key.first;
      c.direction = key.second;
      const double law = friction_force_N(paper_friction_constants(), c);
      EXPECT_NEAR(value.first / value.second, law, 4 * 0.05 / std::sqrt(value.second) + 1e-3)
          << to_string(sign) << " at " << key.first << " m/s, direction " << key.second;
    }
    EXPECT_TRUE(log.reports.at(0).warnings.empty()) << to_string(sign);
  }
}

TEST_F(RawFriction, AWrongSignConventionIsAWarning) {
  RawFrictionRigConfig rig = quiet_rig();
  rig.force_sign = ForceSign::opposes_motion;
  RawFrictionRigOutput made = generate_raw_friction_logs(one_setup(), rig, {});
  const auto manifest = write_set(made);
  const auto warnings = [&](ForceSign read_as) {
    RawFrictionOptions o;
    o.force_sign = read_as;
    return load_friction_dataset(manifest, nullptr, o, {"force_sign"}).log.reports.at(0).warnings;
  };
  const auto reversed = warnings(ForceSign::follows_motion);
  ASSERT_EQ(reversed.size(), 1u);
  EXPECT_NE(reversed[0].find("looks reversed; give --force-sign opposes-motion"), std::string::npos) << reversed[0];

  rig.force_sign = ForceSign::magnitude;
  made = generate_raw_friction_logs(one_setup(), rig, {});
  write_set(made);
  const auto magnitude = warnings(ForceSign::follows_motion);
  ASSERT_EQ(magnitude.size(), 1u);
  EXPECT_NE(magnitude[0].find("looks like a magnitude"), std::string::npos) << magnitude[0];
  EXPECT_TRUE(warnings(ForceSign::magnitude).empty());
}

// A slow steady acceleration below the threshold stays in the plateau; the inertia m·a is
// taken off the force exactly.
TEST(RawSegmentation, InertiaIsTakenOffTheForce) {
  raw::RunSamples run;
  const double a = 0.01, m = 100, F = 20;  // m·a = 1 N
  for (int k = 0; k < 200; ++k) {
    const double t = 0.01 * k, v = 0.05 + a * t;
    run.time_s.push_back(t);
    run.motion.push_back(v);
    run.force_N.push_back(F + m * a);
  }
  RawFrictionOptions o;
  o.moving_mass_kg = m;
  o.settling_s = 0;
  const raw::Segmented s = raw::segment(run, raw::Motion::velocity_m_s, o);
  ASSERT_EQ(s.plateaus.size(), 1u);
  for (std::size_t i = 0; i < run.time_s.size(); ++i) EXPECT_NEAR(raw::friction_N(run, s, o, i), F, 1e-9) << i;
  o.moving_mass_kg = 0;
  EXPECT_NEAR(raw::friction_N(run, s, o, 100), F + m * a, 1e-9);
}

TEST(RawSegmentation, LocalSlopeIsExactOnAQuadratic) {
  std::vector<double> t, x;
  for (int k = 0; k < 50; ++k) {
    t.push_back(1e6 + 0.1 * k);  // epoch-like times: centred sums keep the digits
    x.push_back(3 + 2 * (0.1 * k));
  }
  const auto v = raw::local_slope(t, x, 7);
  for (double vi : v) EXPECT_NEAR(vi, 2.0, 1e-6);
}

TEST(RawSegmentation, TheVelocityWindowIsBoundedBeforeTheFilterRuns) {
  // Issue 36: velocity_window = 299999 filtered for 85 s (samples × window).
  RawFrictionOptions o;
  o.velocity_window = 299'999;
  EXPECT_THROW(o.validate(), InvalidParameter);
  o.velocity_window = io::kMaxVelocityWindow;
  EXPECT_NO_THROW(o.validate());
  // 2.1·10^6 samples × 10001 is beyond kMaxFilterWork: refused at once, the filter not run.
  raw::RunSamples run;
  run.time_s.resize(2'100'000);
  std::iota(run.time_s.begin(), run.time_s.end(), 0.0);
  run.motion = run.force_N = run.time_s;
  try {
    raw::segment(run, raw::Motion::position_m, o);
    FAIL() << "a filter of 2.1e10 operations was run";
  } catch (const raw::SampleError& e) {
    EXPECT_EQ(e.sample, 0u);
    EXPECT_NE(std::string(e.what()).find("velocity_window = 10001"), std::string::npos) << e.what();
  }
}

std::string raw_csv(const std::vector<std::string>& rows) {
  std::string text = "run,time_s,position_mm,force_N,load_N,preload_um,block_length_mm,temperature_C\n";
  for (const auto& r : rows) text += r + "\n";
  return text;
}

// 30 samples of one plateau at 10 mm/s, from line 2 on.
std::vector<std::string> plateau_rows(double t0 = 0, double x0_mm = 0) {
  std::vector<std::string> rows;
  for (int k = 0; k < 30; ++k)
    rows.push_back(fmt::format("a,{},{},20,1000,2.5,120.2,24", t0 + 0.1 * k, x0_mm + 1.0 * k));
  return rows;
}

// Options that keep every sample of a plateau of at least `min_samples`.
RawFrictionOptions keep_all(std::size_t min_samples) {
  RawFrictionOptions o;
  o.settling_s = 0;
  o.min_plateau_samples = min_samples;
  return o;
}

TEST_F(RawFriction, RepeatedTimesAreAveragedByDefaultOrRefusedAsAsked) {
  std::vector<std::string> rows = plateau_rows();
  rows.insert(rows.begin() + 10, "a,0.9,9,22,1000,2.5,120.2,24");  // line 12 repeats line 11's time
  const auto file = write("dup.csv", raw_csv(rows));
  RawFrictionOptions o = keep_all(10);
  {
    RawFrictionOptions refuse = o;
    refuse.duplicate_times = DuplicateTimes::refuse;
    const InputError e = test::refusal([&] { load_friction_log(file, refuse); });
    EXPECT_EQ(e.line(), 12);
    EXPECT_TRUE(test::says(e, "duplicate_times = refuse"));
  }
  ASSERT_EQ(o.duplicate_times, DuplicateTimes::average);  // the default
  const FrictionLog log = load_friction_log(file, o);
  ASSERT_EQ(log.segmentation.size(), 1u);
  EXPECT_EQ(log.segmentation[0].averaged_duplicates, 1u);
  EXPECT_EQ(log.segmentation[0].samples, 30u);
  EXPECT_EQ(log.reports[0].skipped.at("merged into a sample at the same time"), 1u);
  const auto at = std::find(log.time_s.begin(), log.time_s.end(), 0.9) - log.time_s.begin();
  EXPECT_DOUBLE_EQ(log.friction_N[static_cast<std::size_t>(at)], 21.0);  // (20 + 22) / 2
}

TEST_F(RawFriction, APositionThatGoesBackWithinAPlateauIsRefusedAtItsCell) {
  std::vector<std::string> rows = plateau_rows();
  rows[20] = "a,2,18.5,20,1000,2.5,120.2,24";  // line 22: behind line 21's 19 mm
  const auto file = write("back.csv", raw_csv(rows));
  const InputError e = test::refusal([&] { load_friction_log(file, keep_all(5)); });
  EXPECT_EQ(e.line(), 22);
  EXPECT_EQ(e.column(), 5);  // the position cell
  EXPECT_TRUE(test::says(e, "monotone between reversals"));
}

// Positions that move 100 mm a millisecond: a plateau at 100 m/s, beyond a rig's speeds (the speed
// column's range), refused at its first kept sample rather than fitted.
TEST_F(RawFriction, APlateauFasterThanARigRunsIsRefusedAtItsFirstSample) {
  std::vector<std::string> rows;
  for (int k = 0; k < 30; ++k) rows.push_back(fmt::format("a,{},{},20,1000,2.5,120.2,24", 0.001 * k, 100 * k));
  const auto file = write("fast.csv", raw_csv(rows));
  const InputError e = test::refusal([&] { load_friction_log(file, keep_all(10)); });
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.column(), 5);  // the position cell
  EXPECT_TRUE(test::says(e, "run 'a': the plateau's velocity_m_s = 100 is beyond the range of a rig's values (-20 to 20 m/s)"))
      << e.what();
}

TEST_F(RawFriction, ARunWithNoLongEnoughPlateauIsRefused) {
  const auto file = write("short.csv", raw_csv(plateau_rows()));
  RawFrictionOptions o;
  o.min_plateau_samples = 50;
  const InputError e = test::refusal([&] { load_friction_log(file, o); });
  EXPECT_EQ(e.line(), 2);
  EXPECT_TRUE(test::says(e, "too few samples per plateau"));
}

TEST_F(RawFriction, TheRigsRawRunsFitToTheTrueConstants) {
  FrictionRigConfig c = one_setup({0.002, 0.005, 0.01, 0.03, 0.066, 0.11});
  c.guides = {"SRG 25C", "SRN 35C"};
  c.preload_um = {1.5, 2.5, 4.0};
  c.load_N = {1000, 3000};
  c.temperature_C = {22, 40};
  c.noise_N = 0.15;
  RawFrictionRigConfig rig = quiet_rig();
  rig.sample_rate_Hz = 20;
  rig.stroke_m = 0.05;
  rig.cycles = 1;
  const RawFrictionRigOutput made = generate_raw_friction_logs(c, rig, {});
  RawFrictionOptions o;
  o.settling_s = 0.2;
  o.velocity_window = 5;
  o.min_plateau_samples = 5;
  const FrictionDataSet set = load_friction_dataset(write_set(made), nullptr, o, {"settling_s", "velocity_window", "min_plateau_samples"});
  EXPECT_EQ(set.log.run_names.size(), 24u);
  const FrictionFitResult fit = fit_friction(set.log, {});
  ASSERT_TRUE(fit.fit.solver.usable);
  const auto k = paper_friction_constants();
  const double truth[] = {k.k1, k.k2, k.mu_st, k.v_st_m_s, k.mu_v, k.beta_per_K, k.f0};
  for (std::size_t j = 0; j < 7; ++j) {
    const ParameterEstimate& p = fit.fit.parameters[j];
    EXPECT_LE(std::abs(p.value - truth[j]), 4 * p.se) << p.name << " = " << p.value << " ± " << p.se;
  }
  EXPECT_NEAR(fit.rmse_N, 0.15, 0.02);
}

// ---- Friction manifests ---------------------------------------------------------------------

const char* kTidyHeader = "run,time_s,velocity_m_s,load_N,preload_um,block_length_mm,temperature_C,friction_N,direction\n";

// A few setups, one a run, several speeds each: enough for every constant of the law.
FrictionLog few_setups_log() {
  FrictionRigConfig c = one_setup({0.002, 0.005, 0.01, 0.02, 0.05, 0.11});
  c.load_N = {1000, 3000};
  c.temperature_C = {22, 40};
  c.preload_um = {1.5, 4.0};
  c.one_setup_per_run = true;
  c.runs = 2;
  c.temperature_noise_K = 0;  // a run's temperature is one value, as a key gives it
  return generate_friction_log(c, {}).log;
}

TEST_F(RawFriction, ConditionsAsKeysGiveTheSameLogAndFitAsColumns) {
  const FrictionLog columns = few_setups_log();
  const auto tidy = write("columns.csv", friction_log_csv(columns));

  // The same samples, with the conditions moved into the manifest.
  std::string lean = "run,time_s,velocity_m_s,friction_N,direction\n", manifest = "name = \"lean\"\nfile = \"lean.csv\"\n";
  std::vector<bool> described(columns.run_names.size(), false);
  for (std::size_t i = 0; i < columns.size(); ++i) {
    const std::uint32_t r = columns.run[i];
    lean += fmt::format("{},{},{},{},{}\n", columns.run_names[r], columns.time_s[i], columns.velocity_m_s[i],
                        columns.friction_N[i], columns.direction[i]);
    if (described[r]) continue;
    described[r] = true;
    manifest += fmt::format(
        "[[run]]\nid = \"{}\"\nguide = \"{}\"\nload_kN = {}\npreload_um = {}\ntemperature_C = {}\n"
        "viscosity40_mm2_s = {}\n",
        columns.run_names[r], columns.guide_names[columns.guide[i]], columns.load_N[i] / 1000, columns.preload_um[i],
        columns.temperature_C[i], columns.viscosity40_mm2_s[i]);
  }
  write("lean.csv", lean);
  const FrictionDataSet set = load_friction_dataset(write("lean.toml", manifest));
  const FrictionLog& keys = set.log;
  ASSERT_EQ(keys.size(), columns.size());
  EXPECT_EQ(keys.run_names, columns.run_names);
  EXPECT_EQ(keys.load_N, columns.load_N);
  EXPECT_EQ(keys.preload_um, columns.preload_um);
  EXPECT_EQ(keys.block_length_mm, columns.block_length_mm);  // from the catalog, by the guide
  EXPECT_EQ(keys.temperature_C, columns.temperature_C);
  EXPECT_EQ(keys.friction_N, columns.friction_N);
  const FrictionFitResult a = fit_friction(load_friction_log(tidy), {});
  const FrictionFitResult b = fit_friction(keys, {});
  for (std::size_t j = 0; j < 7; ++j) EXPECT_EQ(a.fit.parameters[j].value, b.fit.parameters[j].value) << j;
}

TEST_F(RawFriction, AManifestRefusesAConditionGivenTwiceOrNotAtAll) {
  write("both.csv", std::string(kTidyHeader) + "r1,0,0.01,1000,2.5,120.2,24,20,1\n");
  const auto both = write("both.toml", "file = \"both.csv\"\n[[run]]\nid = \"r1\"\nload_N = 1000\n");
  {
    const InputError e = test::refusal([&] { load_friction_dataset(both); });
    EXPECT_EQ(e.line(), 1);
    EXPECT_TRUE(test::says(e, "'load_N' is both a column of this file and a key of run 'r1'"));
  }
  write("lean.csv", "run,velocity_m_s,friction_N\nr1,0.01,20\nr2,0.01,21\n");
  const auto partial = write("partial.toml",
                             "file = \"lean.csv\"\n[[run]]\nid = \"r1\"\nguide = \"SRN 35C\"\nload_N = 1000\n"
                             "preload_um = 2.5\ntemperature_C = 24\n");
  {
    const InputError e = test::refusal([&] { load_friction_dataset(partial); });
    EXPECT_EQ(e.line(), 3);  // r2's row: the manifest does not list it
    EXPECT_TRUE(test::says(e, "run 'r2' has no load_N"));
  }
  write("one.csv", "run,velocity_m_s,friction_N\nr1,0.01,20\n");
  const auto listed = write("listed.toml",
                            "file = \"one.csv\"\n[[run]]\nid = \"r1\"\nguide = \"SRN 35C\"\nload_N = 1000\n"
                            "preload_um = 2.5\ntemperature_C = 24\n[[run]]\nid = \"R2\"\nguide = \"SRN 35C\"\n"
                            "load_N = 1000\npreload_um = 2.5\ntemperature_C = 24\n");
  {
    const InputError e = test::refusal([&] { load_friction_dataset(listed); });
    EXPECT_EQ(e.line(), 8);  // the [[run]] of R2
    EXPECT_TRUE(test::says(e, "run 'R2' is listed, but"));
  }
  const auto unknown = write("unknown.toml",
                             "file = \"one.csv\"\n[[run]]\nid = \"r1\"\nguide = \"MY 30\"\nload_N = 1000\n"
                             "preload_um = 2.5\ntemperature_C = 24\n");
  {
    const InputError e = test::refusal([&] { load_friction_dataset(unknown); });
    EXPECT_TRUE(test::says(e, "run 'r1' has no block_length_mm"));
    EXPECT_TRUE(test::says(e, "unknown model 'MY 30'"));
  }
  std::ofstream(dir_ / "unknown.toml", std::ios::app) << "block_length_mm = 100\n";  // then the guide is a name
  EXPECT_EQ(load_friction_dataset(unknown).log.guide_names.at(0), "MY 30");
  const auto bad_key = write("bad.toml", "file = \"lean.csv\"\n[[run]]\nid = \"r1\"\nload_lb = 3\n");
  {
    const InputError e = test::refusal([&] { load_friction_dataset(bad_key); });
    EXPECT_EQ(e.line(), 4);
    EXPECT_TRUE(test::says(e, "unknown unit 'lb'"));
  }
}

TEST_F(RawFriction, SignedFrictionInATidyLogIsAWarning) {
  std::string text = kTidyHeader;
  for (int k = 0; k < 10; ++k)
    text += fmt::format("a,{},0.01,1000,2.5,120.2,24,{},{}\n", k, k % 2 ? -20 : 20, k % 2 ? -1 : 1);
  const auto warnings = load_friction_log(write("signed.csv", text)).reports.at(0).warnings;
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("negative on 5 of the 5 samples with direction = -1"), std::string::npos) << warnings[0];
}

// ---- Rotary drives, repeated times, preambles (issue 37) -----------------------------------

// A rig's runs as raw logs with a signed velocity column: each tidy sample becomes a plateau of
// 8 samples, 50 ms apart, at its speed in its sense, the force following the motion (with a
// ripple of 10 mN); the runs' conditions as [[run]] keys.
struct RawRows {
  std::vector<std::string> run;
  std::vector<double> time_s, velocity_m_s, force_N;
  std::string run_keys;  // the manifest's [[run]] tables
};
RawRows raw_rows_of(const FrictionLog& rig) {
  RawRows rows;
  std::vector<bool> described(rig.run_names.size(), false);
  std::vector<double> next_time_s(rig.run_names.size(), 0);
  for (std::size_t i = 0; i < rig.size(); ++i) {
    const std::uint32_t r = rig.run[i];
    for (int k = 0; k < 8; ++k) {
      rows.run.push_back(rig.run_names[r]);
      rows.time_s.push_back(next_time_s[r]);
      next_time_s[r] += 0.05;
      rows.velocity_m_s.push_back(rig.direction[i] * rig.velocity_m_s[i]);
      rows.force_N.push_back(rig.direction[i] * (rig.friction_N[i] + 0.01 * std::sin(k)));
    }
    if (described[r]) continue;
    described[r] = true;
    rows.run_keys += fmt::format("[[run]]\nid = \"{}\"\nload_N = {}\npreload_um = {}\nblock_length_mm = {}\n"
                                 "temperature_C = {}\n",
                                 rig.run_names[r], rig.load_N[i], rig.preload_um[i], rig.block_length_mm[i],
                                 rig.temperature_C[i]);
  }
  return rows;
}

// Settings that keep the rig's short plateaus.
constexpr const char* kDriveRaw = "[raw]\nsettling_s = 0\nmin_plateau_samples = 5\nvelocity_window = 3\n";

// Expects two logs to hold the same samples (1e-9 relative) and to fit to the same constants.
void expect_same_samples_and_fit(const FrictionLog& a, const FrictionLog& b, bool same_lines = true) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 100u);
  EXPECT_EQ(a.direction, b.direction);
  if (same_lines) {
    EXPECT_EQ(a.line, b.line);
  }
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_NEAR(a.velocity_m_s[i], b.velocity_m_s[i], 1e-9 * a.velocity_m_s[i]) << i;
    ASSERT_NEAR(a.friction_N[i], b.friction_N[i], 1e-9 * std::abs(a.friction_N[i])) << i;
  }
  FrictionFitOptions o;  // one least-squares solve: its minimum, not the run variance's alternation
  o.run_offsets = RunOffsets::none;
  o.per_run_fits = false;
  const FrictionFitResult fa = fit_friction(a, o), fb = fit_friction(b, o);
  ASSERT_TRUE(fa.fit.solver.usable);
  for (std::size_t j = 0; j < 7; ++j) {
    const double va = fa.fit.parameters[j].value, vb = fb.fit.parameters[j].value;
    EXPECT_NEAR(va, vb, 1e-9 * std::abs(va)) << fa.fit.parameters[j].name;
  }
}

// The rig's runs converted by hand to a motor's speed and torque (the equations written out
// here, not the library's) read through [drive], against the same runs in m/s and N.
TEST_F(RawFriction, ARotaryDriveGivesTheSamplesAndFitOfTheLogConvertedByHand) {
  const RawRows rows = raw_rows_of(few_setups_log());
  std::string linear = "run,time_s,velocity_m_s,force_N\n";
  std::string screw = "run,time_s,velocity_rpm,torque_Nm\n";
  std::string pinion = "run,time_s,velocity_rad_s,torque_percent\n";
  const double lead_m = 0.010, screw_ratio = 3, screw_eta = 0.9;                 // ball screw behind a belt
  const double radius_m = 0.020, pinion_ratio = 5, pinion_eta = 0.95, nominal_Nm = 2.5;  // rack and pinion
  for (std::size_t i = 0; i < rows.run.size(); ++i) {
    const double v = rows.velocity_m_s[i], f = rows.force_N[i];
    linear += fmt::format("{},{:.17g},{:.17g},{:.17g}\n", rows.run[i], rows.time_s[i], v, f);
    const double rpm = v / lead_m * screw_ratio * 60;                 // screw turns/s × ratio, per minute
    const double screw_Nm = f * lead_m / (2 * M_PI * screw_eta * screw_ratio);
    screw += fmt::format("{},{:.17g},{:.17g},{:.17g}\n", rows.run[i], rows.time_s[i], rpm, screw_Nm);
    const double rad_s = v / radius_m * pinion_ratio;
    const double percent = 100 * f * radius_m / (pinion_eta * pinion_ratio) / nominal_Nm;
    pinion += fmt::format("{},{:.17g},{:.17g},{:.17g}\n", rows.run[i], rows.time_s[i], rad_s, percent);
  }
  write("linear.csv", linear);
  write("screw.csv", screw);
  write("pinion.csv", pinion);
  const FrictionLog by_hand =
      load_friction_dataset(write("linear.toml", "file = \"linear.csv\"\n" + std::string(kDriveRaw) + rows.run_keys)).log;
  const FrictionDataSet screwed = load_friction_dataset(
      write("screw.toml", "file = \"screw.csv\"\n[drive]\nlead_mm = 10\ngear_ratio = 3\nefficiency = 0.9\n" +
                              std::string(kDriveRaw) + rows.run_keys));
  expect_same_samples_and_fit(by_hand, screwed.log);
  EXPECT_NE(screwed.log.reports[0].conversions.at("velocity_rpm").find("screw, lead 10 mm, gear ratio 3"),
            std::string::npos);
  const FrictionDataSet pinioned = load_friction_dataset(
      write("pinion.toml", "file = \"pinion.csv\"\n[drive]\npinion_radius_mm = 20\ngear_ratio = 5\nefficiency = 0.95\n"
                           "nominal_torque_Nm = 2.5\n" + std::string(kDriveRaw) + rows.run_keys));
  expect_same_samples_and_fit(by_hand, pinioned.log);

  // The same drive as settings (the flags' and the Python dict's path) rather than [drive].
  RawFrictionOptions flags;
  flags.drive.set("lead_mm", 10);
  flags.drive.set("gear_ratio", 3);
  flags.drive.set("efficiency", 0.9);
  const FrictionDataSet given = load_friction_dataset(
      write("screw_flags.toml", "file = \"screw.csv\"\n" + std::string(kDriveRaw) + rows.run_keys), nullptr, flags,
      {"lead_mm", "gear_ratio", "efficiency"});
  EXPECT_EQ(given.log.friction_N, screwed.log.friction_N);
  EXPECT_EQ(given.log.velocity_m_s, screwed.log.velocity_m_s);
}

// Reflected to the carriage, a rotor's J·(2π·N/p)² joins the moving mass whose inertia is taken
// off the force; without a moving mass it is only reported.
TEST(Drive, RotorInertiaIsReflectedByTheRatioSquared) {
  Drive screw;
  screw.set("lead_mm", 10);
  screw.set("gear_ratio", 3);
  screw.set("rotor_inertia_kg_m2", 1e-4);
  EXPECT_NEAR(screw.reflected_inertia_kg(), 1e-4 * std::pow(2 * M_PI * 3 / 0.010, 2), 1e-12);
  Drive pinion;
  pinion.set("pinion_radius_mm", 20);
  pinion.set("gear_ratio", 5);
  pinion.set("rotor_inertia_kg_m2", 1e-4);
  EXPECT_NEAR(pinion.reflected_inertia_kg(), 1e-4 * std::pow(5 / 0.020, 2), 1e-12);
  // Power balance: F·v = η·τ·ω.
  screw.set("efficiency", 0.8);
  EXPECT_NEAR(screw.force_per_motor_Nm() * screw.speed_per_motor_rad_s(), 0.8, 1e-15);
  EXPECT_THROW(screw.set("efficiency", 1.5), InvalidParameter);
  EXPECT_THROW(screw.set("lead_mm", 0), InvalidParameter);
  EXPECT_THROW(screw.set("gear_ratio", -1), InvalidParameter);
  screw.pinion_radius_mm = 20;
  EXPECT_THROW(screw.validate(), InvalidParameter);
}

TEST_F(RawFriction, ARotorsInertiaJoinsAGivenMovingMass) {
  std::string text = "run,time_s,velocity_rpm,torque_Nm,load_N,preload_um,block_length_mm,temperature_C\n";
  for (int k = 0; k < 60; ++k) {  // accelerating at 0.06 m/s² for 1 s, then 2 s at 60 mm/s (3600 rpm with a 1 mm lead)
    const double t = 0.05 * k, v = t < 1 ? 0.06 * t : 0.06;
    text += fmt::format("a,{},{},{},1000,2.5,120.2,24\n", t, v / 0.001 * 60, 0.01);
  }
  write("inertia.csv", text);
  RawFrictionOptions o = keep_all(5);
  o.drive.set("lead_mm", 1);
  o.drive.set("rotor_inertia_kg_m2", 1e-6);  // 1e-6 · (2π / 1 mm)² = 39.5 kg at the carriage
  const FrictionLog plain = load_friction_log(dir_ / "inertia.csv", o);
  EXPECT_NE(plain.reports[0].conversions.at("rotor_inertia_kg_m2").find("39.4784 kg at the carriage, part of the moving mass"),
            std::string::npos)
      << plain.reports[0].conversions.at("rotor_inertia_kg_m2");
  o.moving_mass_kg = 2;
  const FrictionLog with_mass = load_friction_log(dir_ / "inertia.csv", o);
  EXPECT_NE(with_mass.reports[0].conversions.at("rotor_inertia_kg_m2").find("added to moving_mass_kg (2 kg)"),
            std::string::npos);
}

// Duplicates by a logger that writes too few digits of the time: each pair's mean is the sample
// the log deduplicated by hand has.
TEST_F(RawFriction, RepeatedTimesAverageToTheLogDeduplicatedByHand) {
  const RawRows rows = raw_rows_of(few_setups_log());
  std::string once = "run,time_s,velocity_m_s,force_N\n", twice = once;
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < rows.run.size(); ++i) {
    const double v = rows.velocity_m_s[i], f = rows.force_N[i], t = rows.time_s[i];
    once += fmt::format("{},{:.17g},{:.17g},{:.17g}\n", rows.run[i], t, v, f);
    if (i % 4 == 0) {  // two readings around the sample, at its time: 0.25 and 0.5 are exact in binary
      twice += fmt::format("{},{:.17g},{:.17g},{:.17g}\n", rows.run[i], t, v - 0.25 * v, f + 0.5);
      twice += fmt::format("{},{:.17g},{:.17g},{:.17g}\n", rows.run[i], t, v + 0.25 * v, f - 0.5);
      ++pairs;
    } else {
      twice += fmt::format("{},{:.17g},{:.17g},{:.17g}\n", rows.run[i], t, v, f);
    }
  }
  write("once.csv", once);
  write("twice.csv", twice);
  const std::string manifest = std::string(kDriveRaw) + rows.run_keys;
  const FrictionLog a = load_friction_dataset(write("once.toml", "file = \"once.csv\"\n" + manifest)).log;
  const FrictionLog b = load_friction_dataset(write("twice.toml", "file = \"twice.csv\"\n" + manifest)).log;
  std::size_t merged = 0;
  for (const RunSegmentation& s : b.segmentation) merged += s.averaged_duplicates;
  EXPECT_EQ(merged, pairs);
  expect_same_samples_and_fit(a, b, false);
  // Refused when asked.
  const auto refuse = write("refuse.toml", "file = \"twice.csv\"\n" + std::string(kDriveRaw) +
                                               "duplicate_times = \"refuse\"\n" + rows.run_keys);
  EXPECT_TRUE(test::says(test::refusal([&] { load_friction_dataset(refuse); }), "refused as asked"));
}

// A logger's preamble: three lines before the column names, skipped by skip_lines (a setting, or
// a manifest's key for its file); errors name the file's own lines.
TEST_F(RawFriction, APreambleIsSkippedAndErrorsNameTheFilesLines) {
  const std::string preamble = "Logger XY-200, firmware 1.2\nchannel A: load cell\nsample rate: 10 Hz\n";
  const std::string rows = raw_csv(plateau_rows());
  write("plain.csv", rows);
  write("preamble.csv", preamble + rows);
  const FrictionLog plain = load_friction_log(dir_ / "plain.csv", keep_all(10));
  RawFrictionOptions o = keep_all(10);
  o.skip_lines = 3;
  const FrictionLog skipped = load_friction_log(dir_ / "preamble.csv", o);
  EXPECT_EQ(skipped.friction_N, plain.friction_N);
  EXPECT_EQ(skipped.velocity_m_s, plain.velocity_m_s);
  ASSERT_EQ(skipped.line.size(), plain.line.size());
  EXPECT_EQ(skipped.line.front(), plain.line.front() + 3);  // the file's own line numbers
  // As a manifest's key: of its file, or of a run's own file.
  const std::string raw = "[raw]\nsettling_s = 0\nmin_plateau_samples = 10\n";
  EXPECT_EQ(load_friction_dataset(write("top.toml", "file = \"preamble.csv\"\nskip_lines = 3\n" + raw)).log.friction_N,
            plain.friction_N);
  std::string runless = preamble + rows.substr(rows.find(',') + 1);  // the run column dropped
  for (std::size_t at = runless.find("\na,"); at != std::string::npos; at = runless.find("\na,", at)) runless.erase(at + 1, 2);
  write("runless.csv", runless);
  const auto manifest = write("run.toml", "[[run]]\nid = \"p\"\nfile = \"runless.csv\"\nskip_lines = 3\n" + raw);
  EXPECT_EQ(load_friction_dataset(manifest).log.friction_N, plain.friction_N);
  // Without it, the preamble is read as the header.
  EXPECT_THROW(load_friction_log(dir_ / "preamble.csv", keep_all(10)), InputError);

  // An error in a row, and one found after the run was read (a plateau too fast), at the real line.
  std::vector<std::string> bad = plateau_rows();
  bad[4] = "a,0.4,4,twenty,1000,2.5,120.2,24";  // line 6 of the log, 9 of the file
  write("bad_cell.csv", preamble + raw_csv(bad));
  EXPECT_EQ(test::refusal([&] { load_friction_log(dir_ / "bad_cell.csv", o); }).line(), 9);
  std::vector<std::string> fast;
  for (int k = 0; k < 30; ++k) fast.push_back(fmt::format("a,{},{},20,1000,2.5,120.2,24", 0.001 * k, 100 * k));
  write("fast.csv", preamble + raw_csv(fast));
  const InputError e = test::refusal([&] { load_friction_log(dir_ / "fast.csv", o); });
  EXPECT_EQ(e.line(), 5);  // the first sample: line 2 of the log
  EXPECT_EQ(e.column(), 5);
}

}  // namespace
}  // namespace lmcal
