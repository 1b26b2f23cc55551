// Thermal runs: one CSV per run with `time_s`, one or more `ambient…_C` and one or more
// `tc…_C` columns (any time or temperature unit of units.hpp: `tc1_K`, `time_min`), and a
// TOML manifest per data set listing its runs.
//
// Manifest (paths relative to the manifest's folder; keys carry units, any accepted unit):
//   name = "bundled"
//   description = "..."
//   [[run]]
//   id = "v110"
//   file = "thermal/v110.csv"
//   guide = "SRN 35C"
//   velocity_m_s = 0.11
//   load_N = 3000
//   preload_um = 4
//   stroke_m = 0.2
//   rail_length_m = 0.6
//   contact_length_mm = 82.2        # optional: the catalog's
//   block_length_mm = 120.2         # optional: the catalog's
//   mean_friction_N = 44.1          # optional: measured friction force, its mean over the run
//   mean_friction_uncertainty_N = 0.9  # optional: its standard uncertainty (1 σ)
//   start_friction_N = 47.0         # optional: measured friction at the start temperature
//   [run.sensors_m]                 # position of every tc column from the rail centre
//   tc1_C = 0.0
//   tc2_C = 0.05
//   [run.guide_overrides]           # optional overrides of catalog values (not [run.guide]:
//   conductivity_W_mK = 36          #   TOML cannot have `guide` both a string and a table)
//
// Rules: time strictly increasing; an empty or NaN temperature cell is kept as NaN and
// counted in report.missing (fits skip it); intervals longer than 1.5x the median step
// are counted in report.time_gaps. A thermal run needs velocity > 0, load >= 0,
// stroke > 0, rail length > stroke + contact length, and a position for every tc column;
// mean_friction_uncertainty_N needs mean_friction_N (it is that value's uncertainty).
//
// Trap: mean_friction_N is the run's mean (what a load cell's log averages to), not the
// friction of the cold rail: the grease thins as the rail warms, so a mean over a 6 h run is
// below the start's. A thermal fit takes the heat from start_friction_N·V when it is given
// (the heat at the start temperature, where a friction-temperature coupling starts), else
// from mean_friction_N·V (and a coupled heat then keeps that mean over the run).
// Bad input throws InputError(file, line, column, what was expected), for the CSV and
// for the manifest alike, before anything is returned.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "lmcal/io/load_report.hpp"

namespace lmcal {

struct TemperatureChannel {
  std::string name;            // the header as written, e.g. "tc1_C"
  std::vector<double> values;  // °C, NaN = missing sample
};

struct ThermalTrace {
  std::vector<double> time_s;
  std::vector<TemperatureChannel> ambient;
  std::vector<TemperatureChannel> rail;  // the tc… columns
  LoadReport report;
  std::size_t size() const { return time_s.size(); }
};

ThermalTrace load_thermal_trace(const std::filesystem::path& file);
// Writes a trace in canonical units (°C, s) with the given '#' comment lines first.
std::string thermal_trace_csv(const ThermalTrace& trace, const std::vector<std::string>& comments = {});

struct ThermalRun {
  std::string id;
  std::filesystem::path file;
  std::string guide;
  double velocity_m_s = 0;
  double load_N = 0;
  std::optional<double> preload_um;
  double stroke_m = 0;
  double rail_length_m = 0;
  std::optional<double> contact_length_mm;
  std::optional<double> block_length_mm;
  std::optional<double> mean_friction_N;             // its mean over the run
  std::optional<double> mean_friction_uncertainty_N;  // standard uncertainty (1 σ) of mean_friction_N
  std::optional<double> start_friction_N;             // friction at the start temperature (the run's first minutes)
  std::map<std::string, double> sensor_position_m;  // tc column name -> x from the rail centre
  std::map<std::string, double> guide_overrides;    // catalog field -> value
  ThermalTrace trace;
};

struct ThermalDataSet {
  std::string name;
  std::string description;
  std::filesystem::path manifest;
  std::vector<ThermalRun> runs;
};

ThermalDataSet load_thermal_dataset(const std::filesystem::path& manifest);
// The manifest text for a data set (file paths written relative to `folder`).
std::string thermal_manifest_toml(const ThermalDataSet& set, const std::filesystem::path& folder);

}  // namespace lmcal
