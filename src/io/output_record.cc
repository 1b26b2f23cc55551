#include "lmcal/io/output_record.hpp"

#include <nlohmann/json.hpp>

#include "lmcal/version.hpp"

namespace lmcal {

std::string with_output_record(const std::string& json_text, const std::vector<std::string>& command,
                               const std::vector<std::pair<std::string, std::string>>* inputs,
                               const std::vector<std::pair<std::string, std::string>>* options) {
  nlohmann::json j = nlohmann::json::parse(json_text);
  if (!command.empty() && !j.contains("command")) j["command"] = command;
  if (inputs && !j.contains("inputs")) {
    j["inputs"] = nlohmann::json::array();
    for (const auto& [file, hash] : *inputs) j["inputs"].push_back({{"file", file}, {"sha256", hash}});
  }
  if (options && !j.contains("options")) {
    j["options"] = nlohmann::json::object();
    for (const auto& [name, value] : *options) j["options"][name] = value.empty() ? nlohmann::json(nullptr) : nlohmann::json(value);
  }
  if (!j.contains("schema_version")) j["schema_version"] = kOutputSchemaVersion;
  j["software"] = nlohmann::json::object();
  for (const auto& [name, version] : software_versions()) j["software"][name] = version;
  return j.dump(2) + "\n";
}

}  // namespace lmcal
