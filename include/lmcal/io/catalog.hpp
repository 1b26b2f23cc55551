// Guide catalog: the geometry and material of the LM guides lmcal knows.
//
// The catalog is a TOML file (src/data/guides.toml is built into the binary;
// `load_catalog` reads another). One [[guide]] table per model. A value the
// sources do not give is written as the string "missing" and loads as an empty
// optional: the catalog never invents a number. A user's catalog may also hold [[bar]]
// tables — a plain heated bar of a lab experiment, named by `name`, with the rail's fields
// (area_m2, perimeter_m, conductivity_W_mK, density_kg_m3, specific_heat_J_kgK, and
// contact_length_mm, the heated length):
//   [[bar]]
//   name = "steel bar 20x20"
//   area_m2 = 4e-4
//   perimeter_m = 0.08
//   ... Each value may carry a note
// (its source, or "estimate: ..."), kept in GuideSpec::notes.
//
// Units are in the field names. Lb (block_length_mm) is the block length the
// paper's friction law uses; contact_length_mm (Lb1) is the block body length,
// over which the heat enters the rail.
//
// Example:
//   auto guide = lmcal::builtin_catalog().find("SRN 35C");
//   guide = lmcal::with_overrides(guide, {{"conductivity_W_mK", 36.0}});
//   double k = lmcal::require(guide, &lmcal::GuideSpec::conductivity_W_mK, "conductivity_W_mK");
//
// Trap: `find` matches model names ignoring case and spaces ("srn35c" finds "SRN 35C").
#pragma once

#include "lmcal/export.hpp"

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace LMCAL_API lmcal {

struct GuideSpec {
  std::string model;                              // e.g. "SRN 35C"; a bar's name
  std::string kind = "guide";                     // "guide" ([[guide]]) or "bar" ([[bar]]: a plain heated bar)
  std::string source;                             // the catalog it came from ("<built-in>" or the file)
  std::optional<double> block_length_mm;          // Lb (friction law)
  std::optional<double> contact_length_mm;        // Lb1 (heat input length)
  std::optional<double> rail_width_mm;
  std::optional<double> rail_height_mm;
  std::optional<double> rail_mass_kg_m;
  std::optional<double> area_m2;                  // rail cross-section A
  std::optional<double> perimeter_m;              // rail perimeter p (convection)
  std::optional<double> preload_um;               // pc used with this guide in the paper
  std::optional<double> density_kg_m3;            // ρ
  std::optional<double> specific_heat_J_kgK;      // c
  std::optional<double> conductivity_W_mK;        // k
  std::map<std::string, std::string> notes;       // field name -> source or estimate note
};

// Names of the numeric fields of GuideSpec, as used in the TOML file and by with_overrides.
const std::vector<std::string>& guide_field_names();

// Whether `value` lies in the physical range of the field called `name` (one of
// guide_field_names()): nullopt, or what was expected ("0.01 to 2000"). The catalog's rule, for
// overrides given elsewhere.
std::optional<std::string> guide_field_range_problem(std::string_view name, double value);

// The value of the field called `name` (one of guide_field_names()); InvalidParameter if unknown.
std::optional<double> field_value(const GuideSpec& spec, std::string_view name);

struct GuideCatalog {
  std::string source;  // file name, or "<built-in>"
  std::vector<GuideSpec> guides;

  // Throws InvalidParameter("guide", ...) listing the known models when not found.
  const GuideSpec& find(std::string_view model) const;
};

// Parses catalog text; errors are InputError with source name, line and column: an unknown
// key, a duplicate name, a value outside its physical range (density 100-30000 kg/m³,
// conductivity 0.01-2000 W/mK, …: a typo or a wrong unit).
GuideCatalog parse_catalog(std::string_view toml_text, const std::string& source_name);
GuideCatalog load_catalog(const std::filesystem::path& file);
const GuideCatalog& builtin_catalog();

// `model` from the user's catalog when it has it, else from the built-in one (a user catalog
// adds guides and bars, and may redefine a built-in guide). InvalidParameter listing both
// catalogs' names when neither has it.
const GuideSpec& find_guide(std::string_view model, const GuideCatalog* user = nullptr);

// Returns a copy with the named fields replaced; unknown names and non-physical
// values (<= 0, NaN, outside the field's physical range) throw InvalidParameter.
GuideSpec with_overrides(GuideSpec spec, const std::map<std::string, double>& overrides);

// The value of a field, or InvalidParameter saying that the catalog lacks it for this guide
// and how to supply it.
double require(const GuideSpec& spec, std::optional<double> GuideSpec::*field, const char* name);

}  // namespace lmcal
