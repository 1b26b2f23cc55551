#include "lmcal/rig/virtual_rig.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <random>

#include "lmcal/error.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/models/rail_thermal.hpp"
#include "lmcal/models/thermal_effects.hpp"

namespace lmcal {

namespace {

// Reproducible random numbers: mt19937_64's sequence is fixed by the standard, and the
// transforms below are ours (std::normal_distribution differs between libraries).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  double normal() {  // Box-Muller
    const double u1 = 1.0 - uniform(), u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }

 private:
  std::mt19937_64 engine_;
};

// Independent streams per run from one seed (splitmix64).
std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// The random numbers of the later options (heat_factor, the gain error) come from a
// generator of their own, so the per-run streams above, and every data set made without
// these options, stay as they were.
constexpr std::uint64_t kLaterStreamKey = 0x6A09E667F3BCC909ull;
// The phase of the daily ambient swing of each run (its start in the day): a stream of its own.
constexpr std::uint64_t kDailyStreamKey = 0xBB67AE8584CAA73Bull;

// Sensor noise with memory: an AR(1) series of marginal σ and lag-1 autocorrelation φ,
// e_0 = σ z_0, e_t = φ e_{t-1} + sqrt(1 − φ²) σ z_t. The caller draws the white z_t, so the
// stream is the same for any φ, and φ = 0 gives σ z_t exactly (the bytes of old data).
class Ar1Noise {
 public:
  Ar1Noise(double sigma, double phi) : sigma_(sigma), phi_(phi), innovation_(std::sqrt(1 - phi * phi)) {}
  double next(double z) {
    unit_ = started_ ? phi_ * unit_ + innovation_ * z : z;
    started_ = true;
    return sigma_ * unit_;
  }

 private:
  double sigma_, phi_, innovation_;
  double unit_ = 0;  // e_t / σ
  bool started_ = false;
};

// 1 + relative_sigma · z, refused when it is not > 0 (no negative heat or gain).
double positive_factor(const char* parameter, double relative_sigma, double z, const std::string& what) {
  const double factor = 1 + relative_sigma * z;
  if (!(factor > 0)) {
    throw InvalidParameter(parameter, relative_sigma,
                           fmt::format("small enough that 1 + {}·z > 0 ({}; this seed drew z = {:.3f})", parameter,
                                       what, z));
  }
  return factor;
}

// Rounds to `decimals` places; dividing the integer by a power of ten gives the double
// nearest to the decimal, so the CSV shows "22.08", not "22.080000000000002".
double round_to(double value, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(value * scale) / scale;
}

// A named effect of the rig: a friction effect (a slot of FrictionEffects, from the
// library in friction_effects.hpp) or a thermal one (a member of ThermalRigEffects).
struct EffectEntry {
  RigEffectInfo info;
  std::optional<std::size_t> friction_slot;
  double ThermalRigEffects::*thermal = nullptr;
  double HiddenFrictionEffects::*hidden = nullptr;

  double& ref(RigEffects& e) const {
    return friction_slot ? e.friction[*friction_slot] : hidden ? e.hidden.*hidden : e.thermal.*thermal;
  }
  double value(const RigEffects& e) const { return const_cast<EffectEntry*>(this)->ref(const_cast<RigEffects&>(e)); }
};

const std::vector<EffectEntry>& effect_table() {
  static const std::vector<EffectEntry> table = [] {
    std::vector<EffectEntry> t;
    for (std::size_t slot = 0; slot < kFrictionEffectCount; ++slot) {
      const FrictionEffectInfo& f = FrictionEffectLibrary::infos[slot];
      t.push_back({{f.name, f.unit, f.neutral, f.description}, slot});
    }
    auto hidden = [&](const char* name, const char* unit, double neutral, const char* description,
                      double HiddenFrictionEffects::*member) {
      t.push_back({{name, unit, neutral, description}, std::nullopt, nullptr, member});
    };
    hidden("running_in", "1", 0.0, "not in the library: F (1 + a exp(-s/l)), s the sliding distance since the log's start",
           &HiddenFrictionEffects::running_in);
    hidden("running_in_scale_m", "m", HiddenFrictionEffects{}.running_in_scale_m, "the running-in's distance scale l",
           &HiddenFrictionEffects::running_in_scale_m);
    hidden("lubricant_lag_s", "s", 0.0,
           "not in the library: the law at the lubricant's temperature, lagging the logged one with time constant tau",
           &HiddenFrictionEffects::lubricant_lag_s);
    hidden("temperature_speed", "N/(K m/s)", 0.0, "not in the library: F + c (T - T_i) V", &HiddenFrictionEffects::temperature_speed);
    auto thermal = [&](const char* name, const char* unit, const char* description, double ThermalRigEffects::*member,
                       double neutral = 0.0) { t.push_back({{name, unit, neutral, description}, std::nullopt, member}); };
    thermal("convection_velocity", "W/m2K/sqrt(m/s)", "forced convection h = h0 + c sqrt(V)",
            &ThermalRigEffects::convection_velocity);
    thermal("base_loss", "W/mK", "heat loss through the rail base to the bed (at ambient)", &ThermalRigEffects::base_loss);
    thermal("coupling", "0/1", "Q from the friction law at the rail temperature (two-way coupling)",
            &ThermalRigEffects::coupling);
    thermal("tc_lag", "s", "thermocouple first-order time constant", &ThermalRigEffects::tc_lag);
    thermal("alpha_velocity", "1/(m/s)", "α = α0 + s (V - 0.1 m/s)", &ThermalRigEffects::alpha_velocity);
    thermal("moving_source", "0/1", "the block moves (truth simulated with the moving source)",
            &ThermalRigEffects::moving_source);
    thermal("ambient_daily_K", "K",
            "not in the library: the air swings daily, A sin(2 pi t/86400 s + phase of the run); the rail sees all of it",
            &ThermalRigEffects::ambient_daily_K);
    thermal("ambient_daily_seen", "1", "the share of that daily swing the logged ambient sensors see",
            &ThermalRigEffects::ambient_daily_seen, 1.0);
    thermal("tc_drift_K_per_h", "K/h", "not in the library: every rail thermocouple drifts linearly from the run's start",
            &ThermalRigEffects::tc_drift_K_per_h);
    return t;
  }();
  return table;
}

const EffectEntry& find_effect(std::string_view name) {
  for (const auto& e : effect_table())
    if (e.info.name == name) return e;
  std::string known;
  for (const auto& e : effect_table()) known += (known.empty() ? "" : ", ") + e.info.name;
  throw InvalidParameter("effect", fmt::format("unknown effect '{}'; known: {}", name, known));
}

nlohmann::json effects_json(const RigEffects& effects) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& e : effect_table()) {
    const double value = e.value(effects);
    j[e.info.name] = {{"value", value}, {"unit", e.info.unit}, {"active", value != e.info.neutral}};
  }
  return j;
}

nlohmann::json constants_json(const FrictionConstants<double>& k) {
  return {{"k1", k.k1},       {"k2", k.k2},         {"mu_st", k.mu_st},
          {"v_st_m_s", k.v_st_m_s}, {"mu_v", k.mu_v}, {"beta_per_K", k.beta_per_K},
          {"f0", k.f0},       {"nu_ref_mm2_s", k.nu_ref_mm2_s}, {"T_ref_C", k.T_ref_C}};
}

std::uint32_t index_of(std::vector<std::string>& names, const std::string& name) {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<std::uint32_t>(i);
  names.push_back(name);
  return static_cast<std::uint32_t>(names.size() - 1);
}

}  // namespace

const std::vector<RigEffectInfo>& rig_effects() {
  static const std::vector<RigEffectInfo> infos = [] {
    std::vector<RigEffectInfo> v;
    for (const auto& e : effect_table()) v.push_back(e.info);
    return v;
  }();
  return infos;
}

void set_rig_effect(RigEffects& effects, std::string_view name, double value) {
  require_finite(std::string(name).c_str(), value);
  find_effect(name).ref(effects) = value;
}

double rig_effect(const RigEffects& effects, std::string_view name) {
  return find_effect(name).value(effects);
}

void require_autocorrelation(const char* parameter, double phi) {
  if (!(phi >= 0 && phi < 1)) throw InvalidParameter(parameter, phi, "a value in [0, 1)");
}

FrictionRigOutput generate_friction_log(const FrictionRigConfig& config, const RigEffects& effects) {
  validate(config.constants);
  if (config.runs < 1) throw InvalidParameter("runs", config.runs, "at least 1");
  require_non_negative("noise_N", config.noise_N);
  require_autocorrelation("noise_ar1", config.noise_ar1);
  require_non_negative("run_offset_N", config.run_offset_N);
  require_non_negative("temperature_noise_K", config.temperature_noise_K);
  require_positive("load_cell_range_N", config.load_cell_range_N);
  require_positive("running_in_scale_m", effects.hidden.running_in_scale_m);
  require_non_negative("lubricant_lag_s", effects.hidden.lubricant_lag_s);

  FrictionRigOutput out;
  FrictionLog& log = out.log;
  nlohmann::json runs = nlohmann::json::array();
  std::size_t out_of_range = 0;
  // The setups, in sweep order; a run covers all of them or one.
  struct Setup {
    std::string model;
    double pc, P, T;
  };
  std::vector<Setup> setups;
  for (const auto& model : config.guides)
    for (double pc : config.preload_um)
      for (double P : config.load_N)
        for (double T : config.temperature_C) setups.push_back({model, pc, P, T});
  if (config.temperature_outermost)
    std::stable_sort(setups.begin(), setups.end(), [&](const Setup& a, const Setup& b) {
      auto rank = [&](double T) { return std::find(config.temperature_C.begin(), config.temperature_C.end(), T); };
      return rank(a.T) < rank(b.T);
    });
  const std::size_t per_run = config.one_setup_per_run ? 1 : setups.size();
  const int run_count = config.runs * static_cast<int>(setups.size() / per_run);
  double distance_m = 0;  // slid since the log's start (the hidden running-in)
  for (int r = 0; r < run_count; ++r) {
    Rng rng(derive_seed(config.seed, static_cast<std::uint64_t>(r)));
    const double offset_N = config.run_offset_N * rng.normal();
    Ar1Noise load_cell(config.noise_N, config.noise_ar1);
    const std::string run_name = fmt::format("run{:02d}", r + 1);
    runs.push_back({{"run", run_name}, {"zero_offset_N", offset_N}});
    const std::uint32_t run_index = index_of(log.run_names, run_name);
    double time_s = 0;
    // The lubricant's temperature (hidden lag): its state at the last logged sample, and the
    // temperature it was relaxing towards since.
    double lubricant_C = std::numeric_limits<double>::quiet_NaN(), lubricant_target_C = 0, lubricant_time_s = 0;
    const std::size_t first = config.one_setup_per_run ? static_cast<std::size_t>(r) % setups.size() : 0;
    for (std::size_t k = first; k < first + per_run; ++k) {
      const Setup& setup = setups[k];
      const GuideSpec& spec = builtin_catalog().find(setup.model);
      const double Lb = require(spec, &GuideSpec::block_length_mm, "block_length_mm");
      const std::uint32_t guide_index = index_of(log.guide_names, spec.model);
      for (double V : config.velocity_m_s)
        for (int direction : config.directions) {
          const FrictionConditions<double> c{.load_N = setup.P, .preload_um = setup.pc, .block_length_mm = Lb,
                                             .velocity_m_s = V, .temperature_C = setup.T,
                                             .direction = double(direction)};
          validate(c);
          // The hidden effects (not in the library): the law at the lubricant's temperature,
          // running-in over the sliding distance, a temperature × speed term.
          const HiddenFrictionEffects& hidden = effects.hidden;
          FrictionConditions<double> at_lubricant = c;
          double lubricant_now_C = setup.T;
          if (hidden.lubricant_lag_s > 0 && !std::isnan(lubricant_C))
            lubricant_now_C = lubricant_target_C + (lubricant_C - lubricant_target_C) *
                                                       std::exp(-(time_s - lubricant_time_s) / hidden.lubricant_lag_s);
          if (hidden.lubricant_lag_s > 0) at_lubricant.temperature_C = lubricant_now_C;
          double F = friction_force_with_effects_N(config.constants, effects.friction, at_lubricant);
          if (hidden.running_in != 0) F *= 1 + hidden.running_in * std::exp(-distance_m / hidden.running_in_scale_m);
          F += hidden.temperature_speed * (setup.T - config.constants.T_ref_C) * V;
          // Draw the noise even for skipped conditions, so the sequence does not depend on them;
          // the load cell's noise series runs over the logged samples only.
          const double z = rng.normal();
          const double temperature_noise = config.temperature_noise_K * rng.normal();
          if (F > 0.95 * config.load_cell_range_N) {
            if (r < static_cast<int>(setups.size() / per_run)) ++out_of_range;
            continue;
          }
          FrictionConditions<double> logged = c;
          logged.temperature_C = round_to(setup.T + temperature_noise, 2);
          log.append(run_index, guide_index, time_s, logged, round_to(F + offset_N + load_cell.next(z), 3),
                     config.constants.nu_ref_mm2_s);
          lubricant_C = lubricant_now_C;
          lubricant_target_C = setup.T;
          lubricant_time_s = time_s;
          time_s += config.seconds_per_sample;
          distance_m += V * config.seconds_per_sample;
        }
    }
  }
  nlohmann::json truth = {
      {"kind", "friction"},
      {"generator", fmt::format("lmcal {} virtual rig", LMCAL_VERSION)},
      {"seed", config.seed},
      {"friction_constants", constants_json(config.constants)},
      {"effects", effects_json(effects)},
      {"noise_N", config.noise_N},
      {"run_offset_sigma_N", config.run_offset_N},
      {"one_setup_per_run", config.one_setup_per_run},
      {"temperature_noise_K", config.temperature_noise_K},
      {"load_cell_range_N", config.load_cell_range_N},
      {"conditions_beyond_load_cell_skipped", out_of_range},
      {"runs", runs},
      {"note", "friction_N = law with effects at the true temperature + zero_offset_N (per run) + noise; "
               "temperature_C is the true temperature plus noise"}};
  if (config.noise_ar1 != 0) truth["noise_ar1"] = config.noise_ar1;
  if (config.temperature_outermost) truth["temperature_outermost"] = true;
  out.truth_json = truth.dump(2) + "\n";
  return out;
}

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
  const GuideSpec spec = with_overrides(builtin_catalog().find(config.guide), config.guide_overrides);
  const double Lb = require(spec, &GuideSpec::block_length_mm, "block_length_mm");
  const double Lb1 = require(spec, &GuideSpec::contact_length_mm, "contact_length_mm");
  const double pc = require(spec, &GuideSpec::preload_um, "preload_um");
  const bool moving = effects.thermal.moving_source != 0;
  const bool coupled = effects.thermal.coupling != 0;
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
  for (double V : config.velocity_m_s) {
    for (int r = 0; r < config.repeats; ++r, ++stream) {
      Rng rng(derive_seed(config.seed, stream));
      const std::string id = config.repeats == 1 ? fmt::format("v{:03.0f}", V * 1000)
                                                 : fmt::format("v{:03.0f}_r{}", V * 1000, r + 1);
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
      const RailGeometry geometry{.rail_length_m = config.rail_length_m,
                                  .area_m2 = require(spec, &GuideSpec::area_m2, "area_m2"),
                                  .perimeter_m = require(spec, &GuideSpec::perimeter_m, "perimeter_m"),
                                  .stroke_m = config.stroke_m,
                                  .contact_length_m = Lb1 * 1e-3,
                                  .velocity_m_s = V};
      const RailParams<double> params{
          .heat_partition = alpha_with_velocity(config.alpha, effects.thermal.alpha_velocity, V),
          .heat_rate_W = heat_at(T0),
          .h_W_m2K = convection_with_velocity(config.h_W_m2K, effects.thermal.convection_velocity, V),
          .conductivity_W_mK = require(spec, &GuideSpec::conductivity_W_mK, "conductivity_W_mK"),
          .density_kg_m3 = require(spec, &GuideSpec::density_kg_m3, "density_kg_m3"),
          .specific_heat_J_kgK = require(spec, &GuideSpec::specific_heat_J_kgK, "specific_heat_J_kgK"),
          .initial_temperature_C = T0,
          .base_loss_W_mK = effects.thermal.base_loss};
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
      run.preload_um = pc;
      run.stroke_m = config.stroke_m;
      run.rail_length_m = config.rail_length_m;
      run.guide_overrides = config.guide_overrides;
      run.trace.time_s = times;
      nlohmann::json ambient_truth = nlohmann::json::array(), tc_truth = nlohmann::json::array();
      for (int a = 0; a < config.ambient_sensors; ++a) {
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
      double mean_Q = 0;
      for (double q : sol.heat_rate_W) mean_Q += q;
      mean_Q /= static_cast<double>(sol.heat_rate_W.size());
      // The load cell sees the friction, not the heat factor; it has the data set's gain error.
      // Logged as the run's mean (its time average over the records), as a load cell's log
      // averages to: with coupling, below the friction at the start.
      const double mean_friction_true_N = mean_Q / heat_factor / V;
      run.mean_friction_N =
          round_to(mean_friction_true_N * friction_gain + config.friction_noise_N * rng.normal(), 2);
      if (config.stated_friction_uncertainty > 0)
        run.mean_friction_uncertainty_N = round_to(config.stated_friction_uncertainty * *run.mean_friction_N, 4);
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
      {"friction_constants", constants_json(config.constants)},
      {"effects", effects_json(effects)},
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
