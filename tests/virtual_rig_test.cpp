#include "lmcal/rig/virtual_rig.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <nlohmann/json.hpp>

#include "lmcal/error.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/models/rail_thermal.hpp"
#include "lmcal/rig/axis_rig.hpp"

namespace lmcal {
namespace {

FrictionRigConfig small_friction_rig() {
  FrictionRigConfig c;
  c.guides = {"SRN 35C"};
  c.preload_um = {2.5, 4};
  c.load_N = {1000, 3000};
  c.velocity_m_s = {0.005, 0.05, 0.11};
  c.temperature_C = {26, 40};
  c.runs = 3;
  return c;
}

ThermalRigConfig short_thermal_rig() {
  ThermalRigConfig c;
  c.velocity_m_s = {0.11};
  c.duration_s = 1800;
  c.record_every_s = 10;
  return c;
}

// Standard deviation and lag-1 autocorrelation of noise series, pooled over the series
// (each about its own mean; no product spans two series).
struct NoiseStats {
  double sd = 0;
  double lag1 = 0;
};

NoiseStats noise_stats(const std::vector<std::vector<double>>& series) {
  double sum2 = 0, sum_lag = 0, count = 0;
  for (const auto& x : series) {
    double mean = 0;
    for (double v : x) mean += v;
    mean /= static_cast<double>(x.size());
    for (std::size_t t = 0; t < x.size(); ++t) {
      sum2 += (x[t] - mean) * (x[t] - mean);
      if (t > 0) sum_lag += (x[t] - mean) * (x[t - 1] - mean);
    }
    count += static_cast<double>(x.size());
  }
  return {std::sqrt(sum2 / count), sum_lag / sum2};
}

// The load cell's noise, run by run in time order: the log minus the same log made
// without noise (same seed: same offsets, same draws).
std::vector<std::vector<double>> load_cell_noise(FrictionRigConfig config) {
  const FrictionLog noisy = generate_friction_log(config, {}).log;
  config.noise_N = 0;
  const FrictionLog clean = generate_friction_log(config, {}).log;
  std::vector<std::vector<double>> noise(noisy.run_names.size());
  for (std::size_t i = 0; i < noisy.size(); ++i)
    noise[noisy.run[i]].push_back(noisy.friction_N[i] - clean.friction_N[i]);
  return noise;
}

// A rail thermocouple's noise: the trace minus the same run made without noise.
std::vector<std::vector<double>> thermocouple_noise(ThermalRigConfig config) {
  const auto noisy = generate_thermal_dataset(config, {}, "noisy");
  config.noise_K = 0;
  const auto clean = generate_thermal_dataset(config, {}, "clean");
  std::vector<std::vector<double>> noise;
  for (std::size_t r = 0; r < noisy.set.runs.size(); ++r) {
    const auto& a = noisy.set.runs[r].trace.rail[0].values;
    const auto& b = clean.set.runs[r].trace.rail[0].values;
    noise.emplace_back(a.size());
    for (std::size_t t = 0; t < a.size(); ++t) noise.back()[t] = a[t] - b[t];
  }
  return noise;
}

TEST(VirtualRig, SameSeedSameDataOtherSeedOtherData) {
  const auto a = generate_friction_log(small_friction_rig(), {});
  const auto b = generate_friction_log(small_friction_rig(), {});
  EXPECT_EQ(a.log.friction_N, b.log.friction_N);
  EXPECT_EQ(a.truth_json, b.truth_json);
  auto other = small_friction_rig();
  other.seed = 2;
  EXPECT_NE(generate_friction_log(other, {}).log.friction_N, a.log.friction_N);
  const auto t1 = generate_thermal_dataset(short_thermal_rig(), {}, "x");
  const auto t2 = generate_thermal_dataset(short_thermal_rig(), {}, "x");
  EXPECT_EQ(t1.set.runs[0].trace.rail[0].values, t2.set.runs[0].trace.rail[0].values);
}

TEST(VirtualRig, NoiselessFrictionIsTheLawAndEffectsAddTheirTerm) {
  auto config = small_friction_rig();
  config.noise_N = config.run_offset_N = config.temperature_noise_K = 0;
  RigEffects effects;
  set_rig_effect(effects, "seal_drag", 200.0);
  const auto clean = generate_friction_log(config, {}).log;
  const auto sealed = generate_friction_log(config, effects).log;
  ASSERT_EQ(clean.size(), 3u * 2 * 2 * 3 * 2 * 2);
  for (std::size_t i = 0; i < clean.size(); ++i) {
    const auto c = clean.conditions(i);
    EXPECT_NEAR(clean.friction_N[i], friction_force_N(paper_friction_constants(), c), 0.0005 + 1e-12);
    EXPECT_NEAR(sealed.friction_N[i] - clean.friction_N[i], 200 * c.velocity_m_s * c.velocity_m_s, 0.001 + 1e-12);
  }
}

TEST(VirtualRig, FrictionNoiseAndRunOffsetsMatchTheTruthFile) {
  auto config = small_friction_rig();
  config.runs = 6;
  config.temperature_noise_K = 0;
  const auto made = generate_friction_log(config, {});
  const auto truth = nlohmann::json::parse(made.truth_json);
  std::vector<double> sum(6, 0), sum2(6, 0), count(6, 0);
  for (std::size_t i = 0; i < made.log.size(); ++i) {
    const double r = made.log.friction_N[i] - friction_force_N(paper_friction_constants(), made.log.conditions(i));
    const auto run = made.log.run[i];
    sum[run] += r;
    sum2[run] += r * r;
    count[run] += 1;
  }
  for (std::size_t run = 0; run < 6; ++run) {
    const double mean = sum[run] / count[run];
    const double sd = std::sqrt(sum2[run] / count[run] - mean * mean);
    EXPECT_NEAR(mean, truth["runs"][run]["zero_offset_N"].get<double>(), 4 * 0.15 / std::sqrt(count[run]));
    EXPECT_NEAR(sd, 0.15, 0.05);
  }
}

TEST(VirtualRig, LoadCellRangeSkipsTheSameConditionsInEveryRun) {
  FrictionRigConfig config;
  config.guides = {"SRG 45C"};
  config.velocity_m_s = {0.05, 0.15};
  config.temperature_C = {22};
  config.runs = 2;
  const auto made = generate_friction_log(config, {});
  const auto truth = nlohmann::json::parse(made.truth_json);
  EXPECT_GT(truth["conditions_beyond_load_cell_skipped"].get<int>(), 0);
  EXPECT_EQ(made.log.size() % 2, 0u);
  for (double F : made.log.friction_N) EXPECT_LT(F, 0.95 * 98.0665 + 1.5);
}

// With bias and noise off, the thermocouples read the rail solver at their positions.
TEST(VirtualRig, CleanThermocouplesReadTheRailModel) {
  auto config = short_thermal_rig();
  config.tc_bias_K = config.ambient_bias_K = config.noise_K = 0;
  config.ambient_drift_K_per_h = config.ambient_wave_K = 0;
  const auto made = generate_thermal_dataset(config, {}, "clean");
  const auto& run = made.set.runs.at(0);
  const auto& spec = builtin_catalog().find("SRN 35C");
  const RailGeometry g{.rail_length_m = 0.6, .area_m2 = *spec.area_m2, .perimeter_m = *spec.perimeter_m,
                       .stroke_m = 0.2, .contact_length_m = *spec.contact_length_mm * 1e-3, .velocity_m_s = 0.11};
  FrictionConditions<double> c{.load_N = 3000, .preload_um = 4, .block_length_mm = 120.2, .velocity_m_s = 0.11,
                               .temperature_C = 24.0};
  const RailParams<double> p{.heat_partition = 0.6, .heat_rate_W = heat_rate_W(paper_friction_constants(), c),
                             .initial_temperature_C = 24.0};
  const RailOutputs out{.duration_s = 1800, .sensor_positions_m = {0.0, 0.05, 0.1}, .output_times_s = {1800}};
  const auto sol = simulate_rail(g, {.source = SourceModel::averaged, .half_rail_segments = 400, .time_step_s = 5}, out,
                                 p, AmbientTrace::constant(24.0));
  for (std::size_t s = 0; s < 3; ++s) EXPECT_NEAR(run.trace.rail[s].values.back(), sol.temperature_C(0, s), 0.01);
  EXPECT_EQ(run.trace.ambient.size(), 2u);
  EXPECT_NEAR(run.trace.ambient[0].values.back(), 24.0, 1e-9);
  EXPECT_NEAR(*run.mean_friction_N, p.heat_rate_W / 0.11, 4 * 0.25);
}

TEST(VirtualRig, ThermalEffectsLeaveTheirMark) {
  auto config = short_thermal_rig();
  config.noise_K = 0;
  const auto base = generate_thermal_dataset(config, {}, "base");
  auto hot_end = [](const ThermalRigOutput& o) { return o.set.runs[0].trace.rail[0].values.back(); };
  RigEffects coupled;
  set_rig_effect(coupled, "coupling", 1);
  const auto c = generate_thermal_dataset(config, coupled, "coupled");
  const auto truth = nlohmann::json::parse(c.truth_json);
  EXPECT_LT(truth["runs"][0]["heat_rate_end_W"].get<double>(), truth["runs"][0]["heat_rate_start_W"].get<double>());
  EXPECT_LT(hot_end(c), hot_end(base));
  RigEffects lag;
  set_rig_effect(lag, "tc_lag", 120);
  EXPECT_LT(generate_thermal_dataset(config, lag, "lag").set.runs[0].trace.rail[0].values[30],
            base.set.runs[0].trace.rail[0].values[30]);
  RigEffects convective;
  set_rig_effect(convective, "convection_velocity", 10);
  EXPECT_LT(hot_end(generate_thermal_dataset(config, convective, "h")), hot_end(base));
  RigEffects moving;
  set_rig_effect(moving, "moving_source", 1);
  EXPECT_NEAR(hot_end(generate_thermal_dataset(config, moving, "m")), hot_end(base), 0.2);
  EXPECT_THROW(set_rig_effect(moving, "warp_drive", 1), InvalidParameter);
}

// With φ = 0.9 the noise isolated from a generation has lag-1 autocorrelation 0.9 and the
// requested σ; with φ = 0, about 0 and the same σ.
template <class Config, class Noise>
void expect_ar1_noise(Config config, double sigma, Noise noise_of) {
  for (const double phi : {0.9, 0.0}) {
    config.noise_ar1 = phi;
    const NoiseStats stats = noise_stats(noise_of(config));
    EXPECT_NEAR(stats.lag1, phi, 0.05) << "phi " << phi;
    EXPECT_NEAR(stats.sd, sigma, 0.1 * sigma) << "phi " << phi;
  }
}

TEST(VirtualRig, LoadCellNoiseHasTheRequestedAutocorrelationAndSd) {
  FrictionRigConfig config;  // the full sweep: ~2000 samples per run, 10 runs
  expect_ar1_noise(config, config.noise_N, [](const FrictionRigConfig& c) { return load_cell_noise(c); });
}

TEST(VirtualRig, ThermocoupleNoiseHasTheRequestedAutocorrelationAndSd) {
  ThermalRigConfig config;
  config.velocity_m_s = {0.11};
  config.duration_s = 100000;  // 20 000 records at 5 s
  config.noise_K = 0.2;        // well above the logger's 0.01 K
  expect_ar1_noise(config, config.noise_K, [](const ThermalRigConfig& c) { return thermocouple_noise(c); });
}

TEST(VirtualRig, HeatVariationScalesEachRunsRiseAndHidesFromTheLoggedFriction) {
  auto config = short_thermal_rig();
  config.repeats = 40;
  config.record_every_s = 30;
  config.noise_K = config.ambient_drift_K_per_h = config.ambient_wave_K = 0;  // the rise is the heating alone
  const auto steady = generate_thermal_dataset(config, {}, "steady");
  config.heat_variation = 0.1;
  const auto varied = generate_thermal_dataset(config, {}, "varied");
  const auto truth = nlohmann::json::parse(varied.truth_json);
  EXPECT_EQ(truth["heat_variation"].get<double>(), 0.1);

  double sum = 0, sum2 = 0;
  for (std::size_t r = 0; r < 40; ++r) {
    const double factor = truth["runs"][r]["heat_factor"].get<double>();
    sum += factor;
    sum2 += factor * factor;
    const auto rise = [&](const ThermalRigOutput& o) {
      const auto& tc1 = o.set.runs[r].trace.rail[0].values;
      return tc1.back() - tc1.front();
    };
    // Linear in the heat: the rise scales with the factor (to the logger's 0.01 K, twice).
    EXPECT_NEAR(rise(varied), factor * rise(steady), 0.01 * (1 + factor) + 1e-9) << "run " << r;
    EXPECT_EQ(varied.set.runs[r].mean_friction_N, steady.set.runs[r].mean_friction_N) << "run " << r;
  }
  const double mean = sum / 40, sd = std::sqrt(sum2 / 40 - mean * mean);
  EXPECT_NEAR(mean, 1, 4 * 0.1 / std::sqrt(40.0));
  EXPECT_NEAR(sd, 0.1, 0.03);
}

TEST(VirtualRig, FrictionGainErrorShiftsEveryRunByTheSameFactor) {
  auto config = short_thermal_rig();
  config.velocity_m_s = {0.066, 0.083, 0.11};
  config.repeats = 2;
  config.record_every_s = 30;
  config.friction_noise_N = 0;  // the logged friction is then the true one times the gain, at 0.01 N
  config.friction_gain_error = 0.05;
  const auto made = generate_thermal_dataset(config, {}, "gain");
  const auto truth = nlohmann::json::parse(made.truth_json);
  const double g = truth["friction_gain_error"].get<double>();
  EXPECT_EQ(truth["friction_gain_error_sigma"].get<double>(), 0.05);
  ASSERT_GT(std::abs(g) * 20, 0.1) << "this seed's gain error is too small to see against the 0.01 N rounding";
  ASSERT_EQ(made.set.runs.size(), 6u);
  for (std::size_t r = 0; r < 6; ++r) {
    const double true_N = truth["runs"][r]["mean_friction_true_N"].get<double>();
    EXPECT_GT(true_N, 20);
    EXPECT_NEAR(*made.set.runs[r].mean_friction_N, true_N * (1 + g), 0.005 + 1e-9) << "run " << r;
  }
}

TEST(VirtualRig, StatedFrictionUncertaintyIsRelativeToTheLoggedFriction) {
  auto config = short_thermal_rig();
  config.velocity_m_s = {0.066, 0.11};
  config.stated_friction_uncertainty = 0.02;
  const auto made = generate_thermal_dataset(config, {}, "stated");
  for (const ThermalRun& run : made.set.runs) {
    ASSERT_TRUE(run.mean_friction_uncertainty_N) << run.id;
    EXPECT_NEAR(*run.mean_friction_uncertainty_N, 0.02 * *run.mean_friction_N, 0.00005 + 1e-12) << run.id;
  }
  EXPECT_FALSE(generate_thermal_dataset(short_thermal_rig(), {}, "unstated").set.runs[0].mean_friction_uncertainty_N);
}

// The bytes a data set is made of: every run's CSV, the manifest and the truth.
std::string thermal_bytes(const ThermalRigOutput& o) {
  std::string bytes = thermal_manifest_toml(o.set, "") + o.truth_json;
  for (const ThermalRun& run : o.set.runs) bytes += thermal_trace_csv(run.trace);
  return bytes;
}

TEST(VirtualRig, NewImperfectionsOffLeaveTheBytesAsBefore) {
  auto friction = small_friction_rig();
  const auto friction_default = generate_friction_log(friction, {});
  friction.noise_ar1 = 0;
  const auto friction_zero = generate_friction_log(friction, {});
  EXPECT_EQ(friction_log_csv(friction_zero.log), friction_log_csv(friction_default.log));
  EXPECT_EQ(friction_zero.truth_json, friction_default.truth_json);

  auto thermal = short_thermal_rig();
  thermal.repeats = 2;
  const auto thermal_default = generate_thermal_dataset(thermal, {}, "x");
  thermal.noise_ar1 = thermal.heat_variation = thermal.friction_gain_error = thermal.stated_friction_uncertainty = 0;
  EXPECT_EQ(thermal_bytes(generate_thermal_dataset(thermal, {}, "x")), thermal_bytes(thermal_default));

  // Switched on, they draw from a stream of their own: what they do not touch stays put.
  friction.noise_ar1 = 0.5;
  const auto friction_red = generate_friction_log(friction, {});
  EXPECT_EQ(friction_red.log.temperature_C, friction_default.log.temperature_C);
  EXPECT_NE(friction_red.log.friction_N, friction_default.log.friction_N);
  thermal.heat_variation = 0.1;
  thermal.friction_gain_error = 0.05;
  const auto thermal_on = generate_thermal_dataset(thermal, {}, "x");
  for (std::size_t r = 0; r < 2; ++r) {
    const auto& on = thermal_on.set.runs[r].trace;
    const auto& off = thermal_default.set.runs[r].trace;
    for (std::size_t a = 0; a < on.ambient.size(); ++a) EXPECT_EQ(on.ambient[a].values, off.ambient[a].values);
    EXPECT_NE(on.rail[0].values, off.rail[0].values);
  }
}

TEST(VirtualRig, RefusesBadImperfectionSettings) {
  auto friction = small_friction_rig();
  friction.noise_ar1 = 1;
  EXPECT_THROW(generate_friction_log(friction, {}), InvalidParameter);
  auto thermal = short_thermal_rig();
  thermal.noise_ar1 = -0.1;
  EXPECT_THROW(generate_thermal_dataset(thermal, {}, "x"), InvalidParameter);
  thermal = short_thermal_rig();
  thermal.heat_variation = std::nan("");
  EXPECT_THROW(generate_thermal_dataset(thermal, {}, "x"), InvalidParameter);
  thermal = short_thermal_rig();
  thermal.friction_gain_error = -0.01;
  EXPECT_THROW(generate_thermal_dataset(thermal, {}, "x"), InvalidParameter);
  thermal = short_thermal_rig();
  thermal.stated_friction_uncertainty = INFINITY;
  EXPECT_THROW(generate_thermal_dataset(thermal, {}, "x"), InvalidParameter);
  thermal = short_thermal_rig();
  thermal.heat_variation = 100;  // a factor 1 + 100 z <= 0 for about half the seeds
  thermal.velocity_m_s = {0.05, 0.066, 0.083, 0.11, 0.15};
  EXPECT_THROW(generate_thermal_dataset(thermal, {}, "x"), InvalidParameter);
}

}  // namespace
}  // namespace lmcal

namespace lmcal {
namespace {

namespace fs = std::filesystem;

fs::path fresh_folder(const char* name) {
  const fs::path dir = fs::temp_directory_path() / (std::string("lmcal_rig_test_") + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Generate -> write -> load gives back the same values, bit for bit.
TEST(VirtualRig, GeneratedDataRoundTripsThroughTheLoaders) {
  RigEffects effects;
  set_rig_effect(effects, "direction_asymmetry", 0.05);
  const auto friction = generate_friction_log(small_friction_rig(), effects);
  const fs::path dir = fresh_folder("friction");
  write_file_atomically(dir / "friction.csv", friction_log_csv(friction.log, {"synthetic"}));
  const FrictionLog loaded = load_friction_log(dir / "friction.csv");
  EXPECT_EQ(loaded.run_names, friction.log.run_names);
  EXPECT_EQ(loaded.friction_N, friction.log.friction_N);
  EXPECT_EQ(loaded.velocity_m_s, friction.log.velocity_m_s);
  EXPECT_EQ(loaded.temperature_C, friction.log.temperature_C);
  EXPECT_EQ(loaded.direction, friction.log.direction);
  EXPECT_EQ(loaded.time_s, friction.log.time_s);

  auto config = short_thermal_rig();
  config.repeats = 2;
  config.stated_friction_uncertainty = 0.02;
  const auto thermal = generate_thermal_dataset(config, {}, "roundtrip");
  const fs::path tdir = fresh_folder("thermal");
  ThermalDataSet placed = thermal.set;
  OutputSet out;
  for (ThermalRun& run : placed.runs) {
    run.file = tdir / run.file;
    out.add(run.file, thermal_trace_csv(run.trace));
  }
  out.add(tdir / "thermal.toml", thermal_manifest_toml(placed, tdir));
  out.commit();
  const ThermalDataSet back = load_thermal_dataset(tdir / "thermal.toml");
  ASSERT_EQ(back.runs.size(), 2u);
  for (std::size_t r = 0; r < 2; ++r) {
    const auto& a = thermal.set.runs[r];
    const auto& b = back.runs[r];
    EXPECT_EQ(b.id, a.id);
    EXPECT_EQ(b.velocity_m_s, a.velocity_m_s);
    EXPECT_EQ(b.mean_friction_N, a.mean_friction_N);
    ASSERT_TRUE(b.mean_friction_uncertainty_N);
    EXPECT_EQ(b.mean_friction_uncertainty_N, a.mean_friction_uncertainty_N);
    EXPECT_EQ(b.sensor_position_m, a.sensor_position_m);
    EXPECT_EQ(b.trace.time_s, a.trace.time_s);
    for (std::size_t s = 0; s < a.trace.rail.size(); ++s) EXPECT_EQ(b.trace.rail[s].values, a.trace.rail[s].values);
    for (std::size_t s = 0; s < a.trace.ambient.size(); ++s)
      EXPECT_EQ(b.trace.ambient[s].values, a.trace.ambient[s].values);
  }
  fs::remove_all(dir);
  fs::remove_all(tdir);
}


// ---- The closed-loop axis (axis_rig.hpp) ----

// One setup, a few speeds: a run of about 15 s.
FrictionRigConfig axis_setup(std::vector<double> speeds = {0.005, 0.05, 0.15}) {
  FrictionRigConfig c;
  c.guides = {"SRN 35C"};
  c.preload_um = {2.5};
  c.load_N = {1000};
  c.temperature_C = {26};
  c.velocity_m_s = std::move(speeds);
  c.runs = 1;
  c.seed = 3;
  return c;
}

// No noise, a fine encoder: what the physics checks read.
AxisRigConfig quiet_axis() {
  AxisRigConfig a;
  a.current_noise_A = 0;
  a.encoder_resolution_m = 1e-9;
  return a;
}

// A run's log as written: time, position in m, drive force in N.
struct AxisLog {
  std::vector<double> time_s, position_m, force_N;
  std::size_t size() const { return time_s.size(); }
};

AxisLog parse_axis_log(const std::string& csv) {
  AxisLog log;
  std::istringstream in(csv);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#' || line[0] == 't') continue;  // comments, the header
    double t, x_mm, F;
    char comma;
    std::istringstream(line) >> t >> comma >> x_mm >> comma >> F;
    log.time_s.push_back(t);
    log.position_m.push_back(x_mm * 1e-3);
    log.force_N.push_back(F);
  }
  return log;
}

// The law at the run's conditions with the regularised sign, as the plant applies it.
double axis_friction_N(const AxisRigConfig& a, const FrictionConstants<double>& k, double v) {
  FrictionConditions<double> c{.load_N = 1000, .preload_um = 2.5, .block_length_mm = 120.2,
                               .velocity_m_s = std::abs(v), .temperature_C = 26, .direction = v < 0 ? -1.0 : 1.0};
  return std::tanh(v / a.regularisation_m_s) * friction_force_with_effects_N(k, FrictionEffects<double>{}, c);
}

constexpr double kG = 9.80665;

// Friction and gravity off, no noise: the logged force is M·a of the logged positions. The
// integrator's steps give M Δ²x/h² = the force averaged over ±h with triangular weights, which
// for a smooth force is (F_{k-1} + 10 F_k + F_{k+1}) / 12 (Numerov); what is left is the
// encoder's rounding (4 counts/h² in Δ²x) and the force's rounding, except at the reference's
// corners where the feedforward steps.
TEST(VirtualRigAxis, WithoutFrictionAndGravityTheForceIsMassTimesAcceleration) {
  FrictionRigConfig setup = axis_setup();
  setup.constants.k1 = setup.constants.k2 = setup.constants.mu_st = setup.constants.mu_v = setup.constants.f0 = 0;
  const AxisRigConfig a = quiet_axis();
  const AxisRigOutput made = generate_axis_logs(setup, a, {});
  const AxisLog log = parse_axis_log(made.run_files.at(0).second);
  const double h = 1 / a.log_rate_Hz, M = a.moving_mass_kg;
  const double tolerance_N = M * 4 * a.encoder_resolution_m / (h * h) + 2e-4;
  std::size_t within = 0, n = 0;
  double worst_N = 0, max_force_N = 0;
  for (std::size_t k = 1; k + 1 < log.size(); ++k, ++n) {
    const double inertia_N = M * (log.position_m[k + 1] - 2 * log.position_m[k] + log.position_m[k - 1]) / (h * h);
    const double force_N = (log.force_N[k - 1] + 10 * log.force_N[k] + log.force_N[k + 1]) / 12;
    const double residual_N = std::abs(inertia_N - force_N);
    within += residual_N <= tolerance_N;
    worst_N = std::max(worst_N, residual_N);
    max_force_N = std::max(max_force_N, std::abs(log.force_N[k]));
  }
  EXPECT_GT(max_force_N, 0.9 * M * a.acceleration_m_s2);  // it accelerates (the check is not 0 = 0)
  EXPECT_GE(static_cast<double>(within), 0.99 * static_cast<double>(n)) << "worst " << worst_N << " N";
  EXPECT_LT(worst_N, M * a.acceleration_m_s2);  // at the corners: less than the feedforward's step
}

// Energy over each move of a run on a 20° incline with the paper's friction: the drive's work
// = friction work + the potential energy's change (the kinetic energy is 0 at both ends, the
// carriage dwells there), from the logged samples alone and the library's law.
TEST(VirtualRigAxis, DriveWorkIsFrictionWorkPlusPotentialEnergyOverEachMove) {
  const FrictionRigConfig setup = axis_setup({0.01, 0.1});
  AxisRigConfig a = quiet_axis();
  a.incline_deg = 20;
  a.cycles = 1;
  const AxisRigOutput made = generate_axis_logs(setup, a, {});
  const AxisLog log = parse_axis_log(made.run_files.at(0).second);
  const AxisTrace& trace = made.traces.at(0);
  const double h = 1 / a.log_rate_Hz, G = a.moving_mass_kg * kG * std::sin(20 * std::numbers::pi / 180);
  // The moves: between the samples where the reference rests at one end and then leaves it.
  std::vector<std::size_t> rests;
  for (std::size_t k = 1; k < log.size(); ++k)
    if (trace.reference_m[k] == trace.reference_m[k - 1] && (k + 1 == log.size() || trace.reference_m[k + 1] != trace.reference_m[k]))
      rests.push_back(k);
  ASSERT_EQ(rests.size(), 1 + 2 * setup.velocity_m_s.size());  // out and back per speed
  for (std::size_t m = 0; m + 1 < rests.size(); ++m) {
    double drive_J = 0, friction_J = 0;
    for (std::size_t k = rests[m]; k < rests[m + 1]; ++k) {
      const double dx = log.position_m[k + 1] - log.position_m[k];
      drive_J += 0.5 * (log.force_N[k] + log.force_N[k + 1]) * dx;
      friction_J += axis_friction_N(a, setup.constants, dx / h) * dx;
    }
    const double potential_J = G * (log.position_m[rests[m + 1]] - log.position_m[rests[m]]);
    const double v0 = trace.velocity_m_s[rests[m]], v1 = trace.velocity_m_s[rests[m + 1]];
    const double kinetic_J = 0.5 * a.moving_mass_kg * (v1 * v1 - v0 * v0);
    EXPECT_GT(std::abs(potential_J), 1.0) << "move " << m;
    EXPECT_GT(friction_J, 0.01) << "move " << m;
    EXPECT_NEAR(drive_J, friction_J + potential_J + kinetic_J, 0.005 * friction_J + 1e-3) << "move " << m;
  }
}

// The controllers follow the reference: the cascaded P-PI within 0.1 mm (rms 5 µm), the PD within
// 1 mm (rms 0.3 mm: it sags by M g sin θ / K_p = 0.21 mm, having no integral), at the rig's
// default speeds on a 20° incline, as the encoder logs the position.
TEST(VirtualRigAxis, ControllersTrackTheReference) {
  for (const AxisController controller : {AxisController::p_pi, AxisController::pd}) {
    AxisRigConfig a;
    a.controller = controller;
    a.incline_deg = 20;
    FrictionRigConfig setup = axis_setup(FrictionRigConfig{}.velocity_m_s);
    const AxisRigOutput made = generate_axis_logs(setup, a, {});
    const AxisLog log = parse_axis_log(made.run_files.at(0).second);
    const AxisTrace& trace = made.traces.at(0);
    ASSERT_EQ(log.size(), trace.reference_m.size());
    double worst_m = 0, sum2 = 0;
    for (std::size_t k = 0; k < log.size(); ++k) {
      const double error = log.position_m[k] - trace.reference_m[k];
      worst_m = std::max(worst_m, std::abs(error));
      sum2 += error * error;
    }
    const double rms_m = std::sqrt(sum2 / static_cast<double>(log.size()));
    const bool cascaded = controller == AxisController::p_pi;
    EXPECT_LT(worst_m, cascaded ? 1e-4 : 1e-3) << to_string(controller);
    EXPECT_LT(rms_m, cascaded ? 5e-6 : 3e-4) << to_string(controller);
    EXPECT_GT(worst_m, 0) << to_string(controller);
  }
}

// At constant speed on a 30° incline the drive holds friction + G going up and G − friction going
// down: half the sum of the mean forces is M g sin θ, half the difference the law's friction,
// with the current's noise on; the horizontal axis's mean force is the friction alone.
TEST(VirtualRigAxis, InclineAddsTheWeightInBothDirections) {
  const double V = 0.05;
  const FrictionRigConfig setup = axis_setup({V});
  for (const double incline_deg : {30.0, 0.0}) {
    AxisRigConfig a;
    a.incline_deg = incline_deg;
    a.cycles = 3;
    const AxisRigOutput made = generate_axis_logs(setup, a, {});
    const AxisLog log = parse_axis_log(made.run_files.at(0).second);
    const AxisTrace& trace = made.traces.at(0);
    double up_N = 0, down_N = 0;
    std::size_t ups = 0, downs = 0;
    for (std::size_t k = 0; k < log.size(); ++k) {
      const double v = trace.velocity_m_s[k];
      if (std::abs(std::abs(v) - V) > 1e-5 * V) continue;  // at cruise speed, settled
      (v > 0 ? up_N : down_N) += log.force_N[k];
      ++(v > 0 ? ups : downs);
    }
    ASSERT_GT(ups, 1000u);
    ASSERT_GT(downs, 1000u);
    up_N /= static_cast<double>(ups);
    down_N /= static_cast<double>(downs);
    const double G = a.moving_mass_kg * kG * std::sin(incline_deg * std::numbers::pi / 180);
    const double sigma_N = a.force_constant_N_A * a.current_noise_A / std::sqrt(static_cast<double>(std::min(ups, downs)));
    EXPECT_NEAR((up_N + down_N) / 2, G, 5 * sigma_N) << incline_deg << "°";
    EXPECT_NEAR((up_N - down_N) / 2, axis_friction_N(a, setup.constants, V), 5 * sigma_N) << incline_deg << "°";
  }
}

// The log's shape: a reversal between consecutive moves (two per out-and-back but the last), never at rest for longer than a dwell
// (plus the controller's settling), the fastest speed reached, and the truth's numbers.
TEST(VirtualRigAxis, TheLogReversesAndNeverRestsLong) {
  const FrictionRigConfig setup = axis_setup();
  AxisRigConfig a;
  a.incline_deg = 20;
  const AxisRigOutput made = generate_axis_logs(setup, a, {});
  const AxisLog log = parse_axis_log(made.run_files.at(0).second);
  const nlohmann::json truth = nlohmann::json::parse(made.truth_json);
  EXPECT_EQ(truth["runs"][0]["reversals"], 2 * a.cycles * static_cast<int>(setup.velocity_m_s.size()) - 1);
  EXPECT_EQ(truth["runs"][0]["samples"], log.size());
  EXPECT_NEAR(truth["gravity_N"].get<double>(), a.moving_mass_kg * kG * std::sin(20 * std::numbers::pi / 180), 1e-9);
  const double h = 1 / a.log_rate_Hz;
  std::size_t still = 0, longest_still = 0;
  double fastest = 0;
  for (std::size_t k = 1; k < log.size(); ++k) {
    const double v = (log.position_m[k] - log.position_m[k - 1]) / h;
    still = std::abs(v) < 1e-3 ? still + 1 : 0;
    longest_still = std::max(longest_still, still);
    if (k >= 10) fastest = std::max(fastest, std::abs(log.position_m[k] - log.position_m[k - 10]) / (10 * h));
  }
  EXPECT_LE(static_cast<double>(longest_still) * h, a.dwell_s + 0.1);
  EXPECT_NEAR(fastest, 0.15, 0.01 * 0.15);
}

TEST(VirtualRigAxis, SameSeedSameBytesOtherSeedOtherNoise) {
  FrictionRigConfig setup = axis_setup({0.02, 0.1});
  AxisRigConfig a;
  a.current_noise_ar1 = 0.5;
  a.reference = AxisReference::sinusoid;
  a.duration_s = 5;
  const AxisRigOutput one = generate_axis_logs(setup, a, {}), two = generate_axis_logs(setup, a, {});
  EXPECT_EQ(one.run_files, two.run_files);
  EXPECT_EQ(one.manifest_toml, two.manifest_toml);
  EXPECT_EQ(one.truth_json, two.truth_json);
  setup.seed = 4;
  const AxisRigOutput other = generate_axis_logs(setup, a, {});
  EXPECT_NE(other.run_files.at(0).second, one.run_files.at(0).second);
  EXPECT_EQ(other.manifest_toml, one.manifest_toml);
}

// Without the trajectory keys the manifest is one the plateau reader takes as it is (a run per
// setup, its conditions as keys); with them its [raw] table names the trajectory and the incline.
TEST(VirtualRigAxis, TheFrictionLoaderReadsTheManifest) {
  FrictionRigConfig setup = axis_setup();
  setup.load_N = {1000, 2000};
  AxisRigConfig a;
  a.incline_deg = 10;
  a.trajectory_keys = false;
  const AxisRigOutput made = generate_axis_logs(setup, a, {}, {"synthetic"});
  ASSERT_EQ(made.run_files.size(), 2u);
  const fs::path dir = fresh_folder("axis");
  OutputSet out;
  for (const auto& [file, text] : made.run_files) out.add(dir / file, text);
  out.add(dir / "friction.toml", made.manifest_toml);
  out.commit();
  const FrictionDataSet set = load_friction_dataset(dir / "friction.toml");
  EXPECT_EQ(set.log.run_names, made.run_names);
  ASSERT_EQ(set.log.segmentation.size(), 2u);
  EXPECT_GT(set.log.size(), 0u);
  for (std::size_t i = 0; i < set.log.size(); i += 101) {
    EXPECT_EQ(set.log.load_N[i], setup.load_N[set.log.run[i]]);
    EXPECT_EQ(set.log.preload_um[i], 2.5);
    EXPECT_EQ(set.log.block_length_mm[i], 120.2);
  }
  fs::remove_all(dir);
  EXPECT_EQ(made.manifest_toml.find("segmentation"), std::string::npos);
  a.trajectory_keys = true;
  const std::string with_keys = generate_axis_logs(setup, a, {}).manifest_toml;
  EXPECT_NE(with_keys.find("[raw]\nforce_sign = \"follows-motion\"\nsegmentation = \"trajectory\"\naxis_incline_deg = 10\n"),
            std::string::npos)
      << with_keys;
}

TEST(VirtualRigAxis, RefusesBadSettings) {
  const FrictionRigConfig setup = axis_setup();
  const auto refused = [&](const char* what, auto change) {
    AxisRigConfig a;
    change(a);
    EXPECT_THROW(generate_axis_logs(setup, a, {}), InvalidParameter) << what;
  };
  refused("mass", [](AxisRigConfig& a) { a.moving_mass_kg = 0; });
  refused("incline", [](AxisRigConfig& a) { a.incline_deg = 95; });
  refused("stroke shorter than the ramps", [](AxisRigConfig& a) { a.stroke_m = 0.01; });
  refused("a loop too fast for the step", [](AxisRigConfig& a) { a.substeps = 1; a.velocity_bandwidth_Hz = 500; });
  refused("noise ar1", [](AxisRigConfig& a) { a.current_noise_ar1 = 1; });
  RigEffects thermal;
  set_rig_effect(thermal, "tc_lag", 5);
  EXPECT_THROW(generate_axis_logs(setup, AxisRigConfig{}, thermal), InvalidParameter);
}

}  // namespace
}  // namespace lmcal
