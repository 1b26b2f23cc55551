// lmcal fleet's summary of 10,000 sets (2,500 units on 4 dates each, 8 constants with SEs):
// parsing the records, the populations and their outliers, 20,000 drift tests, fleet.json,
// fleet.csv and fleet.html. Target: under 5 s. (The calibrations themselves are measured by
// bench/fleet_scaling.sh.)
#include <benchmark/benchmark.h>

#include <fmt/format.h>

#include <random>

#include "lmcal/fleet/fleet_summary.hpp"

namespace {

void BM_FleetSummary10000Sets(benchmark::State& state) {
  const std::size_t units = 2500, dates = 4;
  lmcal::Fleet fleet{.root = "plant", .source = "folders"};
  std::vector<std::string> records;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> z;  // benchmark data only: any normal will do
  const std::vector<std::pair<std::string, double>> constants = {
      {"k1", 0.32}, {"k2", 0.031}, {"mu_st", 1.52}, {"v_st_m_s", 0.015}, {"mu_v", 0.003}, {"beta_per_K", 0.067}, {"f0", 0.026}};
  for (std::size_t u = 0; u < units; ++u) {
    for (std::size_t d = 0; d < dates; ++d) {
      lmcal::FleetSet s{.id = fmt::format("u{:04}/2026-09-{:02}", u, 1 + 7 * d), .unit = fmt::format("u{:04}", u),
                        .date = fmt::format("2026-09-{:02}", 1 + 7 * d)};
      lmcal::FleetRecord r{.id = s.id, .unit = s.unit, .date = s.date, .lmcal_version = LMCAL_VERSION};
      for (const auto& [name, value] : constants) {
        const double v = value * (1 + 0.05 * z(rng)), se = 0.01 * value;
        r.parameters.push_back({.model = "friction", .name = name, .unit = "1", .value = v, .se = se,
                                .low = v - 2 * se, .high = v + 2 * se, .interval = "linear"});
      }
      r.parameters.push_back({.model = "thermal", .name = "alpha", .unit = "1", .value = 0.6 + 0.03 * z(rng), .se = 0.01,
                              .low = 0.58, .high = 0.62, .interval = "linear"});
      records.push_back(lmcal::fleet_record_json(r));
      fleet.sets.push_back(std::move(s));
    }
  }
  for (auto _ : state) {
    const lmcal::FleetSummary summary = lmcal::summarize_fleet(fleet, records);
    const auto outputs = lmcal::fleet_summary_outputs(summary);
    benchmark::DoNotOptimize(outputs.back().second.size());
  }
  state.counters["sets"] = static_cast<double>(records.size());
}
BENCHMARK(BM_FleetSummary10000Sets)->Unit(benchmark::kMillisecond)->MinTime(3.0);

}  // namespace
