// Writing outputs whole or not at all.
//
// A set of files is committed in steps that a kill at any moment leaves recoverable:
//   1. the output folder is locked (flock on the folder itself): two writers into one folder
//      take turns, and one's files never mix with the other's;
//   2. what a killed commit left there is finished (recover_outputs);
//   3. every file is written to a temporary in its folder, `.NAME.lmcal-PID.tmp`, and fsynced;
//   4. a journal naming every rename and removal is written and fsynced (`.lmcal-commit`):
//      from here on the set is committed;
//   5. the temporaries are renamed over their targets, the files the set replaces removed,
//      the folders fsynced, and the journal removed.
// A kill before step 4 leaves the old files and temporaries that the next commit (or
// recover_outputs) removes; a kill after it leaves a journal that the next commit completes.
// SIGINT and SIGTERM wait until the commit is over (blocked during it, delivered after).
// Folders the commit created are removed again when it fails.
//
// Example:
//   lmcal::OutputSet out;
//   out.add("fits/run.csv", csv_text);
//   out.add("fits/run.json", json_text);
//   out.remove("fits/run_diagnosis.json");  // an earlier set's file this one does not have
//   out.commit();   // throws InputError naming the file and the system's reason
//
// Trap: nothing reaches disk before commit(); build all contents first.
#pragma once

#include "lmcal/export.hpp"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace LMCAL_API lmcal {

class OutputSet {
 public:
  // A file of the set; the same path twice is refused (std::invalid_argument: a caller's bug).
  void add(std::filesystem::path path, std::string contents);
  // A file an earlier set wrote that this one replaces by nothing: removed in the commit,
  // if present (a path also added is kept).
  void remove(std::filesystem::path path);
  // Writes all files (creating parent folders), then moves them into place.
  void commit();
  const std::vector<std::pair<std::filesystem::path, std::string>>& files() const { return files_; }

 private:
  std::vector<std::pair<std::filesystem::path, std::string>> files_;
  std::vector<std::filesystem::path> removals_;
};

void write_file_atomically(const std::filesystem::path& path, const std::string& contents);

// Free space a command's outputs need, roughly: a calibration's report and samples of a large log.
inline constexpr std::uintmax_t kMinFreeOutputBytes = std::uintmax_t{64} << 20;

// Why outputs could not be committed into `folder` (created by the commit if missing), or
// nullopt: the nearest folder on its path that exists is not a folder, is not writable, or has
// less than `needed_bytes` free. For a check before a long computation: a read-only or full
// disk is told at once, not after it.
std::optional<std::string> output_folder_problem(const std::filesystem::path& folder,
                                                 std::uintmax_t needed_bytes = kMinFreeOutputBytes);

// Finishes what a killed commit left in `folder`: completes a journaled commit and removes
// temporaries no commit will use. Takes the folder's lock; nothing to do returns at once.
void recover_outputs(const std::filesystem::path& folder);

}  // namespace lmcal
