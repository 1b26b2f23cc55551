// lmcal predict on the bundled calibrated model (coupling, forced convection): the 24 h duty of
// examples/duty/two_shifts.toml (two 4 h shifts, a break, the night; outputs every minute)
// with 200 parameter draws for the bands. Target: under 1 s. And lmcal plan friction.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "lmcal/fit/model_file.hpp"
#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/predict/plan.hpp"
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

namespace {

// lmcal plan friction over a 1,000-condition grid (10 speeds × 5 loads × 4 preloads × 5
// temperatures) for the bundled log (21.5 k samples), 5 conditions: the design alone (the fit
// before it is the friction fit's benchmark). Target: under 2 s.
void BM_PlanFriction1000Conditions(benchmark::State& state) {
  const std::filesystem::path source(LMCAL_SOURCE_DIR);
  lmcal::FrictionLog log = lmcal::load_friction_log(source / "measurements/cheng2017/friction.csv");
  // One guide: the grid's 1,000 conditions are speeds × loads × preloads × temperatures.
  lmcal::FrictionLog one;
  one.run_names = log.run_names;
  one.guide_names = {log.guide_names[log.guide[0]]};
  for (std::size_t i = 0; i < log.size(); ++i)
    if (log.guide[i] == log.guide[0])
      one.append(log.run[i], 0, log.time_s[i], log.conditions(i), log.friction_N[i], log.viscosity40_mm2_s[i]);
  lmcal::FrictionFitOptions options;
  options.per_run_fits = false;
  options.fit.bootstrap = 0;
  const lmcal::FrictionFitResult fit = lmcal::fit_friction(one, options);
  const auto candidates = lmcal::friction_candidates(
      one, {.velocity_m_s = {0.002, 0.005, 0.01, 0.02, 0.03, 0.05, 0.066, 0.083, 0.11, 0.15},
            .load_N = {500, 1000, 2000, 3000, 4000},
            .preload_um = {1.5, 2.5, 4.0, 6.0},
            .temperature_C = {20, 25, 30, 35, 40},
            .directions = {1}});
  for (auto _ : state) {
    const lmcal::FrictionPlan plan = lmcal::plan_friction(one, fit, candidates, {.conditions = 5});
    benchmark::DoNotOptimize(plan.picks.back().gain);
  }
  state.counters["candidates"] = static_cast<double>(candidates.size());
  state.counters["samples"] = static_cast<double>(one.size());
}
BENCHMARK(BM_PlanFriction1000Conditions)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
