#include "lmcal/io/drive.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lmcal/error.hpp"

namespace lmcal {

namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

// Beyond them, a typo or a wrong unit (a lead of 10 m, a ratio of 1e9).
constexpr double kMaxLength_mm = 1e4;
constexpr double kMaxGearRatio = 1e6;

void check_length(const char* key, double value_mm) {
  if (!(value_mm > 0 && value_mm <= kMaxLength_mm))
    throw InvalidParameter(key, value_mm, fmt::format("a length > 0 and at most {:g} mm", kMaxLength_mm));
}

}  // namespace

const std::vector<std::string_view>& Drive::keys() {
  static const std::vector<std::string_view> names{"lead_mm",    "pinion_radius_mm",    "gear_ratio",
                                                   "efficiency", "rotor_inertia_kg_m2", "nominal_torque_Nm"};
  return names;
}

bool Drive::is_key(std::string_view key) { return std::find(keys().begin(), keys().end(), key) != keys().end(); }

void Drive::set(std::string_view key, double value) {
  Drive one;  // the key alone against its range
  if (key == "lead_mm") one.lead_mm = value;
  else if (key == "pinion_radius_mm") one.pinion_radius_mm = value;
  else if (key == "gear_ratio") one.gear_ratio = value;
  else if (key == "efficiency") one.efficiency = value;
  else if (key == "rotor_inertia_kg_m2") one.rotor_inertia_kg_m2 = value;
  else if (key == "nominal_torque_Nm") one.nominal_torque_Nm = value;
  else throw InvalidParameter("drive", fmt::format("unknown key '{}'; known: {}", key, fmt::join(keys(), ", ")));
  one.validate();
  if (key == "lead_mm") lead_mm = value;
  else if (key == "pinion_radius_mm") pinion_radius_mm = value;
  else copy_key(key, one);
}

void Drive::copy_key(std::string_view key, const Drive& from) {
  if (key == "lead_mm" || key == "pinion_radius_mm") {
    lead_mm = from.lead_mm;
    pinion_radius_mm = from.pinion_radius_mm;
  } else if (key == "gear_ratio") {
    gear_ratio = from.gear_ratio;
  } else if (key == "efficiency") {
    efficiency = from.efficiency;
  } else if (key == "rotor_inertia_kg_m2") {
    rotor_inertia_kg_m2 = from.rotor_inertia_kg_m2;
  } else if (key == "nominal_torque_Nm") {
    nominal_torque_Nm = from.nominal_torque_Nm;
  }
}

void Drive::validate() const {
  if (lead_mm && pinion_radius_mm)
    throw InvalidParameter("pinion_radius_mm", "a drive is a screw (lead_mm) or a rack and pinion (pinion_radius_mm), "
                                               "not both: give one");
  if (lead_mm) check_length("lead_mm", *lead_mm);
  if (pinion_radius_mm) check_length("pinion_radius_mm", *pinion_radius_mm);
  if (!(gear_ratio > 0 && gear_ratio <= kMaxGearRatio))
    throw InvalidParameter("gear_ratio", gear_ratio, fmt::format("> 0 and at most {:g} (motor turns per screw or pinion turn)", kMaxGearRatio));
  if (!(efficiency > 0 && efficiency <= 1)) throw InvalidParameter("efficiency", efficiency, "> 0 and <= 1");
  if (!(rotor_inertia_kg_m2 >= 0 && std::isfinite(rotor_inertia_kg_m2)))
    throw InvalidParameter("rotor_inertia_kg_m2", rotor_inertia_kg_m2, ">= 0");
  if (nominal_torque_Nm && !(*nominal_torque_Nm > 0 && std::isfinite(*nominal_torque_Nm)))
    throw InvalidParameter("nominal_torque_Nm", *nominal_torque_Nm, "> 0");
}

// Per radian of the screw or pinion the carriage moves p / 2π (screw) or r (pinion), in m.
double Drive::speed_per_motor_rad_s() const {
  const double per_rad_m = lead_mm ? *lead_mm * 1e-3 / kTwoPi : pinion_radius_mm.value_or(0) * 1e-3;
  return per_rad_m / gear_ratio;
}

// Power balance through the drive: F · v = η · τ · ω.
double Drive::force_per_motor_Nm() const { return efficiency / speed_per_motor_rad_s(); }

double Drive::reflected_inertia_kg() const {
  const double k = speed_per_motor_rad_s();
  return rotor_inertia_kg_m2 / (k * k);
}

std::string Drive::describe() const {
  std::string text = lead_mm ? fmt::format("screw, lead {:g} mm", *lead_mm)
                             : fmt::format("rack and pinion, pinion radius {:g} mm", pinion_radius_mm.value_or(0));
  text += fmt::format(", gear ratio {:g}, efficiency {:g}", gear_ratio, efficiency);
  if (nominal_torque_Nm) text += fmt::format(", nominal torque {:g} N·m", *nominal_torque_Nm);
  if (rotor_inertia_kg_m2 > 0)
    text += fmt::format(", rotor inertia {:g} kg·m² ({:.4g} kg at the carriage)", rotor_inertia_kg_m2, reflected_inertia_kg());
  return text;
}

}  // namespace lmcal
