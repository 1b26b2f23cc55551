// load_friction_log on fuzzed CSV (a tidy log or a raw load-cell log): refused with an
// InputError at a line of the file, or loaded finite and written back (friction_log_csv) to
// the same samples.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace lmcal::fuzz;
  const fs::path file = write_file("friction.csv", as_text(data, size));
  const auto log = loaded_or_refused([&] { return lmcal::load_friction_log(file); }, {file}, true);
  if (!log) return 0;
  check_loaded(*log);
  check_round_trip(*log);
  return 0;
}
