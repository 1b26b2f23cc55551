#include "io/json_input.hpp"

#include <fmt/format.h>

#include <cmath>

#include "io/file_kind.hpp"
#include "io/input_file.hpp"
#include "lmcal/error.hpp"
#include "lmcal/version.hpp"

namespace lmcal::io {

namespace {

// The line and column (1-based) of byte `offset` of `text`.
std::pair<long, long> line_and_column(const std::string& text, std::size_t offset) {
  long line = 1, column = 1;
  for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return {line, column};
}

}  // namespace

std::string json_type(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::null: return "null";
    case nlohmann::json::value_t::object: return "an object";
    case nlohmann::json::value_t::array: return "an array";
    case nlohmann::json::value_t::string: return "a string";
    case nlohmann::json::value_t::boolean: return "true or false";
    case nlohmann::json::value_t::binary: return "binary data";
    case nlohmann::json::value_t::discarded: return "nothing";
    default: return "a number";
  }
}

void JsonFile::fail(const std::string& at, const std::string& what) const {
  throw InputError(file, 0, 0, fmt::format("field {}: {}", at, what));
}

namespace {

const nlohmann::json& member(const JsonFile& f, const nlohmann::json& parent, const std::string& key, const std::string& at) {
  if (!parent.is_object()) f.fail(at, "expected an object, found " + json_type(parent));
  const auto it = parent.find(key);
  if (it == parent.end()) f.fail(at.empty() ? key : at + "." + key, "missing");
  return *it;
}

std::string path(const std::string& at, const std::string& key) { return at.empty() ? key : at + "." + key; }

}  // namespace

const nlohmann::json& JsonFile::object(const nlohmann::json& parent, const std::string& key, const std::string& at) const {
  const nlohmann::json& j = member(*this, parent, key, at);
  if (!j.is_object()) fail(path(at, key), "expected an object, found " + json_type(j));
  return j;
}

const nlohmann::json& JsonFile::array(const nlohmann::json& parent, const std::string& key, const std::string& at) const {
  const nlohmann::json& j = member(*this, parent, key, at);
  if (!j.is_array()) fail(path(at, key), "expected an array, found " + json_type(j));
  return j;
}

std::string JsonFile::text(const nlohmann::json& parent, const std::string& key, const std::string& at) const {
  const nlohmann::json& j = member(*this, parent, key, at);
  if (!j.is_string()) fail(path(at, key), "expected a string, found " + json_type(j));
  return j.get<std::string>();
}

double JsonFile::number(const nlohmann::json& parent, const std::string& key, const std::string& at, bool null_is_nan) const {
  const nlohmann::json& j = member(*this, parent, key, at);
  if (j.is_null() && null_is_nan) return std::nan("");
  if (!j.is_number()) fail(path(at, key), "expected a number, found " + json_type(j));
  const double value = j.get<double>();
  if (!std::isfinite(value)) fail(path(at, key), "expected a finite number");
  return value;
}

bool JsonFile::flag(const nlohmann::json& parent, const std::string& key, const std::string& at, bool otherwise) const {
  if (!parent.is_object()) fail(at, "expected an object, found " + json_type(parent));
  const auto it = parent.find(key);
  if (it == parent.end()) return otherwise;
  if (!it->is_boolean()) fail(path(at, key), "expected true or false, found " + json_type(*it));
  return it->get<bool>();
}

namespace {

// A file of another layout (schema_version) or another major version of lmcal may have other
// fields or units: refused, not misread, as a model file of another major version is. A file
// without them (written before they were recorded) is read as it is.
void require_this_layout(const JsonFile& f) {
  if (const auto it = f.root.find("schema_version"); it != f.root.end() && !(it->is_number_integer() && *it == kOutputSchemaVersion))
    f.fail("schema_version", fmt::format("{}: written in another layout than this lmcal's ({}); rerun it with lmcal {}",
                                         it->dump(), kOutputSchemaVersion, LMCAL_VERSION));
  const auto version = f.root.find("lmcal_version");
  if (version == f.root.end()) return;
  if (!version->is_string()) f.fail("lmcal_version", "expected a string, found " + json_type(*version));
  const auto major = [](std::string_view v) { return v.substr(0, v.find('.')); };
  const std::string written = version->get<std::string>();
  if (major(written) != major(LMCAL_VERSION))
    f.fail("lmcal_version", fmt::format("{}: written by another major version of lmcal (this is {}); rerun it with this version",
                                        nlohmann::json(written).dump(), LMCAL_VERSION));
}

}  // namespace

JsonFile read_json_file(const std::filesystem::path& file, const std::string& expected) {
  const std::string text = read_text_file(file, expected);
  JsonFile out{file.string(), {}};
  try {
    out.root = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    const std::string kind = looks_like(text);
    if (!kind.empty() && kind != "a JSON document")
      throw InputError(out.file, 0, 0, fmt::format("this looks like {}; expected {}", kind, expected));
    const auto [line, column] = line_and_column(text, e.byte > 0 ? e.byte - 1 : 0);
    throw InputError(out.file, line, column, "not valid JSON: expected " + expected);
  } catch (const nlohmann::json::exception&) {  // out_of_range.406: 1e400
    throw InputError(out.file, 0, 0, "a number beyond the range of a double: expected " + expected);
  }
  if (!out.root.is_object()) throw InputError(out.file, 0, 0, fmt::format("expected {}, found {}", expected, json_type(out.root)));
  require_this_layout(out);
  return out;
}

}  // namespace lmcal::io
