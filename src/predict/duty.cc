// The duty cycle file of `lmcal predict` (prediction.hpp): TOML, keys with their unit in the
// name (duration_h, velocity_mm_s, load_kN …, as in the manifests), checked as they are read.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <thread>

#include "io/input_file.hpp"
#include "io/manifest.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"
#include "lmcal/predict/prediction.hpp"

namespace lmcal {

namespace {

using manifest::Manifest;

// A numeric key: its name without the unit, the quantity its unit belongs to, and its range
// in internal units (SI, °C, µm, mm, mm²/s).
struct NumberKey {
  std::string_view base;
  Quantity quantity;
  double low, high;
  bool low_open = false;  // the range excludes `low` (a duration > 0)
  std::string_view expected;
};

constexpr NumberKey kDuration{"duration", Quantity::time, 0, 1e7, true, "a duration > 0 and at most 1e7 s (116 days)"};
constexpr NumberKey kVelocity{"velocity", Quantity::velocity, 0, 10, false, "a speed in [0, 10] m/s (0: idle)"};
constexpr NumberKey kLoad{"load", Quantity::force, 0, 1e6, false, "a load in [0, 1e6] N"};
constexpr NumberKey kStroke{"stroke", Quantity::distance_m, 0, 100, true, "a stroke > 0 m"};
constexpr NumberKey kPreload{"preload", Quantity::preload, 0, 1000, false, "a preload in [0, 1000] µm"};
constexpr NumberKey kBlockLength{"block_length", Quantity::length_mm, 0, 10000, true, "a block length > 0 mm"};
constexpr NumberKey kViscosity{"viscosity40", Quantity::viscosity, 1e-3, 1e5, false, "a viscosity in [1e-3, 1e5] mm²/s"};
constexpr NumberKey kRailLength{"rail_length", Quantity::distance_m, 0, 100, true, "a rail length in (0, 100] m"};
constexpr NumberKey kAmbient{"ambient", Quantity::temperature, -50, 200, false, "a temperature in [-50, 200] °C"};
constexpr NumberKey kInitial{"initial", Quantity::temperature, -50, 200, false, "a temperature in [-50, 200] °C"};
constexpr NumberKey kOutputEvery{"output_every", Quantity::time, 0, 1e7, true, "an interval > 0 s"};

// The keys a table gave, by quantity: two keys for one (rail_length_m and rail_length_mm) are
// refused at the later one, as in the manifests.
using GivenKeys = std::map<std::string_view, std::optional<manifest::Given>>;

// The value of `key` if it gives `spec` (its name with a unit), in internal units.
std::optional<double> read_number(const Manifest& m, const toml::key& key, const toml::node& node, const NumberKey& spec,
                                  GivenKeys& given) {
  const auto conversion = manifest::unit_key(m, key, spec.base, spec.quantity);
  if (!conversion) return std::nullopt;
  manifest::remember(m, given[spec.base], {&key, &node}, spec.base);
  const double v = conversion->apply(manifest::number_of(m, key, node));
  const bool ok = (spec.low_open ? v > spec.low : v >= spec.low) && v <= spec.high && std::isfinite(v);
  if (!ok) m.fail(node.source(), fmt::format("{} = {}: expected {}", key.str(), manifest::number_of(m, key, node), spec.expected));
  return v;
}

// A list of positions (m from the rail centre) within the rail, at most kMaxDutyPositions.
std::vector<double> positions_of(const Manifest& m, const toml::key& key, const toml::node& node) {
  const auto* a = node.as_array();
  if (!a || a->empty()) m.fail(node.source(), fmt::format("{}: expected a list of positions in m, e.g. [0, 0.1]", key.str()));
  if (a->size() > io::kMaxDutyPositions)
    m.fail(node.source(), fmt::format("{}: {} positions: at most {} (docs/formats.md#limits)", key.str(), a->size(),
                                      io::kMaxDutyPositions));
  std::vector<double> out;
  for (const auto& item : *a) out.push_back(manifest::number_of(m, key, item));
  return out;
}

void check_on_rail(const Manifest& m, const toml::node& where, std::string_view what, double x, double rail_length_m) {
  if (std::abs(x) > 0.5 * rail_length_m + 1e-12)
    m.fail(where.source(), fmt::format("{} = {} m lies off the rail (|x| <= {} m from its centre)", what, x, 0.5 * rail_length_m));
}

// What a segment may inherit from the top level.
struct SegmentDefaults {
  std::optional<double> load_N, stroke_m, preload_um, block_length_mm, viscosity40_mm2_s;
};

// A key a segment may inherit from the top level, read into `d`; false for another key.
bool read_default(const Manifest& m, const toml::key& key, const toml::node& node, SegmentDefaults& d, GivenKeys& given) {
  std::optional<double> v;
  if ((v = read_number(m, key, node, kLoad, given))) d.load_N = v;
  else if ((v = read_number(m, key, node, kStroke, given))) d.stroke_m = v;
  else if ((v = read_number(m, key, node, kPreload, given))) d.preload_um = v;
  else if ((v = read_number(m, key, node, kBlockLength, given))) d.block_length_mm = v;
  else if ((v = read_number(m, key, node, kViscosity, given))) d.viscosity40_mm2_s = v;
  else return false;
  return true;
}

constexpr const char* kSegmentKeys =
    "name, duration_s, velocity_m_s, load_N, stroke_m, preload_um, block_length_mm, viscosity40_mm2_s (any unit)";
constexpr const char* kTopKeys =
    "guide, catalog, rail_length_m, ambient_C, ambient_trace, initial_C, positions_m, output_every_s, repeat, load_N, "
    "stroke_m, preload_um, block_length_mm, viscosity40_mm2_s, [scale], [[segment]]";

LinearScale read_scale(const Manifest& m, const toml::table& t, double rail_length_m) {
  LinearScale s{.from_m = -0.5 * rail_length_m, .to_m = 0.5 * rail_length_m};
  bool positions_given = false;
  for (const auto& [key, node] : t) {
    const std::string_view k = key.str();
    if (k == "from_m") s.from_m = manifest::number_of(m, key, node);
    else if (k == "to_m") s.to_m = manifest::number_of(m, key, node);
    else if (k == "expansion_per_K") {
      s.expansion_per_K = manifest::number_of(m, key, node);
      if (!(s.expansion_per_K > 0 && s.expansion_per_K < 1e-3))
        m.fail(node.source(), fmt::format("expansion_per_K = {}: expected a coefficient in (0, 1e-3) 1/K (steel 11.5e-6)",
                                          s.expansion_per_K));
    } else if (k == "mounting") {
      const std::string& v = manifest::string_of(m, key, node);
      if (v == "end") s.mounting = ScaleMounting::end;
      else if (v == "centre" || v == "center") s.mounting = ScaleMounting::centre;
      else m.fail(node.source(), fmt::format("mounting = \"{}\": expected \"end\" (fixed at from_m) or \"centre\"", v));
    } else if (k == "positions_m") {
      s.positions_m = positions_of(m, key, node);
      positions_given = true;
    } else {
      m.fail(key.source(), fmt::format("unknown key '{}' in [scale]; expected from_m, to_m, mounting, expansion_per_K, positions_m", k));
    }
  }
  for (const char* k : {"from_m", "to_m"})
    if (const toml::node* n = t.get(k)) check_on_rail(m, *n, fmt::format("[scale] {}", k), k[0] == 'f' ? s.from_m : s.to_m, rail_length_m);
  if (!(s.to_m > s.from_m)) m.fail(t.source(), fmt::format("[scale]: expected from_m < to_m, found {} and {}", s.from_m, s.to_m));
  if (!positions_given) {
    s.positions_m = {s.to_m};
    if (s.mounting == ScaleMounting::centre) s.positions_m.insert(s.positions_m.begin(), s.from_m);
  }
  for (double x : s.positions_m)
    if (x < s.from_m - 1e-12 || x > s.to_m + 1e-12)
      m.fail(t.get("positions_m")->source(), fmt::format("[scale] positions_m: {} m lies off the scale [{}, {}] m", x, s.from_m, s.to_m));
  return s;
}

}  // namespace

double DutyCycle::duration_s() const {
  return std::accumulate(segments.begin(), segments.end(), 0.0, [](double t, const DutySegment& s) { return t + s.duration_s; });
}

DutyCycle duty_of_runs(const ThermalDataSet& data, double ambient_C) {
  if (data.runs.empty()) throw InvalidParameter("runs", "no thermal runs to take a cycle from");
  const ThermalRun& first = data.runs.front();
  double speed = 0, duration = 0;
  for (const ThermalRun& run : data.runs) {
    speed = std::max(speed, run.velocity_m_s);
    if (run.trace.size() > 1) duration = std::max(duration, run.trace.time_s.back() - run.trace.time_s.front());
  }
  if (!(speed > 0 && duration > 0)) throw InvalidParameter("runs", "no run with a speed and a duration to take a cycle from");
  DutyCycle d;
  d.file = data.manifest.string() + " (the runs' cycle)";
  d.guide = resolved_guide(first);
  if (first.contact_length_mm) d.guide.contact_length_mm = first.contact_length_mm;
  d.rail_length_m = first.rail_length_m;
  d.ambient = AmbientTrace::constant(ambient_C);
  for (const auto& [sensor, x] : first.sensor_position_m) d.positions_m.push_back(x);
  std::sort(d.positions_m.begin(), d.positions_m.end());
  d.scale = {.from_m = -0.5 * d.rail_length_m, .to_m = 0.5 * d.rail_length_m, .positions_m = {0.5 * d.rail_length_m}};
  const double preload = first.preload_um ? *first.preload_um : require(d.guide, &GuideSpec::preload_um, "preload_um");
  const double block = first.block_length_mm ? *first.block_length_mm : require(d.guide, &GuideSpec::block_length_mm, "block_length_mm");
  const DutySegment run{.name = "running", .duration_s = duration, .velocity_m_s = speed, .load_N = first.load_N,
                        .stroke_m = first.stroke_m, .preload_um = preload, .block_length_mm = block,
                        .viscosity40_mm2_s = first.viscosity40_mm2_s.value_or(99.0)};
  DutySegment rest = run;
  rest.name = "at rest";
  rest.velocity_m_s = 0;
  d.segments = {run, rest};
  return d;
}

namespace {

// The guide `node` names, from the user's catalog, the file's own (`catalog = …`) or the
// built-in one; it must give what the rail's simulation needs.
GuideSpec read_guide(const Manifest& m, const toml::node& node, const GuideCatalog* catalog) {
  try {
    GuideSpec guide = find_guide(manifest::string_of(m, toml::key("guide"), node), catalog);
    // The rail the prediction simulates: the catalog must give its section, material and contact.
    rail_geometry_of(guide, 1, 1, 0, 0);
    rail_material_of(guide);
    require(guide, &GuideSpec::contact_length_mm, "contact_length_mm");
    return guide;
  } catch (const InvalidParameter& e) {
    m.fail(node.source(), e.what());
  }
}

// ambient_trace = [[t_s, T_C], ...]: times increasing, temperatures those of a rig.
AmbientTrace read_ambient_trace(const Manifest& m, const toml::node& node) {
  const auto* a = node.as_array();
  if (!a || a->empty()) m.fail(node.source(), "ambient_trace: expected [[t_s, T_C], ...]");
  if (a->size() > io::kMaxAmbientTracePoints)
    m.fail(node.source(), fmt::format("ambient_trace: {} points: at most {} (docs/formats.md#limits)", a->size(),
                                      io::kMaxAmbientTracePoints));
  AmbientTrace trace;
  for (const auto& item : *a) {
    const auto* pair = item.as_array();
    if (!pair || pair->size() != 2) m.fail(item.source(), "ambient_trace: expected [t_s, T_C] pairs");
    const toml::key key("ambient_trace");
    const double t = manifest::number_of(m, key, (*pair)[0]), T = manifest::number_of(m, key, (*pair)[1]);
    if (!trace.time_s.empty() && !(t > trace.time_s.back()))
      m.fail(item.source(), fmt::format("ambient_trace: time {} s is not after {} s", t, trace.time_s.back()));
    if (!(T >= -50 && T <= 200)) m.fail(item.source(), fmt::format("ambient_trace: {} °C: expected a temperature in [-50, 200] °C", T));
    trace.time_s.push_back(t);
    trace.temperature_C.push_back(T);
  }
  return trace;
}

// One [[segment]] table, what it leaves out taken from the top's defaults, then the guide's.
DutySegment read_segment(const Manifest& m, const toml::table& t, const SegmentDefaults& defaults, const DutyCycle& d) {
  DutySegment s;
  s.line = static_cast<long>(t.source().begin.line);
  s.column = static_cast<long>(t.source().begin.column);
  s.duration_s = NAN;
  SegmentDefaults own = defaults;
  GivenKeys given_here;
  for (const auto& [key, node] : t) {
    std::optional<double> v;
    if ((v = read_number(m, key, node, kDuration, given_here))) s.duration_s = *v;
    else if ((v = read_number(m, key, node, kVelocity, given_here))) s.velocity_m_s = *v;
    else if (key.str() == "name") s.name = manifest::string_of(m, key, node);
    else if (!read_default(m, key, node, own, given_here))
      m.fail(key.source(), fmt::format("unknown key '{}' in [[segment]]; expected {}", key.str(), kSegmentKeys));
  }
  if (std::isnan(s.duration_s)) m.fail(t.source(), "[[segment]]: expected duration_s (any time unit: duration_min, duration_h)");
  const auto needed = [&](const std::optional<double>& v, std::optional<double> GuideSpec::*field, const char* what) {
    if (v) return *v;
    if (field && d.guide.*field) return *(d.guide.*field);
    m.fail(t.source(), fmt::format("[[segment]]: expected {} (here or at the top)", what));
  };
  s.load_N = needed(own.load_N, nullptr, "load_N");
  s.preload_um = needed(own.preload_um, &GuideSpec::preload_um, "preload_um");
  s.block_length_mm = needed(own.block_length_mm, &GuideSpec::block_length_mm, "block_length_mm");
  s.viscosity40_mm2_s = own.viscosity40_mm2_s.value_or(99.0);
  if (s.velocity_m_s > 0) {
    s.stroke_m = needed(own.stroke_m, nullptr, "stroke_m");
    const double contact_m = *d.guide.contact_length_mm * 1e-3;
    if (s.stroke_m + contact_m > d.rail_length_m)
      m.fail(t.source(), fmt::format("[[segment]]: stroke {} m plus the block's contact length {} m is longer than the rail "
                                     "({} m)",
                                     s.stroke_m, contact_m, d.rail_length_m));
  } else {
    s.stroke_m = own.stroke_m.value_or(0.5 * d.rail_length_m);
  }
  return s;
}

// The [[segment]] tables read into `d.segments`, `repeat` times over (unnamed ones numbered on),
// within the limits of a duty's segments, duration and outputs.
void read_segments(const Manifest& m, const toml::table& root, const SegmentDefaults& defaults, long repeat, DutyCycle& d) {
  const toml::node* list_node = root.get("segment");
  const auto* list = list_node ? list_node->as_array() : nullptr;
  if (!list || list->empty()) m.fail(list_node ? list_node->source() : root.source(), "expected [[segment]] tables");
  // Sizes before the segments are read or laid out: each repeat is simulated for every draw.
  if (list->size() * static_cast<std::size_t>(repeat) > io::kMaxDutySegments)
    m.fail(root.get("repeat") ? root.get("repeat")->source() : list_node->source(),
           fmt::format("{} segments × repeat {} = {} segments: at most {} (docs/formats.md#limits)", list->size(), repeat,
                       list->size() * static_cast<std::size_t>(repeat), io::kMaxDutySegments));
  std::vector<DutySegment> one_cycle;
  for (const auto& item : *list) one_cycle.push_back(read_segment(m, manifest::table_of(m, item, "[[segment]]"), defaults, d));
  // The duration and the outputs from one cycle, before the repeats are laid out.
  const double cycle = std::accumulate(one_cycle.begin(), one_cycle.end(), 0.0,
                                       [](double t, const DutySegment& s) { return t + s.duration_s; });
  const double duration = cycle * static_cast<double>(repeat);
  if (duration > 1e7) m.fail(root.source(), fmt::format("the duty lasts {} s: at most 1e7 s (116 days)", duration));
  if (duration / d.output_every_s > static_cast<double>(io::kMaxDutyOutputs))
    m.fail(root.get("output_every_s") ? root.get("output_every_s")->source() : root.source(),
           fmt::format("output_every_s = {} gives {} outputs: at most {} (docs/formats.md#limits)", d.output_every_s,
                       duration / d.output_every_s, io::kMaxDutyOutputs));
  d.segments.reserve(one_cycle.size() * static_cast<std::size_t>(repeat));
  for (long r = 0; r < repeat; ++r)
    for (const DutySegment& s : one_cycle) {
      d.segments.push_back(s);
      if (d.segments.back().name.empty()) d.segments.back().name = fmt::format("segment {}", d.segments.size());
    }
}

}  // namespace

DutyCycle load_duty_cycle(const std::filesystem::path& path, const GuideCatalog* user_catalog, const InputScope& scope) {
  const Manifest m{path.string(), path.parent_path(), scope, "duty-cycle file"};
  const toml::table root = m.parse();
  DutyCycle d;
  d.file = path.string();
  SegmentDefaults defaults;
  std::optional<GuideCatalog> own_catalog;
  const toml::node* guide_node = nullptr;
  std::optional<double> rail_length, ambient, initial, every;
  long repeat = 1;
  const toml::node* trace_node = nullptr;
  const toml::node* positions_node = nullptr;
  GivenKeys given;
  for (const auto& [key, node] : root) {
    const std::string_view k = key.str();
    std::optional<double> v;
    if (k == "guide") guide_node = &node;
    else if (k == "catalog") {
      if (!user_catalog) own_catalog = load_catalog(m.existing_file(node, manifest::string_of(m, key, node)));
    } else if (k == "ambient_trace") trace_node = &node;
    else if (k == "positions_m") positions_node = &node;
    else if (k == "repeat") {
      const auto* i = node.as_integer();
      if (!i || i->get() < 1 || i->get() > 100000) m.fail(node.source(), "repeat: expected a whole number in [1, 100000]");
      repeat = i->get();
    } else if (k == "scale" || k == "segment") continue;
    else if ((v = read_number(m, key, node, kRailLength, given))) rail_length = v;
    else if ((v = read_number(m, key, node, kAmbient, given))) ambient = v;
    else if ((v = read_number(m, key, node, kInitial, given))) initial = v;
    else if ((v = read_number(m, key, node, kOutputEvery, given))) every = v;
    else if (!read_default(m, key, node, defaults, given))
      m.fail(key.source(), fmt::format("unknown key '{}'; expected {}", k, kTopKeys));
  }
  if (!guide_node) m.fail(root.source(), "expected guide = \"...\" (a model of the catalog, e.g. \"SRN 35C\")");
  d.guide = read_guide(m, *guide_node, user_catalog ? user_catalog : own_catalog ? &*own_catalog : nullptr);
  if (!rail_length) m.fail(root.source(), "expected rail_length_m (any length unit: rail_length_mm, …)");
  d.rail_length_m = *rail_length;
  if (trace_node) {
    if (ambient) m.fail(trace_node->source(), "ambient_trace and ambient_C both given: one or the other");
    d.ambient = read_ambient_trace(m, *trace_node);
  } else {
    if (!ambient) m.fail(root.source(), "expected ambient_C (or ambient_trace = [[t_s, T_C], ...])");
    d.ambient = AmbientTrace::constant(*ambient);
  }
  d.initial_C = initial;
  d.output_every_s = every.value_or(60.0);
  d.positions_m = positions_node ? positions_of(m, toml::key("positions_m"), *positions_node) : std::vector<double>{0.0};
  if (positions_node)
    for (double x : d.positions_m) check_on_rail(m, *positions_node, "positions_m", x, d.rail_length_m);
  if (const toml::node* n = root.get("scale")) d.scale = read_scale(m, manifest::table_of(m, *n, "[scale]"), d.rail_length_m);
  else d.scale = read_scale(m, toml::table{}, d.rail_length_m);
  read_segments(m, root, defaults, repeat, d);
  const double laid_out = d.duration_s();
  if (d.ambient.time_s.size() > 1 && (d.ambient.time_s.front() > 0 || d.ambient.time_s.back() < laid_out))
    m.fail(trace_node->source(), fmt::format("ambient_trace covers [{}, {}] s; the duty runs [0, {}] s", d.ambient.time_s.front(),
                                             d.ambient.time_s.back(), laid_out));
  return d;
}

PredictionCost prediction_cost(const DutyCycle& duty, const PredictionOptions& o) {
  // Measured with lmcal predict on the bundled model (docs/formats.md#limits): 2.5 ns per rail
  // node and time step, 70 µs per segment's set-up, 2.5 ns per node and quantity at an
  // output; each draw holds its outputs (8 bytes a value, half again for the bands), each
  // thread one segment's profiles.
  const double nodes = 2.0 * std::max(o.half_rail_segments, 1) + 1;
  const double outputs = duty.duration_s() / duty.output_every_s + static_cast<double>(duty.segments.size());
  const double quantities = static_cast<double>(duty.positions_m.size() + duty.scale.positions_m.size() + 3);
  const double segments = static_cast<double>(duty.segments.size());
  const double steps = duty.duration_s() / o.time_step_s + segments;
  const double draws = static_cast<double>(o.samples) + 1;
  const double threads = std::max(1u, std::thread::hardware_concurrency());
  const double scale_positions = static_cast<double>(duty.scale.positions_m.size());
  const double per_draw_s = 70e-6 * segments + 2.5e-9 * nodes * (steps + outputs * (scale_positions + 2)) +
                            2e-9 * segments * static_cast<double>(duty.ambient.time_s.size());
  return {.cpu_s = draws * per_draw_s, .bytes = outputs * (12 * draws * quantities + 8 * nodes * threads)};
}

void check_prediction_size(const DutyCycle& duty, const PredictionOptions& o) {
  if (o.samples > io::kMaxPredictionSamples)
    throw InvalidParameter("samples", static_cast<double>(o.samples),
                           fmt::format("at most {} draws (docs/formats.md#limits)", io::kMaxPredictionSamples));
  if (o.half_rail_segments > io::kMaxRailSegments)
    throw InvalidParameter("half_rail_segments", o.half_rail_segments,
                           fmt::format("at most {} (docs/formats.md#limits)", io::kMaxRailSegments));
  require_positive("time_step_s", o.time_step_s);
  const PredictionCost cost = prediction_cost(duty, o);
  const auto refuse = [&](std::string_view what) {
    throw InvalidParameter(
        "duty", fmt::format("{}: {} segments, {:.3g} outputs at {} positions, {} draws of a {}-segment rail at {} s steps "
                            "would take some {:.2g} CPU hours and {}: {} (docs/formats.md#limits); fewer --samples, a longer "
                            "output_every_s, fewer positions or a longer --dt",
                            duty.file, duty.segments.size(), duty.duration_s() / duty.output_every_s,
                            duty.positions_m.size() + duty.scale.positions_m.size(), o.samples, o.half_rail_segments,
                            o.time_step_s, cost.cpu_s / 3600, io::byte_size(static_cast<std::uintmax_t>(std::min(cost.bytes, 1e18))), what));
  };
  if (cost.bytes > static_cast<double>(io::kMaxPredictionBytes))
    refuse(fmt::format("memory beyond {}", io::byte_size(io::kMaxPredictionBytes)));
  if (cost.cpu_s > io::kMaxPredictionCpu_s) refuse(fmt::format("beyond {:g} CPU hours", io::kMaxPredictionCpu_s / 3600));
}

}  // namespace lmcal
