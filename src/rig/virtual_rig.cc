#include "lmcal/rig/virtual_rig.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <random>

#include "lmcal/error.hpp"
#include "rig/rig_common.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/models/friction_terms.hpp"
#include "lmcal/models/rail_thermal.hpp"
#include "lmcal/models/thermal_effects.hpp"

namespace lmcal {

namespace {

using rig::Ar1Noise;
using rig::derive_seed;
using rig::Rng;
using rig::round_to;

// A named effect of the rig: a friction effect (a slot of FrictionEffects, from the
// library in friction_effects.hpp), a hidden one (a member of HiddenFrictionEffects) or a
// thermal one: a mechanism of the library in thermal_mechanisms.hpp (a slot of
// ThermalRigEffects::mechanisms) or one the library lacks (a member).
struct EffectEntry {
  RigEffectInfo info;
  std::optional<std::size_t> friction_slot;
  double ThermalRigEffects::*thermal = nullptr;
  double HiddenFrictionEffects::*hidden = nullptr;
  // false: the truth file lists it only when one of these later effects is on (they came after
  // data sets were committed, and data made without them keeps its bytes).
  bool listed_when_neutral = true;
  std::optional<std::size_t> mechanism_slot;  // held in ThermalRigEffects::mechanisms
  bool mechanism_listed_when_off = false;     // a mechanism the truth file lists at 0 too (below)

  double& ref(RigEffects& e) const {
    return friction_slot    ? e.friction[*friction_slot]
           : hidden         ? e.hidden.*hidden
           : mechanism_slot ? e.thermal.mechanisms[*mechanism_slot]
                            : e.thermal.*thermal;
  }
  bool is_thermal() const { return thermal || mechanism_slot; }
  double value(const RigEffects& e) const { return const_cast<EffectEntry*>(this)->ref(const_cast<RigEffects&>(e)); }
};

// The mechanisms the rig made before it read the library: data sets made since list them in
// their truth file even when off, and keep their bytes so. A closed list: a mechanism
// registered later is listed only when on, so that adding one leaves every data set as it was.
bool listed_when_off(std::string_view rig_name) {
  constexpr std::string_view kBefore[] = {"convection_velocity", "base_loss", "coupling", "tc_lag", "alpha_velocity",
                                          "moving_source"};
  return std::find(std::begin(kBefore), std::end(kBefore), rig_name) != std::end(kBefore);
}

const std::vector<EffectEntry>& effect_table() {
  static const std::vector<EffectEntry> table = [] {
    std::vector<EffectEntry> t;
    for (std::size_t slot = 0; slot < kFrictionEffectCount; ++slot) {
      const FrictionEffectInfo& f = FrictionEffectLibrary::infos[slot];
      if (f.dynamics) continue;  // the drive's mass and weight: the axis rig's own settings (axis_rig.hpp)
      t.push_back({{f.name, f.unit, f.neutral, f.description}, slot});
    }
    // The hidden friction effects; the later ones (listed_when_neutral false) came after data
    // sets were committed.
    struct Hidden {
      const char* name;
      const char* unit;
      double neutral;
      const char* description;
      double HiddenFrictionEffects::*member;
      bool listed_when_neutral;
    };
    using H = HiddenFrictionEffects;
    const Hidden hidden[] = {
        {"running_in", "1", 0.0, "not in the library: F (1 + a exp(-s/l)), s the sliding distance since the log's start",
         &H::running_in, true},
        {"running_in_scale_m", "m", H{}.running_in_scale_m, "the running-in's distance scale l", &H::running_in_scale_m, true},
        {"lubricant_lag_s", "s", 0.0,
         "not in the library: the law at the lubricant's temperature, lagging the logged one with time constant tau",
         &H::lubricant_lag_s, true},
        {"temperature_speed", "N/(K m/s)", 0.0, "not in the library: F + c (T - T_i) V", &H::temperature_speed, true},
        {"hot_offset_K", "K", 0.0, "not in the library: the law at T + d where T > hot_above_C", &H::hot_offset_K, false},
        {"hot_above_C", "C", H{}.hot_above_C, "the temperature above which hot_offset_K applies", &H::hot_above_C, false},
        {"temperature_drift_K_per_h", "K/h", 0.0,
         "not in the library: the law at T + r t, t the rig's clock since the log's start", &H::temperature_drift_K_per_h,
         false},
        {"run_decay", "1", 0.0, "not in the library: F (1 + a exp(-k/l)), k the run's place in the order made",
         &H::run_decay, false},
        {"run_decay_scale", "runs", H{}.run_decay_scale, "the run decay's scale l", &H::run_decay_scale, false},
        {"run_scale_sigma", "1", 0.0, "not in the library: each run's friction x (1 + s z), z ~ N(0, 1) per run",
         &H::run_scale_sigma, false},
        {"viscous_load_curvature", "1", 0.0,
         "not in the library: the viscous part (not the seal's) times 1 + a (P/1 kN - 2)^2", &H::viscous_load_curvature,
         false}};
    for (const Hidden& h : hidden)
      t.push_back({{h.name, h.unit, h.neutral, h.description}, std::nullopt, nullptr, h.member, h.listed_when_neutral});
    auto thermal = [&](const char* name, const char* unit, const char* description, double ThermalRigEffects::*member,
                       double neutral = 0.0) { t.push_back({{name, unit, neutral, description}, std::nullopt, member}); };
    // The library's mechanisms with a rig effect, in its order.
    for (std::size_t slot = 0; slot < kThermalMechanismCount; ++slot)
      if (const auto& rig = ThermalMechanismLibrary::infos[slot].rig)
        t.push_back({{rig->name, rig->unit, 0.0, rig->description}, std::nullopt, nullptr, nullptr, true, slot,
                     listed_when_off(rig->name)});
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

std::uint32_t index_of(std::vector<std::string>& names, const std::string& name) {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<std::uint32_t>(i);
  names.push_back(name);
  return static_cast<std::uint32_t>(names.size() - 1);
}

}  // namespace

namespace rig {

nlohmann::json effects_json(const RigEffects& effects) {
  nlohmann::json j = nlohmann::json::object();
  bool later_on = false;
  for (const auto& e : effect_table()) later_on = later_on || (!e.listed_when_neutral && e.value(effects) != e.info.neutral);
  for (const auto& e : effect_table()) {
    const double value = e.value(effects);
    if (!e.listed_when_neutral && !later_on) continue;
    // A mechanism registered since the rig read the library is listed when on, so that data
    // made without it keeps its bytes (listed_when_off).
    if (e.mechanism_slot && !e.mechanism_listed_when_off && value == e.info.neutral) continue;
    j[e.info.name] = {{"value", value}, {"unit", e.info.unit}, {"active", value != e.info.neutral}};
  }
  return j;
}

nlohmann::json constants_json(const FrictionConstants<double>& k) {
  return {{"k1", k.k1},       {"k2", k.k2},         {"mu_st", k.mu_st},
          {"v_st_m_s", k.v_st_m_s}, {"mu_v", k.mu_v}, {"beta_per_K", k.beta_per_K},
          {"f0", k.f0},       {"nu_ref_mm2_s", k.nu_ref_mm2_s}, {"T_ref_C", k.T_ref_C}};
}

}  // namespace rig


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

namespace rig {

void require_no_thermal_effects(const RigEffects& effects) {
  std::vector<std::string> given;
  for (const auto& e : effect_table())
    if (e.is_thermal() && e.value(effects) != e.info.neutral) given.push_back(e.info.name);
  if (!given.empty())
    throw InvalidParameter("--effect", fmt::format("{} {} thermal: a friction log does not see {}; give {} to generate thermal",
                                                   fmt::join(given, ", "), given.size() == 1 ? "is" : "are",
                                                   given.size() == 1 ? "it" : "them", given.size() == 1 ? "it" : "them"));
}

}  // namespace rig

namespace {

// A setup of the sweep: the guide, preload, load and temperature a run holds.
struct Setup {
  std::string model;
  double pc, P, T;
};

// The setups, in sweep order (temperature innermost, or outermost when asked).
std::vector<Setup> sweep_setups(const FrictionRigConfig& config) {
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
  return setups;
}

// The first setup of each run, in the order the runs are made.
std::vector<std::size_t> run_firsts(const FrictionRigConfig& config, std::size_t setups, int run_count) {
  std::vector<std::size_t> run_first(static_cast<std::size_t>(run_count));
  for (std::size_t r = 0; r < run_first.size(); ++r) run_first[r] = config.one_setup_per_run ? r % setups : 0;
  if (config.shuffle_runs) {  // Fisher-Yates from a stream of its own
    Rng order(derive_seed(config.seed ^ rig::kLaterStreamKey, 1));
    for (std::size_t r = run_first.size(); r > 1; --r)
      std::swap(run_first[r - 1], run_first[static_cast<std::size_t>(order.uniform() * static_cast<double>(r))]);
  }
  return run_first;
}

// Each run's hidden scale, from a stream of its own (the runs' streams stay as they were).
std::vector<double> run_scales(const FrictionRigConfig& config, const HiddenFrictionEffects& hidden, std::size_t runs) {
  std::vector<double> run_scale(runs, 1.0);
  if (hidden.run_scale_sigma != 0) {
    Rng scales(derive_seed(config.seed ^ rig::kLaterStreamKey, 2));
    for (double& scale : run_scale)
      scale = rig::positive_factor("run_scale_sigma", hidden.run_scale_sigma, scales.normal(), "a run's friction");
  }
  return run_scale;
}

// Where a sample of run r stands when it is logged: the lubricant's temperature, the distance
// slid and the rig's clock since the log's start (the hidden effects' inputs).
struct SampleState {
  double lubricant_C, distance_m, clock_s;
  int run;
  double run_scale;
};

// The true friction of a sample: the law with the library's effects at the lubricant's
// temperature, and the hidden effects (not in the library): running-in over the sliding
// distance, the run's decay and scale, the viscous part's load curvature, a temperature × speed
// term.
double true_friction_N(const FrictionRigConfig& config, const RigEffects& effects, const FrictionConditions<double>& c,
                       const SampleState& at) {
  const HiddenFrictionEffects& hidden = effects.hidden;
  FrictionConditions<double> at_lubricant = c;
  if (hidden.lubricant_lag_s > 0) at_lubricant.temperature_C = at.lubricant_C;
  if (c.temperature_C > hidden.hot_above_C) at_lubricant.temperature_C += hidden.hot_offset_K;
  at_lubricant.temperature_C += hidden.temperature_drift_K_per_h * at.clock_s / 3600;
  double F = friction_force_with_effects_N(config.constants, effects.friction, at_lubricant);
  if (hidden.running_in != 0) F *= 1 + hidden.running_in * std::exp(-at.distance_m / hidden.running_in_scale_m);
  if (hidden.run_decay != 0) F *= 1 + hidden.run_decay * std::exp(-at.run / hidden.run_decay_scale);
  F *= at.run_scale;
  if (hidden.viscous_load_curvature != 0) {
    const auto b = friction_breakdown(config.constants, at_lubricant);
    const double viscous_N = law_part_N(config.constants, b, c.block_length_mm, TermCovariate::viscous_N);
    F += hidden.viscous_load_curvature * viscous_N * std::pow(c.load_N / 1000 - 2, 2);
  }
  F += hidden.temperature_speed * (c.temperature_C - config.constants.T_ref_C) * c.velocity_m_s;
  return F;
}

// The friction log's truth file.
std::string friction_truth(const FrictionRigConfig& config, const RigEffects& effects, nlohmann::json runs,
                           std::size_t out_of_range) {
  nlohmann::json truth = {
      {"kind", "friction"},
      {"generator", fmt::format("lmcal {} virtual rig", LMCAL_VERSION)},
      {"seed", config.seed},
      {"friction_constants", rig::constants_json(config.constants)},
      {"effects", rig::effects_json(effects)},
      {"noise_N", config.noise_N},
      {"run_offset_sigma_N", config.run_offset_N},
      {"one_setup_per_run", config.one_setup_per_run},
      {"temperature_noise_K", config.temperature_noise_K},
      {"load_cell_range_N", config.load_cell_range_N},
      {"conditions_beyond_load_cell_skipped", out_of_range},
      {"runs", std::move(runs)},
      {"note", "friction_N = law with effects at the true temperature + zero_offset_N (per run) + noise; "
               "temperature_C is the true temperature plus noise"}};
  if (config.noise_ar1 != 0) truth["noise_ar1"] = config.noise_ar1;
  if (config.temperature_outermost) truth["temperature_outermost"] = true;
  if (config.shuffle_runs) truth["shuffle_runs"] = true;
  return truth.dump(2) + "\n";
}

}  // namespace

FrictionRigOutput generate_friction_log(const FrictionRigConfig& config, const RigEffects& effects) {
  rig::require_no_thermal_effects(effects);
  validate(config.constants);
  if (config.runs < 1) throw InvalidParameter("runs", config.runs, "at least 1");
  require_non_negative("noise_N", config.noise_N);
  require_autocorrelation("noise_ar1", config.noise_ar1);
  require_non_negative("run_offset_N", config.run_offset_N);
  require_non_negative("temperature_noise_K", config.temperature_noise_K);
  require_positive("load_cell_range_N", config.load_cell_range_N);
  require_positive("running_in_scale_m", effects.hidden.running_in_scale_m);
  require_non_negative("lubricant_lag_s", effects.hidden.lubricant_lag_s);
  require_positive("run_decay_scale", effects.hidden.run_decay_scale);

  FrictionRigOutput out;
  FrictionLog& log = out.log;
  log.force_sensor = ForceSensor::load_cell;  // the rig's: a load cell on a horizontal axis
  log.incline_stated = true;
  nlohmann::json runs = nlohmann::json::array();
  std::size_t out_of_range = 0;
  // A run covers all the setups or one.
  const std::vector<Setup> setups = sweep_setups(config);
  const std::size_t per_run = config.one_setup_per_run ? 1 : setups.size();
  const int run_count = config.runs * static_cast<int>(setups.size() / per_run);
  const std::vector<std::size_t> run_first = run_firsts(config, setups.size(), run_count);
  const std::vector<double> run_scale = run_scales(config, effects.hidden, run_first.size());
  double distance_m = 0;  // slid since the log's start (the hidden running-in)
  double clock_s = 0;     // the rig's clock since the log's start (the hidden temperature drift)
  for (int r = 0; r < run_count; ++r) {
    Rng rng(derive_seed(config.seed, static_cast<std::uint64_t>(r)));
    const double offset_N = config.run_offset_N * rng.normal();
    Ar1Noise load_cell(config.noise_N, config.noise_ar1);
    const std::string run_name = fmt::format("run{:02d}", r + 1);
    runs.push_back({{"run", run_name}, {"zero_offset_N", offset_N}});
    if (effects.hidden.run_scale_sigma != 0) runs.back()["friction_scale"] = run_scale[static_cast<std::size_t>(r)];
    const std::uint32_t run_index = index_of(log.run_names, run_name);
    double time_s = 0;
    // The lubricant's temperature (hidden lag): its state at the last logged sample, and the
    // temperature it was relaxing towards since.
    double lubricant_C = std::numeric_limits<double>::quiet_NaN(), lubricant_target_C = 0, lubricant_time_s = 0;
    const std::size_t first = run_first[static_cast<std::size_t>(r)];
    for (std::size_t k = first; k < first + per_run; ++k) {
      const Setup& setup = setups[k];
      const GuideSpec& spec = find_guide(setup.model, config.catalog);
      const double Lb = require(spec, &GuideSpec::block_length_mm, "block_length_mm");
      const std::uint32_t guide_index = index_of(log.guide_names, spec.model);
      for (double V : config.velocity_m_s)
        for (int direction : config.directions) {
          const FrictionConditions<double> c{.load_N = setup.P, .preload_um = setup.pc, .block_length_mm = Lb,
                                             .velocity_m_s = V, .temperature_C = setup.T,
                                             .direction = double(direction)};
          validate(c);
          const double lag_s = effects.hidden.lubricant_lag_s;
          double lubricant_now_C = setup.T;
          if (lag_s > 0 && !std::isnan(lubricant_C))
            lubricant_now_C = lubricant_target_C + (lubricant_C - lubricant_target_C) *
                                                       std::exp(-(time_s - lubricant_time_s) / lag_s);
          const double F = true_friction_N(config, effects, c,
                                           {lubricant_now_C, distance_m, clock_s, r, run_scale[static_cast<std::size_t>(r)]});
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
          clock_s += config.seconds_per_sample;
        }
    }
  }
  out.truth_json = friction_truth(config, effects, std::move(runs), out_of_range);
  return out;
}

}  // namespace lmcal
