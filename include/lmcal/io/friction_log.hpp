// Friction logs: tidy CSV from a load-cell rig, one row per sample.
//
// Required columns (any accepted unit, see units.hpp):
//   run, velocity_m_s, load_N, preload_um, block_length_mm, temperature_C, friction_N
// Optional: time_s, viscosity40_mm2_s (default 99), direction (+1/-1, default +1), guide.
// Lines starting with '#' are comments. Columns lmcal does not know are ignored and
// listed in the report; a known quantity with an unknown unit is an error.
//
// Rules: velocity is a speed (>= 0; the direction column gives the sense), load and
// preload >= 0, block length > 0, temperature above absolute zero, time (if present)
// non-decreasing within a run. An empty or NaN friction cell skips the row and is
// counted in report.skipped; any other empty, NaN or non-numeric cell is an error.
//
// Bad input throws InputError(file, line, column, what was expected) before anything
// is returned; the column is the 1-based character position of the offending cell.
//
// Example:
//   auto log = lmcal::load_friction_log("measurements/friction/srn35c.csv");
//   for (std::size_t i = 0; i < log.size(); ++i) use(log.conditions(i), log.friction_N[i]);
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "lmcal/io/load_report.hpp"
#include "lmcal/models/friction.hpp"

namespace lmcal {

// Columns, one entry per kept sample (struct of arrays: fast to load and to fit).
struct FrictionLog {
  std::vector<std::string> run_names;    // run index -> name as written in the file(s)
  std::vector<std::string> guide_names;  // guide index -> model ("" when the file has no guide column)
  std::vector<std::uint32_t> run;        // index into run_names
  std::vector<std::uint32_t> guide;      // index into guide_names
  std::vector<double> time_s;            // NaN when the file has no time column
  std::vector<double> velocity_m_s;
  std::vector<double> load_N;
  std::vector<double> preload_um;
  std::vector<double> block_length_mm;
  std::vector<double> temperature_C;
  std::vector<double> friction_N;
  std::vector<double> viscosity40_mm2_s;
  std::vector<std::int8_t> direction;    // +1 or -1
  std::vector<LoadReport> reports;       // one per file loaded

  std::size_t size() const { return friction_N.size(); }
  // The operating point of sample i for the friction law, direction included (ν_ref is per
  // sample: viscosity40_mm2_s).
  FrictionConditions<double> conditions(std::size_t i) const;
  // Appends one sample to every column.
  void append(std::uint32_t run_index, std::uint32_t guide_index, double time, const FrictionConditions<double>& c,
              double friction, double viscosity40);
};

FrictionLog load_friction_log(const std::filesystem::path& file);
// Several files into one log; run names are shared across files (same name = same run).
FrictionLog load_friction_logs(const std::vector<std::filesystem::path>& files);

// Writes a log in the canonical units (the inverse of load_friction_log), with the given
// '#' comment lines first.
std::string friction_log_csv(const FrictionLog& log, const std::vector<std::string>& comments = {});

}  // namespace lmcal
