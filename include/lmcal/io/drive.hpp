// The drive between a motor and the carriage: what turns a rotary log's joint quantities (a
// motor's speed in rpm or rad/s, its torque in N·m or in % of its nominal torque) into the
// guide's linear speed and force. A friction manifest's [drive] table, the --lead /
// --pinion-radius / --gear-ratio / --efficiency / --rotor-inertia / --nominal-torque flags and
// the Python `raw` dict's keys of the same names set it (RawFrictionOptions::drive).
//
// With N the gear ratio (motor turns per screw or pinion turn), ω the motor's speed (rad/s), τ
// its torque (N·m), η the efficiency, p the screw lead (m), r the pinion radius (m):
//   screw:   v = ω / N · p / (2π)       F = η · τ · N · 2π / p
//   pinion:  v = ω / N · r              F = η · τ · N / r
//   rotor inertia J (kg·m²) reflected to the carriage:  J · (2π·N / p)²  or  J · (N / r)²  (kg)
// Both are linear: the loader folds them into a column's unit conversion, so a log read through
// a drive gives the samples the same log converted by hand to m/s and N gives.
//
// Example:  [drive]  lead_mm = 10  gear_ratio = 3  efficiency = 0.9
//   a motor at 1500 rpm drives the carriage at 1500·2π/60 / 3 · 0.010 / (2π) = 0.0833 m/s.
//
// Trap: the efficiency scales the motor's torque as the drive delivers it (motor driving the
// carriage). A backdriven screw (the carriage driving the motor) loses in the other sense;
// a log of that is read with the same η, so give η = 1 and correct by hand if that matters.
#pragma once

#include "lmcal/export.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace LMCAL_API lmcal {

struct Drive {
  std::optional<double> lead_mm;           // a ball or lead screw's lead (travel per screw turn)
  std::optional<double> pinion_radius_mm;  // a rack and pinion's pitch radius
  double gear_ratio = 1;                   // motor turns per screw or pinion turn (> 0)
  double efficiency = 1;                   // 0 < η <= 1
  double rotor_inertia_kg_m2 = 0;          // motor and gearbox, at the motor (>= 0; 0: not given)
  std::optional<double> nominal_torque_Nm;  // for torque_percent columns (> 0)

  // A lead or a pinion radius was given: the drive can convert joint quantities.
  bool given() const { return lead_mm.has_value() || pinion_radius_mm.has_value(); }
  // The keys, as manifests, flags' field names and the Python dict spell them.
  static const std::vector<std::string_view>& keys();
  static bool is_key(std::string_view key);
  // Sets key `key` (one of keys()) to `value`; InvalidParameter naming the key for a value out
  // of range (a zero lead, an efficiency of 1.5, a negative ratio).
  void set(std::string_view key, double value);
  // Copies key `key` from `from`; lead_mm and pinion_radius_mm go together (one names the kind
  // of drive, so a flag for either replaces a manifest's other).
  void copy_key(std::string_view key, const Drive& from);
  // InvalidParameter for a lead and a radius both, or a value out of range.
  void validate() const;

  // m/s of the carriage per rad/s of the motor; N of the carriage per N·m of the motor.
  double speed_per_motor_rad_s() const;
  double force_per_motor_Nm() const;
  // The rotor inertia seen at the carriage, kg.
  double reflected_inertia_kg() const;
  // "screw, lead 10 mm, gear ratio 3, efficiency 0.9" for reports.
  std::string describe() const;
};

}  // namespace lmcal
