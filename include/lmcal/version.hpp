// What lmcal was built from: its version and commit, and the libraries' versions, for
// `lmcal --version`, the report's provenance and the outputs' records.
//
// Example: for (auto& [name, version] : lmcal::software_versions()) std::cout << name << " " << version;
//
// Trap: the git commit is the build's, not the outputs': it is in --version only, so the same
// inputs give the same output files from any commit of the same version.
#pragma once

#include "lmcal/export.hpp"

#include <string>
#include <utility>
#include <vector>

namespace LMCAL_API lmcal {

// The layout of every JSON output ("schema_version"; docs/schema/lmcal-output.schema.json).
// 2: one parameter record everywhere (parameter_json: "ci95" the quoted interval), and the
// provenance of every file calibrate writes (command, inputs, options, software).
inline constexpr int kOutputSchemaVersion = 2;

// lmcal, Ceres Solver, Eigen, NLopt, fmt, nlohmann-json, toml++, Boost, OpenSSL and the
// compiler, each "major.minor.patch" (the compiler as it names itself).
std::vector<std::pair<std::string, std::string>> software_versions();

// The commit lmcal was built from ("-dirty" with local changes), or "unknown".
std::string git_commit();

}  // namespace lmcal
