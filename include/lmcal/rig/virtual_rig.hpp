// The virtual rig: friction logs and thermal data sets made by the physics core, with
// the imperfections of a real rig and, on request, named physical effects that the
// paper's baseline leaves out. Every true value goes to a truth file next to the data.
//
// Imperfections (all seeded, reproducible):
//   friction: load-cell noise per sample, a zero offset per run, thermocouple noise on
//             the logged temperature; conditions beyond the load cell's range are not
//             measured (a 10 kgf cell on the paper's rig).
//   thermal:  thermocouple bias (T-type class: uniform within ±0.5 K) and noise per
//             sensor, two ambient sensors with their own biases, ambient drift and a
//             slow wave, logger resolution 0.01 K.
// Off by default (0), as real rigs show them:
//   noise_ar1 (both)   the sensor noise has memory: an AR(1) series in time order of
//                      marginal σ (noise_N, noise_K) and lag-1 autocorrelation φ,
//                      e_0 = σ z_0, e_t = φ e_{t-1} + sqrt(1 − φ²) σ z_t, restarted per run
//                      (friction: the load cell over a run's samples; thermal: every
//                      temperature channel, before the 0.01 K rounding). 0 <= φ < 1.
//   heat_variation     the heat reaching the rail differs from run to run: the run's true
//                      heat rate (and with coupling its friction-law heat) is multiplied by
//                      1 + heat_variation·z_run. No logged quantity sees it: the manifest's
//                      mean_friction_N does not. Truth: runs[].heat_factor.
//   friction_gain_error the load cell that logs mean_friction_N has one gain error g ~
//                      N(0, friction_gain_error) for the whole data set: mean_friction_N =
//                      F_true (1 + g) + N(0, friction_noise_N). Truth: friction_gain_error.
//   stated_friction_uncertainty  > 0: every run states mean_friction_uncertainty_N =
//                      stated_friction_uncertainty · mean_friction_N in the manifest (the
//                      user's claim; the rig's actual errors are the two above).
// A truth key of these options is written only when the option is on, so data made
// without them keeps its bytes. Trap: a large heat_variation or friction_gain_error can
// draw a factor <= 0; the rig refuses that seed rather than make negative heat or force.
//
// Effects (rig_effects() lists them with units and neutral values):
//   friction: the library in friction_effects.hpp (stribeck_exponent, viscous_load,
//             direction_asymmetry, seal_drag, coulomb_temperature); a newly registered
//             effect is a rig effect too
//   thermal:  the library in thermal_mechanisms.hpp, each mechanism with a rig effect
//             (convection_velocity, base_loss, coupling, tc_lag, alpha_velocity,
//             moving_source), made by the mechanism's own physics; a newly registered
//             mechanism with one is a rig effect too
//             not in the library: ambient_daily_K (with ambient_daily_seen), tc_drift_K_per_h
//
// Determinism: the same config and seed give bit-identical output on any machine
// (the random numbers come from std::mt19937_64, whose sequence the standard fixes, and
// our own normal transform, not from std::normal_distribution). The AR(1) noise filters
// the same white draws as before; heat_factor and g come from a stream of their own.
#pragma once

#include "lmcal/export.hpp"

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "lmcal/io/friction_log.hpp"
#include "lmcal/io/thermal_run.hpp"
#include "lmcal/models/friction_effects.hpp"
#include "lmcal/models/thermal_mechanisms.hpp"

namespace LMCAL_API lmcal {

struct ThermalRigEffects {
  // The value of each mechanism of the library (thermal_mechanisms.hpp) with a rig effect, by
  // slot: its parameter, or 1 for a switch; 0 leaves it out. set_rig_effect sets them by name
  // (its unit and meaning: rig_effects(), or the mechanism's header).
  std::array<double, kThermalMechanismCount> mechanisms{};
  // Not in the library (the empirical term's tests hide them): the air around the rail swings
  // daily, A sin(2π t/86400 s + φ_run) (φ_run: the run's start in the day, from a stream of
  // its own); the rail sees all of it, the logged ambient sensors only the share `seen`.
  double ambient_daily_K = 0;      // A, K
  double ambient_daily_seen = 1;   // share of the swing the ambient sensors log
  double tc_drift_K_per_h = 0;     // every rail thermocouple drifts linearly from the run's start
};

// Friction effects the library does not have (its fits and diagnoses cannot name them): the
// tests of the empirical term hide them in the data.
struct HiddenFrictionEffects {
  double running_in = 0;             // a: F ← F (1 + a exp(-s/ℓ)), s the sliding distance since the log's start
  double running_in_scale_m = 500;   // ℓ, m
  double lubricant_lag_s = 0;        // τ > 0: the law at the lubricant's temperature, a first-order lag (τ) of the logged one
  double temperature_speed = 0;      // c: F ← F + c (T - T_i) V, N per (K·m/s)
  // The law at a temperature off the logged one (an input the law does not see):
  double hot_offset_K = 0;           // d: the law at T + d where the true T > hot_above_C
  double hot_above_C = 35;
  double temperature_drift_K_per_h = 0;  // r: the law at T + r·t, t the rig's clock since the log's start
  // Friction falling over the campaign: F ← F (1 + a exp(-k/ℓ)), k = 0, 1, … the run's place in
  // the order the runs were made (FrictionRigConfig::shuffle_runs makes it differ from the design's).
  double run_decay = 0;              // a
  double run_decay_scale = 20;       // ℓ, runs
  // Each run's friction × (1 + s·z_run), z_run ~ N(0, 1) from a stream of its own: runs that
  // differ by a factor nothing logged follows.
  double run_scale_sigma = 0;        // s
  // The viscous part alone (Lb μv pc V ν, not the seal's Lb f0) × (1 + a (P/1 kN − 2)²).
  double viscous_load_curvature = 0; // a
};

struct RigEffects {
  FrictionEffects<double> friction;
  HiddenFrictionEffects hidden;
  ThermalRigEffects thermal;
};

struct RigEffectInfo {
  std::string name;
  std::string unit;
  double neutral;
  std::string description;
};

// The named effects, in a fixed order.
const std::vector<RigEffectInfo>& rig_effects();
// Sets an effect by name; InvalidParameter for an unknown name or a non-finite value.
void set_rig_effect(RigEffects& effects, std::string_view name, double value);
double rig_effect(const RigEffects& effects, std::string_view name);

struct FrictionRigConfig {
  FrictionConstants<double> constants = paper_friction_constants();
  std::vector<std::string> guides{"SRG 25C", "SRN 35C", "SRG 45C"};
  std::vector<double> preload_um{1.5, 2.5, 4.0};  // Normal, C1, C0
  std::vector<double> load_N{1000, 2000, 3000};
  std::vector<double> velocity_m_s{0.002, 0.005, 0.01, 0.02, 0.03, 0.05, 0.066, 0.083, 0.11, 0.15};
  std::vector<double> temperature_C{22, 26, 32, 40};
  std::vector<int> directions{+1, -1};
  int runs = 10;                        // repeats of the whole sweep
  // true: each setup (guide, preload, load, temperature) is a run of its own, swept over speed
  // and direction — what most rigs log; `runs` repeats the set of runs. false: a run sweeps all.
  bool one_setup_per_run = false;
  // true: the temperature changes slowest (the rig heats or cools step by step, every other
  // setup at each temperature before the next), as a rig with a heated bath does; false:
  // temperature is the innermost setup loop.
  bool temperature_outermost = false;
  // true: the runs are made in a random order (seeded), not in the design's; with
  // one_setup_per_run, what a run's place in the campaign follows is then not its setup.
  bool shuffle_runs = false;
  double noise_N = 0.15;                // load-cell noise per sample, σ
  double noise_ar1 = 0;                 // lag-1 autocorrelation of that noise within a run, [0, 1)
  double run_offset_N = 0.2;            // zero offset per run, σ
  double temperature_noise_K = 0.1;     // σ of the logged temperature
  double load_cell_range_N = 98.0665;   // 10 kgf: conditions above 95 % of it are skipped
  double seconds_per_sample = 2.0;
  std::uint64_t seed = 1;
  const GuideCatalog* catalog = nullptr;  // a user catalog searched before the built-in one
};

struct ThermalRigConfig {
  std::string guide = "SRN 35C";
  std::map<std::string, double> guide_overrides;  // catalog field -> value
  std::vector<double> velocity_m_s{0.066, 0.083, 0.11};
  int repeats = 1;                      // runs per velocity
  double load_N = 3000;
  double stroke_m = 0.2;
  double rail_length_m = 0.6;
  std::vector<double> sensor_position_m{0.0, 0.05, 0.1};
  double duration_s = 21600;
  double record_every_s = 5;
  FrictionConstants<double> constants = paper_friction_constants();
  double alpha = 0.6;                   // true heat partition (for the true source model)
  double h_W_m2K = 5.3;
  double ambient_C = 24.0;
  double ambient_drift_K_per_h = 0.25;
  double ambient_wave_K = 0.3;          // amplitude of a slow wave (2 h period)
  int ambient_sensors = 2;
  double ambient_bias_K = 0.5;          // each ambient sensor: uniform within ±
  double tc_bias_K = 0.5;               // each rail thermocouple: uniform within ±
  double noise_K = 0.05;                // σ, every temperature channel
  double noise_ar1 = 0;                 // lag-1 autocorrelation of that noise per channel, [0, 1)
  double heat_variation = 0;            // relative σ of a run's true heat rate, one draw per run
  double friction_noise_N = 0.25;       // σ of the logged mean friction force
  double friction_gain_error = 0;       // relative σ of the load cell's gain, one draw per data set
  double stated_friction_uncertainty = 0;  // > 0: mean_friction_uncertainty_N = this · mean_friction_N
  std::uint64_t seed = 1;
  // Runs as rigs produce them. A heater (heat_rate_W) heats the rail instead of the block's
  // friction: one run per repeat ("heater", "heater_r2"), velocity_m_s unused; it switches off
  // at heater_off_s and the run goes on cooling. stop_s: the block stops then (velocity 0, no
  // friction heat). Neither works with the moving source or coupling (refused).
  std::optional<double> heat_rate_W;
  std::optional<double> heater_off_s;
  std::optional<double> stop_s;
  double stated_heat_uncertainty = 0;   // > 0: heat_rate_uncertainty_W = this · heat_rate_W
  // false: no ambient columns; the manifest's ambient_C (ambient_C above) instead. The true
  // air keeps its drift and wave: zero them for a room that is truly constant.
  bool ambient_columns = true;
  const GuideCatalog* catalog = nullptr;  // a user catalog searched before the built-in one
};

struct FrictionRigOutput {
  FrictionLog log;
  std::string truth_json;
};

// A raw load-cell rig: every setup of a FrictionRigConfig (guide, preload, load, temperature)
// is a run of its own, logged as a time series while the block moves back and forth over the
// stroke at each speed in turn. A move is trapezoidal: accelerate at acceleration_m_s2 to the
// speed, cruise, decelerate, dwell at rest, reverse. Logged: time, the encoder's position
// (rounded to its resolution) or the velocity, and the load cell's signed force = the friction
// law at the instantaneous speed (with the library's friction effects; the hidden effects are
// not applied) in the motion's sense, + m·a, + the run's zero offset, + a drift, + AR(1) noise
// (FrictionRigConfig's noise_N, noise_ar1, run_offset_N).
struct RawFrictionRigConfig {
  double sample_rate_Hz = 100;
  double acceleration_m_s2 = 0.5;
  double stroke_m = 0.1;
  int cycles = 1;                      // back-and-forth moves per speed
  double dwell_s = 0.3;                // at rest at each end
  double encoder_resolution_m = 1e-6;
  double moving_mass_kg = 2.0;
  double drift_N_per_h = 0.5;          // the load cell's zero, drifting over the run
  bool log_velocity = false;           // log velocity_m_s instead of position_mm
  ForceSign force_sign = ForceSign::follows_motion;  // how the logged force is signed
};

// A constant-velocity phase of the motion, as generated: samples [first, last] of its run.
struct CruiseSegment {
  std::size_t first_sample = 0, last_sample = 0;
  double start_s = 0, end_s = 0, velocity_m_s = 0;  // signed
};

struct RawFrictionRigOutput {
  // The manifest (runs' conditions and the [raw] settings) and each run's CSV text; files
  // relative to the data set's folder: "friction/<run>.csv".
  std::string manifest_toml;
  std::vector<std::pair<std::string, std::string>> run_files;  // file name -> CSV text
  std::vector<std::string> run_names;
  std::vector<std::vector<CruiseSegment>> cruises;  // per run
  std::string truth_json;
};

RawFrictionRigOutput generate_raw_friction_logs(const FrictionRigConfig& config, const RawFrictionRigConfig& raw,
                                                const RigEffects& effects, const std::vector<std::string>& comments = {});

struct ThermalRigOutput {
  ThermalDataSet set;  // runs[i].file is "thermal/<id>.csv", relative to the data set's folder
  std::string truth_json;
};

// Throws InvalidParameter naming `parameter` unless 0 <= phi < 1 (a lag-1 autocorrelation).
void require_autocorrelation(const char* parameter, double phi);

FrictionRigOutput generate_friction_log(const FrictionRigConfig& config, const RigEffects& effects);
ThermalRigOutput generate_thermal_dataset(const ThermalRigConfig& config, const RigEffects& effects,
                                          const std::string& name);

}  // namespace lmcal
