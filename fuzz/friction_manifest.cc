// load_friction_dataset on a fuzzed friction manifest (TOML) beside fixed companion files
// (fuzz/companions: a tidy log with a run column, a run's own tidy file, a raw load-cell log, a
// user catalog): refused with an InputError at a line of the manifest or of a file it names, or
// loaded finite, the log written back (friction_log_csv) to the same samples. There is no
// friction manifest writer, so the log is the round trip.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace lmcal::fuzz;
  copy_companions();
  const fs::path manifest = write_file("friction.toml", as_text(data, size));
  const auto set = loaded_or_refused([&] { return lmcal::load_friction_dataset(manifest); }, {manifest}, true);
  if (!set) return 0;
  finite(set->raw.max_acceleration_m_s2, "raw.max_acceleration_m_s2");
  finite(set->raw.settling_s, "raw.settling_s");
  finite(set->raw.min_speed_m_s, "raw.min_speed_m_s");
  finite(set->raw.velocity_tolerance, "raw.velocity_tolerance");
  finite(set->raw.moving_mass_kg, "raw.moving_mass_kg");
  check_loaded(set->log);
  check_round_trip(set->log);
  return 0;
}
