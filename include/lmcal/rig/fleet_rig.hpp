// The virtual rig's fleet: many units (a guide, or one axis of a machine), each with its own
// friction constants and heat partition drawn around the paper's, some logged on several
// dates, for `lmcal fleet` and its tests. What a production lot or a plant's weekly logs look
// like, with a known truth:
//
//   unit u's value of constant c:  c_paper · (1 + spread_c · z_uc) · outlier factor
//                                  · (1 + drift · d / (dates − 1)) on its d-th date
//
// z_uc standard normal (one stream per unit); the unit-to-unit SD of c is thus spread_c ·
// c_paper. Each set is a friction log (FrictionRigConfig, one guide) and, unless thermal is
// off, a thermal data set (ThermalRigConfig) made with that unit's constants and α. A corrupt
// unit's first set has a friction log whose last row is cut short (a logger that lost power).
//
// Layout: ROOT/u01/2026-09-01/… for a dated unit, ROOT/u05/… for the others; fleet.toml
// names each set's unit, machine (four units to a machine) and date; fleet_truth.json holds
// every unit's true values, the spreads, outliers, drifts and corrupt sets.
//
// Trap: the fleet's sets are small on purpose (one guide, a few conditions, short thermal
// runs), so a fleet of 50 calibrates in seconds; the SEs are then those of small sets.
#pragma once

#include "lmcal/export.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "lmcal/rig/virtual_rig.hpp"

namespace LMCAL_API lmcal {

struct FleetRigChange {
  std::size_t unit = 0;   // 1-based
  std::string parameter;  // a friction constant's name (kFrictionConstantNames) or "alpha"
  double value = 0;       // outlier: a factor; drift: the relative change from first to last date
};

struct FleetRigConfig {
  std::size_t units = 40;
  std::size_t dated_units = 4;  // units 1..dated_units are logged on `dates` dates, the others once
  std::size_t dates = 8;
  std::string first_date = "2026-09-01";
  int days_between = 7;
  // Relative unit-to-unit SD of each constant ("alpha" too); the others are the paper's.
  std::map<std::string, double> spread{{"mu_v", 0.08}, {"mu_st", 0.05}, {"alpha", 0.05}};
  std::vector<FleetRigChange> outliers, drifts;
  std::vector<std::size_t> corrupt;  // 1-based units whose first set is corrupt
  bool thermal = true;
  FrictionRigConfig friction = small_friction();
  ThermalRigConfig thermal_rig = small_thermal();
  std::uint64_t seed = 1;

  static FrictionRigConfig small_friction();
  static ThermalRigConfig small_thermal();
};

struct FleetRigOutput {
  std::vector<std::pair<std::filesystem::path, std::string>> files;  // relative to ROOT
  std::size_t sets = 0;
};

// InvalidParameter for a change naming an unknown unit or parameter, a drift on an undated
// unit, or a factor <= 0.
FleetRigOutput generate_fleet(const FleetRigConfig& config);

}  // namespace lmcal
