// The virtual rig's closed-loop positioning axis: a controller drives a carriage along a
// reference, the plant integrated with the library's friction law, logged as a drive logs it
// (axis_rig.hpp).
#include "lmcal/rig/axis_rig.hpp"

#include <ceres/jet.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "io/toml_text.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/io/csv_writer.hpp"
#include "lmcal/models/friction_effects/axis_gravity.hpp"
#include "rig/rig_common.hpp"

namespace lmcal {

std::string_view to_string(AxisController controller) { return controller == AxisController::pd ? "pd" : "p-pi"; }

AxisController parse_axis_controller(std::string_view name) {
  for (AxisController c : {AxisController::pd, AxisController::p_pi})
    if (name == to_string(c)) return c;
  throw InvalidParameter("controller", fmt::format("'{}': expected pd or p-pi", name));
}

std::string_view to_string(AxisReference reference) {
  return reference == AxisReference::trapezoidal ? "trapezoidal" : "sinusoid";
}

AxisReference parse_axis_reference(std::string_view name) {
  for (AxisReference r : {AxisReference::trapezoidal, AxisReference::sinusoid})
    if (name == to_string(r)) return r;
  throw InvalidParameter("reference", fmt::format("'{}': expected trapezoidal or sinusoid", name));
}

namespace {


struct ReferencePoint {
  double x_m = 0, v_m_s = 0, a_m_s2 = 0;
};

// One phase of constant reference acceleration (0: a cruise or a dwell).
struct ReferencePhase {
  double t0_s, duration_s, x0_m, v0_m_s, a_m_s2;
  ReferencePoint at(double t) const {
    const double tau = t - t0_s;
    return {x0_m + v0_m_s * tau + 0.5 * a_m_s2 * tau * tau, v0_m_s + a_m_s2 * tau, a_m_s2};
  }
};

// The reference as a function of time: a list of phases (trapezoidal) or the sinusoid.
class Reference {
 public:
  explicit Reference(const FrictionRigConfig& conditions, const AxisRigConfig& axis) : axis_(axis) {
    if (axis.reference == AxisReference::sinusoid) {
      duration_s_ = axis.duration_s;
      return;
    }
    double t = 0, x = 0;
    const auto add = [&](double duration, double v0, double a) {
      phases_.push_back({t, duration, x, v0, a});
      x = phases_.back().at(t + duration).x_m;
      t += duration;
    };
    add(axis.dwell_s, 0, 0);
    for (double V : conditions.velocity_m_s) {
      const double ramp_s = V / axis.acceleration_m_s2;
      const double ramps_m = V * ramp_s;  // the two ramps together
      if (!(axis.stroke_m > ramps_m))
        throw InvalidParameter("stroke_m", axis.stroke_m,
                               fmt::format("longer than the ramps to {} m/s at {} m/s² ({} m)", V, axis.acceleration_m_s2,
                                           ramps_m));
      const double move_m = std::min(axis.stroke_m, ramps_m + V * axis.cruise_s);
      for (int c = 0; c < axis.cycles; ++c)
        for (double sense : {1.0, -1.0}) {
          add(ramp_s, 0, sense * axis.acceleration_m_s2);
          add((move_m - ramps_m) / V, sense * V, 0);
          add(ramp_s, sense * V, -sense * axis.acceleration_m_s2);
          add(axis.dwell_s, 0, 0);
        }
    }
    duration_s_ = t;
  }

  double duration_s() const { return duration_s_; }

  // Non-decreasing t only (the phase found last is where the search starts).
  ReferencePoint at(double t) {
    if (axis_.reference == AxisReference::sinusoid) {
      const double w = 2 * std::numbers::pi * axis_.sine_frequency_Hz, A = axis_.sine_amplitude_m;
      return {A * (1 - std::cos(w * t)), A * w * std::sin(w * t), A * w * w * std::cos(w * t)};
    }
    while (phase_ + 1 < phases_.size() && t >= phases_[phase_ + 1].t0_s) ++phase_;
    return phases_[phase_].at(t);
  }

 private:
  const AxisRigConfig& axis_;
  std::vector<ReferencePhase> phases_;
  std::size_t phase_ = 0;
  double duration_s_ = 0;
};

// The controller's gains in SI units, from the bandwidths and the mass.
struct Gains {
  double kp, kd;  // pd: N/m, N·s/m; p-pi: K_p 1/s, K_v N·s/m
  double ki = 0;  // p-pi: N/m
};

Gains gains_of(const AxisRigConfig& a) {
  const double M = a.moving_mass_kg;
  if (a.controller == AxisController::pd) {
    const double w = 2 * std::numbers::pi * a.pd_bandwidth_Hz;
    return {M * w * w, 2 * a.pd_damping * w * M};
  }
  const double kv = M * 2 * std::numbers::pi * a.velocity_bandwidth_Hz;
  return {a.position_gain_1_s, kv, kv * 2 * std::numbers::pi * a.velocity_integral_Hz};
}

class Controller {
 public:
  explicit Controller(const AxisRigConfig& a) : axis_(a), gains_(gains_of(a)) {}
  // Holding the reference's start at rest against a constant load (gravity) before the log
  // begins: the pd controller sags by load/K_p (returned: the start's offset), the p-pi
  // controller's integral carries the load.
  double hold(double load_N) {
    if (axis_.controller == AxisController::pd) return -load_N / gains_.kp;
    if (gains_.ki == 0) return -load_N / (gains_.kd * gains_.kp);
    integral_ = load_N / gains_.ki;
    return 0;
  }
  // The force for the next step of dt, from the reference and the state at its start.
  double force_N(const ReferencePoint& r, double x, double v, double dt) {
    const double feedforward = axis_.acceleration_feedforward * axis_.moving_mass_kg * r.a_m_s2;
    if (axis_.controller == AxisController::pd) return gains_.kp * (r.x_m - x) + gains_.kd * (r.v_m_s - v) + feedforward;
    const double error = r.v_m_s + gains_.kp * (r.x_m - x) - v;
    const double F = gains_.kd * error + gains_.ki * integral_ + feedforward;
    integral_ += error * dt;
    return F;
  }

 private:
  const AxisRigConfig& axis_;
  Gains gains_;
  double integral_ = 0;  // ∫(v_cmd − v) dt, m
};

// The carriage: s(v) F_f(|v|) from the library's law with the rig's friction effects.
class Plant {
 public:
  using Jet = ceres::Jet<double, 1>;

  Plant(const FrictionConstants<double>& k, const FrictionEffects<double>& e, const FrictionConditions<double>& c,
        const AxisRigConfig& a)
      : k_(k), e_(e), c_(c.cast<Jet>()), M_(a.moving_mass_kg), v_s_(a.regularisation_m_s),
        gravity_N_(axis_weight_N(a.moving_mass_kg, a.incline_deg)) {}

  double gravity_N() const { return gravity_N_; }

  // s(v) F_f(|v|), N, and its derivative in v.
  Jet friction(double v) {
    const Jet u(v, 0);
    c_.velocity_m_s = abs(u);
    c_.direction = Jet(v < 0 ? -1.0 : 1.0);
    c_.position_m = Jet(x_);
    c_.distance_since_reversal_m = Jet(std::abs(x_ - x_turn_));
    return tanh(u / v_s_) * friction_force_with_effects_N(k_, e_, c_);
  }

  // One step of dt under the motor force F: the velocity with the friction at the new velocity
  // (Newton from the old one: its first iterate is the linearly implicit step), then the
  // position with the new velocity.
  void step(double F, double dt) {
    const double push = F - gravity_N_;
    double u = v_;
    for (int it = 0; it < 20; ++it) {
      const Jet f = friction(u);
      const double g = u - v_ - dt / M_ * (push - f.a);
      const double du = g / (1 + dt / M_ * f.v[0]);
      u -= du;
      if (std::abs(du) <= 1e-15 + 1e-12 * std::abs(u)) break;
    }
    // The travel since the last reversal or rest (pre-sliding's state) restarts where the
    // velocity changes sign or is within the regularisation's reach of rest.
    if (std::abs(u) < 10 * v_s_ || (u < 0) != (v_ < 0)) x_turn_ = x_;
    v_ = u;
    x_ += dt * v_;
  }

  double x() const { return x_; }
  double v() const { return v_; }
  void place(double x) { x_ = x_turn_ = x; }

 private:
  const FrictionConstants<double>& k_;
  const FrictionEffects<double>& e_;
  FrictionConditions<Jet> c_;
  double M_, v_s_, gravity_N_;
  double x_ = 0, v_ = 0;
  double x_turn_ = 0;  // where the carriage last reversed or rested
};

void validate(const AxisRigConfig& a) {
  require_positive("moving_mass_kg", a.moving_mass_kg);
  require_in_range("incline_deg", a.incline_deg, -90, 90);
  require_positive("force_constant_N_A", a.force_constant_N_A);
  require_positive("pd_bandwidth_Hz", a.pd_bandwidth_Hz);
  require_positive("pd_damping", a.pd_damping);
  require_positive("position_gain_1_s", a.position_gain_1_s);
  require_positive("velocity_bandwidth_Hz", a.velocity_bandwidth_Hz);
  require_non_negative("velocity_integral_Hz", a.velocity_integral_Hz);
  require_finite("acceleration_feedforward", a.acceleration_feedforward);
  require_positive("acceleration_m_s2", a.acceleration_m_s2);
  require_non_negative("cruise_s", a.cruise_s);
  require_positive("stroke_m", a.stroke_m);
  if (a.cycles < 1) throw InvalidParameter("cycles", a.cycles, ">= 1");
  require_non_negative("dwell_s", a.dwell_s);
  require_positive("sine_amplitude_m", a.sine_amplitude_m);
  require_positive("sine_frequency_Hz", a.sine_frequency_Hz);
  require_positive("duration_s", a.duration_s);
  require_positive("log_rate_Hz", a.log_rate_Hz);
  if (a.substeps < 1) throw InvalidParameter("substeps", a.substeps, ">= 1");
  require_positive("regularisation_m_s", a.regularisation_m_s);
  require_positive("encoder_resolution_m", a.encoder_resolution_m);
  require_non_negative("current_noise_A", a.current_noise_A);
  require_autocorrelation("current_noise_ar1", a.current_noise_ar1);
  require_finite("current_offset_A", a.current_offset_A);
  // The controller's loops must be slower than its steps (a discrete loop at ω·dt ~ 1 is unstable).
  const double dt = 1 / (a.log_rate_Hz * a.substeps);
  const double fastest_Hz = a.controller == AxisController::pd ? a.pd_bandwidth_Hz : a.velocity_bandwidth_Hz;
  if (2 * std::numbers::pi * fastest_Hz * dt > 0.3)
    throw InvalidParameter(a.controller == AxisController::pd ? "pd_bandwidth_Hz" : "velocity_bandwidth_Hz", fastest_Hz,
                           fmt::format("below 0.3 / (2π dt) = {:.4g} Hz for the control step dt = {:.3g} s (or more "
                                       "substeps)", 0.3 / (2 * std::numbers::pi * dt), dt));
}

// Decimal places of a position in mm that keep every encoder step.
int position_decimals(double resolution_m) {
  return std::clamp(static_cast<int>(std::ceil(-std::log10(resolution_m * 1e3))) + 2, 6, 12);
}

struct RunResult {
  std::string csv;
  AxisTrace trace;
  nlohmann::json truth;
};

RunResult simulate_run(const FrictionRigConfig& conditions, const AxisRigConfig& axis, const RigEffects& effects,
                       const FrictionConditions<double>& c, std::uint64_t stream, const std::vector<std::string>& comments) {
  Reference reference(conditions, axis);
  Controller controller(axis);
  Plant plant(conditions.constants, effects.friction, c, axis);
  plant.place(reference.at(0).x_m + controller.hold(plant.gravity_N()));
  rig::Rng rng(rig::derive_seed(conditions.seed, stream));
  rig::Ar1Noise current_noise(axis.current_noise_A, axis.current_noise_ar1);
  const double h = 1 / axis.log_rate_Hz, dt = h / axis.substeps;
  const auto samples = static_cast<std::size_t>(std::floor(reference.duration_s() * axis.log_rate_Hz)) + 1;
  const int decimals = position_decimals(axis.encoder_resolution_m);

  RunResult out;
  AxisTrace& trace = out.trace;
  for (auto* column : {&trace.time_s, &trace.reference_m, &trace.position_m, &trace.velocity_m_s, &trace.drive_N,
                       &trace.friction_N})
    column->reserve(samples);
  CsvText csv({"time_s", "position_mm", "force_N"}, comments);
  csv.expect_rows(samples);
  std::size_t reversals = 0;
  double last_sense = 0, max_error_m = 0, sum_error2 = 0;
  for (std::size_t k = 0; k < samples; ++k) {
    const double t_k = static_cast<double>(k) * h;
    for (int s = 0; s < axis.substeps; ++s) {
      const double t = t_k + s * dt;
      const ReferencePoint r = reference.at(t);
      const double x = plant.x(), v = plant.v();
      const double F = controller.force_N(r, x, v, dt);
      if (s == 0) {  // the sample: the state, and the force the drive applies from now on
        trace.time_s.push_back(t_k);
        trace.reference_m.push_back(r.x_m);
        trace.position_m.push_back(x);
        trace.velocity_m_s.push_back(v);
        trace.drive_N.push_back(F);
        trace.friction_N.push_back(plant.friction(v).a);
        const double current_A = F / axis.force_constant_N_A + axis.current_offset_A + current_noise.next(rng.normal());
        const double position_mm =
            std::round(x / axis.encoder_resolution_m) * axis.encoder_resolution_m * 1e3;
        csv.cell(rig::round_to(t_k, 6))
            .cell(rig::round_to(position_mm, decimals))
            .cell(rig::round_to(axis.force_constant_N_A * current_A, 4))
            .end_row();
        const double error = r.x_m - x;
        max_error_m = std::max(max_error_m, std::abs(error));
        sum_error2 += error * error;
      }
      plant.step(F, dt);
    }
    // Reversals of the true motion (a sense held for more than a regularisation's speed).
    const double v = plant.v();
    const double sense = v > 10 * axis.regularisation_m_s ? 1.0 : v < -10 * axis.regularisation_m_s ? -1.0 : 0.0;
    if (sense != 0 && last_sense != 0 && sense != last_sense) ++reversals;
    if (sense != 0) last_sense = sense;
  }
  out.csv = csv.str();
  out.truth = {{"samples", samples},
               {"duration_s", static_cast<double>(samples - 1) * h},
               {"reversals", reversals},
               {"max_tracking_error_m", max_error_m},
               {"rms_tracking_error_m", std::sqrt(sum_error2 / static_cast<double>(samples))}};
  return out;
}

nlohmann::json controller_json(const AxisRigConfig& a) {
  const Gains g = gains_of(a);
  nlohmann::json j = {{"type", to_string(a.controller)}, {"acceleration_feedforward", a.acceleration_feedforward},
                      {"control_rate_Hz", a.log_rate_Hz * a.substeps}};
  if (a.controller == AxisController::pd) {
    j.update({{"bandwidth_Hz", a.pd_bandwidth_Hz}, {"damping", a.pd_damping}, {"kp_N_m", g.kp}, {"kd_N_s_m", g.kd}});
  } else {
    j.update({{"position_gain_1_s", g.kp}, {"velocity_bandwidth_Hz", a.velocity_bandwidth_Hz},
              {"velocity_integral_Hz", a.velocity_integral_Hz}, {"kv_N_s_m", g.kd}, {"ki_N_m", g.ki}});
  }
  return j;
}

nlohmann::json reference_json(const FrictionRigConfig& conditions, const AxisRigConfig& a) {
  if (a.reference == AxisReference::sinusoid)
    return {{"type", "sinusoid"}, {"amplitude_m", a.sine_amplitude_m}, {"frequency_Hz", a.sine_frequency_Hz},
            {"duration_s", a.duration_s}, {"max_speed_m_s", 2 * std::numbers::pi * a.sine_frequency_Hz * a.sine_amplitude_m},
            {"note", "x_ref = A (1 - cos 2 pi f t)"}};
  return {{"type", "trapezoidal"}, {"max_speeds_m_s", conditions.velocity_m_s}, {"acceleration_m_s2", a.acceleration_m_s2},
          {"cruise_s", a.cruise_s}, {"stroke_m", a.stroke_m}, {"cycles", a.cycles}, {"dwell_s", a.dwell_s},
          {"note", "per speed V, cycles moves 0 -> L -> 0, L = min(stroke_m, V^2/a + V cruise_s)"}};
}

// The plant has the carriage's inertia and weight itself: a friction effect that models either
// (as a trajectory fit does) would count it twice.
void require_no_plant_effects(const RigEffects& effects) {
  for (const char* name : {"moving_mass", "axis_gravity", "moving_mass_error"})
    if (const auto slot = find_friction_effect(name); slot && effects.friction[*slot] != FrictionEffectLibrary::infos[*slot].neutral)
      throw InvalidParameter("--effect", fmt::format("{} is the axis's own (the plant's moving_mass_kg and incline_deg): "
                                                     "give --mass and --incline instead", name));
}

}  // namespace

FrictionRigConfig bundled_axis_setup(std::uint64_t seed) {
  FrictionRigConfig setup;
  setup.guides = {"SRN 35C"};
  setup.preload_um = {2.5};
  setup.load_N = {1000, 2000, 3000};
  setup.temperature_C = {26};
  setup.velocity_m_s = {0.005, 0.02, 0.05, 0.1, 0.15};
  setup.runs = 1;
  setup.seed = seed;
  return setup;
}

AxisRigOutput generate_axis_logs(const FrictionRigConfig& conditions, const AxisRigConfig& axis, const RigEffects& effects,
                                 const std::vector<std::string>& comments) {
  rig::require_no_thermal_effects(effects);
  require_no_plant_effects(effects);
  validate(conditions.constants);
  validate(axis);
  if (conditions.runs < 1) throw InvalidParameter("runs", conditions.runs, "at least 1");
  if (axis.reference == AxisReference::trapezoidal && conditions.velocity_m_s.empty())
    throw InvalidParameter("velocity_m_s", "at least one speed for a trapezoidal reference");
  for (double V : conditions.velocity_m_s) require_positive("velocity_m_s", V);

  AxisRigOutput out;
  const double gravity_N = axis_weight_N(axis.moving_mass_kg, axis.incline_deg);
  std::string manifest = fmt::format(
      "# SYNTHETIC closed-loop axis log made by the lmcal virtual rig, not measured.\n"
      "name = \"virtual closed-loop axis\"\n\n[raw]\nforce_sign = {}\n",
      manifest::toml_string(to_string(ForceSign::follows_motion)));
  if (axis.trajectory_keys)
    manifest += fmt::format("segmentation = \"trajectory\"\naxis_incline_deg = {}\n", axis.incline_deg);
  nlohmann::json runs = nlohmann::json::array();
  std::uint64_t r = 0;
  for (const rig::RunSetup& setup : rig::run_setups(conditions)) {
      const GuideSpec& spec = *setup.spec;
      const FrictionConditions<double> c = setup.conditions;
      const double pc = c.preload_um, P = c.load_N, T = c.temperature_C;
      validate(c);
      const std::string name = fmt::format("run{:02d}", r + 1);
      RunResult run = simulate_run(conditions, axis, effects, c, r++, comments);
      std::string file;
      manifest += rig::raw_run_manifest_toml(name, spec.model, c, conditions.constants.nu_ref_mm2_s,
                                             conditions.catalog != nullptr, file);
      run.truth.update({{"run", name}, {"guide", spec.model}, {"load_N", P}, {"preload_um", pc},
                        {"block_length_mm", c.block_length_mm}, {"temperature_C", T}});
      runs.push_back(std::move(run.truth));
      out.run_files.emplace_back(file, std::move(run.csv));
      out.run_names.push_back(name);
      out.traces.push_back(std::move(run.trace));
  }
  out.manifest_toml = manifest;
  nlohmann::json truth = {
      {"kind", "friction_axis"},
      {"generator", fmt::format("lmcal {} virtual rig", LMCAL_VERSION)},
      {"seed", conditions.seed},
      {"moving_mass_kg", axis.moving_mass_kg},
      {"incline_deg", axis.incline_deg},
      {"gravity_N", gravity_N},
      {"g_m_s2", kStandardGravity_m_s2},
      {"force_constant_N_A", axis.force_constant_N_A},
      {"current_noise_A", axis.current_noise_A},
      {"current_noise_ar1", axis.current_noise_ar1},
      {"current_offset_A", axis.current_offset_A},
      {"force_offset_N", axis.force_constant_N_A * axis.current_offset_A},
      {"friction_constants", rig::constants_json(conditions.constants)},
      {"effects", rig::effects_json(effects)},
      {"regularisation_m_s", axis.regularisation_m_s},
      {"controller", controller_json(axis)},
      {"reference", reference_json(conditions, axis)},
      {"log_rate_Hz", axis.log_rate_Hz},
      {"integration_step_s", 1 / (axis.log_rate_Hz * axis.substeps)},
      {"encoder_resolution_m", axis.encoder_resolution_m},
      {"runs", runs},
      {"note", "M x'' = F_motor - tanh(v/v_s) F_f(|v|) - M g sin(theta), +x up the incline; force_N = K_f (i + "
               "current_offset_A + noise) = F_motor + force_offset_N + K_f noise (the drive's force, carrying M a and "
               "gravity_N); F_f the library law with the effects (not the hidden ones); semi-implicit Euler at "
               "integration_step_s, the controller held over each step"}};
  out.truth_json = truth.dump(2) + "\n";
  return out;
}

}  // namespace lmcal
