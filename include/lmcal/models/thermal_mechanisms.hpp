// The library of thermal mechanisms (see thermal_mechanism.hpp for what one is). Register a
// new mechanism here: its include and one line in ThermalMechanismLibrary.
//
// The order is the library's everywhere (fit thermal --extension, the diagnosis, the model
// file, the rig's effects): a tie in a diagnosis is represented by the candidate listed
// first, so the plainer form comes first (a constant h that differs from the assumed one
// before a base loss or an h(V)).
#pragma once

#include "lmcal/export.hpp"

#include <array>
#include <cstddef>
#include <optional>
#include <string_view>
#include <utility>

#include "lmcal/models/thermal_mechanism.hpp"
#include "lmcal/models/thermal_mechanisms/alpha_velocity.hpp"
#include "lmcal/models/thermal_mechanisms/base_loss.hpp"
#include "lmcal/models/thermal_mechanisms/convection_scale.hpp"
#include "lmcal/models/thermal_mechanisms/convection_velocity.hpp"
#include "lmcal/models/thermal_mechanisms/coupling.hpp"
#include "lmcal/models/thermal_mechanisms/source_model.hpp"
#include "lmcal/models/thermal_mechanisms/tc_lag.hpp"

namespace LMCAL_API lmcal {

template <class... Mechanisms>
struct ThermalMechanismList {
  static constexpr std::size_t size = sizeof...(Mechanisms);
  static constexpr std::array<ThermalMechanismInfo, size> infos{thermal_mechanism_info<Mechanisms>()...};

  // f.template operator()<Mechanism, slot>() for each mechanism, in library order.
  template <class F>
  static constexpr void for_each(F&& f) {
    [&]<std::size_t... slot>(std::index_sequence<slot...>) {
      (f.template operator()<Mechanisms, slot>(), ...);
    }(std::index_sequence_for<Mechanisms...>{});
  }
};

using ThermalMechanismLibrary = ThermalMechanismList<
    ConvectionScale,
    ConvectionVelocity,
    BaseLoss,
    Coupling,
    ThermocoupleLag,
    AlphaVelocity,
    SourceSwitch<SourceModel::averaged>,
    SourceSwitch<SourceModel::moving>,
    SourceSwitch<SourceModel::paper>>;

inline constexpr std::size_t kThermalMechanismCount = ThermalMechanismLibrary::size;

// The slot of a named mechanism, or none.
constexpr std::optional<std::size_t> find_thermal_mechanism(std::string_view name) {
  for (std::size_t i = 0; i < kThermalMechanismCount; ++i)
    if (name == ThermalMechanismLibrary::infos[i].name) return i;
  return std::nullopt;
}

}  // namespace lmcal
