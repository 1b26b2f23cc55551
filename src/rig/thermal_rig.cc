// The virtual rig's thermal data sets (virtual_rig.hpp).
#include "lmcal/rig/virtual_rig.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <set>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <random>

#include "lmcal/error.hpp"
#include "rig/rig_common.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/models/rail_thermal.hpp"
#include "lmcal/models/thermal_effects.hpp"
#include "lmcal/models/thermal_mechanisms.hpp"

namespace lmcal {

namespace {

// The heater's and the stop's options, checked against each other and the effects.
void validate_phases(const ThermalRigConfig& config, bool moving, bool coupled) {
  if (config.heat_rate_W) require_non_negative("heat_rate_W", *config.heat_rate_W);
  if (config.heater_off_s && !config.heat_rate_W)
    throw InvalidParameter("heater_off_s", *config.heater_off_s, "a heater (heat_rate_W) to switch off");
  if (config.heater_off_s) require_in_range("heater_off_s", *config.heater_off_s, 1e-9, config.duration_s);
  if (config.stop_s && config.heat_rate_W)
    throw InvalidParameter("stop_s", *config.stop_s, "a block heated by friction, not a heater run");
  if (config.stop_s) require_in_range("stop_s", *config.stop_s, 1e-9, config.duration_s);
  require_non_negative("stated_heat_uncertainty", config.stated_heat_uncertainty);
  const bool phased = config.heat_rate_W || config.stop_s;
  if (phased && moving) throw InvalidParameter("heat_rate_W", "a heater run or a stop needs the static source, not the moving block");
  if (phased && coupled) throw InvalidParameter("heat_rate_W", "a heater run or a stop cannot have the friction-temperature coupling");
}

// The phase that ends the heat (the heater off, the block stopped), if any, s since the start.
std::optional<double> heat_end_s(const ThermalRigConfig& config) {
  return config.heat_rate_W ? config.heater_off_s : config.stop_s;
}

// The manifest's record of the heat: the heater's heat_rate_W, or a schedule with the phase
// that ends it.
void record_heat(const ThermalRigConfig& config, double V, ThermalRun& run) {
  const std::optional<double> end_s = heat_end_s(config);
  if (config.heat_rate_W && !end_s) run.heat_rate_W = *config.heat_rate_W;
  if (config.heat_rate_W && end_s)
    run.schedule = {{.from_s = 0, .heat_rate_W = *config.heat_rate_W}, {.from_s = *end_s, .heat_rate_W = 0.0}};
  if (!config.heat_rate_W && end_s)
    run.schedule = {{.from_s = 0, .velocity_m_s = V}, {.from_s = *end_s, .velocity_m_s = 0.0}};
  if (config.heat_rate_W && config.stated_heat_uncertainty > 0)
    run.heat_rate_uncertainty_W = rig::round_to(config.stated_heat_uncertainty * *config.heat_rate_W, 4);
}

// The rig's value of each mechanism of the library (thermal_mechanisms.hpp), by slot; 0 for a
// mechanism without a rig effect or left out.
std::array<double, kThermalMechanismCount> mechanism_values(const RigEffects& effects) {
  std::array<double, kThermalMechanismCount> values{};
  for (std::size_t slot = 0; slot < kThermalMechanismCount; ++slot)
    if (const auto& rig = ThermalMechanismLibrary::infos[slot].rig) {
      values[slot] = rig_effect(effects, rig->name);
      if (rig->non_negative) require_non_negative(rig->name, values[slot]);
    }
  return values;
}

// The source model of the truth: the averaged source unless a mechanism switches it.
SourceModel truth_source(const std::array<double, kThermalMechanismCount>& values) {
  SourceModel source = SourceModel::averaged;
  ThermalMechanismLibrary::for_each([&]<class Mechanism, std::size_t slot>() {
    if (values[slot] != 0)
      if (const auto switched = Mechanism::source()) source = *switched;
  });
  return source;
}

// Whether a mechanism that is on makes the heat follow the rail temperature.
bool heat_follows_rail(const std::array<double, kThermalMechanismCount>& values) {
  bool follows = false;
  ThermalMechanismLibrary::for_each([&]<class Mechanism, std::size_t slot>() {
    if constexpr (requires { Mechanism::heat_follows_rail; }) follows = follows || (values[slot] != 0 && Mechanism::heat_follows_rail);
  });
  return follows;
}

// The true run: every mechanism that is on applied at its value, by its own physics (apply,
// or make where the rig's differs: thermal_mechanism.hpp).
void apply_mechanisms(ThermalRunSetup<double>& run, const std::array<double, kThermalMechanismCount>& values) {
  ThermalMechanismLibrary::for_each([&]<class Mechanism, std::size_t slot>() {
    if (values[slot] == 0) return;
    LMCAL_ASSERT(Mechanism::parameters().size() <= 1, "a rig effect is a mechanism of one parameter or a switch");
    if constexpr (requires { Mechanism::make(run, values[slot]); }) Mechanism::make(run, values[slot]);
    else Mechanism::template apply<double>(run, &values[slot]);
  });
}

using rig::Ar1Noise;
using rig::derive_seed;
using rig::kDailyStreamKey;
using rig::kLaterStreamKey;
using rig::positive_factor;
using rig::Rng;
using rig::round_to;

// What the runs of a data set share, checked: the guide and its block, the mechanisms that
// are on, the truth's numerics and the record times.
struct Campaign {
  GuideSpec spec;
  bool heater = false;                     // a heater heats the rail, not the block's friction
  double Lb_mm = 0, Lb1_mm = 0, pc_um = 0;  // block length, contact length, preload
  std::array<double, kThermalMechanismCount> mechanisms{};
  RailNumerics numerics;
  std::vector<double> times;
};

Campaign checked_campaign(const ThermalRigConfig& config, const RigEffects& effects) {
  validate(config.constants);
  if (config.repeats < 1) throw InvalidParameter("repeats", config.repeats, "at least 1");
  if (config.ambient_sensors < 1) throw InvalidParameter("ambient_sensors", config.ambient_sensors, "at least 1");
  require_positive("record_every_s", config.record_every_s);
  require_positive("duration_s", config.duration_s);
  Campaign c;
  c.mechanisms = mechanism_values(effects);
  require_autocorrelation("noise_ar1", config.noise_ar1);
  require_non_negative("heat_variation", config.heat_variation);
  require_non_negative("friction_gain_error", config.friction_gain_error);
  require_non_negative("stated_friction_uncertainty", config.stated_friction_uncertainty);
  c.spec = with_overrides(find_guide(config.guide, config.catalog), config.guide_overrides);
  const bool moving = truth_source(c.mechanisms) == SourceModel::moving;
  validate_phases(config, moving, heat_follows_rail(c.mechanisms));
  // A run is named after its speed in mm/s: two speeds that round alike would be one run twice.
  std::set<long> speeds_mm_s;
  for (double v : config.velocity_m_s)
    if (!speeds_mm_s.insert(std::lround(v * 1000)).second)
      throw InvalidParameter("velocity", v, "each speed once (a run per speed; --repeats repeats them)");
  c.heater = config.heat_rate_W.has_value();
  // A heater needs no friction law, hence no block length or preload (a plain bar has none).
  c.Lb_mm = c.heater ? 0.0 : require(c.spec, &GuideSpec::block_length_mm, "block_length_mm");
  c.Lb1_mm = require(c.spec, &GuideSpec::contact_length_mm, "contact_length_mm");
  c.pc_um = c.heater ? 0.0 : require(c.spec, &GuideSpec::preload_um, "preload_um");
  // Truth numerics: converged (2 mm cells; 1 s steps for the moving block, 5 s otherwise).
  c.numerics = {.source = truth_source(c.mechanisms),
                .scheme = TimeScheme::crank_nicolson,
                .half_rail_segments = static_cast<int>(std::lround(config.rail_length_m / 2 / 0.002)),
                .time_step_s = moving ? 1.0 : 5.0};
  for (long i = 0;; ++i) {
    const double t = static_cast<double>(i) * config.record_every_s;
    if (t > config.duration_s + 1e-9) break;
    c.times.push_back(t);
  }
  return c;
}

// One run's true air: drift plus a slow wave with a random phase; with the hidden daily swing,
// the rail's air has all of it and the ambient sensors log the share `seen`.
struct RunAir {
  AmbientTrace air;
  std::vector<double> logged;  // what the ambient sensors see (before bias and noise)
  double phase_rad = 0, daily_phase_rad = 0;
};

RunAir true_air(const ThermalRigConfig& config, const ThermalRigEffects& effects, const std::vector<double>& times,
                Rng& rng, std::size_t stream) {
  RunAir a;
  a.phase_rad = rng.uniform(0, 2 * std::numbers::pi);
  a.daily_phase_rad = Rng(derive_seed(config.seed ^ kDailyStreamKey, stream)).uniform(0, 2 * std::numbers::pi);
  for (double t : times) {
    const double air = config.ambient_C + config.ambient_drift_K_per_h * t / 3600 +
                       config.ambient_wave_K * std::sin(2 * std::numbers::pi * t / 7200 + a.phase_rad);
    const double daily = effects.ambient_daily_K * std::sin(2 * std::numbers::pi * t / 86400 + a.daily_phase_rad);
    a.air.time_s.push_back(t);
    a.air.temperature_C.push_back(air + daily);
    a.logged.push_back(air + effects.ambient_daily_seen * daily);
  }
  return a;
}

// One run's truth: the rail with every mechanism that is on, from the air's first temperature.
struct TrueRun {
  ThermalRunSetup<double> setup;
  RailSolution<double> solution;
};

TrueRun simulate_true_run(const ThermalRigConfig& config, const RigEffects& effects, const Campaign& c, double V,
                          double heat_factor, const AmbientTrace& air) {
  const double T0 = air.temperature_C.front();
  TrueRun run{.setup = {.velocity_m_s = V,
                        .friction = &config.constants,
                        .friction_effects = &effects.friction,
                        .conditions = {.load_N = config.load_N, .preload_um = c.pc_um, .block_length_mm = c.Lb_mm,
                                       .velocity_m_s = V, .temperature_C = T0},
                        .params = rail_material_of(c.spec),
                        .heat_factor = heat_factor}};
  RailParams<double>& params = run.setup.params;
  params.heat_partition = config.alpha;
  params.heat_rate_W = c.heater ? heat_factor * *config.heat_rate_W
                                : heat_factor * heat_rate_with_effects_W(config.constants, effects.friction,
                                                                         run.setup.conditions);
  params.h_W_m2K = config.h_W_m2K;
  params.initial_temperature_C = T0;
  // The heat ends with the heater switched off or the block stopped.
  if (const auto end_s = heat_end_s(config))
    params.heat_schedule = HeatRateSchedule<double>::steps({0.0, *end_s}, {params.heat_rate_W, 0.0});
  apply_mechanisms(run.setup, c.mechanisms);
  const RailGeometry geometry = rail_geometry_of(c.spec, config.rail_length_m, config.stroke_m, c.Lb1_mm * 1e-3, V);
  const RailOutputs outputs{
      .duration_s = c.times.back(), .sensor_positions_m = config.sensor_position_m, .output_times_s = c.times};
  run.solution = simulate_rail(geometry, c.numerics, outputs, params, air, run.setup.heat_rate);
  return run;
}

// The logger's temperature: truth + bias + AR(1) noise, at 0.01 K.
TemperatureChannel logged_channel(const ThermalRigConfig& config, std::string column, const std::vector<double>& true_C,
                                  double bias_K, Rng& rng) {
  TemperatureChannel channel{std::move(column), {}};
  Ar1Noise noise(config.noise_K, config.noise_ar1);
  for (double T : true_C) channel.values.push_back(round_to(T + bias_K + noise.next(rng.normal()), 2));
  return channel;
}

// The run's ambient columns, each with its bias; their truth.
nlohmann::json log_ambient(const ThermalRigConfig& config, const RunAir& air, Rng& rng, ThermalRun& run) {
  nlohmann::json truth = nlohmann::json::array();
  for (int a = 0; a < (config.ambient_columns ? config.ambient_sensors : 0); ++a) {
    const double bias = rng.uniform(-config.ambient_bias_K, config.ambient_bias_K);
    TemperatureChannel channel = logged_channel(config, fmt::format("ambient{}_C", a + 1), air.logged, bias, rng);
    truth.push_back({{"column", channel.name}, {"bias_K", bias}});
    run.trace.ambient.push_back(std::move(channel));
  }
  return truth;
}

// The run's thermocouples: the rail's truth through the sensors' lag and drift, each with its
// bias; their truth.
nlohmann::json log_thermocouples(const ThermalRigConfig& config, const ThermalRigEffects& effects,
                                 const std::vector<double>& times, const TrueRun& truth_run, Rng& rng, ThermalRun& run) {
  nlohmann::json truth_json = nlohmann::json::array();
  for (std::size_t s = 0; s < config.sensor_position_m.size(); ++s) {
    std::vector<double> truth(times.size());
    for (std::size_t t = 0; t < times.size(); ++t) truth[t] = truth_run.solution.temperature_C(t, s);
    auto lagged = first_order_lag(times, truth, truth_run.setup.sensor_lag_s);
    for (std::size_t t = 0; t < times.size(); ++t) lagged[t] += effects.tc_drift_K_per_h * times[t] / 3600;
    const double bias = rng.uniform(-config.tc_bias_K, config.tc_bias_K);
    TemperatureChannel channel = logged_channel(config, fmt::format("tc{}_C", s + 1), lagged, bias, rng);
    run.sensor_position_m[channel.name] = config.sensor_position_m[s];
    truth_json.push_back({{"column", channel.name}, {"position_m", config.sensor_position_m[s]}, {"bias_K", bias},
                          {"true_final_C", truth.back()}});
    run.trace.rail.push_back(std::move(channel));
  }
  return truth_json;
}

// The run's manifest entry, before its channels and its logged friction.
ThermalRun run_record(const ThermalRigConfig& config, const Campaign& c, const std::string& id, double V) {
  ThermalRun run;
  run.id = id;
  run.file = "thermal/" + id + ".csv";
  run.guide = c.spec.model;
  run.velocity_m_s = V;
  run.load_N = config.load_N;
  if (!c.heater) run.preload_um = c.pc_um;
  run.stroke_m = config.stroke_m;
  run.rail_length_m = config.rail_length_m;
  run.guide_overrides = config.guide_overrides;
  run.guide_spec = c.spec;
  record_heat(config, V, run);
  if (!config.ambient_columns) run.ambient_C = round_to(config.ambient_C, 2);
  run.trace.time_s = c.times;
  return run;
}

// The mean heat while the block moves (a stopped block makes none, its load cell reads none).
double mean_moving_heat_W(const ThermalRigConfig& config, const std::vector<double>& times,
                          const RailSolution<double>& solution) {
  double mean_Q = 0, moving_records = 0;
  for (std::size_t t = 0; t < times.size(); ++t) {
    if (config.stop_s && times[t] >= *config.stop_s) continue;
    mean_Q += solution.heat_rate_W[t];
    moving_records += 1;
  }
  return mean_Q / moving_records;
}

// One run of the data set, made: its truth, its logged channels and friction. `later` is the
// data set's stream of the later options (the heat factor), `friction_gain` its load cell's.
ThermalRun make_run(const ThermalRigConfig& config, const RigEffects& effects, const Campaign& c, double V,
                    const std::string& id, std::size_t stream, Rng& later, double friction_gain,
                    nlohmann::json& runs_truth) {
  Rng rng(derive_seed(config.seed, stream));
  const double heat_factor =
      positive_factor("heat_variation", config.heat_variation, later.normal(), "the heat factor of run " + id);
  const RunAir air = true_air(config, effects.thermal, c.times, rng, stream);
  const TrueRun truth = simulate_true_run(config, effects, c, V, heat_factor, air.air);
  const RailParams<double>& params = truth.setup.params;
  const RailSolution<double>& sol = truth.solution;

  ThermalRun run = run_record(config, c, id, V);
  const nlohmann::json ambient_truth = log_ambient(config, air, rng, run);
  const nlohmann::json tc_truth = log_thermocouples(config, effects.thermal, c.times, truth, rng, run);
  const double mean_Q = mean_moving_heat_W(config, c.times, sol);
  // The load cell sees the friction, not the heat factor; it has the data set's gain error.
  // Logged as the run's mean (its time average over the records), as a load cell's log
  // averages to: with coupling, below the friction at the start.
  const double mean_friction_true_N = c.heater ? 0.0 : mean_Q / heat_factor / V;
  if (!c.heater) {
    run.mean_friction_N = round_to(mean_friction_true_N * friction_gain + config.friction_noise_N * rng.normal(), 2);
    if (config.stated_friction_uncertainty > 0)
      run.mean_friction_uncertainty_N = round_to(config.stated_friction_uncertainty * *run.mean_friction_N, 4);
  }
  nlohmann::json j = {{"id", id},
                      {"velocity_m_s", V},
                      {"alpha", params.heat_partition},
                      {"h_W_m2K", params.h_W_m2K},
                      {"base_loss_W_mK", params.base_loss_W_mK},
                      {"initial_temperature_C", params.initial_temperature_C},
                      {"heat_rate_start_W", sol.heat_rate_W.front()},
                      {"heat_rate_end_W", sol.heat_rate_W.back()},
                      {"heat_rate_mean_W", mean_Q},
                      {"mean_friction_true_N", mean_friction_true_N},
                      {"ambient", {{"base_C", config.ambient_C},
                                   {"drift_K_per_h", config.ambient_drift_K_per_h},
                                   {"wave_K", config.ambient_wave_K},
                                   {"wave_period_s", 7200},
                                   {"wave_phase_rad", air.phase_rad},
                                   {"sensors", ambient_truth}}},
                      {"thermocouples", tc_truth}};
  if (config.heat_variation != 0) j["heat_factor"] = heat_factor;
  if (c.heater) j["heater"] = {{"heat_rate_W", *config.heat_rate_W}};
  if (config.heater_off_s) j["heater"]["off_s"] = *config.heater_off_s;
  if (config.stop_s) j["stop_s"] = *config.stop_s;
  if (!config.ambient_columns) j["ambient"]["logged"] = {{"columns", false}, {"ambient_C", *run.ambient_C}};
  if (effects.thermal.ambient_daily_K != 0) {
    j["ambient"]["daily_K"] = effects.thermal.ambient_daily_K;
    j["ambient"]["daily_period_s"] = 86400;
    j["ambient"]["daily_phase_rad"] = air.daily_phase_rad;
    j["ambient"]["daily_seen_by_sensors"] = effects.thermal.ambient_daily_seen;
  }
  runs_truth.push_back(std::move(j));
  return run;
}

// The data set's truth file.
std::string data_set_truth(const ThermalRigConfig& config, const RigEffects& effects, const Campaign& c,
                           nlohmann::json runs_truth, double friction_gain) {
  nlohmann::json truth = {
      {"kind", "thermal"},
      {"generator", fmt::format("lmcal {} virtual rig", LMCAL_VERSION)},
      {"seed", config.seed},
      {"guide", c.spec.model},
      {"friction_constants", rig::constants_json(config.constants)},
      {"effects", rig::effects_json(effects)},
      {"alpha_reference", config.alpha},
      {"alpha_source_model", to_string(c.numerics.source)},
      {"h_reference_W_m2K", config.h_W_m2K},
      {"load_N", config.load_N},
      {"preload_um", c.pc_um},
      {"stroke_m", config.stroke_m},
      {"rail_length_m", config.rail_length_m},
      {"noise_K", config.noise_K},
      {"friction_noise_N", config.friction_noise_N},
      {"truth_numerics", {{"source", to_string(c.numerics.source)},
                          {"scheme", to_string(c.numerics.scheme)},
                          {"half_rail_segments", c.numerics.half_rail_segments},
                          {"time_step_s", c.numerics.time_step_s}}},
      {"runs", std::move(runs_truth)}};
  if (config.noise_ar1 != 0) truth["noise_ar1"] = config.noise_ar1;
  if (config.heat_variation != 0) {
    truth["heat_variation"] = config.heat_variation;
    truth["heat_variation_note"] = "runs[].heat_factor multiplies the heat reaching the rail (heat_rate_* include "
                                   "it); mean_friction_true_N and the logged mean_friction_N do not see it";
  }
  if (config.friction_gain_error != 0) {
    truth["friction_gain_error_sigma"] = config.friction_gain_error;
    truth["friction_gain_error"] = friction_gain - 1;
  }
  if (config.stated_friction_uncertainty != 0)
    truth["stated_friction_uncertainty"] = config.stated_friction_uncertainty;
  return truth.dump(2) + "\n";
}

}  // namespace

ThermalRigOutput generate_thermal_dataset(const ThermalRigConfig& config, const RigEffects& effects,
                                          const std::string& name) {
  const Campaign c = checked_campaign(config, effects);
  ThermalRigOutput out;
  out.set.name = name;
  out.set.description = "Synthetic: made by the lmcal virtual rig (see the truth file); not measured.";
  if (config.catalog) out.set.catalog_file = config.catalog->source;
  Rng later(config.seed ^ kLaterStreamKey);
  const double friction_gain =  // 1 + g
      positive_factor("friction_gain_error", config.friction_gain_error, later.normal(), "the load cell's gain");
  nlohmann::json runs_truth = nlohmann::json::array();
  std::size_t stream = 0;
  // A heater data set has one "speed" (none: the block stands still).
  const std::vector<double> speeds = c.heater ? std::vector<double>{0.0} : config.velocity_m_s;
  for (double V : speeds)
    for (int r = 0; r < config.repeats; ++r, ++stream) {
      const std::string stem = c.heater ? std::string("heater") : fmt::format("v{:03.0f}", V * 1000);
      const std::string id = config.repeats == 1 ? stem : fmt::format("{}_r{}", stem, r + 1);
      out.set.runs.push_back(make_run(config, effects, c, V, id, stream, later, friction_gain, runs_truth));
    }
  out.truth_json = data_set_truth(config, effects, c, std::move(runs_truth), friction_gain);
  return out;
}

}  // namespace lmcal
