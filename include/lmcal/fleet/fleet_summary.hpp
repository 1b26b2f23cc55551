// What a fleet's records say together (fleet.json, fleet.csv, fleet.html):
//
//   population  per constant of the law (k1 … f0) and of the rail model (α, h), over the
//               units (series: unit and axis), each by its EARLIEST calibrated set (as
//               delivered; later dates are the drift's): the random-effects mean, the
//               between-unit SD τ with its interval, and the share of the spread that is real
//               unit-to-unit difference rather than estimation noise (I²) — population.hpp;
//   outliers    units outside the population given their own uncertainty (Bonferroni over
//               units and constants at 5 %), named, and left out of the population they are
//               outside of;
//   drift       per series with >= 3 dated sets and per constant: a trend test and a
//               change-point test, Holm-adjusted over every series and constant tested; a
//               significant one is named: "u07: mu_v +24 % from 2026-09-01 to 2026-10-20
//               (since 2026-09-29), p = 0.0004";
//   causes      how many units' diagnoses accepted each cause (seal_drag, …) at any date;
//   failed      every set that could not be calibrated, with its error.
// Plots (fleet.html): a forest plot per constant (each unit's estimate and 95 % interval, the
// population mean, and the band μ ± 1.96 τ where a new unit is expected), drift lines per unit.
//
// Example:
//   auto summary = lmcal::summarize_fleet(fleet, run_records, {"lmcal", "fleet", "logs"});
//   for (auto& [name, text] : lmcal::fleet_summary_outputs(summary)) ...
//
// Trap: an outlier or a drift is relative to each unit's own SE: a calibration whose SEs are too
// small (issue: dependent residuals) turns estimation noise into "unit-to-unit difference".
#pragma once

#include "lmcal/export.hpp"

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "lmcal/fleet/fleet.hpp"
#include "lmcal/fleet/fleet_record.hpp"
#include "lmcal/fit/population.hpp"

namespace LMCAL_API lmcal {

struct PopulationOfParameter {
  std::string model, name, unit;
  std::vector<std::string> series, set_ids;  // the units in it and the set each came from
  std::vector<Estimate> estimates;
  PopulationFit fit;  // empty (k = 0) when fewer than 3 units estimated it; `note` says so
  std::string note;
};

struct OutlierFinding {
  std::string series, set_id, model, parameter, unit;
  double value = 0, se = 0, z = 0, p_adjusted = 0;
  double population_mean = 0;
  std::string text;
};

struct DriftFinding {
  std::string series, model, parameter, unit;
  std::vector<std::string> set_ids, dates;
  std::vector<DatedEstimate> points;  // day: days since 1970-01-01
  Drift drift;
  double p_holm = 1;  // over every series and constant tested
  bool significant = false;
  std::string text;
};

struct CauseCount {
  std::string model, cause;
  std::vector<std::string> series;  // the units whose diagnosis accepted it (at any date)
};

struct FleetSummary {
  std::string root, source;  // as given; "fleet.toml" or "folders"
  std::vector<std::string> command;
  double alpha = 0.05;  // family-wise level of the outlier and drift tests
  std::vector<FleetRecord> records;  // every set, in order of id
  std::size_t units = 0, ok = 0, failed = 0;
  std::vector<PopulationOfParameter> population;
  std::vector<OutlierFinding> outliers;  // flagged only
  std::vector<DriftFinding> drift;       // every series and constant tested
  std::vector<CauseCount> causes;
};

// The summary of the fleet's records (one per set, in the fleet's order; InputError naming the
// set for a record that is not one).
FleetSummary summarize_fleet(const Fleet& fleet, const std::vector<std::string>& records,
                             std::vector<std::string> command = {});

// fleet.json, fleet.csv (a row per set) and fleet.html, name -> contents.
std::vector<std::pair<std::string, std::string>> fleet_summary_outputs(const FleetSummary& summary);

// A few lines for the terminal: counts, the population's headline, the findings.
std::string fleet_summary_text(const FleetSummary& summary);

}  // namespace lmcal
