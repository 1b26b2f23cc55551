// Writing outputs whole or not at all.
//
// Each file is written to a temporary sibling and renamed over the target only
// after every file of the set was written successfully, so an error leaves no
// half-written output behind (a reader sees the old file or the new one).
//
// Example:
//   lmcal::OutputSet out;
//   out.add("fits/run.csv", csv_text);
//   out.add("fits/run.json", json_text);
//   out.commit();   // throws InputError naming the file that could not be written
//
// Trap: nothing reaches disk before commit(); build all contents first.
#pragma once

#include "lmcal/export.hpp"

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace LMCAL_API lmcal {

class OutputSet {
 public:
  void add(std::filesystem::path path, std::string contents);
  // Writes all files (creating parent folders), then renames them into place.
  void commit();
  const std::vector<std::pair<std::filesystem::path, std::string>>& files() const { return files_; }

 private:
  std::vector<std::pair<std::filesystem::path, std::string>> files_;
};

void write_file_atomically(const std::filesystem::path& path, const std::string& contents);

}  // namespace lmcal
