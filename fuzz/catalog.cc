// parse_catalog on fuzzed TOML: refused with an InputError at a line of the text, or every
// guide and bar loaded with finite values and found by its own name (no two entries share a
// name up to case and spaces). The catalog has no writer, so no round trip.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace lmcal::fuzz;
  const std::string source = "fuzz_catalog.toml";
  const auto catalog =
      loaded_or_refused([&] { return lmcal::parse_catalog(as_text(data, size), source); }, {source}, true);
  if (!catalog) return 0;
  for (const lmcal::GuideSpec& spec : catalog->guides) {
    check_loaded(spec);
    const lmcal::GuideSpec* found = nullptr;
    try {
      found = &catalog->find(spec.model);
    } catch (const std::exception& e) {
      finding(fmt::format("catalog entry '{}' is not found by its name: {}", spec.model, e.what()));
    }
    if (found != &spec) finding(fmt::format("catalog entries '{}' and '{}' share a name", found->model, spec.model));
  }
  return 0;
}
