// The virtual rig's closed-loop positioning axis: the log a machine's own drive writes while
// its controller moves the carriage along ordinary trajectories (PHYSICS.md §8), with the
// friction law of the library (friction.hpp and the effects of friction_effects.hpp) inside.
//
// Plant (SI units; +x points up the incline, θ = 0 horizontal, 90° vertical):
//
//   M ẍ = F_motor − s(ẋ) · F_f(|ẋ|) − M g sin θ,     F_motor = K_f · i,    g = 9.80665 m/s²
//   s(v) = tanh(v / v_s)                    the regularised sgn: v_s = regularisation_m_s
//
// F_f is friction_force_with_effects_N at the run's conditions (guide, load, preload,
// temperature of the FrictionRigConfig's setup) and |ẋ|, in the motion's sense; the hidden
// effects are not applied. Near rest the tanh makes the friction a steep viscous law (slope
// F_f(0)/v_s): no stick-slip and no static friction, which the log's readers treat by a
// rule of their own anyway.
//
// Controller, updated every integration step and held over it (the drive's current loop is
// taken as ideal, no saturation; it sees the true position and velocity, the encoder's
// quantisation is the log's), e = x_ref − x:
//   pd:    F = M ω² e + 2 ζ ω M ė + a_ff M a_ref,               ω = 2π pd_bandwidth_Hz
//   p-pi:  v_cmd = v_ref + K_p e,  F = K_v (v_cmd − v) + K_i ∫(v_cmd − v) dt + a_ff M a_ref,
//          K_v = M 2π velocity_bandwidth_Hz,  K_i = K_v 2π velocity_integral_Hz
// Reference:
//   trapezoidal: for each speed V of FrictionRigConfig::velocity_m_s, `cycles` moves from 0 to
//                +L and back (accelerate at acceleration_m_s2, cruise, decelerate, dwell_s at
//                each end), L = min(stroke_m, V²/a + V·cruise_s): every speed cruises cruise_s
//                unless the stroke is shorter; a reversal between consecutive moves.
//   sinusoid:    x_ref = A (1 − cos 2π f t) for duration_s (starts at rest; reversals every
//                half period, speeds 0 … 2π f A).
// Integration: semi-implicit Euler at dt = 1 / (log_rate_Hz · substeps): the velocity step
// takes the friction at the new velocity (Newton on the library law, so the steep tanh near
// rest is stable for any v_s), the position step the new velocity (symplectic Euler).
//
// Logged at log_rate_Hz, one CSV per run (time_s, position_mm, force_N):
//   position_mm = the position rounded to encoder_resolution_m,
//   force_N     = K_f (i + i_offset + n),  n AR(1) noise of σ current_noise_A and lag-1
//                 autocorrelation current_noise_ar1 — the drive's force with its measurement
//                 noise, not the friction: it carries M·a and M g sin θ.
// The manifest (friction.toml) names each run's conditions as keys; its [raw] table carries
// force_sign = "follows-motion" and, with trajectory_keys, segmentation = "trajectory" and
// axis_incline_deg (a reader without trajectory support refuses those two keys: switch them
// off for it). Truth: M, θ, M g sin θ, K_f, the constants and effects, noise, controller gains,
// reference settings, and per run its conditions, reversals and tracking error.
//
// Example: a 40 kg carriage on a 20° incline, cascaded controller, the rig's default speeds.
//   lmcal::AxisRigConfig axis{.incline_deg = 20};
//   lmcal::FrictionRigConfig setup;  setup.guides = {"SRN 35C"}; setup.preload_um = {2.5};
//   setup.load_N = {1000}; setup.temperature_C = {26}; setup.runs = 1;
//   auto made = lmcal::generate_axis_logs(setup, axis, {});
//
// Trap: FrictionRigConfig's load-cell settings (noise_N, run_offset_N, noise_ar1, directions,
// load_cell_range_N, seconds_per_sample, one_setup_per_run) do not apply here: every setup is a
// run of its own, and the noise is the current's.
#pragma once

#include "lmcal/export.hpp"

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "lmcal/rig/virtual_rig.hpp"

namespace LMCAL_API lmcal {

enum class AxisController { pd, p_pi };
std::string_view to_string(AxisController controller);  // "pd", "p-pi"
// "pd", "p-pi"; InvalidParameter otherwise.
AxisController parse_axis_controller(std::string_view name);

enum class AxisReference { trapezoidal, sinusoid };
std::string_view to_string(AxisReference reference);  // "trapezoidal", "sinusoid"
AxisReference parse_axis_reference(std::string_view name);

struct AxisRigConfig {
  double moving_mass_kg = 40;            // M
  double incline_deg = 0;                // θ, [-90, 90]; +x up the incline
  double force_constant_N_A = 80;        // K_f
  AxisController controller = AxisController::p_pi;
  double pd_bandwidth_Hz = 20;           // pd: ω / 2π
  double pd_damping = 0.7;               // pd: ζ
  double position_gain_1_s = 50;         // p-pi: K_p
  double velocity_bandwidth_Hz = 100;    // p-pi: K_v / (2π M)
  double velocity_integral_Hz = 15;      // p-pi: K_i / (2π K_v)
  double acceleration_feedforward = 1;   // a_ff: the share of M·a_ref fed forward
  AxisReference reference = AxisReference::trapezoidal;
  double acceleration_m_s2 = 1;          // trapezoidal
  double cruise_s = 1;                   // trapezoidal: cruise of every move, unless the stroke is shorter
  double stroke_m = 0.3;                 // trapezoidal: the longest move
  int cycles = 2;                        // trapezoidal: out-and-back moves per speed
  double dwell_s = 0.05;                 // trapezoidal: at each end of a move (and before the first)
  double sine_amplitude_m = 0.05;        // sinusoid: A
  double sine_frequency_Hz = 0.5;        // sinusoid: f
  double duration_s = 60;                // sinusoid: length of a run
  double log_rate_Hz = 1000;
  int substeps = 10;                     // integration (and control) steps per logged sample
  double regularisation_m_s = 1e-4;      // v_s
  double encoder_resolution_m = 1e-6;
  double current_noise_A = 0.02;         // σ of the logged current's noise
  double current_noise_ar1 = 0;          // its lag-1 autocorrelation (between logged samples), [0, 1)
  double current_offset_A = 0;           // a constant offset of the logged current
  bool trajectory_keys = true;           // [raw] segmentation = "trajectory", axis_incline_deg
};

// A run's true motion at the logged samples (not written; for checks and plots).
struct AxisTrace {
  std::vector<double> time_s, reference_m, position_m, velocity_m_s;
  std::vector<double> drive_N;     // K_f · i, the force on the carriage (no noise, no offset)
  std::vector<double> friction_N;  // s(v) F_f(|v|): signed, opposing the motion where positive towards +x
};

struct AxisRigOutput {
  std::string manifest_toml;                                   // friction.toml
  std::vector<std::pair<std::string, std::string>> run_files;  // "friction/<run>.csv" -> CSV text
  std::vector<std::string> run_names;
  std::vector<AxisTrace> traces;                               // per run
  std::string truth_json;
};

// The conditions of the bundled axis set (measurements/axis, scripts/make-bundled-data.sh):
// one SRN 35C at 2.5 µm preload and 26 °C, a run at each of 1, 2 and 3 kN, top speeds 0.005,
// 0.02, 0.05, 0.1 and 0.15 m/s; seeded by `seed`.
FrictionRigConfig bundled_axis_setup(std::uint64_t seed);

// Every setup of `conditions` (guide × preload × load × temperature, `runs` times) is one run:
// one trajectory of the reference at those conditions. Seeded by conditions.seed.
AxisRigOutput generate_axis_logs(const FrictionRigConfig& conditions, const AxisRigConfig& axis,
                                 const RigEffects& effects, const std::vector<std::string>& comments = {});

}  // namespace lmcal
