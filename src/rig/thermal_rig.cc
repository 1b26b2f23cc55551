// The virtual rig's thermal data sets (virtual_rig.hpp).
#include "lmcal/rig/virtual_rig.hpp"

#include <fmt/format.h>

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

}  // namespace

using rig::Ar1Noise;
using rig::derive_seed;
using rig::kDailyStreamKey;
using rig::kLaterStreamKey;
using rig::positive_factor;
using rig::Rng;
using rig::round_to;

ThermalRigOutput generate_thermal_dataset(const ThermalRigConfig& config, const RigEffects& effects,
                                          const std::string& name) {
  validate(config.constants);
  if (config.repeats < 1) throw InvalidParameter("repeats", config.repeats, "at least 1");
  if (config.ambient_sensors < 1) throw InvalidParameter("ambient_sensors", config.ambient_sensors, "at least 1");
  require_positive("record_every_s", config.record_every_s);
  require_positive("duration_s", config.duration_s);
  require_non_negative("tc_lag", effects.thermal.tc_lag);
  require_autocorrelation("noise_ar1", config.noise_ar1);
  require_non_negative("heat_variation", config.heat_variation);
  require_non_negative("friction_gain_error", config.friction_gain_error);
  require_non_negative("stated_friction_uncertainty", config.stated_friction_uncertainty);
  const GuideSpec spec = with_overrides(find_guide(config.guide, config.catalog), config.guide_overrides);
  const bool moving = effects.thermal.moving_source != 0;
  const bool coupled = effects.thermal.coupling != 0;
  validate_phases(config, moving, coupled);
  // A run is named after its speed in mm/s: two speeds that round alike would be one run twice.
  std::set<long> speeds_mm_s;
  for (double v : config.velocity_m_s)
    if (!speeds_mm_s.insert(std::lround(v * 1000)).second)
      throw InvalidParameter("velocity", v, "each speed once (a run per speed; --repeats repeats them)");
  const bool heater = config.heat_rate_W.has_value();
  // A heater needs no friction law, hence no block length or preload (a plain bar has none).
  const double Lb = heater ? 0.0 : require(spec, &GuideSpec::block_length_mm, "block_length_mm");
  const double Lb1 = require(spec, &GuideSpec::contact_length_mm, "contact_length_mm");
  const double pc = heater ? 0.0 : require(spec, &GuideSpec::preload_um, "preload_um");
  // Truth numerics: converged (2 mm cells; 1 s steps for the moving block, 5 s otherwise).
  const RailNumerics numerics{.source = moving ? SourceModel::moving : SourceModel::averaged,
                              .scheme = TimeScheme::crank_nicolson,
                              .half_rail_segments = static_cast<int>(std::lround(config.rail_length_m / 2 / 0.002)),
                              .time_step_s = moving ? 1.0 : 5.0};

  std::vector<double> times;
  for (long i = 0;; ++i) {
    const double t = static_cast<double>(i) * config.record_every_s;
    if (t > config.duration_s + 1e-9) break;
    times.push_back(t);
  }

  ThermalRigOutput out;
  out.set.name = name;
  out.set.description = "Synthetic: made by the lmcal virtual rig (see the truth file); not measured.";
  if (config.catalog) out.set.catalog_file = config.catalog->source;
  nlohmann::json runs_truth = nlohmann::json::array();
  // The logger's temperature: truth + bias + AR(1) noise, at 0.01 K.
  const auto logged_channel = [&](std::string column, const std::vector<double>& true_C, double bias_K, Rng& rng) {
    TemperatureChannel channel{std::move(column), {}};
    Ar1Noise noise(config.noise_K, config.noise_ar1);
    for (double T : true_C) channel.values.push_back(round_to(T + bias_K + noise.next(rng.normal()), 2));
    return channel;
  };
  Rng later(config.seed ^ kLaterStreamKey);
  const double friction_gain =  // 1 + g
      positive_factor("friction_gain_error", config.friction_gain_error, later.normal(), "the load cell's gain");
  std::size_t stream = 0;
  // A heater data set has one "speed" (none: the block stands still).
  const std::vector<double> speeds = heater ? std::vector<double>{0.0} : config.velocity_m_s;
  for (double V : speeds) {
    for (int r = 0; r < config.repeats; ++r, ++stream) {
      Rng rng(derive_seed(config.seed, stream));
      const std::string stem = heater ? std::string("heater") : fmt::format("v{:03.0f}", V * 1000);
      const std::string id = config.repeats == 1 ? stem : fmt::format("{}_r{}", stem, r + 1);
      const double heat_factor =
          positive_factor("heat_variation", config.heat_variation, later.normal(), "the heat factor of run " + id);
      // The true ambient: drift plus a slow wave with a random phase; with the hidden daily
      // swing, the rail's air has all of it and the ambient sensors log the share `seen`.
      const double phase = rng.uniform(0, 2 * std::numbers::pi);
      const double daily_phase = Rng(derive_seed(config.seed ^ kDailyStreamKey, stream)).uniform(0, 2 * std::numbers::pi);
      AmbientTrace ambient;
      std::vector<double> ambient_logged;  // what the ambient sensors see (before bias and noise)
      for (double t : times) {
        const double air = config.ambient_C + config.ambient_drift_K_per_h * t / 3600 +
                           config.ambient_wave_K * std::sin(2 * std::numbers::pi * t / 7200 + phase);
        const double daily = effects.thermal.ambient_daily_K * std::sin(2 * std::numbers::pi * t / 86400 + daily_phase);
        ambient.time_s.push_back(t);
        ambient.temperature_C.push_back(air + daily);
        ambient_logged.push_back(air + effects.thermal.ambient_daily_seen * daily);
      }
      const double T0 = ambient.temperature_C.front();
      auto heat_at = [&](double T) {
        const FrictionConditions<double> c{.load_N = config.load_N, .preload_um = pc, .block_length_mm = Lb,
                                           .velocity_m_s = V, .temperature_C = T};
        return heat_factor * heat_rate_with_effects_W(config.constants, effects.friction, c);
      };
      const RailGeometry geometry = rail_geometry_of(spec, config.rail_length_m, config.stroke_m, Lb1 * 1e-3, V);
      RailParams<double> params = rail_material_of(spec);
      params.heat_partition = alpha_with_velocity(config.alpha, effects.thermal.alpha_velocity, V);
      params.heat_rate_W = heater ? heat_factor * *config.heat_rate_W : heat_at(T0);
      params.h_W_m2K = convection_with_velocity(config.h_W_m2K, effects.thermal.convection_velocity, V);
      params.initial_temperature_C = T0;
      params.base_loss_W_mK = effects.thermal.base_loss;
      // The heat ends with the heater switched off or the block stopped.
      if (const auto end_s = heat_end_s(config))
        params.heat_schedule = HeatRateSchedule<double>::steps({0.0, *end_s}, {params.heat_rate_W, 0.0});
      const RailOutputs outputs{
          .duration_s = times.back(), .sensor_positions_m = config.sensor_position_m, .output_times_s = times};
      const HeatRateModel<double> coupling = heat_at;
      const auto sol = simulate_rail(geometry, numerics, outputs, params, ambient,
                                     coupled ? coupling : HeatRateModel<double>{});

      ThermalRun run;
      run.id = id;
      run.file = "thermal/" + id + ".csv";
      run.guide = spec.model;
      run.velocity_m_s = V;
      run.load_N = config.load_N;
      if (!heater) run.preload_um = pc;
      run.stroke_m = config.stroke_m;
      run.rail_length_m = config.rail_length_m;
      run.guide_overrides = config.guide_overrides;
      run.guide_spec = spec;
      record_heat(config, V, run);
      if (!config.ambient_columns) run.ambient_C = round_to(config.ambient_C, 2);
      run.trace.time_s = times;
      nlohmann::json ambient_truth = nlohmann::json::array(), tc_truth = nlohmann::json::array();
      for (int a = 0; a < (config.ambient_columns ? config.ambient_sensors : 0); ++a) {
        const double bias = rng.uniform(-config.ambient_bias_K, config.ambient_bias_K);
        TemperatureChannel channel =
            logged_channel(fmt::format("ambient{}_C", a + 1), ambient_logged, bias, rng);
        ambient_truth.push_back({{"column", channel.name}, {"bias_K", bias}});
        run.trace.ambient.push_back(std::move(channel));
      }
      for (std::size_t s = 0; s < config.sensor_position_m.size(); ++s) {
        std::vector<double> truth(times.size());
        for (std::size_t t = 0; t < times.size(); ++t) truth[t] = sol.temperature_C(t, s);
        auto lagged = first_order_lag(times, truth, effects.thermal.tc_lag);
        for (std::size_t t = 0; t < times.size(); ++t) lagged[t] += effects.thermal.tc_drift_K_per_h * times[t] / 3600;
        const double bias = rng.uniform(-config.tc_bias_K, config.tc_bias_K);
        TemperatureChannel channel = logged_channel(fmt::format("tc{}_C", s + 1), lagged, bias, rng);
        run.sensor_position_m[channel.name] = config.sensor_position_m[s];
        tc_truth.push_back({{"column", channel.name}, {"position_m", config.sensor_position_m[s]}, {"bias_K", bias},
                            {"true_final_C", truth.back()}});
        run.trace.rail.push_back(std::move(channel));
      }
      // The mean heat while the block moves (a stopped block makes none, its load cell reads none).
      double mean_Q = 0, moving_records = 0;
      for (std::size_t t = 0; t < times.size(); ++t) {
        if (config.stop_s && times[t] >= *config.stop_s) continue;
        mean_Q += sol.heat_rate_W[t];
        moving_records += 1;
      }
      mean_Q /= moving_records;
      // The load cell sees the friction, not the heat factor; it has the data set's gain error.
      // Logged as the run's mean (its time average over the records), as a load cell's log
      // averages to: with coupling, below the friction at the start.
      const double mean_friction_true_N = heater ? 0.0 : mean_Q / heat_factor / V;
      if (!heater) {
        run.mean_friction_N =
            round_to(mean_friction_true_N * friction_gain + config.friction_noise_N * rng.normal(), 2);
        if (config.stated_friction_uncertainty > 0)
          run.mean_friction_uncertainty_N = round_to(config.stated_friction_uncertainty * *run.mean_friction_N, 4);
      }
      runs_truth.push_back({{"id", id},
                            {"velocity_m_s", V},
                            {"alpha", params.heat_partition},
                            {"h_W_m2K", params.h_W_m2K},
                            {"base_loss_W_mK", params.base_loss_W_mK},
                            {"initial_temperature_C", T0},
                            {"heat_rate_start_W", sol.heat_rate_W.front()},
                            {"heat_rate_end_W", sol.heat_rate_W.back()},
                            {"heat_rate_mean_W", mean_Q},
                            {"mean_friction_true_N", mean_friction_true_N},
                            {"ambient", {{"base_C", config.ambient_C},
                                         {"drift_K_per_h", config.ambient_drift_K_per_h},
                                         {"wave_K", config.ambient_wave_K},
                                         {"wave_period_s", 7200},
                                         {"wave_phase_rad", phase},
                                         {"sensors", ambient_truth}}},
                            {"thermocouples", tc_truth}});
      if (config.heat_variation != 0) runs_truth.back()["heat_factor"] = heat_factor;
      if (heater) runs_truth.back()["heater"] = {{"heat_rate_W", *config.heat_rate_W}};
      if (config.heater_off_s) runs_truth.back()["heater"]["off_s"] = *config.heater_off_s;
      if (config.stop_s) runs_truth.back()["stop_s"] = *config.stop_s;
      if (!config.ambient_columns)
        runs_truth.back()["ambient"]["logged"] = {{"columns", false}, {"ambient_C", *run.ambient_C}};
      if (effects.thermal.ambient_daily_K != 0) {
        runs_truth.back()["ambient"]["daily_K"] = effects.thermal.ambient_daily_K;
        runs_truth.back()["ambient"]["daily_period_s"] = 86400;
        runs_truth.back()["ambient"]["daily_phase_rad"] = daily_phase;
        runs_truth.back()["ambient"]["daily_seen_by_sensors"] = effects.thermal.ambient_daily_seen;
      }
      out.set.runs.push_back(std::move(run));
    }
  }
  nlohmann::json truth = {
      {"kind", "thermal"},
      {"generator", fmt::format("lmcal {} virtual rig", LMCAL_VERSION)},
      {"seed", config.seed},
      {"guide", spec.model},
      {"friction_constants", rig::constants_json(config.constants)},
      {"effects", rig::effects_json(effects)},
      {"alpha_reference", config.alpha},
      {"alpha_source_model", to_string(numerics.source)},
      {"h_reference_W_m2K", config.h_W_m2K},
      {"load_N", config.load_N},
      {"preload_um", pc},
      {"stroke_m", config.stroke_m},
      {"rail_length_m", config.rail_length_m},
      {"noise_K", config.noise_K},
      {"friction_noise_N", config.friction_noise_N},
      {"truth_numerics", {{"source", to_string(numerics.source)},
                          {"scheme", to_string(numerics.scheme)},
                          {"half_rail_segments", numerics.half_rail_segments},
                          {"time_step_s", numerics.time_step_s}}},
      {"runs", runs_truth}};
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
  out.truth_json = truth.dump(2) + "\n";
  return out;
}

}  // namespace lmcal
