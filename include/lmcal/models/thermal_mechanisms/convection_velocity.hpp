// Forced convection: the moving block stirs the air along the rail, h(V) = h0 + c_V·√V
// (laminar flat plate, Nu ∝ Re^½). Shows as a steady state that falls with speed faster
// than the heat rate alone explains.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/thermal_mechanism.hpp"
#include "lmcal/models/thermal_effects.hpp"

namespace LMCAL_API lmcal {

struct ConvectionVelocity {
  static constexpr const char* name = "convection_velocity";
  static constexpr const char* description = "convection coefficient rising with speed, h = h0 + c_V sqrt(V)";
  static constexpr const char* measure = "runs over a wider speed range, and the cool-down after each run";
  static constexpr bool linear = false;
  static std::vector<ThermalMechanismParameter> parameters() {
    return {{"convection_velocity", "W/m2K/sqrt(m/s)", 1.0, 0.0, 50.0, 1.0}};
  }
  static std::optional<SourceModel> source() { return std::nullopt; }
  static constexpr ThermalMechanismPrecondition precondition{.varies = "velocity_m_s"};
  static constexpr ThermalRigEffect rig{"convection_velocity", "W/m2K/sqrt(m/s)", "forced convection h = h0 + c sqrt(V)"};
  template <typename T>
  static void apply(ThermalRunSetup<T>& run, const T* c_V) {
    run.params.h_W_m2K = convection_with_velocity(run.params.h_W_m2K, c_V[0], run.velocity_m_s);
  }
};

}  // namespace lmcal
