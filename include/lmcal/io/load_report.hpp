// What a loader did besides returning values: rows read and skipped (and why), columns
// ignored, unit conversions applied, gaps found. Part of every loaded result.
#pragma once

#include "lmcal/export.hpp"

#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace LMCAL_API lmcal {

struct LoadReport {
  std::string file;
  std::size_t rows_read = 0;                       // data rows (not comments or the header)
  std::size_t rows_kept = 0;
  std::map<std::string, std::size_t> skipped;      // reason -> count, e.g. "friction_N empty or NaN"
  std::map<std::string, std::size_t> missing;      // column -> samples stored as NaN (thermal traces)
  std::vector<std::string> ignored_columns;        // header names lmcal does not use
  std::map<std::string, std::string> conversions;  // column -> "kgf -> N"
  std::size_t time_gaps = 0;                       // intervals longer than 1.5x the median step
  double bytes = 0;
  // Likely mistakes that did not stop the load (a column that looks like a known one but is
  // not read, a magnitude where a signed value was expected, …): printed by `check`, kept in
  // the JSON outputs and listed in the report's "data loaded" section.
  std::vector<std::string> warnings;
  // What the loader assumed where the file is silent (a run named after the file, conditions
  // not given): printed by `check` and kept with the warnings' neighbours.
  std::vector<std::string> notes;
};

}  // namespace lmcal
