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
// Runs as rigs produce them (all optional):
//   catalog = "my_guides.toml"      # top level: a user catalog (catalog.hpp), searched before the
//                                   #   built-in one; a user_catalog argument (the command line) wins
//   heat_rate_W = 8.0               # the heat, given (a heater, a measured power): not with
//   heat_rate_uncertainty_W = 0.1   #   mean/start_friction_N; its 1 σ, into α's interval
//   ambient_C = 23.5                # a constant ambient, for a CSV without ambient columns
//   h_W_m2K = 6.0                   # this run's convection coefficient (the fit's h where h is not fitted)
//   viscosity40_mm2_s = 68          # the oil's ν40, for a heat from the friction law (default 99)
//   [[run.schedule]]                # piecewise-constant phases from their from_s to the next one's:
//   from_s = 0                      #   the first at 0 (the first record), ascending, the last to
//   heat_rate_W = 10                #   the end; each gives velocity_m_s (0 = stopped; heat =
//   [[run.schedule]]                #   friction × that speed) or heat_rate_W, not both
//   from_h = 2
//   heat_rate_W = 0
// The CSV may carry a `heat_rate_W` column (a measured power, W): linear between records, like
// the ambient; it gives the run's heat, so no heat key or schedule goes with it.
//
// Rules: time strictly increasing; an empty or NaN temperature cell is kept as NaN and
// counted in report.missing (fits skip it); intervals longer than 1.5x the median step
// are counted in report.time_gaps. A thermal run needs velocity > 0 (optional when the heat is
// given: heat_rate_W, a schedule or the CSV column), load >= 0,
// stroke > 0, rail length > stroke + contact length, and a position for every tc column;
// mean_friction_uncertainty_N needs mean_friction_N (it is that value's uncertainty), and
// heat_rate_uncertainty_W a given heat (taken at the largest: a gain error of the power
// meter); an ambient column or ambient_C; a guide whose catalog entry (with the overrides)
// has area, perimeter, k, ρ, c and contact length — refused at load, not in the fit.
//
// Trap: mean_friction_N is the run's mean (what a load cell's log averages to), not the
// friction of the cold rail: the grease thins as the rail warms, so a mean over a 6 h run is
// below the start's. A thermal fit takes the heat from start_friction_N·V when it is given
// (the heat at the start temperature, where a friction-temperature coupling starts), else
// from mean_friction_N·V (and a coupled heat then keeps that mean over the run).
// Bad input throws InputError(file, line, column, what was expected), for the CSV and
// for the manifest alike, before anything is returned.
#pragma once

#include "lmcal/export.hpp"

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "lmcal/io/catalog.hpp"
#include "lmcal/io/input_scope.hpp"
#include "lmcal/io/load_report.hpp"

namespace LMCAL_API lmcal {

struct TemperatureChannel {
  std::string name;            // the header as written, e.g. "tc1_C"
  std::vector<double> values;  // °C, NaN = missing sample
};

// The longest time a trace may span, first record to last: 10^7 s, about 116 days (a guideway
// test runs hours; the rail model steps through every second of it).
inline constexpr double kMaxRunSpan_s = 1e7;

struct ThermalTrace {
  std::vector<double> time_s;
  std::vector<TemperatureChannel> ambient;
  std::vector<TemperatureChannel> rail;  // the tc… columns
  std::vector<double> heat_rate_W;       // the optional heat_rate_W column (empty: none), W
  std::vector<std::uint32_t> line;       // each record's line in report.file (empty: not read from a file)
  LoadReport report;
  std::size_t size() const { return time_s.size(); }
};

// `skip_lines`: lines before the column names (a logger's preamble), skipped whatever they hold;
// errors still name the file's own lines. A manifest's [[run]] gives it as `skip_lines = N`.
ThermalTrace load_thermal_trace(const std::filesystem::path& file, std::size_t skip_lines = 0);
// Writes a trace in canonical units (°C, s) with the given '#' comment lines first.
std::string thermal_trace_csv(const ThermalTrace& trace, const std::vector<std::string>& comments = {});

// One [[run.schedule]] phase: from from_s (since the first record) until the next phase.
struct ThermalPhase {
  double from_s = 0;
  std::optional<double> velocity_m_s;  // the block's speed (0: stopped), heat = friction × speed
  std::optional<double> heat_rate_W;   // or the heat, given
};

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
  std::optional<double> heat_rate_W;                // the heat, given (not friction × speed)
  std::optional<double> heat_rate_uncertainty_W;    // its standard uncertainty (1 σ)
  std::optional<double> ambient_C;                  // constant ambient (no ambient column)
  std::optional<double> h_W_m2K;                    // this run's convection coefficient
  std::optional<double> viscosity40_mm2_s;          // the oil's ν40 for the friction law
  std::vector<ThermalPhase> schedule;               // empty: one phase, the whole run
  GuideSpec guide_spec;  // the catalog entry of `guide` with guide_overrides applied (filled at load)
  ThermalTrace trace;
};

// The run's guide: guide_spec when the loader filled it, else (a run made in code) the built-in
// catalog's entry with the overrides.
GuideSpec resolved_guide(const ThermalRun& run);

struct ThermalDataSet {
  std::string name;
  std::string description;
  std::filesystem::path manifest;
  std::filesystem::path catalog_file;  // the user catalog the guides were resolved with (empty: none)
  std::vector<ThermalRun> runs;
};

// `user_catalog` (the command line's) wins over the manifest's `catalog` key; its source names
// the file recorded in catalog_file. The files it names must lie inside `scope` (input_scope.hpp:
// by default the manifest's folder).
ThermalDataSet load_thermal_dataset(const std::filesystem::path& manifest, const GuideCatalog* user_catalog = nullptr,
                                    const InputScope& scope = {});
// The manifest text for a data set (file paths written relative to `folder`).
std::string thermal_manifest_toml(const ThermalDataSet& set, const std::filesystem::path& folder);

}  // namespace lmcal
