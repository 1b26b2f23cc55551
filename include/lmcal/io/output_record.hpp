// Where a JSON output came from, as every one records it (schema_version 2,
// docs/schema/lmcal-output.schema.json):
//   "command": ["lmcal", …], "inputs": [{"file", "sha256"}], "software": {name: version},
//   "schema_version": 2, and where the writer knows them the options it ran with,
//   "options": {name: value} (the command line's, given or default; null: neither)
//
// Example: text = lmcal::with_output_record(text, {"lmcal", "fit", "friction", "a.csv"}, &inputs);
//
// Trap: what the writer already recorded stays as it wrote it (a fit records its own inputs);
// only "software" is always (re)written.
#pragma once

#include "lmcal/export.hpp"

#include <string>
#include <utility>
#include <vector>

namespace LMCAL_API lmcal {

// `json_text` (a JSON object) with the record added: the command unless empty, the inputs
// (file -> sha256) and the options (name -> value, "" for none) unless null, the software's
// versions and the schema version.
std::string with_output_record(const std::string& json_text, const std::vector<std::string>& command = {},
                               const std::vector<std::pair<std::string, std::string>>* inputs = nullptr,
                               const std::vector<std::pair<std::string, std::string>>* options = nullptr);

}  // namespace lmcal
