#include "lmcal/rig/virtual_rig.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "lmcal/error.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/models/rail_thermal.hpp"

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

}  // namespace
}  // namespace lmcal
