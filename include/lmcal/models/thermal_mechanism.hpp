// A thermal mechanism: one physical mechanism the published rail model (Eqs. 11-15) leaves
// out, with its own parameter(s) (shared/PHYSICS.md §7); what a friction effect is to the
// friction law (friction_effect.hpp).
//
// Adding one is a new header in thermal_mechanisms/ plus its line (and include) in
// thermal_mechanisms.hpp. The thermal fit (`lmcal fit thermal --extension NAME`), the model
// file, `lmcal simulate thermal --model`, the plan, the thermal diagnosis and the virtual rig
// (`lmcal generate thermal --effect NAME=VALUE`) all take the library from there. The header
// defines a struct with
//
//   static constexpr const char* name, *description, *measure;   // measure: what to log to see it
//   static constexpr bool linear;     // temperatures stay linear in α, offsets and its parameters
//   static constexpr bool heat_follows_rail;  // optional (default false): Q_f follows the rail
//                                             // temperature, so the field is not affine in α
//                                             // whatever the mechanism's parameters
//   static std::vector<ThermalMechanismParameter> parameters();   // none for a switch
//   static std::optional<SourceModel> source();                   // a source-model switch, or none
//   template <typename T> static void apply(ThermalRunSetup<T>& run, const T* values);
//   static constexpr ThermalMechanismPrecondition precondition;   // optional: when data can tell it
//   static constexpr ThermalRigEffect rig;                        // optional: the rig's --effect
//   static void make(ThermalRunSetup<double>& run, double value); // optional: the rig's, if not apply
//
// `apply` changes one run's simulation (its parameters, its heat-rate model, the sensor lag)
// from the values of the mechanism's parameters. It is templated like the rail solver: the
// rig makes data with it (T = double) and the fit gets derivatives from it (ceres::Jet), so
// the physics is written once.
//
// The rig. A mechanism with `rig` is an effect of `lmcal generate thermal`: its value is the
// mechanism's parameter (a switch: 0 off, 1 on), 0 leaves it out, and the true run is
// simulated with `apply` at that value (a switch's `source()` selects the truth's source
// model). `rig.name` may differ from `name` where data sets were made under the older name.
// Trap: at value 0 a mechanism must change nothing, since the rig skips it there and the fit
// starts others from the published model.
#pragma once

#include "lmcal/export.hpp"

#include <optional>
#include <string>
#include <vector>

#include "lmcal/models/friction_effects.hpp"
#include "lmcal/models/rail_thermal.hpp"

namespace LMCAL_API lmcal {

// One run's simulation, as the mechanisms see and change it.
template <typename T>
struct ThermalRunSetup {
  double velocity_m_s = 0;
  const FrictionConstants<double>* friction = nullptr;      // the constants behind Q_f
  const FrictionEffects<double>* friction_effects = nullptr;
  FrictionConditions<double> conditions;                    // the run's, at the start temperature
  RailParams<T> params;
  HeatRateModel<T> heat_rate;  // empty: the constant params.heat_rate_W
  // What params.heat_rate_W is once a mechanism makes Q_f follow the rail temperature
  // (heat_rate set): false, Q_f at the start temperature, where the model starts (the
  // friction law there, or start_friction_N·V); true, the run's mean of Q_f (a load cell's
  // mean_friction_N·V), and the simulation scales the model so that its run mean stays that.
  bool heat_rate_is_run_mean = false;
  T sensor_lag_s{0.0};         // thermocouple first-order time constant; 0: none
  bool lagged = false;
  // The true heat's run-to-run factor (the rig's heat_variation), for a rig's `make`; 1 in a fit.
  double heat_factor = 1;
};

struct ThermalMechanismParameter {
  std::string name, unit;
  double start = 0, lower = 0, upper = 0;
  double scale = 0;  // typical size (see ParameterSpec::scale)
};

// When data can tell a mechanism from the model without it; a diagnosis does not try it
// otherwise, and says why.
struct ThermalMechanismPrecondition {
  // A run quantity that must take two values or more across the runs ("velocity_m_s"), or "".
  const char* varies = "";
  // A parameter of the model that, when fitted, already does what the mechanism does
  // ("h_W_m2K"), or "".
  const char* not_with_fitted = "";
};

// The virtual rig's effect for a mechanism (see above).
struct ThermalRigEffect {
  const char* name;
  const char* unit;
  const char* description;  // for `lmcal generate effects`
  bool non_negative = false;  // the rig refuses a value below 0
};

// What the library says of a mechanism without its physics.
struct ThermalMechanismInfo {
  const char* name;
  const char* description;
  const char* measure;
  ThermalMechanismPrecondition precondition;
  std::optional<ThermalRigEffect> rig;
};

template <class Mechanism>
constexpr ThermalMechanismInfo thermal_mechanism_info() {
  ThermalMechanismInfo info{Mechanism::name, Mechanism::description, Mechanism::measure, {}, std::nullopt};
  if constexpr (requires { Mechanism::precondition; }) info.precondition = Mechanism::precondition;
  if constexpr (requires { Mechanism::rig; }) info.rig = Mechanism::rig;
  return info;
}

}  // namespace lmcal
