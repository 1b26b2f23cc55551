// lmcal fleet: every measurement set under a folder calibrated as `lmcal calibrate` would,
// resumably, and the population they form.
//
//   ROOT/                        a folder per unit, or per unit and date:
//     u17/2026-09-01/friction.csv, thermal.toml, …     (unit "u17", date 2026-09-01)
//     u18/friction.csv …                               (unit "u18", no date)
//     fleet.toml                 optional: names each set's unit, date, machine and axis
//
//   OUT/<set>/…                  each set's outputs as `lmcal calibrate` writes them, and
//   OUT/<set>/fleet_set.json     the set's record (below), written last, in the same commit;
//                                it lists the files the set wrote: the only ones a later run removes
//   OUT/fleet.json, fleet.csv, fleet.html   the population (fleet_summary.hpp)
//
// fleet.toml lists the sets (then only those are calibrated):
//   [[set]]
//   folder = "u17/2026-09-01"   # relative to ROOT
//   unit = "17"                 # the unit (a guide, an axis): what repeats over dates
//   axis = "X"                  # optional; with `unit` it names the series ("17 axis X")
//   machine = "M3"              # optional, for grouping
//   date = 2026-09-01           # optional; TOML date or "YYYY-MM-DD"
// Without it every folder under ROOT holding measurements (friction*.csv, friction*.toml,
// thermal*.toml) is a set; a last folder named YYYY-MM-DD is its date, the path above it
// the unit.
//
// A set's record (fleet_set.json) holds its status ("ok" or "failed" with the error), the
// calibrated constants with SE and interval, the accepted causes and verdicts, the SHA-256 of
// every input and of the options. A set whose record matches its inputs and the options is
// up to date and not calibrated again: a killed fleet resumes where it stopped, and a failed
// set stays failed until its files change. The records are the same bytes whoever made them
// (no timings), so the summary is the same with any number of jobs, shards or ranks.
//
// Example:
//   const auto fleet = lmcal::discover_fleet("plant_logs");
//   lmcal::FleetOptions o{.output_dir = "fits/plant_logs", .jobs = 2};
//   const auto run = lmcal::run_fleet(fleet, o);
//   const auto summary = lmcal::summarize_fleet(fleet, run.records);
//
// Trap: the inputs are hashed by their path relative to ROOT; a set whose manifest names a file
// beside it under ROOT is checked by that path ("shared/trace.csv"); one outside ROOT is refused
// unless allow_outside_root.
#pragma once

#include "lmcal/export.hpp"

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "lmcal/calibrate/calibration.hpp"

namespace LMCAL_API lmcal {

struct FleetSet {
  std::string id;  // the folder relative to ROOT, '/'-separated: names the set everywhere
  std::filesystem::path dir;
  std::string unit, axis, machine;
  std::string date;  // "YYYY-MM-DD", or empty
  // The unit and axis: what one series of dates is ("17 axis X").
  std::string series() const;
};

struct Fleet {
  std::filesystem::path root;
  bool allow_outside_root = false;  // the sets' folders and files may lie outside root
  std::vector<FleetSet> sets;       // in order of id
  std::string source;               // "fleet.toml" or "folders"
};

// The sets under `root`; `exclude` (the output folder, if inside root) is not searched. An
// InputError, before any work, for a root without measurement folders, a fleet.toml entry
// naming a missing folder or one without measurements, two entries for one folder or for one
// unit, axis and date, or a bad date. Every folder, and every file a set's manifests name, must
// resolve inside root (a fleet.toml `folder = "../B"`, a link out of root: refused, input_scope.hpp)
// unless `allow_outside_root`; such a set's id is "outside/<absolute path>".
Fleet discover_fleet(const std::filesystem::path& root, const std::filesystem::path& exclude = {},
                     bool allow_outside_root = false);

inline constexpr const char* kFleetRecordFile = "fleet_set.json";

struct FleetOptions {
  CalibrationOptions calibration;
  std::filesystem::path output_dir;  // OUT: each set's outputs in OUT/<id>
  std::size_t jobs = 1;              // sets calibrated at once on this machine
  std::size_t shard = 0, shards = 1; // this process calibrates the sets with index % shards == shard
};

// SHA-256 of the options a set's outputs depend on (the calibration's, and lmcal's version).
std::string fleet_options_hash(const CalibrationOptions& options);

// One set's outcome: its record (fleet_set.json's text) and whether it was calibrated now.
struct FleetSetOutcome {
  std::string record;
  bool computed = false;
  bool failed = false;
};

// The set's record if it is up to date (matching inputs and options), else calibrates it and
// commits its outputs and record whole or not at all. A set that cannot be calibrated (a bad
// file, an unusable fit) gets a record saying why, and its stale outputs are removed; the
// exception does not escape. Safe to call from several threads for different sets.
FleetSetOutcome run_fleet_set(const Fleet& fleet, std::size_t index, const FleetOptions& options,
                              const std::string& options_hash);

// The record of set `index` on disk if it is up to date; nullopt otherwise.
std::optional<std::string> up_to_date_record(const Fleet& fleet, std::size_t index, const FleetOptions& options,
                                             const std::string& options_hash);

struct FleetRun {
  std::vector<std::optional<std::string>> records;  // per set; nullopt: another shard's
  std::size_t computed = 0, skipped = 0, failed = 0;
};

// Called after each set with (sets done, sets of this shard, the set's id, its outcome).
using FleetProgress = std::function<void(std::size_t, std::size_t, const std::string&, const FleetSetOutcome&)>;

// This shard's sets on `options.jobs` threads, each taking the next set when it is free
// (sets differ tenfold in cost). Each thread runs its calibration's OpenMP loops on one thread
// when jobs > 1.
FleetRun run_fleet(const Fleet& fleet, const FleetOptions& options, const FleetProgress& progress = {});

// The records on disk for --summarize: every set's, up to date; InputError naming the sets
// that have none (a shard that did not run or finish) and how to make them.
std::vector<std::string> read_fleet_records(const Fleet& fleet, const FleetOptions& options);

}  // namespace lmcal
