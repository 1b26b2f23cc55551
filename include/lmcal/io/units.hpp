// Units at the edges: column headers and manifest keys carry their unit as a suffix
// (`load_N`, `velocity_mm_s`, `tc1_K`), and loaders convert to the units lmcal uses
// inside (the friction law's: N, µm, mm, m/s, °C, mm²/s; SI otherwise).
//
//   quantity     internal   accepted suffixes
//   time         s          s, ms, min, h
//   velocity     m/s        m_s, mm_s, m_min
//   load         N          N, kN, kgf, lbf
//   friction     N          N, kN, kgf, lbf
//   preload      µm         um, mm
//   length       mm         mm, m            (block_length, contact_length)
//   distance     m          m, mm            (stroke, rail_length, positions)
//   temperature  °C         C, K, F
//   viscosity    mm²/s      mm2_s, cSt, m2_s
//   angular velocity  rad/s  rad_s, rpm      (a motor's or joint's speed: friction logs with a drive)
//   torque       N·m        Nm, percent      (percent: of the drive's nominal torque, see below)
//
// Angular velocity and torque are joint quantities: a friction log turns them into the
// carriage's speed and force through its drive (lmcal/io/drive.hpp); no other input takes them.
// `percent` converts to a fraction (scale 0.01), not to N·m: the loader multiplies by the
// drive's nominal_torque_Nm (is_relative_unit says which units need that).
//
// Example: split_unit("load_kgf", Quantity::force) -> {"load", {9.80665, 0}}.
// Trap: temperature conversions have an offset; always call Conversion::apply.
#pragma once

#include "lmcal/export.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace LMCAL_API lmcal {

enum class Quantity {
  time,
  velocity,
  force,
  preload,
  length_mm,
  distance_m,
  temperature,
  viscosity,
  angular_velocity,
  torque,
  acceleration
};

// value_internal = scale * value_given + offset
struct Conversion {
  double scale = 1.0;
  double offset = 0.0;
  double apply(double value) const { return scale * value + offset; }
};

// The accepted unit suffixes of a quantity, the internal one first (for messages).
const std::vector<std::string>& unit_names(Quantity quantity);

// The conversion for a unit suffix, or nullopt if the quantity does not know it.
std::optional<Conversion> unit_conversion(Quantity quantity, std::string_view unit);

// True for a unit that is a share of a reference the data's owner states elsewhere
// ("percent" of the drive's nominal torque): its conversion gives a fraction, not the internal unit.
bool is_relative_unit(Quantity quantity, std::string_view unit);

// Splits "NAME_UNIT" where UNIT is one of the quantity's suffixes (longest match wins):
// "velocity_mm_s" -> {"velocity", mm/s}. nullopt if no suffix of the quantity matches.
struct SplitName {
  std::string name;
  std::string unit;
  Conversion conversion;
};
std::optional<SplitName> split_unit(std::string_view column, Quantity quantity);

// The values a quantity takes on a real rig, in its internal unit (inclusive): beyond them, a
// typo or a wrong unit, and the models' arithmetic could leave the doubles (a viscosity of
// 1e-320 mm²/s, a speed of 1e308 m/s). Loaders refuse values outside (docs/formats.md#limits);
// signs are the columns' own rules (a speed column is >= 0).
struct PhysicalRange {
  double low, high;
  const char* unit;  // the internal unit, for messages: "m/s"
  bool contains(double value) const { return value >= low && value <= high; }
};
PhysicalRange physical_range(Quantity quantity);
// Of the quantities units.hpp has no units for (heat rates, heat transfer coefficients).
inline constexpr PhysicalRange kHeatRateRange{0, 1e6, "W"};
inline constexpr PhysicalRange kHeatTransferRange{0, 1e5, "W/(m²·K)"};

// "velocity_m_s = 1e308 is beyond the range of a rig's values (-20 to 20 m/s): a typo or a
// wrong unit?" for a value as written, `range` the quantity's.
std::string out_of_range_message(std::string_view name, std::string_view written, const PhysicalRange& range);

}  // namespace lmcal
