// A thermal extension: a thermal mechanism of the library (lmcal/models/thermal_mechanisms.hpp)
// as the fit holds it, its apply<T> taken once per scalar of AutodiffScalars so that the cost
// can call it for double and the ceres::Jet types alike (Ceres stays out of the public header).
#pragma once

#include <ceres/jet.h>

#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "lmcal/models/thermal_mechanism.hpp"
#include "models/autodiff_scalars.hpp"

namespace lmcal::detail {

class ThermalExtension {
 public:
  template <class Mechanism>
  static ThermalExtension of() {
    ThermalExtension e;
    e.name = Mechanism::name;
    e.description = Mechanism::description;
    e.measure = Mechanism::measure;
    e.linear = Mechanism::linear;
    if constexpr (requires { Mechanism::heat_follows_rail; }) e.heat_follows_rail = Mechanism::heat_follows_rail;
    e.parameters = Mechanism::parameters();
    e.source = Mechanism::source();
    [&e]<typename... T>(std::tuple<T...>*) {
      ((std::get<Apply<T>>(e.apply_) = &Mechanism::template apply<T>), ...);
    }(static_cast<AutodiffScalars*>(nullptr));
    return e;
  }

  // T one of AutodiffScalars.
  template <typename T>
  void apply(ThermalRunSetup<T>& run, const T* values) const {
    std::get<Apply<T>>(apply_)(run, values);
  }

  std::string name, description, measure;
  bool linear = false;
  bool heat_follows_rail = false;
  std::vector<ThermalMechanismParameter> parameters;
  std::optional<SourceModel> source;

 private:
  template <typename T>
  using Apply = void (*)(ThermalRunSetup<T>&, const T*);
  template <typename Scalars>
  struct ApplyTable;
  template <typename... T>
  struct ApplyTable<std::tuple<T...>> {
    using type = std::tuple<Apply<T>...>;
  };
  typename ApplyTable<AutodiffScalars>::type apply_{};  // the mechanism's apply<T>, one per scalar
};

// The library, in a fixed order.
const std::vector<ThermalExtension>& thermal_extensions();
// By name; InvalidParameter naming the known ones for an unknown name.
const ThermalExtension& thermal_extension(std::string_view name);

}  // namespace lmcal::detail
