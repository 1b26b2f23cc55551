// Thermocouple lag: a sheathed thermocouple in a drilled hole reads the rail through a
// first-order lag of time constant τ. Shows as readings that trail the model while the
// rail warms (residuals following the heating rate, not the level).
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/thermal_mechanism.hpp"

namespace LMCAL_API lmcal {

struct ThermocoupleLag {
  static constexpr const char* name = "tc_lag";
  static constexpr const char* description = "thermocouples reading through a first-order lag of time constant tau";
  static constexpr const char* measure = "a step test of the thermocouples (plunge into a bath) and a faster logger";
  static constexpr bool linear = false;
  // Bounded away from 0: the lag's derivative with respect to τ is singular at τ = 0.
  static std::vector<ThermalMechanismParameter> parameters() { return {{"tc_lag", "s", 10.0, 0.1, 1800.0, 10.0}}; }
  static std::optional<SourceModel> source() { return std::nullopt; }
  static constexpr ThermalRigEffect rig{"tc_lag", "s", "thermocouple first-order time constant", true};
  template <typename T>
  static void apply(ThermalRunSetup<T>& run, const T* tau) {
    run.sensor_lag_s = tau[0];
    run.lagged = true;
  }
};

}  // namespace lmcal
