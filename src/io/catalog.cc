#include "lmcal/io/catalog.hpp"

#include "io/input_file.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <unordered_map>

namespace lmcal {

namespace {

using Field = std::optional<double> GuideSpec::*;

struct FieldDef {
  const char* name;
  Field member;
  double low, high;  // physical range (inclusive): beyond it, a typo or a wrong unit
};

// The numeric fields of GuideSpec, in member order: the single table that ties
// TOML keys and override names to members, with the range a real rail or bar lies in.
constexpr std::array<FieldDef, 11> kFields{{
    {"block_length_mm", &GuideSpec::block_length_mm, 1, 2000},
    {"contact_length_mm", &GuideSpec::contact_length_mm, 1, 5000},
    {"rail_width_mm", &GuideSpec::rail_width_mm, 1, 1000},
    {"rail_height_mm", &GuideSpec::rail_height_mm, 1, 1000},
    {"rail_mass_kg_m", &GuideSpec::rail_mass_kg_m, 0.01, 1000},
    {"area_m2", &GuideSpec::area_m2, 1e-7, 1},
    {"perimeter_m", &GuideSpec::perimeter_m, 1e-3, 10},
    {"preload_um", &GuideSpec::preload_um, 1e-3, 100},
    {"density_kg_m3", &GuideSpec::density_kg_m3, 100, 30000},
    {"specific_heat_J_kgK", &GuideSpec::specific_heat_J_kgK, 50, 5000},
    {"conductivity_W_mK", &GuideSpec::conductivity_W_mK, 0.01, 2000},
}};

bool in_range(const FieldDef& field, double value) { return value >= field.low && value <= field.high; }

std::string range_text(const FieldDef& field) { return fmt::format("{:g} to {:g}", field.low, field.high); }

constexpr std::string_view kMissing = "missing";
constexpr std::string_view kModelKey = "model";  // [[guide]]
constexpr std::string_view kNameKey = "name";    // [[bar]]
constexpr std::string_view kNotesKey = "notes";

const FieldDef* find_field(std::string_view name) {
  const auto it = std::find_if(kFields.begin(), kFields.end(),
                               [&](const FieldDef& f) { return name == f.name; });
  return it == kFields.end() ? nullptr : &*it;
}

// Model names compare ignoring case and whitespace: "srn35c" == "SRN 35C".
std::string model_key(std::string_view model) {
  std::string key;
  for (const char ch : model) {
    const auto c = static_cast<unsigned char>(ch);
    if (!std::isspace(c)) key += static_cast<char>(std::tolower(c));
  }
  return key;
}

// Builds InputError at the position of a node (or key) in the TOML source.
InputError error_at(const std::string& source_name, const toml::source_region& where,
                    const std::string& what) {
  return InputError(source_name, static_cast<long>(where.begin.line), static_cast<long>(where.begin.column),
                    what);
}

// A numeric field: a finite number in the field's physical range (TOML integer or float), or
// "missing".
std::optional<double> parse_value(const toml::node& node, const FieldDef& field, const std::string& model,
                                  const std::string& source_name) {
  if (const auto* s = node.as_string(); s && s->get() == kMissing) return std::nullopt;
  std::optional<double> value;
  if (const auto* i = node.as_integer()) value = static_cast<double>(i->get());
  if (const auto* f = node.as_floating_point()) value = f->get();
  if (!value || !std::isfinite(*value) || *value <= 0) {
    throw error_at(source_name, node.source(),
                   fmt::format("expected a number > 0 or \"missing\" for {} of {}", field.name, model));
  }
  if (!in_range(field, *value)) {
    throw error_at(source_name, node.source(),
                   fmt::format("{} = {:g} of {} is not physical: expected {} (a typo or another unit?)", field.name,
                               *value, model, range_text(field)));
  }
  return value;
}

// The [guide.notes] sub-table: field name -> string.
std::map<std::string, std::string> parse_notes(const toml::node& node, const std::string& model,
                                               const std::string& source_name) {
  const auto* table = node.as_table();
  if (!table) {
    throw error_at(source_name, node.source(),
                   fmt::format("expected a table of field name = \"text\" for notes of {}", model));
  }
  std::map<std::string, std::string> notes;
  for (const auto& [key, value] : *table) {
    if (!find_field(key.str())) {
      throw error_at(source_name, key.source(),
                     fmt::format("unknown guide field '{}' in notes of {}; known: {}", key.str(), model,
                                 fmt::join(guide_field_names(), ", ")));
    }
    const auto* text = value.as_string();
    if (!text) {
      throw error_at(source_name, value.source(),
                     fmt::format("expected a string for the note on {} of {}", key.str(), model));
    }
    notes.emplace(std::string(key.str()), text->get());
  }
  return notes;
}

// One [[guide]] (named by `model`) or [[bar]] (named by `name`) table.
GuideSpec parse_guide(const toml::table& table, std::string_view kind, const std::string& source_name) {
  GuideSpec spec;
  spec.kind = std::string(kind);
  spec.source = source_name;
  const std::string_view name_key = kind == "bar" ? kNameKey : kModelKey;
  const toml::node* model = table.get(name_key);
  const auto* model_text = model ? model->as_string() : nullptr;
  if (!model_text || model_key(model_text->get()).empty()) {
    throw error_at(source_name, model ? model->source() : table.source(),
                   fmt::format("expected a non-empty string '{}' in each [[{}]]", name_key, kind));
  }
  spec.model = model_text->get();
  if (auto problem = io::name_problem(spec.model))
    throw error_at(source_name, model->source(), fmt::format("{}: {}", name_key, *problem));

  for (const auto& [key, node] : table) {
    if (key.str() == name_key) continue;
    if (key.str() == kNotesKey) {
      spec.notes = parse_notes(node, spec.model, source_name);
    } else if (const FieldDef* field = find_field(key.str())) {
      spec.*field->member = parse_value(node, *field, spec.model, source_name);
    } else {
      // Unknown keys are errors, so that a misspelt field does not silently load as missing.
      throw error_at(source_name, key.source(),
                     fmt::format("unknown key '{}' in {} {}; known: {}, notes, {}", key.str(), kind, spec.model,
                                 name_key, fmt::join(guide_field_names(), ", ")));
    }
  }
  return spec;
}

}  // namespace

const std::vector<std::string>& guide_field_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const FieldDef& f : kFields) v.emplace_back(f.name);
    return v;
  }();
  return names;
}

std::optional<std::string> guide_field_range_problem(std::string_view name, double value) {
  const FieldDef* field = find_field(name);
  if (!field) throw InvalidParameter(std::string(name), "unknown guide field");
  if (in_range(*field, value)) return std::nullopt;
  return range_text(*field);
}

std::optional<double> field_value(const GuideSpec& spec, std::string_view name) {
  const FieldDef* field = find_field(name);
  if (!field)
    throw InvalidParameter(std::string(name),
                           fmt::format("unknown guide field; known: {}", fmt::join(guide_field_names(), ", ")));
  return spec.*field->member;
}

const GuideSpec& GuideCatalog::find(std::string_view model) const {
  const std::string key = model_key(model);
  for (const GuideSpec& guide : guides) {
    if (model_key(guide.model) == key) return guide;
  }
  std::vector<std::string_view> known;
  for (const GuideSpec& guide : guides) known.emplace_back(guide.model);
  throw InvalidParameter("guide", fmt::format("unknown model '{}'; known: {}", model, fmt::join(known, ", ")));
}

GuideCatalog parse_catalog(std::string_view toml_text, const std::string& source_name) {
  toml::table root;
  try {
    root = toml::parse(toml_text, source_name);
  } catch (const toml::parse_error& e) {
    throw error_at(source_name, e.source(), std::string(e.description()));
  }

  GuideCatalog catalog;
  catalog.source = source_name;
  std::unordered_map<std::string, std::size_t> seen;  // model_key → index in catalog.guides
  for (const std::string_view kind : {"guide", "bar"}) {
    const toml::node* node = root.get(kind);
    if (!node) continue;
    const toml::array* entries = node->as_array();
    if (!entries) throw error_at(source_name, node->source(), fmt::format("expected [[{}]] tables", kind));
    if (catalog.guides.size() + entries->size() > io::kMaxCatalogEntries)
      throw error_at(source_name, (*entries)[io::kMaxCatalogEntries - catalog.guides.size()].source(),
                     fmt::format("more than {} [[guide]] and [[bar]] tables: at most {} (docs/formats.md#limits)",
                                 io::kMaxCatalogEntries, io::kMaxCatalogEntries));
    for (const toml::node& element : *entries) {
      const auto* table = element.as_table();
      if (!table) throw error_at(source_name, element.source(), fmt::format("expected each {0} to be a [[{0}]] table", kind));
      GuideSpec spec = parse_guide(*table, kind, source_name);
      const auto [duplicate, added] = seen.try_emplace(model_key(spec.model), catalog.guides.size());
      if (!added) {
        throw error_at(source_name, table->get(kind == "bar" ? kNameKey : kModelKey)->source(),
                       fmt::format("duplicate {} '{}' (same as '{}', ignoring case and spaces)", kind == "bar" ? "name" : "model", spec.model,
                                   catalog.guides[duplicate->second].model));
      }
      catalog.guides.push_back(std::move(spec));
    }
  }
  for (const auto& [key, node] : root) {
    if (key.str() != "guide" && key.str() != "bar")
      throw error_at(source_name, key.source(), fmt::format("unknown key '{}'; expected [[guide]] and [[bar]] tables", key.str()));
  }
  if (catalog.guides.empty()) throw error_at(source_name, {}, "expected one or more [[guide]] or [[bar]] tables");
  return catalog;
}

const GuideSpec& find_guide(std::string_view model, const GuideCatalog* user) {
  if (user) {
    const std::string key = model_key(model);
    for (const GuideSpec& guide : user->guides)
      if (model_key(guide.model) == key) return guide;
    try {
      return builtin_catalog().find(model);
    } catch (const InvalidParameter&) {
      std::vector<std::string_view> known;
      for (const GuideSpec& guide : user->guides) known.emplace_back(guide.model);
      for (const GuideSpec& guide : builtin_catalog().guides) known.emplace_back(guide.model);
      throw InvalidParameter("guide", fmt::format("unknown model '{}' in {} and the built-in catalog; known: {}", model,
                                                  user->source, fmt::join(known, ", ")));
    }
  }
  return builtin_catalog().find(model);
}

GuideCatalog load_catalog(const std::filesystem::path& file) {
  return parse_catalog(io::read_text_file(file, "catalog file"), file.string());
}

const GuideCatalog& builtin_catalog() {
  // src/data/guides.toml as a raw string literal, generated by CMake.
  static constexpr const char* kText =
#include "builtin_catalog.inc"
      ;
  static const GuideCatalog catalog = parse_catalog(kText, "<built-in>");
  return catalog;
}

GuideSpec with_overrides(GuideSpec spec, const std::map<std::string, double>& overrides) {
  for (const auto& [name, value] : overrides) {
    field_value(spec, name);  // refuses unknown names
    const FieldDef* field = find_field(name);
    require_positive(field->name, value);
    if (!in_range(*field, value))
      throw InvalidParameter(field->name, value, fmt::format("a physical value for {}: {}", spec.model, range_text(*field)));
    spec.*field->member = value;
    // The catalog's note described the replaced value; keep the provenance honest.
    spec.notes[field->name] = "user override";
  }
  return spec;
}

double require(const GuideSpec& spec, std::optional<double> GuideSpec::*field, const char* name) {
  const std::optional<double>& value = spec.*field;
  if (!value) {
    throw InvalidParameter(name, fmt::format("the catalog ({}) has no value for {} {}; add {} to its entry there, or "
                                             "give it as an override ([run.guide_overrides] in a thermal manifest, "
                                             "--set {}=VALUE on the command line)",
                                             spec.source.empty() ? "<built-in>" : spec.source, spec.kind, spec.model,
                                             name, name));
  }
  return *value;
}

}  // namespace lmcal
