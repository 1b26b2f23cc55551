// A thermal extension: one physical mechanism the published rail model leaves out, added to
// the thermal fit with its own parameter(s) (shared/PHYSICS.md §7). The thermal fit
// (`lmcal fit thermal --extension NAME`) and the thermal diagnosis use the same library.
//
// Adding a mechanism is one new header in thermal_extensions/ plus its line (and include)
// in thermal_extensions.cc. The header defines a struct with
//
//   static constexpr const char* name, *description, *measure;   // measure: what to log to see it
//   static constexpr bool linear;     // temperatures stay linear in α, offsets and its parameters
//   static constexpr bool heat_follows_rail;  // optional (default false): Q_f follows the rail
//                                             // temperature, so the field is not affine in α
//                                             // whatever the mechanism's parameters
//   static std::vector<ExtensionParameter> parameters();          // none for a switch
//   static std::optional<SourceModel> source();                   // a source-model switch, or none
//   template <typename T> static void apply(ThermalRunSetup<T>& run, const T* values);
//
// `apply` changes one run's simulation (its parameters, its heat-rate model, the sensor lag)
// from the values of the extension's parameters; it is instantiated for double and for the
// ceres::Jet types the thermal cost uses, so derivatives come for free.
#pragma once

#include <ceres/jet.h>

#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "lmcal/models/friction_effects.hpp"
#include "models/autodiff_scalars.hpp"
#include "lmcal/models/rail_thermal.hpp"

namespace lmcal::detail {

// One run's simulation, as the extensions see and change it.
template <typename T>
struct ThermalRunSetup {
  double velocity_m_s = 0;
  const FrictionConstants<double>* friction = nullptr;      // the constants behind Q_f
  const FrictionEffects<double>* friction_effects = nullptr;
  FrictionConditions<double> conditions;                    // the run's, at the start temperature
  RailParams<T> params;
  HeatRateModel<T> heat_rate;  // empty: the constant params.heat_rate_W
  // What params.heat_rate_W is once a mechanism makes Q_f follow the rail temperature
  // (heat_rate set): false, Q_f at the start temperature, where the model starts (the
  // friction law there, or start_friction_N·V); true, the run's mean of Q_f (a load cell's
  // mean_friction_N·V), and the simulation scales the model so that its run mean stays that.
  bool heat_rate_is_run_mean = false;
  T sensor_lag_s{0.0};         // thermocouple first-order time constant; 0: none
  bool lagged = false;
};

struct ExtensionParameter {
  std::string name, unit;
  double start = 0, lower = 0, upper = 0;
  double scale = 0;  // typical size (see ParameterSpec::scale)
};

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
  std::vector<ExtensionParameter> parameters;
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
