// load_duty_cycle (the duty of `lmcal predict MODEL DUTY`) on a fuzzed duty file beside the
// companion files (fuzz/companions: a user catalog a duty may name): refused with an InputError
// at a line of the duty or of the catalog it names, or loaded with every number finite and where
// prediction.hpp and docs/formats.md put it — each segment's duration, speed, load, stroke,
// preload, block length and viscosity within the rig's ranges (units.hpp physical_range) and
// of the right sign, the positions on the rail, the ambient within the rig's temperatures — and
// every size within docs/formats.md#limits: the segments after the repeats, the outputs, the
// positions. There is no duty writer, so no round trip.
#include "fuzz_support.hpp"

#include "lmcal/io/limits.hpp"
#include "lmcal/predict/prediction.hpp"

namespace {

using namespace lmcal::fuzz;
namespace io = lmcal::io;

// A segment's number, its quantity's range, and whether 0 is allowed (an idle speed, no load).
struct SegmentField {
  double lmcal::DutySegment::*value;
  const char* name;
  lmcal::Quantity quantity;
  bool zero_ok;
};
constexpr std::array<SegmentField, 7> kSegmentFields{{
    {&lmcal::DutySegment::duration_s, "duration_s", lmcal::Quantity::time, false},
    {&lmcal::DutySegment::velocity_m_s, "velocity_m_s", lmcal::Quantity::velocity, true},
    {&lmcal::DutySegment::load_N, "load_N", lmcal::Quantity::force, true},
    {&lmcal::DutySegment::stroke_m, "stroke_m", lmcal::Quantity::distance_m, false},
    {&lmcal::DutySegment::preload_um, "preload_um", lmcal::Quantity::preload, true},
    {&lmcal::DutySegment::block_length_mm, "block_length_mm", lmcal::Quantity::length_mm, false},
    {&lmcal::DutySegment::viscosity40_mm2_s, "viscosity40_mm2_s", lmcal::Quantity::viscosity, false},
}};

void check_segment(const lmcal::DutySegment& s, double rail_length_m) {
  for (const auto& [value, name, quantity, zero_ok] : kSegmentFields) {
    const double v = s.*value;
    const std::string field = fmt::format("{} {}", io::printable(s.name), name);
    finite(v, field);
    in_range({v}, field, lmcal::physical_range(quantity));
    if (v < 0 || (v == 0 && !zero_ok)) finding(fmt::format("{} = {} got past the loader", field, v));
  }
  if (s.velocity_m_s > 0 && s.stroke_m > rail_length_m)  // an idle segment's stroke moves nothing
    finding(fmt::format("{} stroke_m = {} on a {} m rail got past the loader", io::printable(s.name), s.stroke_m, rail_length_m));
  printable_names({s.name}, "segment name");
}

void on_rail(const std::vector<double>& positions, double rail_length_m, std::string_view what) {
  finite(positions, what);
  if (positions.size() > lmcal::io::kMaxDutyPositions) finding(fmt::format("{} positions in {}", positions.size(), what));
  for (const double x : positions)
    if (std::abs(x) > 0.5 * rail_length_m + 1e-9) finding(fmt::format("{} = {} off a {} m rail got past the loader", what, x, rail_length_m));
}

void check_loaded(const lmcal::DutyCycle& d) {
  lmcal::fuzz::check_loaded(d.guide);
  finite(d.rail_length_m, "rail_length_m");
  in_range({d.rail_length_m}, "rail_length_m", lmcal::physical_range(lmcal::Quantity::distance_m));
  if (!(d.rail_length_m > 0)) finding(fmt::format("rail_length_m = {} got past the loader", d.rail_length_m));
  if (d.ambient.time_s.empty() || d.ambient.time_s.size() != d.ambient.temperature_C.size())
    finding("an ambient trace without points, or of times and temperatures of different lengths");
  if (d.ambient.time_s.size() > lmcal::io::kMaxAmbientTracePoints) finding(fmt::format("{} ambient points", d.ambient.time_s.size()));
  finite(d.ambient.time_s, "ambient_trace time");
  finite(d.ambient.temperature_C, "ambient temperature_C");
  in_range(d.ambient.temperature_C, "ambient temperature_C", lmcal::physical_range(lmcal::Quantity::temperature));
  finite(d.initial_C, "initial_C");
  if (d.initial_C) in_range({*d.initial_C}, "initial_C", lmcal::physical_range(lmcal::Quantity::temperature));
  finite(d.output_every_s, "output_every_s");
  if (!(d.output_every_s > 0)) finding(fmt::format("output_every_s = {} got past the loader", d.output_every_s));
  on_rail(d.positions_m, d.rail_length_m, "positions_m");
  on_rail(d.scale.positions_m, d.rail_length_m, "[scale] positions_m");
  on_rail({d.scale.from_m, d.scale.to_m}, d.rail_length_m, "[scale] from_m, to_m");
  finite(d.scale.expansion_per_K, "[scale] expansion_per_K");

  // Sizes: the segments after the repeats, the duration and the outputs it makes.
  if (d.segments.empty() || d.segments.size() > lmcal::io::kMaxDutySegments)
    finding(fmt::format("a duty of {} segments got past the loader", d.segments.size()));
  for (const lmcal::DutySegment& s : d.segments) check_segment(s, d.rail_length_m);
  const double duration = d.duration_s();
  if (!(duration <= 1e7)) finding(fmt::format("a duty of {} s got past the loader", duration));
  if (!(duration / d.output_every_s <= static_cast<double>(lmcal::io::kMaxDutyOutputs)))
    finding(fmt::format("a duty of {} outputs got past the loader", duration / d.output_every_s));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  copy_companions();
  const fs::path file = write_file("duty.toml", as_text(data, size));
  const auto duty = loaded_or_refused([&] { return lmcal::load_duty_cycle(file); }, {file}, true);
  if (!duty) return 0;
  check_loaded(*duty);
  return 0;
}
