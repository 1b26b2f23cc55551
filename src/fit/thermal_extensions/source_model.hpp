// The source model: where the block's heat enters the rail (heat_source.hpp). The paper's
// rectangle of L1/Lb1 times the block's power against the energy-exact cycle average, and
// the block at its actual position. A switch, without parameters: α is refitted with it.
#pragma once

#include "../thermal_extension.hpp"

namespace lmcal::detail {

template <SourceModel Model>
struct SourceSwitch {
  static constexpr const char* name = Model == SourceModel::averaged ? "source_averaged"
                                      : Model == SourceModel::moving ? "source_moving"
                                                                     : "source_paper";
  static constexpr const char* description =
      Model == SourceModel::averaged ? "heat entering over stroke plus contact length, the moving block's cycle average"
      : Model == SourceModel::moving ? "heat entering under the block at its actual position"
                                     : "heat entering as the paper's rectangle over the stroke";
  static constexpr const char* measure = "thermocouples close to the stroke ends and a fast logger";
  static constexpr bool linear = true;
  static std::vector<ExtensionParameter> parameters() { return {}; }
  static std::optional<SourceModel> source() { return Model; }
  template <typename T>
  static void apply(ThermalRunSetup<T>&, const T*) {}
};

}  // namespace lmcal::detail
