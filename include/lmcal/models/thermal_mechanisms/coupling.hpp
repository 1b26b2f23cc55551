// Two-way friction-temperature coupling: the grease under the block warms with the rail,
// its viscosity falls (Eq. 7), and so does the heat rate. With share κ of the law's
// temperature dependence,
//
//   Q(T_s) = Q_0 · (1 + κ (Q_law(T_s) / Q_law(T_start) - 1))
//
// at the rail temperature under the block T_s; κ = 1 is the friction law as fitted. Q_0 is
// the run's heat at the start temperature (the friction law there, start_friction_N·V); when
// the run's heat is a measured run mean (mean_friction_N·V), Q_0 is instead what makes the
// run mean of Q that value (ThermalRunSetup::heat_rate_is_run_mean): a load cell's mean
// over a run that warms is below the friction at the start.
// Shows as a warm-up that levels off sooner than a constant heat rate gives.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/thermal_mechanism.hpp"

namespace LMCAL_API lmcal {

struct Coupling {
  static constexpr const char* name = "coupling";
  static constexpr const char* description =
      "heat rate from the friction law at the rail temperature under the block (viscosity falls as the rail warms)";
  static constexpr const char* measure = "the friction force logged during the thermal run";
  static constexpr bool linear = false;
  static constexpr bool heat_follows_rail = true;  // held or not: T(α) is not affine
  static std::vector<ThermalMechanismParameter> parameters() { return {{"coupling", "1", 0.5, -1.0, 3.0, 1.0}}; }
  static std::optional<SourceModel> source() { return std::nullopt; }
  static constexpr ThermalRigEffect rig{"coupling", "0/1", "Q from the friction law at the rail temperature (two-way coupling)"};
  template <typename T>
  static void apply(ThermalRunSetup<T>& run, const T* kappa) {
    const double q_start = heat_rate_with_effects_W(*run.friction, *run.friction_effects, run.conditions);
    const FrictionConstants<double>* k = run.friction;
    const FrictionEffects<double>* e = run.friction_effects;
    const FrictionConditions<double> c = run.conditions;
    run.heat_rate = [q0 = run.params.heat_rate_W, q_start, k, e, c, kappa = kappa[0]](const T& source_C) {
      FrictionConditions<T> at = c.template cast<T>();
      at.temperature_C = source_C;
      return q0 * (1.0 + kappa * (heat_rate_with_effects_W(*k, *e, at) / q_start - 1.0));
    };
  }
  // The rig's coupling is a switch, κ = 1: the heat is the friction law's at the rail
  // temperature under the block, times the run's heat factor, taken directly rather than as
  // apply's ratio to the start (equal in exact arithmetic), so that data sets made before the
  // library keep their bits.
  static void make(ThermalRunSetup<double>& run, double) {
    run.heat_rate = [k = run.friction, e = run.friction_effects, c = run.conditions,
                     factor = run.heat_factor](const double& source_C) {
      FrictionConditions<double> at = c;
      at.temperature_C = source_C;
      return factor * heat_rate_with_effects_W(*k, *e, at);
    };
  }
};

}  // namespace lmcal
