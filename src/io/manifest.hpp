// Private TOML manifest machinery shared by the thermal and friction manifests: errors at the
// key's line and column, numbers and strings checked as they are read, keys whose name carries
// a unit ("load_kN"), and one key per quantity.
#pragma once

#include <toml++/toml.h>

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "io/toml_text.hpp"
#include "lmcal/io/input_scope.hpp"
#include "lmcal/io/units.hpp"

namespace lmcal::manifest {

struct Manifest {
  std::string file;                 // as errors name it
  std::filesystem::path folder;     // the files it names are relative to it
  InputScope scope;                 // and must lie inside the scope's root (by default `folder`)
  std::string kind = "manifest file";  // what the file is, as errors name it ("duty-cycle file")

  [[noreturn]] void fail(const toml::source_region& where, const std::string& what) const;
  // The manifest's TOML; a syntax error is an InputError at its line and column.
  toml::table parse() const;
  // `name` relative to the folder; an InputError at `where` when it is outside the scope
  // (checked before anything is opened) or not a file.
  std::filesystem::path existing_file(const toml::node& where, const std::string& name) const;
};

// A key that was given, for duplicate and range messages.
struct Given {
  const toml::key* key = nullptr;
  const toml::node* node = nullptr;
  Conversion conversion;  // for keys with a unit: to internal units
  double value = 0;       // for numbers: in internal units
};

// A finite TOML number (integer or float).
double number_of(const Manifest& m, const toml::key& key, const toml::node& node);
// The key's number in internal units; refused at the value when the conversion overflows
// (load_kN = 1e306 is finite as written, infinite in newtons).
// Also refused beyond `range` (the quantity's physical_range), checked in internal units.
double converted_number_of(const Manifest& m, const toml::key& key, const toml::node& node, const Conversion& conversion,
                           const PhysicalRange& range);
// A string value, checked with io::name_problem (line breaks and tabs allowed only for the
// free text of a `description`).
const std::string& string_of(const Manifest& m, const toml::key& key, const toml::node& node);
// `where` names the table in messages: "[run.sensors_m]".
const toml::table& table_of(const Manifest& m, const toml::node& node, std::string_view where);
// The [[run]] tables of a manifest, at most kMaxRuns of them (lmcal/io/limits.hpp).
const toml::array& run_tables(const Manifest& m, const toml::node& node);

// The conversion of a key with a unit suffix that names `base` ("velocity_mm_s" for
// "velocity"), nullopt for a key that names something else. A missing or unknown unit is an
// error at the key.
std::optional<Conversion> unit_key(const Manifest& m, const toml::key& key, std::string_view base, Quantity quantity);

// Records `given` as the key giving `what`; two keys for one thing (velocity_m_s and
// velocity_mm_s) are an error at the later one.
void remember(const Manifest& m, std::optional<Given>& slot, Given given, std::string_view what);

}  // namespace lmcal::manifest
