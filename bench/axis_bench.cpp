// Issue 37's speed target: a drive's own trajectory log of 10^6 samples at 1 kHz loads, filters
// and fits (moving mass + friction law + the weight along the axis, with covariance) in <= 1 s
// on the 2-core development machine.
//
// The log is the virtual rig's closed-loop axis (lmcal generate axis, rig/axis_rig.hpp), the
// bundled measurements/axis made 49 times longer: a 40 kg carriage on a 20 degree axis under
// the cascaded P-PI controller, trapezoidal moves at 0.005, 0.02, 0.05, 0.1 and 0.15 m/s
// (0.5 s cruise, 49 out-and-back cycles per speed), one run per load (1, 2, 3 kN): three
// files of 333,250 samples each, 999,750 in all (time_s, position_mm, force_N), generated
// once into a temporary folder with their friction manifest. Timed separately:
//   - BM_AxisLoadTrajectory1M: loading the three runs with segmentation = trajectory and the
//     axis incline (the filter's window chosen from the data, v, a and the force filtered, the
//     samples at rest, reversing and pre-sliding dropped); bytes/s of CSV text, samples/s;
//   - BM_AxisFitTrajectory1M: fit_friction on the loaded log (the law, moving_mass and
//     axis_gravity, covariance as the defaults compute it) with the defaults, and lean (one
//     start, no per-run fits); samples/s.
//   - BM_AxisDiagnoseTrajectory100k (issue 38's target, <= 2 s on 2 cores): diagnose_friction
//     with its defaults on the same axis logged for 6 cycles per speed instead of 49 (~10^5
//     samples), every library cause the log can show tried (the trajectory's: direction,
//     gravity, ripple, pre-sliding, ...), the residual tests along the travel, the empirical term
//     when structure remains.
// Run: build/bench/lmcal_axis_bench
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>
#include <vector>

#include "lmcal/diagnose/friction_diagnosis.hpp"
#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/rig/axis_rig.hpp"
#include "scratch_dir.hpp"

namespace {

namespace fs = std::filesystem;
using namespace lmcal;

struct AxisLog {
  fs::path manifest;
  std::vector<fs::path> files;
  std::int64_t bytes = 0;
};

AxisLog write_axis_log(const fs::path& folder, int cycles) {
  const FrictionRigConfig setup = bundled_axis_setup(2027);
  AxisRigConfig axis;
  axis.incline_deg = 20;
  axis.cruise_s = 0.5;
  axis.cycles = cycles;
  const AxisRigOutput made = generate_axis_logs(setup, axis, {});
  AxisLog out;
  fs::create_directories(folder / "friction");
  for (const auto& [name, text] : made.run_files) {
    out.files.push_back(folder / name);
    bench::write(out.files.back(), text);
    out.bytes += static_cast<std::int64_t>(text.size());
  }
  out.manifest = folder / "friction.toml";
  bench::write(out.manifest, made.manifest_toml);
  return out;
}

const AxisLog& axis_log() {
  static const bench::ScratchDir dir("lmcal_axis_bench");
  static const AxisLog log = write_axis_log(dir.path(), 49);
  return log;
}

// The reader's options as `lmcal fit friction --segmentation trajectory --axis-incline 20`
// gives them (the manifest's [raw] says the same).
FrictionDataSet load_axis_log(const AxisLog& files = axis_log()) {
  RawFrictionOptions raw;
  raw.segmentation = RawSegmentation::trajectory;
  raw.axis_incline_deg = 20;
  return load_friction_dataset(files.manifest, nullptr, raw, {"segmentation", "axis_incline_deg"});
}

void BM_AxisLoadTrajectory1M(benchmark::State& state) {
  const AxisLog& files = axis_log();
  std::size_t samples = 0;
  for (auto _ : state) {
    const FrictionDataSet set = load_axis_log();
    benchmark::DoNotOptimize(set.log.friction_N.data());
    samples = 0;
    for (const RunSegmentation& s : set.log.segmentation) samples += s.samples;
  }
  state.SetBytesProcessed(state.iterations() * files.bytes);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(samples));
  const FrictionLog log = load_axis_log().log;
  state.counters["rows"] = static_cast<double>(samples);
  state.counters["kept"] = static_cast<double>(log.size());
  state.counters["window"] = static_cast<double>(log.segmentation.at(0).filter_window);
  state.counters["file_MB"] = static_cast<double>(files.bytes) / 1e6;
}
BENCHMARK(BM_AxisLoadTrajectory1M)->Unit(benchmark::kMillisecond)->MinTime(3.0);

void BM_AxisFitTrajectory1M(benchmark::State& state, FrictionFitOptions options) {
  static const FrictionLog log = load_axis_log().log;
  for (auto _ : state) {
    const FrictionFitResult result = fit_friction(log, options);
    benchmark::DoNotOptimize(result.fit.parameters.data());
    if (!result.fit.solver.covariance_ok) state.SkipWithError("covariance failed");
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(log.size()));
  state.counters["samples"] = static_cast<double>(log.size());
  state.counters["starts"] = options.fit.starts;
}

FrictionFitOptions lean() {
  FrictionFitOptions options;
  options.fit.starts = 1;
  options.per_run_fits = false;
  return options;
}

BENCHMARK_CAPTURE(BM_AxisFitTrajectory1M, defaults, FrictionFitOptions{})->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK_CAPTURE(BM_AxisFitTrajectory1M, lean, lean())->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_AxisDiagnoseTrajectory100k(benchmark::State& state) {
  static const bench::ScratchDir dir("lmcal_axis_bench_100k");
  static const FrictionLog log = load_axis_log(write_axis_log(dir.path(), 6)).log;
  std::size_t tried = 0, accepted = 0;
  for (auto _ : state) {
    const FrictionDiagnosis d = diagnose_friction(log, {});
    benchmark::DoNotOptimize(d.cv_rmse_after_N);
    tried = d.rounds.empty() ? 0 : d.rounds.front().size();
    accepted = d.accepted.size();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(log.size()));
  state.counters["samples"] = static_cast<double>(log.size());
  state.counters["candidates"] = static_cast<double>(tried);
  state.counters["accepted"] = static_cast<double>(accepted);
}
BENCHMARK(BM_AxisDiagnoseTrajectory100k)->Unit(benchmark::kMillisecond)->Iterations(2)->UseRealTime();

}  // namespace
