// The library of thermal extensions (see thermal_extension.hpp). Register a new mechanism
// here: its include and one line in the list.
#include <fmt/format.h>

#include "lmcal/error.hpp"
#include "thermal_extension.hpp"
#include "thermal_extensions/alpha_velocity.hpp"
#include "thermal_extensions/base_loss.hpp"
#include "thermal_extensions/convection_scale.hpp"
#include "thermal_extensions/convection_velocity.hpp"
#include "thermal_extensions/coupling.hpp"
#include "thermal_extensions/source_model.hpp"
#include "thermal_extensions/tc_lag.hpp"

namespace lmcal::detail {

const std::vector<ThermalExtension>& thermal_extensions() {
  // A tie is represented by the candidate listed first: the plainer form comes first (a
  // constant h that differs from the assumed one before a base loss or an h(V)).
  static const std::vector<ThermalExtension> library = {
      ThermalExtension::of<ConvectionScale>(),
      ThermalExtension::of<ConvectionVelocity>(),
      ThermalExtension::of<BaseLoss>(),
      ThermalExtension::of<Coupling>(),
      ThermalExtension::of<ThermocoupleLag>(),
      ThermalExtension::of<AlphaVelocity>(),
      ThermalExtension::of<SourceSwitch<SourceModel::averaged>>(),
      ThermalExtension::of<SourceSwitch<SourceModel::moving>>(),
      ThermalExtension::of<SourceSwitch<SourceModel::paper>>(),
  };
  return library;
}

const ThermalExtension& thermal_extension(std::string_view name) {
  std::string known;
  for (const auto& e : thermal_extensions()) {
    if (e.name == name) return e;
    known += (known.empty() ? "" : ", ") + e.name;
  }
  throw InvalidParameter("extension", fmt::format("unknown thermal extension '{}'; known: {}", name, known));
}

}  // namespace lmcal::detail
