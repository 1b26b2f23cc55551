// Reference kernels: fixed work whose cost tracks the machine, not lmcal. bench/guard divides
// every headline benchmark by them (timed in the same process, interleaved), so that a ratio
// moves when lmcal's code does and stays put when the machine is slower, busier or different.
//   BM_Reference_Thomas      a 500-node tridiagonal system (a rail's implicit step) solved
//                            1,440 times, each solve's answer the next right-hand side:
//                            serial floating-point latency (a division per node), data in L1.
//   BM_Reference_MemoryPass  y = 0.5 y + x over two 8 MB arrays (1 M doubles each): streaming
//                            loads and stores beyond the 2 MB L2, inside L3, where a 100 k-sample
//                            log lives. (Two 32 MB arrays straddled this machine's L3 share and
//                            varied by 12-28 % between repetitions; 8 MB: 4 %.)
// The code never changes with lmcal (a change here resets every ratio: update the baseline).
// Linked into lmcal_reference_bench on its own and into each benchmark binary the guard runs.
#include <benchmark/benchmark.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace {

// Thomas algorithm on the 1D heat equation's implicit operator (-r, 1 + 2r, -r), insulated ends.
void BM_Reference_Thomas(benchmark::State& state) {
  constexpr std::size_t kNodes = 500;
  constexpr int kSteps = 1440;
  constexpr double r = 0.8;
  std::vector<double> lower(kNodes, -r), diag(kNodes, 1 + 2 * r), upper(kNodes, -r);
  upper[0] = -2 * r;
  lower[kNodes - 1] = -2 * r;
  std::vector<double> c(kNodes), d(kNodes), x(kNodes);
  for (auto _ : state) {
    for (std::size_t i = 0; i < kNodes; ++i) x[i] = 20.0 + 0.01 * static_cast<double>(i);
    for (int step = 0; step < kSteps; ++step) {
      x[kNodes / 2] += 0.05;  // a heat input, so that the answer does not settle to a constant
      c[0] = upper[0] / diag[0];
      d[0] = x[0] / diag[0];
      for (std::size_t i = 1; i < kNodes; ++i) {
        const double m = 1.0 / (diag[i] - lower[i] * c[i - 1]);
        c[i] = upper[i] * m;
        d[i] = (x[i] - lower[i] * d[i - 1]) * m;
      }
      x[kNodes - 1] = d[kNodes - 1];
      for (std::size_t i = kNodes - 1; i-- > 0;) x[i] = d[i] - c[i] * x[i + 1];
    }
    benchmark::DoNotOptimize(x.data());
    benchmark::ClobberMemory();
  }
  state.counters["node_steps"] =
      benchmark::Counter(double(kNodes) * kSteps, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Reference_Thomas)->Unit(benchmark::kMillisecond)->MinTime(0.2);

void BM_Reference_MemoryPass(benchmark::State& state) {
  constexpr std::size_t kDoubles = std::size_t{1} << 20;  // 8 MB per array
  std::vector<double> x(kDoubles, 1.0), y(kDoubles, 2.0);
  for (auto _ : state) {
    double* __restrict yp = y.data();
    const double* __restrict xp = x.data();
    for (std::size_t i = 0; i < kDoubles; ++i) yp[i] = 0.5 * yp[i] + xp[i];
    benchmark::DoNotOptimize(y.data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(3 * kDoubles * sizeof(double)));
}
BENCHMARK(BM_Reference_MemoryPass)->Unit(benchmark::kMillisecond)->MinTime(0.2);

}  // namespace
