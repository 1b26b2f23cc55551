// Fit speed targets. Friction (issue 4): 100 k samples, all seven constants, multi-start
// and covariance included, under 0.15 s on one core (numpy/scipy least_squares: ~0.3 s).
#include <benchmark/benchmark.h>

#include <time.h>

#include <cstdlib>

#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/diagnose/friction_diagnosis.hpp"
#include "lmcal/diagnose/thermal_diagnosis.hpp"
#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/rig/virtual_rig.hpp"

namespace {

using namespace lmcal;

FrictionLog hundred_thousand_samples() {
  FrictionRigConfig rig;  // 3 guides x 3 preloads x 3 loads x 10 speeds x 4 temperatures x 2 directions
  rig.runs = 47;          // ~2150 samples per run
  rig.run_offset_N = 0;
  return generate_friction_log(rig, {}).log;
}

// bench/guard's slowdown check (bench/README.md): LMCAL_BENCH_SLOWDOWN_MS=N makes every
// iteration of BM_FrictionFit100k, and nothing else, N ms slower. A busy wait on this thread's
// CPU clock, not a sleep: a slower fit costs CPU time, which is what the guard compares (a sleep
// would show in the wall time only).
double slowdown_ms() {
  static const double ms = [] {
    const char* text = std::getenv("LMCAL_BENCH_SLOWDOWN_MS");
    return text ? std::atof(text) : 0.0;
  }();
  return ms;
}

double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

void injected_slowdown() {
  if (slowdown_ms() <= 0) return;
  const double until = thread_cpu_s() + 1e-3 * slowdown_ms();
  while (thread_cpu_s() < until) {
  }
}

void BM_FrictionFit100k(benchmark::State& state) {
  static const FrictionLog log = hundred_thousand_samples();
  FrictionFitOptions options;
  options.per_run_fits = false;
  for (auto _ : state) {
    const auto result = fit_friction(log, options);
    benchmark::DoNotOptimize(result.fit.parameters.data());
    if (!result.fit.solver.covariance_ok) state.SkipWithError("covariance failed");
    injected_slowdown();
  }
  state.counters["samples"] = static_cast<double>(log.size());
  state.counters["starts"] = options.fit.starts;
  if (slowdown_ms() > 0) state.counters["slowdown_ms"] = slowdown_ms();
}

BENCHMARK(BM_FrictionFit100k)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// Issue 16's figures: the fit with its covariance and nothing else (no bootstrap, no
// profiles, no per-run fits; the multi-start kept), at 100 k and at 1 M samples (linear in
// the samples: normal equations accumulated row by row, no stored Jacobian in the polish).
void plain_fit(benchmark::State& state, const FrictionLog& log) {
  FrictionFitOptions options;
  options.per_run_fits = false;
  options.fit.bootstrap = 0;
  options.fit.profile = ProfileMode::none;
  for (auto _ : state) {
    const auto result = fit_friction(log, options);
    benchmark::DoNotOptimize(result.fit.parameters.data());
    if (!result.fit.solver.covariance_ok) state.SkipWithError("covariance failed");
  }
  state.counters["samples"] = static_cast<double>(log.size());
}

void BM_FrictionFit100kNoExtras(benchmark::State& state) {
  static const FrictionLog log = hundred_thousand_samples();
  plain_fit(state, log);
}
BENCHMARK(BM_FrictionFit100kNoExtras)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The plain fit the defaults are measured against (issue 39: the default, random run
// intercepts on block-mean temperatures, within 1.3x of it): no run offsets, the logged
// temperatures, otherwise BM_FrictionFit100kNoExtras.
void BM_FrictionFit100kPlain(benchmark::State& state) {
  static const FrictionLog log = hundred_thousand_samples();
  FrictionFitOptions options;
  options.per_run_fits = false;
  options.fit.bootstrap = 0;
  options.fit.profile = ProfileMode::none;
  options.run_offsets = RunOffsets::none;
  options.temperature = FrictionTemperature::logged;
  for (auto _ : state) {
    const auto result = fit_friction(log, options);
    benchmark::DoNotOptimize(result.fit.parameters.data());
    if (!result.fit.solver.covariance_ok) state.SkipWithError("covariance failed");
  }
  state.counters["samples"] = static_cast<double>(log.size());
}
BENCHMARK(BM_FrictionFit100kPlain)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// Writing a fit's samples CSV (100 k rows, 13 columns): the text, not the disk.
void BM_WriteFrictionSamplesCsv(benchmark::State& state) {
  static const FrictionLog log = hundred_thousand_samples();
  static const FrictionFitResult result = [] {
    FrictionFitOptions options;
    options.per_run_fits = false;
    options.fit.bootstrap = 0;
    return fit_friction(log, options);
  }();
  std::size_t bytes = 0;
  for (auto _ : state) {
    const std::string text = friction_fit_samples_csv(result, log);
    bytes = text.size();
    benchmark::DoNotOptimize(text.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(bytes));
}
BENCHMARK(BM_WriteFrictionSamplesCsv)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_FrictionFit1MNoExtras(benchmark::State& state) {
  static const FrictionLog log = [] {
    FrictionRigConfig rig;
    rig.runs = 470;  // ~2150 samples per run, 1 M in all
    rig.run_offset_N = 0;
    return generate_friction_log(rig, {}).log;
  }();
  plain_fit(state, log);
}
BENCHMARK(BM_FrictionFit1MNoExtras)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

namespace {

// Thermal fit speed target (issue 5): α for 4 runs of 6 h at 5 s resolution (500 nodes)
// under 0.2 s. Four speeds (the rig takes each once: a repeat was 0.11 twice, which the rig
// refuses since it checks its configuration).
lmcal::ThermalDataSet four_runs() {
  lmcal::ThermalRigConfig rig;
  rig.velocity_m_s = {0.066, 0.083, 0.11, 0.15};
  return lmcal::generate_thermal_dataset(rig, {}, "bench").set;
}

void alpha_fit(benchmark::State& state, bool extras) {
  static const lmcal::ThermalDataSet data = four_runs();
  lmcal::ThermalFitOptions options;
  options.half_rail_segments = 499;  // 500 nodes
  options.time_step_s = 5;
  options.per_run_fits = false;
  options.compare_sources = false;
  if (!extras) {  // the fit and its covariance: no bootstrap, no profile, no α error curve
    options.fit.bootstrap = 0;
    options.fit.profile = lmcal::ProfileMode::none;
    options.curve_points = 0;
  }
  for (auto _ : state) {
    const auto result = lmcal::fit_thermal(data, options);
    benchmark::DoNotOptimize(result.joint.parameters.data());
  }
  state.counters["records"] = static_cast<double>(data.runs[0].trace.size());
}

void BM_ThermalAlpha4Runs(benchmark::State& state) { alpha_fit(state, true); }
BENCHMARK(BM_ThermalAlpha4Runs)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_ThermalAlpha4RunsNoExtras(benchmark::State& state) { alpha_fit(state, false); }
BENCHMARK(BM_ThermalAlpha4RunsNoExtras)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace

namespace {

// A friction diagnosis with default options, timed; the log made once per benchmark.
void diagnose_friction_log(benchmark::State& state, const lmcal::FrictionLog& log) {
  for (auto _ : state) {
    const auto d = lmcal::diagnose_friction(log, {});
    benchmark::DoNotOptimize(d.accepted.data());
  }
  state.counters["samples"] = static_cast<double>(log.size());
  state.counters["runs"] = static_cast<double>(log.run_names.size());
}

lmcal::FrictionLog rig_log(const lmcal::FrictionRigConfig& rig, const char* effect, double value) {
  lmcal::RigEffects effects;
  lmcal::set_rig_effect(effects, effect, value);
  return lmcal::generate_friction_log(rig, effects).log;
}

// Friction diagnosis speed target (issue 6): 100 k samples, every candidate, held-out scoring,
// under 5 s.
void BM_FrictionDiagnosis100k(benchmark::State& state) {
  static const lmcal::FrictionLog log = [] {
    lmcal::FrictionRigConfig rig;
    rig.runs = 47;
    return rig_log(rig, "seal_drag", 60);
  }();
  diagnose_friction_log(state, log);
}

BENCHMARK(BM_FrictionDiagnosis100k)->Unit(benchmark::kMillisecond)->Iterations(2);

// A log from one setup per run (one load, one temperature each), 76 k samples: random run
// offsets, between-run tests and interactions must not make it take minutes (issue 13).
void BM_FrictionDiagnosisOneSetupPerRun76k(benchmark::State& state) {
  static const lmcal::FrictionLog log = [] {
    lmcal::FrictionRigConfig rig;
    rig.one_setup_per_run = true;
    rig.velocity_m_s = {0.002, 0.003, 0.005, 0.007, 0.01, 0.014, 0.02, 0.03, 0.04, 0.05, 0.066, 0.083, 0.1, 0.11, 0.13, 0.15};
    rig.runs = 22;  // 108 setups x 22 repeats x 16 speeds x 2 directions, less what is beyond the load cell
    return rig_log(rig, "coulomb_temperature", 0.05);
  }();
  diagnose_friction_log(state, log);
}

BENCHMARK(BM_FrictionDiagnosisOneSetupPerRun76k)->Unit(benchmark::kMillisecond)->Iterations(1);

// 100 k samples with an effect the library lacks (running-in over the sliding distance): every
// candidate, then the search beyond the library — the dictionary, the sparse regression and the
// joint fit of the term — under 5 s (issue 14).
void BM_FrictionDiagnosisEmpiricalTerm100k(benchmark::State& state) {
  static const lmcal::FrictionLog log = [] {
    lmcal::FrictionRigConfig rig;
    rig.runs = 47;
    lmcal::RigEffects effects;
    effects.hidden.running_in = 0.1;
    effects.hidden.running_in_scale_m = 2000;
    return lmcal::generate_friction_log(rig, effects).log;
  }();
  bool found = false;
  for (auto _ : state) {
    const auto d = lmcal::diagnose_friction(log, {});
    found = d.empirical.found;
    benchmark::DoNotOptimize(d.accepted.data());
  }
  state.counters["samples"] = static_cast<double>(log.size());
  state.counters["term_found"] = found ? 1 : 0;
}

BENCHMARK(BM_FrictionDiagnosisEmpiricalTerm100k)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

namespace {

// Thermal diagnosis speed target (issue 6): 4 runs of 6 h at a record every 5 s, with the
// bundled set's effects (coupling, forced convection, thermocouple lag, moving block), every
// candidate of the library, leave-one-run-out scoring, forward selection: under 10 s on 2 cores.
void BM_ThermalDiagnosis4Runs(benchmark::State& state) {
  static const lmcal::ThermalDataSet data = [] {
    lmcal::ThermalRigConfig rig;
    rig.velocity_m_s = {0.066, 0.083, 0.11, 0.15};
    lmcal::RigEffects effects;
    for (const auto& [name, value] :
         {std::pair{"coupling", 1.0}, {"convection_velocity", 6.0}, {"tc_lag", 30.0}, {"moving_source", 1.0}})
      lmcal::set_rig_effect(effects, name, value);
    return lmcal::generate_thermal_dataset(rig, effects, "bench").set;
  }();
  lmcal::ThermalDiagnosisOptions options;
  options.fit.heat = lmcal::HeatInput::friction_law;
  std::size_t causes = 0;
  for (auto _ : state) {
    const auto d = lmcal::diagnose_thermal(data, options);
    causes = d.accepted.size();
    benchmark::DoNotOptimize(d.accepted.data());
  }
  state.counters["runs"] = static_cast<double>(data.runs.size());
  state.counters["causes"] = static_cast<double>(causes);
}

BENCHMARK(BM_ThermalDiagnosis4Runs)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
