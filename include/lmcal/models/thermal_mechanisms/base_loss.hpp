// Heat loss through the rail base into the machine bed (held at the ambient): a conductance
// b per metre of rail on top of the convection. Shows as a lower, earlier steady state
// at every speed alike.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/thermal_mechanism.hpp"

namespace LMCAL_API lmcal {

struct BaseLoss {
  static constexpr const char* name = "base_loss";
  static constexpr const char* description = "heat loss through the rail base to the bed, b (T - T_ambient) per metre";
  static constexpr const char* measure = "a thermocouple on the bed under the rail";
  static constexpr bool linear = false;
  static std::vector<ThermalMechanismParameter> parameters() { return {{"base_loss", "W/mK", 0.05, 0.0, 20.0, 0.1}}; }
  static std::optional<SourceModel> source() { return std::nullopt; }
  static constexpr ThermalRigEffect rig{"base_loss", "W/mK", "heat loss through the rail base to the bed (at ambient)"};
  template <typename T>
  static void apply(ThermalRunSetup<T>& run, const T* b) {
    run.params.base_loss_W_mK = run.params.base_loss_W_mK + b[0];
  }
};

}  // namespace lmcal
