// Where the files an input names may be read from.
//
// A manifest's `file` and `catalog`, a duty's `catalog`, a fleet.toml's `folder`, and the logs
// and manifests a measurement folder holds must resolve (symlinks followed) inside a root: the
// folder of the file that names them, or the fleet's ROOT for every set of a fleet (a trace
// shared by the sets may then sit beside them: "../shared/trace.csv"). A path outside is refused
// before anything is opened, so that a folder someone else wrote cannot make lmcal read
// /etc/shadow, nor learn from lmcal's answer whether a file exists there.
//
// Example:
//   lmcal::InputScope scope{.root = "plant_logs"};   // a fleet's sets may share files under it
//   auto data = lmcal::load_thermal_dataset("plant_logs/u17/thermal.toml", nullptr, scope);
//
// Trap: `allow_outside` (the command line's --allow-outside-root) lifts the check for every
// file; the paths are still named in outputs as they were written.
#pragma once

#include "lmcal/export.hpp"

#include <filesystem>
#include <optional>
#include <string>

namespace LMCAL_API lmcal {

struct InputScope {
  std::filesystem::path root;  // empty: the folder of the file that names the path
  bool allow_outside = false;  // --allow-outside-root: any path is read

  // The root that applies to a path named by a file in `folder`.
  std::filesystem::path root_for(const std::filesystem::path& folder) const { return root.empty() ? folder : root; }
};

// Why `path` may not be read under `scope` when a file in `folder` names it, or nullopt: it
// resolves (made absolute, `..` applied, symlinks followed) outside the root. The message names
// the path and the root, never anything read from the path.
std::optional<std::string> outside_scope(const std::filesystem::path& path, const std::filesystem::path& folder,
                                         const InputScope& scope);

}  // namespace lmcal
