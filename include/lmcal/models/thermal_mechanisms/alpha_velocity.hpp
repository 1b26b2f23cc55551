// Heat partition changing with speed: α(V) = α0 + s_α (V - 0.1 m/s). Shows as per-run α
// that trend with speed (the spread across runs is not random).
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/thermal_mechanism.hpp"
#include "lmcal/models/thermal_effects.hpp"

namespace LMCAL_API lmcal {

struct AlphaVelocity {
  static constexpr const char* name = "alpha_velocity";
  static constexpr const char* description = "heat partition changing with speed, alpha = alpha0 + s (V - 0.1 m/s)";
  static constexpr const char* measure = "runs at more speeds, each long enough to reach steady state";
  static constexpr bool linear = true;
  static std::vector<ThermalMechanismParameter> parameters() { return {{"alpha_velocity", "1/(m/s)", 0.0, -10.0, 10.0, 1.0}}; }
  static std::optional<SourceModel> source() { return std::nullopt; }
  static constexpr ThermalMechanismPrecondition precondition{.varies = "velocity_m_s"};
  static constexpr ThermalRigEffect rig{"alpha_velocity", "1/(m/s)", "α = α0 + s (V - 0.1 m/s)"};
  template <typename T>
  static void apply(ThermalRunSetup<T>& run, const T* slope) {
    run.params.heat_partition = alpha_with_velocity(run.params.heat_partition, slope[0], run.velocity_m_s);
  }
};

}  // namespace lmcal
