#include "lmcal/io/catalog.hpp"

#include "lmcal/error.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>

namespace lmcal {

namespace {

using Field = std::optional<double> GuideSpec::*;

struct FieldDef {
  const char* name;
  Field member;
};

// The numeric fields of GuideSpec, in member order: the single table that ties
// TOML keys and override names to members.
constexpr std::array<FieldDef, 11> kFields{{
    {"block_length_mm", &GuideSpec::block_length_mm},
    {"contact_length_mm", &GuideSpec::contact_length_mm},
    {"rail_width_mm", &GuideSpec::rail_width_mm},
    {"rail_height_mm", &GuideSpec::rail_height_mm},
    {"rail_mass_kg_m", &GuideSpec::rail_mass_kg_m},
    {"area_m2", &GuideSpec::area_m2},
    {"perimeter_m", &GuideSpec::perimeter_m},
    {"preload_um", &GuideSpec::preload_um},
    {"density_kg_m3", &GuideSpec::density_kg_m3},
    {"specific_heat_J_kgK", &GuideSpec::specific_heat_J_kgK},
    {"conductivity_W_mK", &GuideSpec::conductivity_W_mK},
}};

constexpr std::string_view kMissing = "missing";
constexpr std::string_view kModelKey = "model";
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

// A numeric field: a finite number > 0 (TOML integer or float), or "missing".
std::optional<double> parse_value(const toml::node& node, const char* field, const std::string& model,
                                  const std::string& source_name) {
  if (const auto* s = node.as_string(); s && s->get() == kMissing) return std::nullopt;
  std::optional<double> value;
  if (const auto* i = node.as_integer()) value = static_cast<double>(i->get());
  if (const auto* f = node.as_floating_point()) value = f->get();
  if (!value || !std::isfinite(*value) || *value <= 0) {
    throw error_at(source_name, node.source(),
                   fmt::format("expected a number > 0 or \"missing\" for {} of {}", field, model));
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

GuideSpec parse_guide(const toml::table& table, const std::string& source_name) {
  GuideSpec spec;
  const toml::node* model = table.get(kModelKey);
  const auto* model_text = model ? model->as_string() : nullptr;
  if (!model_text || model_key(model_text->get()).empty()) {
    throw error_at(source_name, model ? model->source() : table.source(),
                   "expected a non-empty string 'model' in each [[guide]]");
  }
  spec.model = model_text->get();

  for (const auto& [key, node] : table) {
    if (key.str() == kModelKey) continue;
    if (key.str() == kNotesKey) {
      spec.notes = parse_notes(node, spec.model, source_name);
    } else if (const FieldDef* field = find_field(key.str())) {
      spec.*field->member = parse_value(node, field->name, spec.model, source_name);
    } else {
      // Unknown keys are errors, so that a misspelt field does not silently load as missing.
      throw error_at(source_name, key.source(),
                     fmt::format("unknown key '{}' in guide {}; known: model, notes, {}", key.str(),
                                 spec.model, fmt::join(guide_field_names(), ", ")));
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

  const toml::node* guide_node = root.get("guide");
  const toml::array* guides = guide_node ? guide_node->as_array() : nullptr;
  if (!guides || guides->empty()) {
    const toml::source_region where = guide_node ? guide_node->source() : toml::source_region{};
    throw error_at(source_name, where, "expected one or more [[guide]] tables");
  }

  GuideCatalog catalog;
  catalog.source = source_name;
  for (const toml::node& element : *guides) {
    const auto* table = element.as_table();
    if (!table) throw error_at(source_name, element.source(), "expected each guide to be a [[guide]] table");
    GuideSpec spec = parse_guide(*table, source_name);
    const std::string key = model_key(spec.model);
    const auto duplicate = std::find_if(catalog.guides.begin(), catalog.guides.end(),
                                        [&](const GuideSpec& g) { return model_key(g.model) == key; });
    if (duplicate != catalog.guides.end()) {
      throw error_at(source_name, table->get(kModelKey)->source(),
                     fmt::format("duplicate model '{}' (same as '{}', ignoring case and spaces)", spec.model,
                                 duplicate->model));
    }
    catalog.guides.push_back(std::move(spec));
  }
  return catalog;
}

GuideCatalog load_catalog(const std::filesystem::path& file) {
  std::error_code ec;
  std::ifstream in(file, std::ios::binary);
  if (!in || std::filesystem::is_directory(file, ec)) throw InputError(file.string(), 0, 0, "cannot open catalog file");
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw InputError(file.string(), 0, 0, "cannot open catalog file");
  return parse_catalog(text, file.string());
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
    spec.*field->member = value;
    // The catalog's note described the replaced value; keep the provenance honest.
    spec.notes[field->name] = "user override";
  }
  return spec;
}

double require(const GuideSpec& spec, std::optional<double> GuideSpec::*field, const char* name) {
  const std::optional<double>& value = spec.*field;
  if (!value) {
    throw InvalidParameter(name,
                           fmt::format("the catalog has no value for guide {}; supply it explicitly", spec.model));
  }
  return *value;
}

}  // namespace lmcal
