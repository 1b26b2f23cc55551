// The friction manifest: a data set's files and its runs' fixed conditions (friction_log.hpp).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <functional>
#include <set>

#include "io/csv_reader.hpp"
#include "io/friction_files.hpp"
#include "io/manifest.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/friction_log.hpp"

namespace lmcal {

namespace {

namespace fs = std::filesystem;
using manifest::Given;
using manifest::Manifest;

// The numeric [[run]] keys, any unit of their quantity ("load_kgf").
struct ConditionKey {
  std::string_view base;
  Quantity quantity;
  std::optional<double> FrictionRunConditions::*field;
  bool strictly_positive;
};
constexpr std::array<ConditionKey, 5> kConditionKeys{{
    {"load", Quantity::force, &FrictionRunConditions::load_N, false},
    {"preload", Quantity::preload, &FrictionRunConditions::preload_um, false},
    {"block_length", Quantity::length_mm, &FrictionRunConditions::block_length_mm, true},
    {"temperature", Quantity::temperature, &FrictionRunConditions::temperature_C, false},
    {"viscosity40", Quantity::viscosity, &FrictionRunConditions::viscosity40_mm2_s, true},
}};

constexpr std::size_t kPreloadKey = 1;
static_assert(kConditionKeys[kPreloadKey].base == "preload");

std::string known_run_keys() {
  std::vector<std::string> keys{"id", "file", "skip_lines", "guide", "preload_class", "preload_N"};
  for (const ConditionKey& k : kConditionKeys) keys.push_back(csv::canonical_name(k.base, k.quantity));
  return fmt::format("{} (numbers in any unit of their quantity)", fmt::join(keys, ", "));
}

// The [raw] settings, by the names of RawFrictionOptions' fields.
struct RawKey {
  std::string_view name;
  std::function<void(RawFrictionOptions&, const RawFrictionOptions&)> copy;
};
const std::vector<RawKey>& raw_keys() {
  static const std::vector<RawKey> keys{
      {"force_sign", [](auto& to, auto& from) { to.force_sign = from.force_sign; }},
      {"skip_lines", [](auto& to, auto& from) { to.skip_lines = from.skip_lines; }},
      {"duplicate_times", [](auto& to, auto& from) { to.duplicate_times = from.duplicate_times; }},
      {"max_acceleration_m_s2", [](auto& to, auto& from) { to.max_acceleration_m_s2 = from.max_acceleration_m_s2; }},
      {"settling_s", [](auto& to, auto& from) { to.settling_s = from.settling_s; }},
      {"min_speed_m_s", [](auto& to, auto& from) { to.min_speed_m_s = from.min_speed_m_s; }},
      {"velocity_tolerance", [](auto& to, auto& from) { to.velocity_tolerance = from.velocity_tolerance; }},
      {"min_plateau_samples", [](auto& to, auto& from) { to.min_plateau_samples = from.min_plateau_samples; }},
      {"velocity_window", [](auto& to, auto& from) { to.velocity_window = from.velocity_window; }},
      {"moving_mass_kg", [](auto& to, auto& from) { to.moving_mass_kg = from.moving_mass_kg; }},
      {"segmentation", [](auto& to, auto& from) { to.segmentation = from.segmentation; }},
      {"trajectory_window", [](auto& to, auto& from) { to.trajectory_window = from.trajectory_window; }},
      {"presliding_m", [](auto& to, auto& from) { to.presliding_m = from.presliding_m; }},
      {"axis_incline_deg", [](auto& to, auto& from) {
         to.axis_incline_deg = from.axis_incline_deg;
         to.incline_stated = true;
       }},
      {"force_sensor", [](auto& to, auto& from) { to.force_sensor = from.force_sensor; }},
  };
  return keys;
}

std::size_t count_of(const Manifest& m, const toml::key& key, const toml::node& node) {
  const double value = manifest::number_of(m, key, node);
  if (!(value >= 0) || value != static_cast<double>(static_cast<std::size_t>(value)))
    m.fail(node.source(), fmt::format("{} = {}: expected a whole number", key.str(), value));
  return static_cast<std::size_t>(value);
}

RawFrictionOptions read_raw(const Manifest& m, const toml::table& table) {
  RawFrictionOptions o;
  for (const auto& [key, node] : table) {
    const std::string_view k = key.str();
    const auto known = std::find_if(raw_keys().begin(), raw_keys().end(), [&](const RawKey& r) { return r.name == k; });
    if (known == raw_keys().end()) {
      std::vector<std::string_view> names;
      for (const RawKey& r : raw_keys()) names.push_back(r.name);
      m.fail(key.source(), fmt::format("unknown key '{}' in [raw]; known: {}", k, fmt::join(names, ", ")));
    }
    try {
      if (k == "force_sign") o.force_sign = parse_force_sign(manifest::string_of(m, key, node));
      else if (k == "skip_lines") o.skip_lines = count_of(m, key, node);
      else if (k == "duplicate_times") o.duplicate_times = parse_duplicate_times(manifest::string_of(m, key, node));
      else if (k == "max_acceleration_m_s2") o.max_acceleration_m_s2 = manifest::number_of(m, key, node);
      else if (k == "settling_s") o.settling_s = manifest::number_of(m, key, node);
      else if (k == "min_speed_m_s") o.min_speed_m_s = manifest::number_of(m, key, node);
      else if (k == "velocity_tolerance") o.velocity_tolerance = manifest::number_of(m, key, node);
      else if (k == "min_plateau_samples") o.min_plateau_samples = count_of(m, key, node);
      else if (k == "velocity_window") o.velocity_window = count_of(m, key, node);
      else if (k == "moving_mass_kg") o.moving_mass_kg = manifest::number_of(m, key, node);
      else if (k == "segmentation") o.segmentation = parse_raw_segmentation(manifest::string_of(m, key, node));
      else if (k == "trajectory_window") o.trajectory_window = count_of(m, key, node);
      else if (k == "presliding_m") o.presliding_m = manifest::number_of(m, key, node);
      else if (k == "axis_incline_deg") o.axis_incline_deg = manifest::number_of(m, key, node), o.incline_stated = true;
      else if (k == "force_sensor") o.force_sensor = parse_force_sensor(manifest::string_of(m, key, node));
      RawFrictionOptions one;  // this key alone against its range
      known->copy(one, o);
      one.validate();
    } catch (const InvalidParameter& e) {
      m.fail(node.source(), e.what());
    }
  }
  return o;
}

// The [drive] table: a rotary log's joint quantities -> the carriage's (drive.hpp). Lead and
// radius both: refused at the later one.
Drive read_drive(const Manifest& m, const toml::table& table) {
  Drive d;
  std::optional<Given> kind;  // lead_mm or pinion_radius_mm
  for (const auto& [key, node] : table) {
    const std::string_view k = key.str();
    if (!Drive::is_key(k))
      m.fail(key.source(), fmt::format("unknown key '{}' in [drive]; known: {}", k, fmt::join(Drive::keys(), ", ")));
    const double value = manifest::number_of(m, key, node);
    try {
      d.set(k, value);
    } catch (const InvalidParameter& e) {
      m.fail(node.source(), e.what());
    }
    if (k != "lead_mm" && k != "pinion_radius_mm") continue;
    const Given given{&key, &node};
    if (kind) {  // keys come in name order; the message points at the later one in the file
      const auto at = [](const Given& g) { return std::pair(g.key->source().begin.line, g.key->source().begin.column); };
      const Given& later = at(given) > at(*kind) ? given : *kind;
      m.fail(later.key->source(), fmt::format("{} and {}: a drive is a screw (lead_mm) or a rack and pinion "
                                              "(pinion_radius_mm), not both; give one",
                                              kind->key->str(), k));
    }
    kind = given;
  }
  return d;
}

struct RunEntry {
  std::string id;
  std::optional<std::string> file;
  std::optional<std::size_t> skip_lines;  // of its file
  const toml::node* file_node = nullptr;
  FrictionRunConditions conditions;
};

RunEntry read_run(const Manifest& m, const toml::table& table, const GuideCatalog* catalog) {
  RunEntry run;
  std::array<std::optional<Given>, kConditionKeys.size()> numbers;
  std::optional<Given> id, file, guide, preload_class, preload_N;
  for (const auto& [key, node] : table) {
    const std::string_view k = key.str();
    // A preload by its catalog class, or only as a force (a spring's: no µm for the law).
    if (k == "preload_class") {
      manifest::string_of(m, key, node);
      manifest::remember(m, preload_class, {&key, &node}, "preload");
      continue;
    }
    if (k == "preload_N") {
      const double value = manifest::number_of(m, key, node);
      if (!(value >= 0) || value > physical_range(Quantity::force).high)
        m.fail(node.source(), fmt::format("preload_N = {}: expected a force >= 0", value));
      manifest::remember(m, preload_N, {&key, &node, {}, value}, "preload");
      run.conditions.preload_N = value;
      continue;
    }
    if (k == "skip_lines") {
      run.skip_lines = count_of(m, key, node);
      continue;
    }
    if (k == "id" || k == "file" || k == "guide") {
      manifest::string_of(m, key, node);
      manifest::remember(m, k == "id" ? id : k == "file" ? file : guide, {&key, &node}, k);
      continue;
    }
    bool known = false;
    for (std::size_t i = 0; i < kConditionKeys.size() && !known; ++i) {
      const ConditionKey& ck = kConditionKeys[i];
      const auto conversion = manifest::unit_key(m, key, ck.base, ck.quantity);
      if (!conversion) continue;
      const double value = manifest::converted_number_of(m, key, node, *conversion, physical_range(ck.quantity));
      const bool ok = ck.quantity == Quantity::temperature ? value > -273.15
                      : ck.strictly_positive                ? value > 0
                                                            : value >= 0;
      if (!ok) {
        m.fail(node.source(), fmt::format("{} = {}: expected {}", k, manifest::number_of(m, key, node),
                                          ck.quantity == Quantity::temperature ? "a temperature above absolute zero"
                                          : ck.strictly_positive               ? "a value > 0"
                                                                               : "a value >= 0"));
      }
      manifest::remember(m, numbers[i], {&key, &node, *conversion, value}, ck.base);
      run.conditions.*ck.field = value;
      known = true;
    }
    if (!known) m.fail(key.source(), fmt::format("unknown key '{}' in [[run]]; known: {}", k, known_run_keys()));
  }
  if (!id) m.fail(table.source(), "missing key 'id' in [[run]]");
  run.id = id->node->as_string()->get();
  if (file) {
    run.file = file->node->as_string()->get();
    run.file_node = file->node;
  }
  if (guide) {
    run.conditions.guide = guide->node->as_string()->get();
  }
  // One preload: in µm, by class, or as a force.
  const std::optional<Given>& preload_um = numbers[kPreloadKey];
  for (const std::optional<Given>* other : {&preload_class, &preload_N}) {
    if (preload_um && *other) {
      m.fail((*other)->key->source(), fmt::format("'{}' and '{}' both give run '{}''s preload: give one",
                                                  preload_um->key->str(), (*other)->key->str(), run.id));
    }
  }
  if (preload_class && preload_N) {
    m.fail(preload_N->key->source(), fmt::format("'preload_class' and 'preload_N' both give run '{}''s preload: give one",
                                                 run.id));
  }
  if (preload_class) {
    const std::string& name = preload_class->node->as_string()->get();
    try {
      run.conditions.preload_um = preload_class_um(name, run.conditions.guide.value_or(""));
    } catch (const InvalidParameter& e) {
      m.fail(preload_class->node->source(), e.what());
    }
    run.conditions.preload_class = name;
  }
  // The guide's catalog entry gives the block length when the run does not; a guide no catalog
  // knows is only a name (as in a guide column), and said so if the block length is missing.
  if (guide && !run.conditions.block_length_mm) {
    try {
      const GuideSpec& spec = find_guide(*run.conditions.guide, catalog);
      if (spec.block_length_mm) {
        run.conditions.block_length_mm = spec.block_length_mm;
        run.conditions.block_length_from_catalog = true;
      } else {
        run.conditions.block_length_note = fmt::format("the catalog ({}) has no block_length_mm for {}", spec.source,
                                                       spec.model);
      }
    } catch (const InvalidParameter& e) {
      run.conditions.block_length_note = e.what();
    }
  }
  return run;
}

// The manifest's catalog, loaded into `own` (a catalog the caller gives wins; its file must
// exist all the same), or the caller's, or none.
const GuideCatalog* catalog_of(const Manifest& m, const toml::table& root, const GuideCatalog* user_catalog,
                               GuideCatalog& own) {
  const GuideCatalog* catalog = user_catalog;
  if (const toml::node* node = root.get("catalog")) {
    const toml::key& key = root.find("catalog")->first;
    const fs::path path = m.existing_file(*node, manifest::string_of(m, key, *node));
    if (!user_catalog) {
      own = load_catalog(path);
      catalog = &own;
    }
  }
  return catalog;
}

// The raw settings given on the command line (`raw_given` names them, `raw` holds them) over the
// manifest's [raw] and [drive].
void override_raw(RawFrictionOptions& set_raw, const RawFrictionOptions& raw, const std::vector<std::string>& raw_given) {
  for (const std::string& name : raw_given) {
    if (Drive::is_key(name)) {  // a flag for the drive wins over the [drive] key
      set_raw.drive.copy_key(name, raw.drive);
      continue;
    }
    const auto it = std::find_if(raw_keys().begin(), raw_keys().end(), [&](const RawKey& r) { return r.name == name; });
    if (it == raw_keys().end()) throw InvalidParameter("raw_given", fmt::format("unknown setting '{}'", name));
    it->copy(set_raw, raw);
  }
}

}  // namespace

FrictionDataSet load_friction_dataset(const fs::path& manifest_file, const GuideCatalog* user_catalog,
                                      const RawFrictionOptions& raw, const std::vector<std::string>& raw_given,
                                      const InputScope& scope) {
  const Manifest m{manifest_file.string(), manifest_file.parent_path(), scope};
  const toml::table root = m.parse();
  FrictionDataSet set;
  set.manifest = manifest_file;
  set.name = manifest_file.stem().string();

  // The catalog first: the runs' guides are looked up in it.
  GuideCatalog own_catalog;
  const GuideCatalog* catalog = catalog_of(m, root, user_catalog, own_catalog);
  if (catalog) set.catalog_file = catalog->source;

  std::optional<std::pair<fs::path, const toml::node*>> common_file;
  std::optional<std::size_t> common_skip_lines;  // of the common file
  Drive drive;                                   // [drive], set after [raw] (which holds it)
  const toml::array* runs = nullptr;
  for (const auto& [key, node] : root) {
    const std::string_view k = key.str();
    if (k == "name") {
      set.name = manifest::string_of(m, key, node);
    } else if (k == "description" || k == "catalog") {
      manifest::string_of(m, key, node);
    } else if (k == "file") {
      common_file.emplace(m.existing_file(node, manifest::string_of(m, key, node)), &node);
    } else if (k == "skip_lines") {
      common_skip_lines = count_of(m, key, node);
    } else if (k == "drive") {
      drive = read_drive(m, manifest::table_of(m, node, "[drive]"));
    } else if (k == "raw") {
      set.raw = read_raw(m, manifest::table_of(m, node, "[raw]"));
    } else if (k == "run") {
      runs = &manifest::run_tables(m, node);
    } else {
      m.fail(key.source(), fmt::format("unknown key '{}'; known: name, description, catalog, file, skip_lines, drive, raw, run",
                                        k));
    }
  }
  set.raw.drive = drive;
  override_raw(set.raw, raw, raw_given);

  std::map<std::string, FrictionRunConditions, std::less<>> conditions;  // of the runs in the common file
  std::set<std::string> ids;
  std::vector<std::pair<std::string, const toml::table*>> in_common_file;  // runs the common file must hold
  std::vector<detail::FrictionFile> files;
  std::set<fs::path> own_files;
  if (runs) {
    for (const toml::node& node : *runs) {
      const toml::table& table = *node.as_table();
      RunEntry run = read_run(m, table, catalog);
      if (!ids.insert(run.id).second) m.fail(table.source(), fmt::format("duplicate run id '{}'", run.id));
      if (run.file) {
        const fs::path path = m.existing_file(*run.file_node, *run.file);
        if (!own_files.insert(path.lexically_normal()).second)
          m.fail(run.file_node->source(), fmt::format("file '{}' is already another run's file", *run.file));
        files.push_back({.path = path,
                         .run = run.id,
                         .runs = {{run.id, run.conditions}},
                         .manifest = m.file,
                         .skip_lines = run.skip_lines});
      } else if (run.skip_lines) {
        m.fail(table.source(), fmt::format("run '{}': skip_lines belongs to a run with its own file; give the "
                                           "top-level file's as a top-level skip_lines",
                                           run.id));
      } else if (!common_file) {
        m.fail(table.source(), fmt::format("run '{}' has no file, and the manifest no top-level file holding it", run.id));
      } else {
        conditions.emplace(run.id, run.conditions);
        in_common_file.emplace_back(run.id, &table);
      }
    }
  }
  if (common_file)
    files.insert(files.begin(), {.path = common_file->first,
                                 .runs = std::move(conditions),
                                 .manifest = m.file,
                                 .skip_lines = common_skip_lines});
  if (files.empty()) m.fail(root.source(), "the manifest names no file: give `file = \"...\"` or a file in a [[run]]");
  for (const auto& f : files) set.files.push_back(f.path);
  set.log = detail::load_friction_files(files, set.raw);
  // A listed run without rows is a typo in an id, or the wrong file.
  for (const auto& [id, table] : in_common_file)
    if (std::find(set.log.run_names.begin(), set.log.run_names.end(), id) == set.log.run_names.end())
      m.fail(table->source(), fmt::format("run '{}' is listed, but {} has no row of it (run ids are case-sensitive)", id,
                                          common_file->first.string()));
  return set;
}

}  // namespace lmcal
