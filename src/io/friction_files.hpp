// Private: friction log files with what a manifest says about them (friction_manifest.cc
// builds the list, friction_log.cc reads it).
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "lmcal/io/friction_log.hpp"

namespace lmcal::detail {

struct FrictionFile {
  std::filesystem::path path;
  std::string run;  // the file's one run when the manifest names it ("": from the run column)
  // The manifest's conditions of the runs this file may hold, by id: what its columns may
  // leave out (empty without a manifest).
  std::map<std::string, FrictionRunConditions, std::less<>> runs;
  std::string manifest;  // the manifest's file, for messages
  std::optional<std::size_t> skip_lines;  // the manifest's skip_lines for this file (else RawFrictionOptions')
};

FrictionLog load_friction_files(const std::vector<FrictionFile>& files, const RawFrictionOptions& raw);

}  // namespace lmcal::detail
