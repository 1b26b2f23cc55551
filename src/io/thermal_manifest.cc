// A thermal data set's manifest (thermal.toml): its runs read and checked (load_thermal_dataset)
// and written (thermal_manifest_toml); each run's trace is thermal_run.cc.
#include "lmcal/io/thermal_run.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "io/csv_reader.hpp"
#include "io/manifest.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/io/csv_writer.hpp"
#include "lmcal/io/units.hpp"

namespace lmcal {

namespace {

namespace fs = std::filesystem;

// ---- Manifest -----------------------------------------------------------------------------

using manifest::Given;
using manifest::number_of;
using manifest::remember;
using manifest::string_of;
using manifest::toml_string;
using manifest::unit_key;

// A thermal manifest as read: its file and folder, and the user's catalog.
struct Manifest : manifest::Manifest {
  const GuideCatalog* catalog = nullptr;  // the user's, searched before the built-in one
};

// Numeric [[run]] keys; each takes any unit of its quantity ("velocity_mm_s"), or, without
// a quantity (units.hpp has no power), only the name as written ("heat_rate_W").
enum class Bound { non_negative, positive, above_absolute_zero };
struct NumberKey {
  std::string_view base;
  std::optional<Quantity> quantity;
  bool required;
  Bound bound;
  PhysicalRange unitless_range = kHeatRateRange;  // a key without a quantity: its values on a rig
};
enum NumberKeyIndex : std::size_t {
  kVelocity,
  kLoad,
  kPreload,
  kStroke,
  kRailLength,
  kContactLength,
  kBlockLength,
  kMeanFrictionUncertainty,
  kMeanFriction,
  kStartFriction,
  kHeatRateUncertainty,
  kHeatRate,
  kAmbientC,
  kConvection,
  kViscosity40
};
// A key is matched against the bases in this order; a base that extends another
// (mean_friction_uncertainty) comes first, so a bad unit on it is reported as its own
// ("mean_friction_uncertainty_kgs": unknown unit 'kgs'), not as mean_friction's.
// velocity is required unless the heat is given (checked once the CSV is read).
constexpr std::array<NumberKey, 15> kNumberKeys{{
    {"velocity", Quantity::velocity, false, Bound::positive},
    {"load", Quantity::force, true, Bound::non_negative},
    {"preload", Quantity::preload, false, Bound::non_negative},
    {"stroke", Quantity::distance_m, true, Bound::positive},
    {"rail_length", Quantity::distance_m, true, Bound::positive},
    {"contact_length", Quantity::length_mm, false, Bound::positive},
    {"block_length", Quantity::length_mm, false, Bound::positive},
    {"mean_friction_uncertainty", Quantity::force, false, Bound::non_negative},
    {"mean_friction", Quantity::force, false, Bound::non_negative},
    {"start_friction", Quantity::force, false, Bound::non_negative},
    {"heat_rate_uncertainty_W", std::nullopt, false, Bound::non_negative},
    {"heat_rate_W", std::nullopt, false, Bound::non_negative},
    {"ambient", Quantity::temperature, false, Bound::above_absolute_zero},
    {"h_W_m2K", std::nullopt, false, Bound::positive, kHeatTransferRange},
    {"viscosity40", Quantity::viscosity, false, Bound::positive},
}};
std::string canonical_name(const NumberKey& k) {
  return k.quantity ? csv::canonical_name(k.base, *k.quantity) : std::string(k.base);
}
// A number key in internal units ("mean_friction_N"), as the writer writes it.
std::string canonical_key(NumberKeyIndex i) { return canonical_name(kNumberKeys[i]); }

// Whether `value` is inside the key's bound; `what` says the bound for messages.
bool within(Bound bound, double value, std::string& what) {
  switch (bound) {
    case Bound::positive: what = "> 0"; return value > 0;
    case Bound::non_negative: what = ">= 0"; return value >= 0;
    case Bound::above_absolute_zero: what = "above absolute zero"; return value > -273.15;
  }
  return false;
}

constexpr std::string_view kSensors = "sensors";  // [run.sensors_m]: positions, any distance unit
constexpr std::string_view kOverrides = "guide_overrides";
constexpr std::string_view kSchedule = "schedule";  // [[run.schedule]] phases
enum TextKeyIndex : std::size_t { kId, kFile, kGuide };
constexpr std::array<std::string_view, 3> kTextKeys{"id", "file", "guide"};

std::string known_run_keys() {
  std::vector<std::string> keys(kTextKeys.begin(), kTextKeys.end());
  for (const NumberKey& k : kNumberKeys) keys.push_back(canonical_name(k));
  keys.push_back(csv::canonical_name(kSensors, Quantity::distance_m));
  keys.emplace_back(kOverrides);
  keys.emplace_back(kSchedule);
  keys.emplace_back("skip_lines");
  return fmt::format("{} (numbers in any unit of their quantity)", fmt::join(keys, ", "));
}

// Everything of a [[run]] table, checked one key at a time.
struct RunKeys {
  std::array<std::optional<Given>, kTextKeys.size()> text;
  std::array<std::optional<Given>, kNumberKeys.size()> number;
  std::optional<Given> sensors;
  std::optional<Given> overrides;
  std::optional<Given> schedule;
  std::optional<Given> skip_lines;  // of the run's file
};

// unit_key for a number key: a key without a quantity matches its name only.
std::optional<Conversion> number_key(const Manifest& m, const toml::key& key, const NumberKey& nk) {
  if (!nk.quantity) return key.str() == nk.base ? std::optional(Conversion{}) : std::nullopt;
  return unit_key(m, key, nk.base, *nk.quantity);
}

// A number key's value in internal units, refused outside its bound.
double bounded_number(const Manifest& m, const toml::key& key, const toml::node& node, const NumberKey& nk,
                      const Conversion& conversion) {
  const double written = number_of(m, key, node);
  const double value =
      converted_number_of(m, key, node, conversion, nk.quantity ? physical_range(*nk.quantity) : nk.unitless_range);
  std::string bound;
  if (!within(nk.bound, value, bound))
    m.fail(node.source(), fmt::format("{} = {}: a thermal run needs {} {}", key.str(), written, nk.base, bound));
  return value;
}

RunKeys read_run_keys(const Manifest& m, const toml::table& table) {
  RunKeys keys;
  for (const auto& [key, node] : table) {
    const std::string_view k = key.str();
    if (const auto text = std::find(kTextKeys.begin(), kTextKeys.end(), k); text != kTextKeys.end()) {
      string_of(m, key, node);
      remember(m, keys.text[static_cast<std::size_t>(text - kTextKeys.begin())], {&key, &node}, k);
      continue;
    }
    if (k == "skip_lines") {
      const double n = number_of(m, key, node);
      if (!(n >= 0 && n <= 1e9 && n == std::floor(n)))
        m.fail(node.source(), fmt::format("skip_lines = {}: expected a whole number of lines", n));
      remember(m, keys.skip_lines, {&key, &node, {}, n}, k);
      continue;
    }
    if (k == kOverrides) {
      manifest::table_of(m, node, fmt::format("[run.{}]", k));
      remember(m, keys.overrides, {&key, &node}, k);
      continue;
    }
    if (k == kSchedule) {
      const auto* phases = node.as_array();
      if (!phases || !phases->is_array_of_tables() || phases->empty())
        m.fail(node.source(), "expected [[run.schedule]] tables");
      remember(m, keys.schedule, {&key, &node}, k);
      continue;
    }
    if (const auto conversion = unit_key(m, key, kSensors, Quantity::distance_m)) {
      manifest::table_of(m, node, fmt::format("[run.{}]", k));
      remember(m, keys.sensors, {&key, &node, *conversion}, kSensors);
      continue;
    }
    bool known = false;
    for (std::size_t i = 0; i < kNumberKeys.size() && !known; ++i) {
      const NumberKey& nk = kNumberKeys[i];
      const auto conversion = number_key(m, key, nk);
      if (!conversion) continue;
      remember(m, keys.number[i], {&key, &node, *conversion, bounded_number(m, key, node, nk, *conversion)}, nk.base);
      known = true;
    }
    if (!known) m.fail(key.source(), fmt::format("unknown key '{}' in [[run]]; known: {}", k, known_run_keys()));
  }
  return keys;
}

// The [run.guide_overrides] table: catalog field -> value > 0, in the field's physical range.
std::map<std::string, double> read_overrides(const Manifest& m, const toml::table& table) {
  std::map<std::string, double> overrides;
  const std::vector<std::string>& fields = guide_field_names();
  for (const auto& [key, node] : table) {
    if (std::find(fields.begin(), fields.end(), key.str()) == fields.end()) {
      m.fail(key.source(), fmt::format("unknown guide field '{}' in [run.{}]; known: {}", key.str(), kOverrides,
                                       fmt::join(fields, ", ")));
    }
    const double value = number_of(m, key, node);
    if (!(value > 0)) m.fail(node.source(), fmt::format("{} = {}: expected a value > 0", key.str(), value));
    if (auto range = guide_field_range_problem(key.str(), value)) {
      m.fail(node.source(),
             fmt::format("{} = {:g} is not physical: expected {} as in a catalog (a typo or another unit?)", key.str(), value, *range));
    }
    overrides.emplace(std::string(key.str()), value);
  }
  return overrides;
}

// The trace channel a sensor key names: the header as written ("tc1_C") or its base ("tc1").
TemperatureChannel* find_channel(std::vector<TemperatureChannel>& rail, std::string_view key) {
  for (TemperatureChannel& channel : rail) {
    const auto split = split_unit(channel.name, Quantity::temperature);
    if (channel.name == key || (split && split->name == key)) return &channel;
  }
  return nullptr;
}

// One [[run.schedule]] table: from_<time unit>, and velocity_<unit> or heat_rate_W.
ThermalPhase read_phase(const Manifest& m, const toml::table& table) {
  static constexpr NumberKey kFrom{"from", Quantity::time, true, Bound::non_negative};
  const std::array<const NumberKey*, 3> keys{&kFrom, &kNumberKeys[kVelocity], &kNumberKeys[kHeatRate]};
  std::array<std::optional<Given>, 3> given;
  for (const auto& [key, node] : table) {
    std::size_t i = 0;
    std::optional<Conversion> conversion;
    for (; i < keys.size() && !conversion; ++i) conversion = number_key(m, key, *keys[i]);
    if (!conversion)
      m.fail(key.source(), fmt::format("unknown key '{}' in [[run.{}]]; known: from_s, velocity_m_s, heat_rate_W (from "
                                       "and velocity in any unit of their quantity)",
                                       key.str(), kSchedule));
    const NumberKey& nk = *keys[i - 1];
    // A stopped block is a phase too: velocity 0 is allowed here.
    const NumberKey bound{nk.base, nk.quantity, false, Bound::non_negative};
    remember(m, given[i - 1], {&key, &node, *conversion, bounded_number(m, key, node, bound, *conversion)}, nk.base);
  }
  if (!given[0]) m.fail(table.source(), fmt::format("[[run.{}]] phase without from_s (its start since the first record)", kSchedule));
  if (given[1].has_value() == given[2].has_value())
    m.fail(table.source(), fmt::format("a [[run.{}]] phase needs one of velocity_m_s (the block's speed; 0: stopped) and "
                                       "heat_rate_W (the heat, given), {}",
                                       kSchedule, given[1] ? "not both" : "found neither"));
  ThermalPhase phase{.from_s = given[0]->value};
  if (given[1]) phase.velocity_m_s = given[1]->value;
  if (given[2]) phase.heat_rate_W = given[2]->value;
  return phase;
}

// The phases in order: the first from 0 (the first record), each later than the one before.
std::vector<ThermalPhase> read_schedule(const Manifest& m, const toml::array& tables) {
  std::vector<ThermalPhase> phases;
  for (const toml::node& element : tables) {
    const toml::table& table = *element.as_table();
    phases.push_back(read_phase(m, table));
    const double from_s = phases.back().from_s;
    if (phases.size() == 1 && from_s != 0)
      m.fail(table.source(), fmt::format("the first [[run.{}]] phase starts at from_s = {}; it must start at 0 (the "
                                         "first record)",
                                         kSchedule, from_s));
    if (phases.size() > 1 && !(from_s > phases[phases.size() - 2].from_s))
      m.fail(table.source(), fmt::format("[[run.{}]] phase at from_s = {} is not later than the one before ({} s); "
                                         "phases go in ascending order",
                                         kSchedule, from_s, phases[phases.size() - 2].from_s));
  }
  return phases;
}

// The run's guide from the user's catalog or the built-in one, with its overrides; the values
// the thermal model cannot do without are required here, at load, not later in a fit.
GuideSpec read_guide(const Manifest& m, const ThermalRun& run, const Given& guide, const std::optional<Given>& overrides) {
  GuideSpec spec;
  try {
    spec = find_guide(run.guide, m.catalog);
  } catch (const InvalidParameter& e) {
    m.fail(guide.node->source(), e.what());
  }
  try {
    spec = with_overrides(spec, run.guide_overrides);
  } catch (const InvalidParameter& e) {
    m.fail(overrides->node->source(), e.what());
  }
  try {
    require(spec, &GuideSpec::area_m2, "area_m2");
    require(spec, &GuideSpec::perimeter_m, "perimeter_m");
    require(spec, &GuideSpec::conductivity_W_mK, "conductivity_W_mK");
    require(spec, &GuideSpec::density_kg_m3, "density_kg_m3");
    require(spec, &GuideSpec::specific_heat_J_kgK, "specific_heat_J_kgK");
    if (!run.contact_length_mm) require(spec, &GuideSpec::contact_length_mm, "contact_length_mm");
  } catch (const InvalidParameter& e) {
    m.fail(guide.node->source(), fmt::format("run '{}': {}", run.id, e.what()));
  }
  return spec;
}

// The heat: given (heat_rate_W, a schedule's heats, the CSV's column) or friction × speed,
// never two sources for one run.
void check_heat(const Manifest& m, const ThermalRun& run, const RunKeys& keys) {
  const auto key_of = [&](NumberKeyIndex i) { return keys.number[i]->key; };
  const bool friction_given = run.mean_friction_N || run.start_friction_N;
  const NumberKeyIndex friction_key = run.mean_friction_N ? kMeanFriction : kStartFriction;
  if (run.heat_rate_W && friction_given)
    m.fail(key_of(kHeatRate)->source(),
           fmt::format("heat_rate_W given with {}: the heat is either given or friction × speed, not both",
                       key_of(friction_key)->str()));
  if (run.heat_rate_W && keys.schedule)
    m.fail(key_of(kHeatRate)->source(), fmt::format("heat_rate_W given with [[run.{}]]: give the heat in each phase", kSchedule));
  const std::string file = run.file.filename().string();
  if (!run.trace.heat_rate_W.empty()) {
    const toml::key* other = run.heat_rate_W ? key_of(kHeatRate) : keys.schedule ? keys.schedule->key
                             : friction_given ? key_of(friction_key) : nullptr;
    if (other)
      m.fail(other->source(), fmt::format("'{}' has a heat_rate_W column, which gives the run's heat; drop {}", file,
                                          other->str()));
  }
  bool heat_given = run.heat_rate_W || !run.trace.heat_rate_W.empty();
  for (const ThermalPhase& phase : run.schedule) heat_given = heat_given || phase.heat_rate_W;
  if (run.heat_rate_uncertainty_W && !heat_given)
    m.fail(key_of(kHeatRateUncertainty)->source(),
           "heat_rate_uncertainty_W given without a heat rate (heat_rate_W, in the run, a phase or the CSV): it is that "
           "value's uncertainty");
}

// A speed where the heat is friction × speed, and an ambient, from columns or ambient_C.
void check_speed_and_ambient(const Manifest& m, const ThermalRun& run, const RunKeys& keys, const toml::table& table) {
  const std::string file = run.file.filename().string();
  if (!keys.number[kVelocity] && !run.heat_rate_W && run.trace.heat_rate_W.empty() && run.schedule.empty())
    m.fail(table.source(),
           fmt::format("missing key 'velocity_m_s' in [[run]] '{}' (accepted units: {}); a run whose heat is given "
                       "(heat_rate_W, [[run.schedule]]) may leave it out",
                       run.id, csv::accepted_names("velocity", Quantity::velocity)));
  if (run.trace.ambient.empty() && !run.ambient_C)
    m.fail(table.source(), fmt::format("'{}' has no ambient column and run '{}' has no ambient_C: give one", file, run.id));
  if (!run.trace.ambient.empty() && run.ambient_C)
    m.fail(keys.number[kAmbientC]->key->source(),
           fmt::format("{} given but '{}' has ambient columns: ambient_C is for a CSV without them",
                       keys.number[kAmbientC]->key->str(), file));
}

ThermalRun read_run(const Manifest& m, const toml::table& table) {
  const RunKeys keys = read_run_keys(m, table);
  const auto text = [&](TextKeyIndex i) -> const std::string& { return keys.text[i]->node->as_string()->get(); };

  ThermalRun run;
  if (!keys.text[kId]) m.fail(table.source(), "missing key 'id' in [[run]]");
  run.id = text(kId);
  for (std::size_t i = kFile; i < kTextKeys.size(); ++i) {
    if (!keys.text[i]) m.fail(table.source(), fmt::format("missing key '{}' in [[run]] '{}'", kTextKeys[i], run.id));
  }
  for (std::size_t i = 0; i < kNumberKeys.size(); ++i) {
    const NumberKey& nk = kNumberKeys[i];
    if (nk.required && !keys.number[i]) {
      m.fail(table.source(), fmt::format("missing key '{}' in [[run]] '{}' (accepted units: {})", canonical_name(nk),
                                         run.id, csv::accepted_names(nk.base, *nk.quantity)));
    }
  }
  const auto value = [&](NumberKeyIndex i) {
    return keys.number[i] ? std::optional(keys.number[i]->value) : std::nullopt;
  };
  run.velocity_m_s = value(kVelocity).value_or(0.0);
  run.load_N = *value(kLoad);
  run.preload_um = value(kPreload);
  run.stroke_m = *value(kStroke);
  run.rail_length_m = *value(kRailLength);
  run.contact_length_mm = value(kContactLength);
  run.block_length_mm = value(kBlockLength);
  run.mean_friction_N = value(kMeanFriction);
  run.mean_friction_uncertainty_N = value(kMeanFrictionUncertainty);
  run.start_friction_N = value(kStartFriction);
  run.heat_rate_W = value(kHeatRate);
  run.heat_rate_uncertainty_W = value(kHeatRateUncertainty);
  run.ambient_C = value(kAmbientC);
  run.h_W_m2K = value(kConvection);
  run.viscosity40_mm2_s = value(kViscosity40);
  if (keys.schedule) run.schedule = read_schedule(m, *keys.schedule->node->as_array());
  if (run.mean_friction_uncertainty_N && !run.mean_friction_N) {
    const Given& u = *keys.number[kMeanFrictionUncertainty];
    m.fail(u.key->source(), fmt::format("{} given without {}: it is the uncertainty of the measured mean friction",
                                        u.key->str(), canonical_key(kMeanFriction)));
  }

  // The guide must be in a catalog; overrides name its fields.
  run.guide = text(kGuide);
  if (keys.overrides) run.guide_overrides = read_overrides(m, *keys.overrides->node->as_table());
  run.guide_spec = read_guide(m, run, *keys.text[kGuide], keys.overrides);

  // The rail must hold the stroke plus the block's contact length.
  const double contact_mm = run.contact_length_mm ? *run.contact_length_mm : *run.guide_spec.contact_length_mm;
  const double needed_m = run.stroke_m + contact_mm * 1e-3;
  if (!(run.rail_length_m > needed_m)) {
    const Given& rail = *keys.number[kRailLength];
    m.fail(rail.node->source(),
           fmt::format("{} = {}: a thermal run needs rail length > stroke + contact length = {:.6g} m",
                       rail.key->str(), number_of(m, *rail.key, *rail.node), needed_m));
  }

  // The CSV, relative to the manifest's folder.
  const std::string& file = text(kFile);
  run.file = m.existing_file(*keys.text[kFile]->node, file);
  run.trace = load_thermal_trace(run.file, keys.skip_lines ? static_cast<std::size_t>(keys.skip_lines->value) : 0);
  check_heat(m, run, keys);
  check_speed_and_ambient(m, run, keys, table);

  // A position for every tc column, and only for tc columns.
  if (keys.sensors) {
    const toml::table& sensors = *keys.sensors->node->as_table();
    std::vector<std::string> known;
    for (const TemperatureChannel& c : run.trace.rail) known.push_back(c.name);
    for (const auto& [key, node] : sensors) {
      TemperatureChannel* channel = find_channel(run.trace.rail, key.str());
      if (!channel) {
        m.fail(key.source(), fmt::format("sensor '{}' names no tc column of '{}' (its tc columns: {})", key.str(), file,
                                         fmt::join(known, ", ")));
      }
      const double x_m = converted_number_of(m, key, node, keys.sensors->conversion, physical_range(Quantity::distance_m));
      if (!run.sensor_position_m.emplace(channel->name, x_m).second) {
        m.fail(key.source(), fmt::format("duplicate position for column '{}'", channel->name));
      }
      if (std::abs(x_m) > 0.5 * run.rail_length_m) {
        m.fail(node.source(), fmt::format("sensor '{}' at {} m lies beyond the rail end ({} m from the centre)",
                                          key.str(), x_m, 0.5 * run.rail_length_m));
      }
    }
  }
  for (const TemperatureChannel& channel : run.trace.rail) {
    if (!run.sensor_position_m.count(channel.name)) {
      m.fail(keys.sensors ? keys.sensors->node->source() : table.source(),
             fmt::format("column '{}' of '{}' has no position; add it to [run.{}]", channel.name, file,
                         csv::canonical_name(kSensors, Quantity::distance_m)));
    }
  }
  return run;
}

// ---- Manifest writer ----------------------------------------------------------------------

std::string toml_key(std::string_view key) {
  const bool bare = !key.empty() && std::all_of(key.begin(), key.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
  return bare ? std::string(key) : toml_string(key);
}

// Shortest text that reads back to the same double, always a TOML float ("3000.0", "-0.0").
std::string toml_number(double value) {
  std::string s = fmt::format("{}", value);
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

}  // namespace

GuideSpec resolved_guide(const ThermalRun& run) {
  if (!run.guide_spec.model.empty()) return run.guide_spec;
  return with_overrides(builtin_catalog().find(run.guide), run.guide_overrides);
}

ThermalDataSet load_thermal_dataset(const fs::path& manifest, const GuideCatalog* user_catalog, const InputScope& scope) {
  Manifest m;
  m.file = manifest.string();
  m.folder = manifest.parent_path();
  m.scope = scope;
  const toml::table root = m.parse();

  ThermalDataSet set;
  set.manifest = manifest;
  set.name = manifest.stem().string();
  const toml::array* runs = nullptr;
  const toml::node* catalog = nullptr;
  for (const auto& [key, node] : root) {
    if (key.str() == "name") {
      set.name = string_of(m, key, node);
    } else if (key.str() == "description") {
      set.description = string_of(m, key, node);
    } else if (key.str() == "catalog") {
      string_of(m, key, node);
      catalog = &node;
    } else if (key.str() == "run") {
      runs = &manifest::run_tables(m, node);
    } else {
      m.fail(key.source(), fmt::format("unknown key '{}'; known: name, description, catalog, run", key.str()));
    }
  }
  // The user's catalog: the caller's (the command line) wins over the manifest's.
  std::optional<GuideCatalog> own;
  if (user_catalog) {
    m.catalog = user_catalog;
    set.catalog_file = user_catalog->source;
  } else if (catalog) {
    set.catalog_file = m.existing_file(*catalog, catalog->as_string()->get());
    own = load_catalog(set.catalog_file);  // its own InputError, naming the catalog's line
    m.catalog = &*own;
  }
  if (!runs || runs->empty()) throw InputError(m.file, 0, 0, "no [[run]] tables; a data set needs at least one run");

  std::map<std::string, long, std::less<>> first_line;  // run id -> line of its id
  for (const toml::node& element : *runs) {
    const toml::table& table = *element.as_table();
    // Duplicate ids first: no need to load a CSV for a run that cannot be kept.
    if (const auto* id = table.get_as<std::string>("id")) {
      const auto [it, inserted] = first_line.emplace(id->get(), static_cast<long>(id->source().begin.line));
      if (!inserted)
        m.fail(id->source(), fmt::format("duplicate run id '{}' (first at line {})", id->get(), it->second));
    }
    set.runs.push_back(read_run(m, table));
  }
  return set;
}

std::string thermal_manifest_toml(const ThermalDataSet& set, const fs::path& folder) {
  // Paths written relative to `folder`, compared lexically (both made absolute if only one is).
  const auto relative = [&](const fs::path& file) {
    const bool absolute = file.is_absolute() || folder.is_absolute();
    const fs::path f = (absolute ? fs::absolute(file) : file).lexically_normal();
    const fs::path d = (absolute ? fs::absolute(folder) : folder).lexically_normal();
    const fs::path r = d.empty() || d == "." ? f : f.lexically_relative(d);
    return (r.empty() ? f : r).generic_string();
  };
  const auto number = [](std::string& out, std::string_view key, double value) {
    out += fmt::format("{} = {}\n", toml_key(key), toml_number(value));
  };
  const auto optional = [&](std::string& out, std::string_view key, const std::optional<double>& value) {
    if (value) number(out, key, *value);
  };

  std::string out = fmt::format("name = {}\n", toml_string(set.name));
  if (!set.description.empty()) out += fmt::format("description = {}\n", toml_string(set.description));
  if (!set.catalog_file.empty()) out += fmt::format("catalog = {}\n", toml_string(relative(set.catalog_file)));
  for (const ThermalRun& run : set.runs) {
    out += "\n[[run]]\n";
    out += fmt::format("id = {}\nfile = {}\nguide = {}\n", toml_string(run.id), toml_string(relative(run.file)),
                       toml_string(run.guide));
    if (run.velocity_m_s > 0) number(out, canonical_key(kVelocity), run.velocity_m_s);
    number(out, canonical_key(kLoad), run.load_N);
    optional(out, canonical_key(kPreload), run.preload_um);
    number(out, canonical_key(kStroke), run.stroke_m);
    number(out, canonical_key(kRailLength), run.rail_length_m);
    optional(out, canonical_key(kContactLength), run.contact_length_mm);
    optional(out, canonical_key(kBlockLength), run.block_length_mm);
    optional(out, canonical_key(kMeanFriction), run.mean_friction_N);
    optional(out, canonical_key(kMeanFrictionUncertainty), run.mean_friction_uncertainty_N);
    optional(out, canonical_key(kStartFriction), run.start_friction_N);
    optional(out, canonical_key(kHeatRate), run.heat_rate_W);
    optional(out, canonical_key(kHeatRateUncertainty), run.heat_rate_uncertainty_W);
    optional(out, canonical_key(kAmbientC), run.ambient_C);
    optional(out, canonical_key(kConvection), run.h_W_m2K);
    optional(out, canonical_key(kViscosity40), run.viscosity40_mm2_s);
    for (const ThermalPhase& phase : run.schedule) {
      out += fmt::format("[[run.{}]]\n", kSchedule);
      number(out, "from_s", phase.from_s);
      optional(out, canonical_key(kVelocity), phase.velocity_m_s);
      optional(out, canonical_key(kHeatRate), phase.heat_rate_W);
    }    if (!run.sensor_position_m.empty()) {
      out += fmt::format("[run.{}]\n", csv::canonical_name(kSensors, Quantity::distance_m));
      for (const auto& [name, x] : run.sensor_position_m) number(out, name, x);
    }
    if (!run.guide_overrides.empty()) {
      out += fmt::format("[run.{}]\n", kOverrides);
      for (const auto& [name, value] : run.guide_overrides) number(out, name, value);
    }
  }
  return out;
}

}  // namespace lmcal