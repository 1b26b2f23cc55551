// load_thermal_dataset on a fuzzed thermal manifest (TOML) beside fixed companion files
// (fuzz/companions: traces with and without ambient columns, in K and minutes, with a logged
// heat rate, and a user catalog): refused with an InputError at a line of the manifest or of a
// file it names, or loaded finite and written back (thermal_manifest_toml) to the same runs.
#include "fuzz_support.hpp"

namespace {

using namespace lmcal::fuzz;

void check_loaded(const lmcal::ThermalRun& run) {
  finite(run.velocity_m_s, "velocity_m_s");
  finite(run.load_N, "load_N");
  finite(run.preload_um, "preload_um");
  finite(run.stroke_m, "stroke_m");
  finite(run.rail_length_m, "rail_length_m");
  finite(run.contact_length_mm, "contact_length_mm");
  finite(run.block_length_mm, "block_length_mm");
  finite(run.mean_friction_N, "mean_friction_N");
  finite(run.mean_friction_uncertainty_N, "mean_friction_uncertainty_N");
  finite(run.start_friction_N, "start_friction_N");
  finite(run.heat_rate_W, "heat_rate_W");
  finite(run.heat_rate_uncertainty_W, "heat_rate_uncertainty_W");
  finite(run.ambient_C, "ambient_C");
  finite(run.h_W_m2K, "h_W_m2K");
  finite(run.viscosity40_mm2_s, "viscosity40_mm2_s");
  finite(run.sensor_position_m, "sensors_m");
  finite(run.guide_overrides, "guide_overrides");
  for (const lmcal::ThermalPhase& phase : run.schedule) {
    finite(phase.from_s, "schedule.from_s");
    finite(phase.velocity_m_s, "schedule.velocity_m_s");
    finite(phase.heat_rate_W, "schedule.heat_rate_W");
  }
  lmcal::fuzz::check_loaded(run.guide_spec);
  lmcal::fuzz::check_loaded(run.trace);
}

void expect_same(const std::optional<double>& a, const std::optional<double>& b, std::string_view what) {
  lmcal::fuzz::expect_same(a.has_value() == b.has_value() && (!a || same(*a, *b)), what, 0);
}

void expect_same(const lmcal::ThermalRun& a, const lmcal::ThermalRun& b) {
  using lmcal::fuzz::expect_same;
  expect_same(a.id == b.id && a.guide == b.guide, "id or guide", 0);
  expect_same(fs::weakly_canonical(a.file) == fs::weakly_canonical(b.file), "file", 0);
  expect_same(same(a.velocity_m_s, b.velocity_m_s), "velocity_m_s", 0);
  expect_same(same(a.load_N, b.load_N), "load_N", 0);
  expect_same(same(a.stroke_m, b.stroke_m), "stroke_m", 0);
  expect_same(same(a.rail_length_m, b.rail_length_m), "rail_length_m", 0);
  ::expect_same(a.preload_um, b.preload_um, "preload_um");
  ::expect_same(a.contact_length_mm, b.contact_length_mm, "contact_length_mm");
  ::expect_same(a.block_length_mm, b.block_length_mm, "block_length_mm");
  ::expect_same(a.mean_friction_N, b.mean_friction_N, "mean_friction_N");
  ::expect_same(a.mean_friction_uncertainty_N, b.mean_friction_uncertainty_N, "mean_friction_uncertainty_N");
  ::expect_same(a.start_friction_N, b.start_friction_N, "start_friction_N");
  ::expect_same(a.heat_rate_W, b.heat_rate_W, "heat_rate_W");
  ::expect_same(a.heat_rate_uncertainty_W, b.heat_rate_uncertainty_W, "heat_rate_uncertainty_W");
  ::expect_same(a.ambient_C, b.ambient_C, "ambient_C");
  ::expect_same(a.h_W_m2K, b.h_W_m2K, "h_W_m2K");
  ::expect_same(a.viscosity40_mm2_s, b.viscosity40_mm2_s, "viscosity40_mm2_s");
  expect_same(a.sensor_position_m == b.sensor_position_m, "sensors_m", 0);
  expect_same(a.guide_overrides == b.guide_overrides, "guide_overrides", 0);
  expect_same(a.schedule.size() == b.schedule.size(), "the schedule's length", a.schedule.size());
  for (std::size_t i = 0; i < a.schedule.size(); ++i) {
    expect_same(same(a.schedule[i].from_s, b.schedule[i].from_s), "schedule.from_s", i);
    ::expect_same(a.schedule[i].velocity_m_s, b.schedule[i].velocity_m_s, "schedule.velocity_m_s");
    ::expect_same(a.schedule[i].heat_rate_W, b.schedule[i].heat_rate_W, "schedule.heat_rate_W");
  }
  for (const std::string& field : lmcal::guide_field_names())
    ::expect_same(lmcal::field_value(a.guide_spec, field), lmcal::field_value(b.guide_spec, field), field);
  expect_same(a.trace, b.trace);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  copy_companions();
  const fs::path manifest = write_file("thermal.toml", as_text(data, size));
  const auto set = loaded_or_refused([&] { return lmcal::load_thermal_dataset(manifest); }, {manifest}, true);
  if (!set) return 0;
  for (const lmcal::ThermalRun& run : set->runs) check_loaded(run);
  const fs::path again = write_file("roundtrip.toml", lmcal::thermal_manifest_toml(*set, work_dir()));
  const auto back = reloaded([&] { return lmcal::load_thermal_dataset(again); }, "thermal_manifest_toml");
  lmcal::fuzz::expect_same(back.name == set->name && back.description == set->description, "name or description", 0);
  lmcal::fuzz::expect_same(back.runs.size() == set->runs.size(), "the run count", set->runs.size());
  for (std::size_t i = 0; i < set->runs.size(); ++i) expect_same(set->runs[i], back.runs[i]);
  return 0;
}
