// The virtual rig's raw load-cell logs: trapezoidal moves over the stroke, sampled as a rig
// logs them (virtual_rig.hpp).
#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "io/toml_text.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/io/csv_writer.hpp"
#include "rig/rig_common.hpp"

namespace lmcal {

namespace {

using rig::Ar1Noise;
using rig::Rng;

// One phase of constant acceleration (0: a cruise or a dwell).
struct Phase {
  double t0_s, duration_s, x0_m, v0_m_s, a_m_s2;
  double end_s() const { return t0_s + duration_s; }
  double position(double t) const {
    const double tau = t - t0_s;
    return x0_m + v0_m_s * tau + 0.5 * a_m_s2 * tau * tau;
  }
  double velocity(double t) const { return v0_m_s + a_m_s2 * (t - t0_s); }
};

// Rest at the stroke's start, then for every speed and cycle a move towards +x and one back,
// each accelerate-cruise-decelerate-dwell.
std::vector<Phase> motion_profile(const std::vector<double>& speeds, const RawFrictionRigConfig& raw) {
  std::vector<Phase> phases;
  double t = 0, x = -0.5 * raw.stroke_m;
  const auto add = [&](double duration, double v0, double a) {
    phases.push_back({t, duration, x, v0, a});
    x = phases.back().position(t + duration);
    t += duration;
  };
  add(raw.dwell_s, 0, 0);
  for (double V : speeds) {
    const double ramp_s = V / raw.acceleration_m_s2;
    const double cruise_m = raw.stroke_m - V * ramp_s;  // the two ramps cover V·ramp_s together
    if (!(cruise_m > 0))
      throw InvalidParameter("stroke_m", raw.stroke_m,
                             fmt::format("longer than the ramps to {} m/s at {} m/s²", V, raw.acceleration_m_s2));
    for (int c = 0; c < raw.cycles; ++c)
      for (double sense : {1.0, -1.0}) {
        add(ramp_s, 0, sense * raw.acceleration_m_s2);
        add(cruise_m / V, sense * V, 0);
        add(ramp_s, sense * V, -sense * raw.acceleration_m_s2);
        add(raw.dwell_s, 0, 0);
      }
  }
  return phases;
}

void validate(const RawFrictionRigConfig& raw) {
  const auto positive = [](const char* name, double v) {
    if (!(v > 0)) throw InvalidParameter(name, v, "> 0");
  };
  positive("sample_rate_Hz", raw.sample_rate_Hz);
  positive("acceleration_m_s2", raw.acceleration_m_s2);
  positive("stroke_m", raw.stroke_m);
  positive("encoder_resolution_m", raw.encoder_resolution_m);
  if (raw.cycles < 1) throw InvalidParameter("cycles", raw.cycles, ">= 1");
  if (!(raw.dwell_s >= 0)) throw InvalidParameter("dwell_s", raw.dwell_s, ">= 0");
  if (!(raw.moving_mass_kg >= 0)) throw InvalidParameter("moving_mass_kg", raw.moving_mass_kg, ">= 0");
  if (!std::isfinite(raw.drift_N_per_h)) throw InvalidParameter("drift_N_per_h", raw.drift_N_per_h, "finite");
}

}  // namespace

RawFrictionRigOutput generate_raw_friction_logs(const FrictionRigConfig& config, const RawFrictionRigConfig& raw,
                                                const RigEffects& effects, const std::vector<std::string>& comments) {
  rig::require_no_thermal_effects(effects);
  validate(raw);
  require_autocorrelation("noise_ar1", config.noise_ar1);
  const std::vector<Phase> phases = motion_profile(config.velocity_m_s, raw);
  const double dt_s = 1.0 / raw.sample_rate_Hz;
  const auto samples = static_cast<std::size_t>(std::floor(phases.back().end_s() / dt_s)) + 1;

  RawFrictionRigOutput out;
  std::string manifest = fmt::format(
      "# SYNTHETIC raw load-cell runs made by the lmcal virtual rig, not measured.\n"
      "name = \"virtual raw rig\"\n\n[raw]\nforce_sign = {}\nmoving_mass_kg = {}\n",
      manifest::toml_string(to_string(raw.force_sign)), raw.moving_mass_kg);
  nlohmann::json runs = nlohmann::json::array();
  int r = 0;
  for (const rig::RunSetup& setup : rig::run_setups(config)) {
      const GuideSpec& spec = *setup.spec;
      const std::string name = fmt::format("run{:02d}", ++r);
      Rng rng(rig::derive_seed(config.seed, static_cast<std::uint64_t>(r - 1)));
      const double offset_N = config.run_offset_N * rng.normal();
      Ar1Noise load_cell(config.noise_N, config.noise_ar1);
      FrictionConditions<double> c = setup.conditions;
      CsvText csv({"time_s", raw.log_velocity ? "velocity_m_s" : "position_mm", "force_N"}, comments);
      std::vector<CruiseSegment> cruises;
      std::size_t phase = 0;
      double turn_m = phases.front().x0_m;  // where the carriage last rested (every move starts from rest)
      for (std::size_t k = 0; k < samples; ++k) {
        const double t = static_cast<double>(k) * dt_s;
        while (phase + 1 < phases.size() && t >= phases[phase].end_s()) ++phase;
        const Phase& p = phases[phase];
        const double v = p.velocity(t);
        const double sense = v > 0 ? 1.0 : v < 0 ? -1.0 : 0.0;
        c.velocity_m_s = std::abs(v);
        c.direction = sense < 0 ? -1.0 : 1.0;
        c.acceleration_m_s2 = p.a_m_s2;
        c.position_m = p.position(t);
        if (sense == 0) turn_m = c.position_m;
        c.distance_since_reversal_m = std::abs(c.position_m - turn_m);
        const double friction_N = sense == 0 ? 0.0 : friction_force_with_effects_N(config.constants, effects.friction, c);
        const double drive_N = sense * friction_N + raw.moving_mass_kg * p.a_m_s2;  // towards +x
        const double zero_N = offset_N + raw.drift_N_per_h * t / 3600.0 + load_cell.next(rng.normal());
        double logged_N = drive_N;
        if (raw.force_sign == ForceSign::opposes_motion) logged_N = -drive_N;
        if (raw.force_sign == ForceSign::magnitude) logged_N = friction_N + sense * raw.moving_mass_kg * p.a_m_s2;
        const double motion = raw.log_velocity
                                  ? rig::round_to(v, 7)
                                  : rig::round_to(std::round(p.position(t) / raw.encoder_resolution_m) *
                                                      raw.encoder_resolution_m * 1e3, 6);
        csv.cell(rig::round_to(t, 6)).cell(motion).cell(rig::round_to(logged_N + zero_N, 4)).end_row();
        if (p.a_m_s2 != 0 || sense == 0) continue;
        if (cruises.empty() || cruises.back().last_sample + 1 != k || cruises.back().velocity_m_s != v)
          cruises.push_back({k, k, t, t, v});
        cruises.back().last_sample = k;
        cruises.back().end_s = t;
      }
      std::string file;
      manifest += rig::raw_run_manifest_toml(name, spec.model, c, config.constants.nu_ref_mm2_s,
                                             config.catalog != nullptr, file);
      nlohmann::json segments = nlohmann::json::array();
      for (const CruiseSegment& s : cruises)
        segments.push_back({{"first_sample", s.first_sample}, {"last_sample", s.last_sample},
                            {"start_s", s.start_s}, {"end_s", s.end_s}, {"velocity_m_s", s.velocity_m_s}});
      runs.push_back({{"run", name}, {"zero_offset_N", offset_N}, {"cruises", segments}});
      out.run_files.emplace_back(file, csv.str());
      out.run_names.push_back(name);
      out.cruises.push_back(std::move(cruises));
  }
  out.manifest_toml = manifest;
  nlohmann::json truth = {
      {"kind", "friction_raw"},
      {"generator", fmt::format("lmcal {} virtual rig", LMCAL_VERSION)},
      {"seed", config.seed},
      {"friction_constants", rig::constants_json(config.constants)},
      {"effects", rig::effects_json(effects)},
      {"noise_N", config.noise_N},
      {"noise_ar1", config.noise_ar1},
      {"run_offset_sigma_N", config.run_offset_N},
      {"sample_rate_Hz", raw.sample_rate_Hz},
      {"acceleration_m_s2", raw.acceleration_m_s2},
      {"stroke_m", raw.stroke_m},
      {"encoder_resolution_m", raw.encoder_resolution_m},
      {"moving_mass_kg", raw.moving_mass_kg},
      {"drift_N_per_h", raw.drift_N_per_h},
      {"force_sign", to_string(raw.force_sign)},
      {"runs", runs},
      {"note", "force = the friction law (library effects, not the hidden ones) at the instantaneous speed in the "
               "motion's sense + moving_mass·a + zero_offset_N + drift + noise; cruises are the constant-velocity "
               "phases, by sample index"}};
  out.truth_json = truth.dump(2) + "\n";
  return out;
}

}  // namespace lmcal
