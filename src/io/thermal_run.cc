#include "lmcal/io/thermal_run.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>

#include "io/csv_reader.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/io/csv_writer.hpp"
#include "lmcal/io/units.hpp"

namespace lmcal {

namespace {

namespace fs = std::filesystem;

// ---- Trace CSV ----------------------------------------------------------------------------

enum TraceSpec : std::size_t { kTime, kAmbient, kRail };
constexpr std::array<csv::ColumnSpec, 3> kTraceSpecs{{
    {.name = "time", .quantity = Quantity::time, .required = true},
    {.name = "ambient",
     .quantity = Quantity::temperature,
     .required = true,
     .family = true,
     .rule = csv::Rule::above_absolute_zero},
    {.name = "tc",
     .quantity = Quantity::temperature,
     .required = true,
     .family = true,
     .rule = csv::Rule::above_absolute_zero},
}};

// A gap is an interval longer than 1.5x the median interval (the logger's step).
constexpr double kGapFactor = 1.5;

std::size_t count_time_gaps(const std::vector<double>& time_s) {
  if (time_s.size() < 3) return 0;
  std::vector<double> steps(time_s.size() - 1);
  for (std::size_t i = 0; i + 1 < time_s.size(); ++i) steps[i] = time_s[i + 1] - time_s[i];
  const auto middle = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
  std::nth_element(steps.begin(), middle, steps.end());  // reorders: the count below uses time_s
  double median = *middle;
  if (steps.size() % 2 == 0) median = 0.5 * (median + *std::max_element(steps.begin(), middle));
  std::size_t gaps = 0;
  for (std::size_t i = 0; i + 1 < time_s.size(); ++i) gaps += time_s[i + 1] - time_s[i] > kGapFactor * median;
  return gaps;
}

// "tc1_K" -> "tc1_C": the header a channel gets in canonical units.
std::string canonical_channel(const std::string& name) {
  const auto split = split_unit(name, Quantity::temperature);
  return csv::canonical_name(split ? split->name : name, Quantity::temperature);
}

// ---- Manifest -----------------------------------------------------------------------------

struct Manifest {
  std::string file;  // as errors name it
  fs::path folder;   // run files are relative to it

  [[noreturn]] void fail(const toml::source_region& where, const std::string& what) const {
    throw InputError(file, static_cast<long>(where.begin.line), static_cast<long>(where.begin.column), what);
  }
};

// Numeric [[run]] keys; each takes any unit of its quantity ("velocity_mm_s").
struct NumberKey {
  std::string_view base;
  Quantity quantity;
  bool required;
  bool strictly_positive;  // > 0, else >= 0
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
  kStartFriction
};
// A key is matched against the bases in this order; a base that extends another
// (mean_friction_uncertainty) comes first, so a bad unit on it is reported as its own
// ("mean_friction_uncertainty_kgs": unknown unit 'kgs'), not as mean_friction's.
constexpr std::array<NumberKey, 10> kNumberKeys{{
    {"velocity", Quantity::velocity, true, true},
    {"load", Quantity::force, true, false},
    {"preload", Quantity::preload, false, false},
    {"stroke", Quantity::distance_m, true, true},
    {"rail_length", Quantity::distance_m, true, true},
    {"contact_length", Quantity::length_mm, false, true},
    {"block_length", Quantity::length_mm, false, true},
    {"mean_friction_uncertainty", Quantity::force, false, false},
    {"mean_friction", Quantity::force, false, false},
    {"start_friction", Quantity::force, false, false},
}};
// A number key in internal units ("mean_friction_N"), as the writer writes it.
std::string canonical_key(NumberKeyIndex i) {
  return csv::canonical_name(kNumberKeys[i].base, kNumberKeys[i].quantity);
}

constexpr std::string_view kSensors = "sensors";  // [run.sensors_m]: positions, any distance unit
constexpr std::string_view kOverrides = "guide_overrides";
enum TextKeyIndex : std::size_t { kId, kFile, kGuide };
constexpr std::array<std::string_view, 3> kTextKeys{"id", "file", "guide"};

std::string known_run_keys() {
  std::vector<std::string> keys(kTextKeys.begin(), kTextKeys.end());
  for (const NumberKey& k : kNumberKeys) keys.push_back(csv::canonical_name(k.base, k.quantity));
  keys.push_back(csv::canonical_name(kSensors, Quantity::distance_m));
  keys.emplace_back(kOverrides);
  return fmt::format("{} (numbers in any unit of their quantity)", fmt::join(keys, ", "));
}

bool before(const toml::source_region& a, const toml::source_region& b) {
  return std::pair(a.begin.line, a.begin.column) < std::pair(b.begin.line, b.begin.column);
}

// A key of a [[run]] that was given, for duplicate and range messages.
struct Given {
  const toml::key* key = nullptr;
  const toml::node* node = nullptr;
  Conversion conversion;  // for keys with a unit: to internal units
  double value = 0;       // for numbers: in internal units
};

// A finite TOML number (integer or float).
double number_of(const Manifest& m, const toml::key& key, const toml::node& node) {
  std::optional<double> value;
  if (const auto* i = node.as_integer()) value = static_cast<double>(i->get());
  if (const auto* f = node.as_floating_point()) value = f->get();
  if (!value) m.fail(node.source(), fmt::format("expected a number for {}", key.str()));
  if (!std::isfinite(*value)) m.fail(node.source(), fmt::format("expected a finite number for {}", key.str()));
  return *value;
}

const std::string& string_of(const Manifest& m, const toml::key& key, const toml::node& node) {
  const auto* s = node.as_string();
  if (!s) m.fail(node.source(), fmt::format("expected a string for {}", key.str()));
  return s->get();
}

const toml::table& table_of(const Manifest& m, const toml::key& key, const toml::node& node) {
  const auto* t = node.as_table();
  if (!t) m.fail(node.source(), fmt::format("expected a table [run.{}]", key.str()));
  return *t;
}

// Records `key` as the one giving `what`; two keys for one thing (velocity_m_s and
// velocity_mm_s) are an error at the later one.
void remember(const Manifest& m, std::optional<Given>& slot, Given given, std::string_view what) {
  if (slot) {
    const bool later = before(slot->key->source(), given.key->source());
    const Given& first = later ? *slot : given;
    const Given& second = later ? given : *slot;
    m.fail(second.key->source(),
           fmt::format("duplicate key '{}': '{}' already gives {}", second.key->str(), first.key->str(), what));
  }
  slot = given;
}

// Everything of a [[run]] table, checked one key at a time.
struct RunKeys {
  std::array<std::optional<Given>, kTextKeys.size()> text;
  std::array<std::optional<Given>, kNumberKeys.size()> number;
  std::optional<Given> sensors;
  std::optional<Given> overrides;
};

// The conversion of a key with a unit suffix that names `base` ("velocity_mm_s" for
// "velocity"), nullopt for a key that names something else. A missing or unknown unit is an
// error at the key.
std::optional<Conversion> unit_key(const Manifest& m, const toml::key& key, std::string_view base, Quantity quantity) {
  const csv::UnitMatch u = csv::match_unit(key.str(), base, quantity);
  switch (u.kind) {
    case csv::UnitMatch::other: return std::nullopt;
    case csv::UnitMatch::no_unit:
      m.fail(key.source(),
             fmt::format("key '{}' has no unit; accepted: {}", key.str(), csv::accepted_names(base, quantity)));
    case csv::UnitMatch::unknown_unit:
      m.fail(key.source(), fmt::format("key '{}': unknown unit '{}'; accepted: {}", key.str(), u.unit,
                                       csv::accepted_names(base, quantity)));
    case csv::UnitMatch::match: break;
  }
  return u.split.conversion;
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
    if (k == kOverrides) {
      table_of(m, key, node);
      remember(m, keys.overrides, {&key, &node}, k);
      continue;
    }
    if (const auto conversion = unit_key(m, key, kSensors, Quantity::distance_m)) {
      table_of(m, key, node);
      remember(m, keys.sensors, {&key, &node, *conversion}, kSensors);
      continue;
    }
    bool known = false;
    for (std::size_t i = 0; i < kNumberKeys.size() && !known; ++i) {
      const NumberKey& nk = kNumberKeys[i];
      const auto conversion = unit_key(m, key, nk.base, nk.quantity);
      if (!conversion) continue;
      const double written = number_of(m, key, node);
      if (!(nk.strictly_positive ? written > 0 : written >= 0)) {
        m.fail(node.source(), fmt::format("{} = {}: a thermal run needs {} {} 0", k, written, nk.base,
                                          nk.strictly_positive ? ">" : ">="));
      }
      remember(m, keys.number[i], {&key, &node, *conversion, csv::to_internal(*conversion, written)}, nk.base);
      known = true;
    }
    if (!known) m.fail(key.source(), fmt::format("unknown key '{}' in [[run]]; known: {}", k, known_run_keys()));
  }
  return keys;
}

// The [run.guide_overrides] table: catalog field -> value > 0.
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
      m.fail(table.source(),
             fmt::format("missing key '{}' in [[run]] '{}' (accepted units: {})",
                         csv::canonical_name(nk.base, nk.quantity), run.id, csv::accepted_names(nk.base, nk.quantity)));
    }
  }
  const auto value = [&](NumberKeyIndex i) {
    return keys.number[i] ? std::optional(keys.number[i]->value) : std::nullopt;
  };
  run.velocity_m_s = *value(kVelocity);
  run.load_N = *value(kLoad);
  run.preload_um = value(kPreload);
  run.stroke_m = *value(kStroke);
  run.rail_length_m = *value(kRailLength);
  run.contact_length_mm = value(kContactLength);
  run.block_length_mm = value(kBlockLength);
  run.mean_friction_N = value(kMeanFriction);
  run.mean_friction_uncertainty_N = value(kMeanFrictionUncertainty);
  run.start_friction_N = value(kStartFriction);
  if (run.mean_friction_uncertainty_N && !run.mean_friction_N) {
    const Given& u = *keys.number[kMeanFrictionUncertainty];
    m.fail(u.key->source(), fmt::format("{} given without {}: it is the uncertainty of the measured mean friction",
                                        u.key->str(), canonical_key(kMeanFriction)));
  }

  // The guide must be in the catalog; overrides name its fields.
  run.guide = text(kGuide);
  const GuideSpec* guide = nullptr;
  try {
    guide = &builtin_catalog().find(run.guide);
  } catch (const InvalidParameter& e) {
    m.fail(keys.text[kGuide]->node->source(), e.what());
  }
  if (keys.overrides) run.guide_overrides = read_overrides(m, *keys.overrides->node->as_table());

  // The rail must hold the stroke plus the block's contact length.
  std::optional<double> contact_mm = run.contact_length_mm;
  if (const auto it = run.guide_overrides.find("contact_length_mm"); !contact_mm && it != run.guide_overrides.end()) {
    contact_mm = it->second;
  }
  if (!contact_mm) contact_mm = field_value(*guide, "contact_length_mm");
  const double needed_m = run.stroke_m + contact_mm.value_or(0) * 1e-3;
  if (!(run.rail_length_m > needed_m)) {
    const Given& rail = *keys.number[kRailLength];
    m.fail(rail.node->source(),
           fmt::format("{} = {}: a thermal run needs rail length > stroke{} = {:.6g} m", rail.key->str(),
                       number_of(m, *rail.key, *rail.node), contact_mm ? " + contact length" : "", needed_m));
  }

  // The CSV, relative to the manifest's folder.
  const std::string& file = text(kFile);
  run.file = m.folder / file;
  std::error_code ec;
  if (!fs::is_regular_file(run.file, ec)) {
    m.fail(keys.text[kFile]->node->source(), fmt::format("file '{}' not found (looked in {})", file,
                                                         m.folder.empty() ? std::string(".") : m.folder.string()));
  }
  run.trace = load_thermal_trace(run.file);

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
      const double x_m = csv::to_internal(keys.sensors->conversion, number_of(m, key, node));
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

std::string read_text_file(const fs::path& file) {
  std::error_code ec;
  std::ifstream in(file, std::ios::binary);
  if (!in || fs::is_directory(file, ec)) throw InputError(file.string(), 0, 0, "cannot open manifest file");
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw InputError(file.string(), 0, 0, "cannot read manifest file");
  return text;
}

// ---- Manifest writer ----------------------------------------------------------------------

std::string toml_string(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
          out += fmt::format("\\u{:04X}", static_cast<unsigned char>(c));
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

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

// ---- Public -------------------------------------------------------------------------------

ThermalTrace load_thermal_trace(const fs::path& file) {
  csv::Reader reader(file);
  ThermalTrace trace;
  LoadReport& report = trace.report;
  report.file = reader.file();
  reader.read_header();
  const std::vector<csv::Column> columns = csv::bind_header(reader, kTraceSpecs, report);
  const csv::Column& time = *csv::find_column(columns, kTime);

  // Channels in header order, ambient and rail apart.
  std::vector<const csv::Column*> channel_columns;
  for (const csv::Column& c : columns) {
    if (c.spec == kTime) continue;
    (c.spec == kAmbient ? trace.ambient : trace.rail).push_back({c.header, {}});
    channel_columns.push_back(&c);
  }
  struct Channel {
    const csv::Column* column;
    std::vector<double>* values;
    std::size_t missing = 0;
  };
  std::vector<Channel> channels;
  std::size_t ambient = 0, rail = 0;
  for (const csv::Column* c : channel_columns) {
    channels.push_back({c, c->spec == kAmbient ? &trace.ambient[ambient++].values : &trace.rail[rail++].values});
  }

  const std::size_t rows = reader.estimated_rows();
  trace.time_s.reserve(rows);
  for (Channel& c : channels) c.values->reserve(rows);

  long previous_line = 0;
  while (reader.next()) {
    const double t = reader.number(time, false);
    if (!trace.time_s.empty() && !(t > trace.time_s.back())) {
      reader.fail(time.cell, fmt::format("{} = {} is not later than the previous row's (line {}); time must "
                                         "increase strictly",
                                         time.header, reader.cell(time.cell), previous_line));
    }
    trace.time_s.push_back(t);
    previous_line = reader.line();
    for (Channel& c : channels) {
      const double value = reader.number(*c.column, true);
      c.missing += std::isnan(value);
      c.values->push_back(value);
    }
  }
  if (trace.time_s.empty()) reader.fail_at(reader.header_line(), 0, "no data rows below the header");

  report.rows_read = report.rows_kept = trace.time_s.size();
  for (const Channel& c : channels) {
    if (c.missing != 0) report.missing[c.column->header] = c.missing;
  }
  report.time_gaps = count_time_gaps(trace.time_s);
  report.bytes = static_cast<double>(reader.bytes());
  return trace;
}

std::string thermal_trace_csv(const ThermalTrace& trace, const std::vector<std::string>& comments) {
  std::vector<std::string> header{csv::canonical_name("time", Quantity::time)};
  std::vector<const std::vector<double>*> columns;
  for (const auto* group : {&trace.ambient, &trace.rail}) {
    for (const TemperatureChannel& channel : *group) {
      LMCAL_ASSERT(channel.values.size() == trace.size(), "temperature channel length differs from time_s");
      header.push_back(canonical_channel(channel.name));
      columns.push_back(&channel.values);
    }
  }
  CsvText csv(header, comments);
  for (std::size_t i = 0; i < trace.size(); ++i) {
    csv.cell(trace.time_s[i]);
    for (const auto* values : columns) csv.cell((*values)[i]);
    csv.end_row();
  }
  return csv.str();
}

ThermalDataSet load_thermal_dataset(const fs::path& manifest) {
  const Manifest m{manifest.string(), manifest.parent_path()};
  const std::string text = read_text_file(manifest);
  toml::table root;
  try {
    root = toml::parse(text, m.file);
  } catch (const toml::parse_error& e) {
    m.fail(e.source(), std::string(e.description()));
  }

  ThermalDataSet set;
  set.manifest = manifest;
  set.name = manifest.stem().string();
  const toml::array* runs = nullptr;
  for (const auto& [key, node] : root) {
    if (key.str() == "name") {
      set.name = string_of(m, key, node);
    } else if (key.str() == "description") {
      set.description = string_of(m, key, node);
    } else if (key.str() == "run") {
      runs = node.as_array();
      if (!runs || !runs->is_array_of_tables()) m.fail(node.source(), "expected [[run]] tables");
    } else {
      m.fail(key.source(), fmt::format("unknown key '{}'; known: name, description, run", key.str()));
    }
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
  for (const ThermalRun& run : set.runs) {
    out += "\n[[run]]\n";
    out += fmt::format("id = {}\nfile = {}\nguide = {}\n", toml_string(run.id), toml_string(relative(run.file)),
                       toml_string(run.guide));
    number(out, canonical_key(kVelocity), run.velocity_m_s);
    number(out, canonical_key(kLoad), run.load_N);
    optional(out, canonical_key(kPreload), run.preload_um);
    number(out, canonical_key(kStroke), run.stroke_m);
    number(out, canonical_key(kRailLength), run.rail_length_m);
    optional(out, canonical_key(kContactLength), run.contact_length_mm);
    optional(out, canonical_key(kBlockLength), run.block_length_mm);
    optional(out, canonical_key(kMeanFriction), run.mean_friction_N);
    optional(out, canonical_key(kMeanFrictionUncertainty), run.mean_friction_uncertainty_N);
    optional(out, canonical_key(kStartFriction), run.start_friction_N);
    if (!run.sensor_position_m.empty()) {
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
