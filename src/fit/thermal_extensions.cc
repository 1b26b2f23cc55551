// The fit's view of the library of thermal mechanisms (lmcal/models/thermal_mechanisms.hpp,
// where a new mechanism is registered).
#include <fmt/format.h>

#include "lmcal/error.hpp"
#include "lmcal/models/thermal_mechanisms.hpp"
#include "thermal_extension.hpp"

namespace lmcal::detail {

const std::vector<ThermalExtension>& thermal_extensions() {
  static const std::vector<ThermalExtension> library = [] {
    std::vector<ThermalExtension> l;
    ThermalMechanismLibrary::for_each([&]<class Mechanism, std::size_t>() { l.push_back(ThermalExtension::of<Mechanism>()); });
    return l;
  }();
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
