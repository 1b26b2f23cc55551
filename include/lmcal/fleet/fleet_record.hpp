// One set of a fleet as its record (fleet_set.json) holds it: who it is, how it went, the
// calibrated constants with their uncertainty, the causes the diagnoses accepted, and the
// hashes that say when it is up to date (fleet.hpp). The same calibration gives the same
// bytes: no timings, no paths but those relative to the fleet's root.
//
//   {"kind": "fleet_set", "id": "u17/2026-09-01", "unit": "u17", "axis": "", "machine": "",
//    "date": "2026-09-01", "status": "ok", "error": "",
//    "parameters": [{"model": "friction", "name": "mu_v", "unit": "...", "value": 0.003,
//                    "se": 4e-5, "low": 0.0029, "high": 0.0031, "interval": "linear"}, ...],
//    "friction_causes": ["seal_drag"], "thermal_causes": [], "friction_verdict": "...", ...,
//    "inputs": [{"file": "u17/2026-09-01/friction.csv", "sha256": "..."}], "options_sha256": "..."}
//
// Trap: a parameter the fit held or could not determine has se, low and high null (NaN here).
#pragma once

#include "lmcal/export.hpp"

#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "lmcal/calibrate/calibration.hpp"

namespace LMCAL_API lmcal {

struct FleetParameter {
  std::string model;  // "friction" or "thermal"
  std::string name, unit;
  double value = NAN, se = NAN;
  double low = NAN, high = NAN;  // the 95 % interval the calibration quotes
  std::string interval;          // "linear" or "profile"
};

struct FleetRecord {
  std::string id, unit, axis, machine, date;
  std::string lmcal_version, options_sha256;
  std::vector<std::pair<std::string, std::string>> inputs;  // file relative to the root -> sha256
  std::string status = "ok";  // "ok" or "failed"
  std::string error;          // why it failed
  // The calibrated model's parameters (the law's constants, the accepted causes' effects, α
  // and the rail's mechanisms); empirical terms and per-run nuisances left out.
  std::vector<FleetParameter> parameters;
  std::vector<std::string> friction_causes, thermal_causes;
  std::string friction_verdict, thermal_verdict;  // the diagnoses' verdicts ("" when not run)
  double friction_rmse_N = NAN;     // the calibrated law's residual RMSE
  double thermal_cv_rmse_K = NAN;   // the calibrated rail model's held-out RMSE
  std::vector<std::string> warnings;
  // The files the set wrote into its output folder besides this record: the only ones a later
  // run of the set may remove (nullopt: a record of an lmcal before 0.2 that did not list them).
  std::optional<std::vector<std::string>> outputs;

  const FleetParameter* find(std::string_view model, std::string_view name) const;
};

// "17 axis X", or the unit alone.
std::string fleet_series(std::string_view unit, std::string_view axis);

// Fills the results of a calibration; a calibrated fit the solver could not make usable fails
// the record (status "failed", the solver's reason).
void fill_fleet_record(FleetRecord& record, const Calibration& c);

std::string fleet_record_json(const FleetRecord& record);
// InputError (naming `file`) for a text that is not a fleet record.
FleetRecord parse_fleet_record(std::string_view json, const std::string& file = "fleet_set.json");

}  // namespace lmcal
