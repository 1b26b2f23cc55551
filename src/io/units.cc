#include "lmcal/io/units.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <span>

namespace lmcal {

namespace {

struct UnitDef {
  const char* name;
  Conversion conversion;  // to the quantity's internal unit
};

// The single table of accepted units, the internal one first (scale 1, offset 0).
// Exact definitions: 1 kgf = 9.80665 N (CGPM 1901), 1 lbf = 4.4482216152605 N (avoirdupois pound
// times standard gravity), T[°C] = T[K] - 273.15, T[°C] = (T[°F] - 32) · 5/9.
constexpr std::array<UnitDef, 4> kTime{{{"s", {1, 0}}, {"ms", {1e-3, 0}}, {"min", {60, 0}}, {"h", {3600, 0}}}};
constexpr std::array<UnitDef, 3> kVelocity{{{"m_s", {1, 0}}, {"mm_s", {1e-3, 0}}, {"m_min", {1.0 / 60, 0}}}};
constexpr std::array<UnitDef, 4> kForce{
    {{"N", {1, 0}}, {"kN", {1e3, 0}}, {"kgf", {9.80665, 0}}, {"lbf", {4.4482216152605, 0}}}};
constexpr std::array<UnitDef, 2> kPreload{{{"um", {1, 0}}, {"mm", {1e3, 0}}}};
constexpr std::array<UnitDef, 2> kLengthMm{{{"mm", {1, 0}}, {"m", {1e3, 0}}}};
constexpr std::array<UnitDef, 2> kDistanceM{{{"m", {1, 0}}, {"mm", {1e-3, 0}}}};
constexpr std::array<UnitDef, 3> kTemperature{
    {{"C", {1, 0}}, {"K", {1, -273.15}}, {"F", {5.0 / 9.0, -32.0 * 5.0 / 9.0}}}};
constexpr std::array<UnitDef, 3> kViscosity{{{"mm2_s", {1, 0}}, {"cSt", {1, 0}}, {"m2_s", {1e6, 0}}}};
// 1 rpm = 2π/60 rad/s. "percent" of a nominal torque converts to a fraction (is_relative_unit).
constexpr double kPi = 3.14159265358979323846;
constexpr std::array<UnitDef, 2> kAngularVelocity{{{"rad_s", {1, 0}}, {"rpm", {2 * kPi / 60, 0}}}};
constexpr std::array<UnitDef, 2> kTorque{{{"Nm", {1, 0}}, {"percent", {0.01, 0}}}};
// 1 g = 9.80665 m/s² (standard gravity, CGPM 1901).
constexpr std::array<UnitDef, 3> kAcceleration{{{"m_s2", {1, 0}}, {"mm_s2", {1e-3, 0}}, {"g", {9.80665, 0}}}};
constexpr std::size_t kQuantities = 11;

std::span<const UnitDef> units_of(Quantity quantity) {
  switch (quantity) {
    case Quantity::time: return kTime;
    case Quantity::velocity: return kVelocity;
    case Quantity::force: return kForce;
    case Quantity::preload: return kPreload;
    case Quantity::length_mm: return kLengthMm;
    case Quantity::distance_m: return kDistanceM;
    case Quantity::temperature: return kTemperature;
    case Quantity::viscosity: return kViscosity;
    case Quantity::angular_velocity: return kAngularVelocity;
    case Quantity::torque: return kTorque;
    case Quantity::acceleration: return kAcceleration;
  }
  return {};
}

}  // namespace

PhysicalRange physical_range(Quantity quantity) {
  switch (quantity) {
    case Quantity::time: return {-1e10, 1e10, "s"};  // seconds since any start, epoch included
    case Quantity::velocity: return {-20, 20, "m/s"};
    case Quantity::force: return {-1e7, 1e7, "N"};
    case Quantity::preload: return {-1000, 1000, "µm"};
    case Quantity::length_mm: return {-1e5, 1e5, "mm"};
    case Quantity::distance_m: return {-1000, 1000, "m"};
    case Quantity::temperature: return {-273.15, 1000, "°C"};
    case Quantity::viscosity: return {1e-3, 1e6, "mm²/s"};
    case Quantity::angular_velocity: return {-1e5, 1e5, "rad/s"};  // ~1e6 rpm
    case Quantity::torque: return {-1e6, 1e6, "N·m"};
    case Quantity::acceleration: return {-1e4, 1e4, "m/s²"};  // ~1000 g
  }
  return {0, 0, ""};
}

std::string out_of_range_message(std::string_view name, std::string_view written, const PhysicalRange& range) {
  return fmt::format("{} = {} is beyond the range of a rig's values ({:g} to {:g} {}): a typo or a wrong unit?", name, written,
                     range.low, range.high, range.unit);
}

const std::vector<std::string>& unit_names(Quantity quantity) {
  // One list per quantity, built once; indexed by the enum's value.
  static const std::array<std::vector<std::string>, kQuantities> names = [] {
    std::array<std::vector<std::string>, kQuantities> all;
    for (std::size_t q = 0; q < all.size(); ++q) {
      for (const UnitDef& unit : units_of(static_cast<Quantity>(q))) all[q].emplace_back(unit.name);
    }
    return all;
  }();
  return names.at(static_cast<std::size_t>(quantity));
}

std::optional<Conversion> unit_conversion(Quantity quantity, std::string_view unit) {
  for (const UnitDef& def : units_of(quantity)) {
    if (unit == def.name) return def.conversion;
  }
  return std::nullopt;
}

bool is_relative_unit(Quantity quantity, std::string_view unit) {
  return quantity == Quantity::torque && unit == "percent";
}

std::optional<SplitName> split_unit(std::string_view column, Quantity quantity) {
  // Longest match, so that a unit that ends another one ("s" inside "m_s") cannot steal
  // part of it. With the '_' separator required, today's tables never match twice; the
  // rule keeps it that way when units are added.
  const UnitDef* best = nullptr;
  for (const UnitDef& def : units_of(quantity)) {
    const std::string_view unit = def.name;
    if (column.size() < unit.size() + 2) continue;  // at least one name character and '_'
    if (!column.ends_with(unit) || column[column.size() - unit.size() - 1] != '_') continue;
    if (!best || unit.size() > std::string_view(best->name).size()) best = &def;
  }
  if (!best) return std::nullopt;
  const std::size_t unit_size = std::string_view(best->name).size();
  return SplitName{std::string(column.substr(0, column.size() - unit_size - 1)), best->name, best->conversion};
}

}  // namespace lmcal
