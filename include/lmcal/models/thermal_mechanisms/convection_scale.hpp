// The convection coefficient differs from the assumed one (5.3 W/m²K, natural convection in
// the paper): h = h_assumed · (1 + s), at every speed alike. A nuisance candidate: radiation,
// draughts, a painted or oily rail all move h. Bounded so that h stays positive (s > -0.9).
//
// Trap: in the 1-D rail model a base loss b is the same as a larger h on the sides
// (b = Δh·p, only the two end faces tell them apart), so on most data it ties with
// base_loss; and with s < 0 it is the only mechanism that lowers h (base_loss >= 0).
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/thermal_mechanism.hpp"

namespace LMCAL_API lmcal {

struct ConvectionScale {
  static constexpr const char* name = "convection_scale";
  static constexpr const char* description = "convection coefficient differing from the assumed one, h = h_assumed (1 + s)";
  static constexpr const char* measure =
      "a heat-flux sensor on the rail's side and a thermocouple on the bed under the rail, or a cool-down of the rail "
      "lifted off the bed (its time constant then gives h alone)";
  static constexpr bool linear = false;
  static std::vector<ThermalMechanismParameter> parameters() { return {{"convection_scale", "1", 0.0, -0.9, 9.0, 0.1}}; }
  static std::optional<SourceModel> source() { return std::nullopt; }
  // With h fitted, the baseline already has what this changes.
  static constexpr ThermalMechanismPrecondition precondition{.not_with_fitted = "h_W_m2K"};
  static constexpr ThermalRigEffect rig{"convection_scale", "1", "h = h_assumed (1 + s), at every speed alike"};
  template <typename T>
  static void apply(ThermalRunSetup<T>& run, const T* s) {
    run.params.h_W_m2K = run.params.h_W_m2K * (1.0 + s[0]);
  }
};

}  // namespace lmcal
