// lmcal predict on the bundled calibrated model (coupling, forced convection): the 24 h duty of
// examples/duty/two_shifts.toml (two 4 h shifts, a break, the night; outputs every minute)
// with 200 parameter draws for the bands. Target: under 1 s.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "lmcal/fit/model_file.hpp"
#include "lmcal/predict/prediction.hpp"

namespace {

void BM_Predict24hDuty200Draws(benchmark::State& state) {
  const std::filesystem::path source(LMCAL_SOURCE_DIR);
  const lmcal::ModelFile model = lmcal::read_model_file(source / "fits/cheng2017/model.toml");
  const lmcal::DutyCycle duty = lmcal::load_duty_cycle(source / "examples/duty/two_shifts.toml");
  for (auto _ : state) {
    const lmcal::Prediction p = lmcal::predict(model, duty, {.samples = 200});
    benchmark::DoNotOptimize(p.elongation_um.high.back());
  }
  state.counters["outputs"] = static_cast<double>(duty.duration_s() / duty.output_every_s);
}
BENCHMARK(BM_Predict24hDuty200Draws)->Unit(benchmark::kMillisecond)->MinTime(3.0);

}  // namespace
