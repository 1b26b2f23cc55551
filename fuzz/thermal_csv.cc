// load_thermal_trace on fuzzed CSV: refused with an InputError at a line of the file, or loaded
// finite (NaN only as a missing temperature) and written back (thermal_trace_csv) to the same trace.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace lmcal::fuzz;
  const fs::path file = write_file("thermal.csv", as_text(data, size));
  const auto trace = loaded_or_refused([&] { return lmcal::load_thermal_trace(file); }, {file}, true);
  if (!trace) return 0;
  check_loaded(*trace);
  const fs::path again = write_file("roundtrip.csv", lmcal::thermal_trace_csv(*trace));
  expect_same(*trace, reloaded([&] { return lmcal::load_thermal_trace(again); }, "thermal_trace_csv"));
  return 0;
}
