// Rail solver speed targets (issue 2):
//   paper resolution, 6 h               well under 1 ms
//   500 nodes x 4,320 steps (5 s), 6 h  under 10 ms
//   moving, 1 mm cells, 0.5 s, 6 h      under 0.2 s
#include <benchmark/benchmark.h>

#include "lmcal/models/rail_thermal.hpp"
#include "support/srn35c.hpp"

namespace {

using namespace lmcal;

void run(benchmark::State& state, SourceModel source, TimeScheme scheme, int segments, double dt) {
  const auto g = test::srn35c_geometry(0.11);
  const auto p = test::srn35c_params();
  const RailNumerics n{.source = source, .scheme = scheme, .half_rail_segments = segments, .time_step_s = dt};
  RailOutputs out{.duration_s = 21600, .sensor_positions_m = {0.0, 0.05, 0.1}};
  for (double t = 0; t <= 21600; t += 600) out.output_times_s.push_back(t);
  const auto ambient = AmbientTrace::constant(26.0);
  for (auto _ : state) {
    auto sol = simulate_rail(g, n, out, p, ambient);
    benchmark::DoNotOptimize(sol.sensor_temperature_C.data());
  }
  state.counters["node_steps"] = benchmark::Counter(
      double(source == SourceModel::moving ? 2 * segments + 1 : segments + 1) * (21600 / dt),
      benchmark::Counter::kIsIterationInvariantRate);
}

// Four runs at once in SIMD lanes (simulate_rails): 500 nodes x 4,320 steps each; the rate
// counts run-node-steps.
void BM_FourRunsInLanes_500Nodes_5s(benchmark::State& state) {
  const auto g = test::srn35c_geometry(0.11);
  const RailNumerics n{.source = SourceModel::averaged, .scheme = TimeScheme::crank_nicolson, .half_rail_segments = 499,
                       .time_step_s = 5};
  RailOutputs out{.duration_s = 21600, .sensor_positions_m = {0.0, 0.05, 0.1}};
  for (double t = 0; t <= 21600; t += 600) out.output_times_s.push_back(t);
  std::vector<RailParams<double>> params(4, test::srn35c_params());
  for (int r = 0; r < 4; ++r) params[r].heat_rate_W *= 1.0 + 0.1 * r;
  const std::vector<AmbientTrace> ambients(4, AmbientTrace::constant(26.0));
  for (auto _ : state) {
    auto sols = simulate_rails(g, n, out, params, ambients);
    benchmark::DoNotOptimize(sols.front().sensor_temperature_C.data());
  }
  state.counters["run_node_steps"] =
      benchmark::Counter(4.0 * 500 * (21600 / 5), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_FourRunsInLanes_500Nodes_5s)->Unit(benchmark::kMillisecond);

void BM_PaperResolution(benchmark::State& s) { run(s, SourceModel::paper, TimeScheme::backward_euler, 50, 600); }
void BM_500Nodes_5s(benchmark::State& s) { run(s, SourceModel::averaged, TimeScheme::crank_nicolson, 499, 5); }
void BM_Moving_1mm_0p5s(benchmark::State& s) { run(s, SourceModel::moving, TimeScheme::crank_nicolson, 300, 0.5); }

BENCHMARK(BM_PaperResolution)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_500Nodes_5s)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Moving_1mm_0p5s)->Unit(benchmark::kMillisecond);

}  // namespace
