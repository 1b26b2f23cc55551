// Reading a JSON file lmcal wrote back in, as strictly as a CSV or a manifest: a document that
// is not JSON is refused at its line and column (and named by the kind it looks like), and a
// field of the wrong type, missing or out of range by its path in the document:
//   friction.json: field parameters[3].value: expected a number, found a string
//
//   const io::JsonFile f = io::read_json_file(path, "a friction fit JSON (friction.json of lmcal fit friction)");
//   for (const auto& p : f.array(f.root, "parameters", "parameters")) { … f.number(p, "value", at) … }
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace lmcal::io {

struct JsonFile {
  std::string file;
  nlohmann::json root;

  // Checked access: `at` is the field's path for messages ("parameters[3]"). Each throws
  // InputError naming the file and the field.
  const nlohmann::json& object(const nlohmann::json& parent, const std::string& key, const std::string& at) const;
  const nlohmann::json& array(const nlohmann::json& parent, const std::string& key, const std::string& at) const;
  std::string text(const nlohmann::json& parent, const std::string& key, const std::string& at) const;
  // A finite number; a null (lmcal writes NaN as null) gives NaN when `null_is_nan`.
  double number(const nlohmann::json& parent, const std::string& key, const std::string& at, bool null_is_nan = false) const;
  // An optional flag: `otherwise` when absent.
  bool flag(const nlohmann::json& parent, const std::string& key, const std::string& at, bool otherwise) const;
  [[noreturn]] void fail(const std::string& at, const std::string& what) const;
};

// The file parsed (a JSON object at the top), or an InputError: at the line and column where
// the text stops being JSON, or "this looks like a CSV file; expected `expected`".
JsonFile read_json_file(const std::filesystem::path& file, const std::string& expected);

// The JSON type of `j` in words, for messages: "a string", "an array", "null".
std::string json_type(const nlohmann::json& j);

}  // namespace lmcal::io
