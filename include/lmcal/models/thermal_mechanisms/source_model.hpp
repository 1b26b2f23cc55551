// The source model: where the block's heat enters the rail (heat_source.hpp). The paper's
// rectangle of L1/Lb1 times the block's power against the energy-exact cycle average, and
// the block at its actual position. A switch, without parameters: α is refitted with it.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/thermal_mechanism.hpp"

namespace LMCAL_API lmcal {

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
  static std::vector<ThermalMechanismParameter> parameters() { return {}; }
  static std::optional<SourceModel> source() { return Model; }
  // The rig's truth is the averaged source unless the block moves.
  static constexpr std::optional<ThermalRigEffect> rig =
      Model == SourceModel::moving
          ? std::optional<ThermalRigEffect>(
                ThermalRigEffect{"moving_source", "0/1", "the block moves (truth simulated with the moving source)"})
          : std::nullopt;
  template <typename T>
  static void apply(ThermalRunSetup<T>&, const T*) {}
};

}  // namespace lmcal
