// Friction fit speed target (issue 4): 100 k samples, all seven constants, multi-start
// and covariance included, under 0.15 s on one core (numpy/scipy least_squares: ~0.3 s).
#include <benchmark/benchmark.h>

#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/rig/virtual_rig.hpp"

namespace {

using namespace lmcal;

FrictionLog hundred_thousand_samples() {
  FrictionRigConfig rig;  // 3 guides x 3 preloads x 3 loads x 10 speeds x 4 temperatures x 2 directions
  rig.runs = 47;          // ~2150 samples per run
  rig.run_offset_N = 0;
  return generate_friction_log(rig, {}).log;
}

void BM_FrictionFit100k(benchmark::State& state) {
  static const FrictionLog log = hundred_thousand_samples();
  FrictionFitOptions options;
  options.per_run_fits = false;
  for (auto _ : state) {
    const auto result = fit_friction(log, options);
    benchmark::DoNotOptimize(result.fit.parameters.data());
    if (!result.fit.solver.covariance_ok) state.SkipWithError("covariance failed");
  }
  state.counters["samples"] = static_cast<double>(log.size());
  state.counters["starts"] = options.fit.starts;
}

BENCHMARK(BM_FrictionFit100k)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
