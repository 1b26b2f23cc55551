// Loading speed of the CSV readers on files the size real rigs produce:
//   - a 6 h thermal log at 50 Hz: 1.08 M rows x 6 columns (time_s, ambient1_C, ambient2_C,
//     tc1_C, tc2_C, tc3_C), numbers as "%.3f", ~55 MB;
//   - a friction log of 1 M samples with all eleven columns;
//   - a raw load-cell run of 1 M samples at 1 kHz (time_s, position_mm, force_N; its conditions
//     in a friction manifest), from the virtual rig: loading includes deriving v and a and
//     cutting the run into plateaus. Target: >= 150 MB/s;
//   - user guide catalogs of 10^3 to 10^5 guides (the limit): linear, 10^5 in under 2 s;
//   - `lmcal check friction` of the 1 M-row friction log as a process (start-up, loading and
//     the report), on 1 and 2 threads (OMP_NUM_THREADS). Target (issue 39): >= 300 MB/s;
//   - `lmcal fit friction` of a 100 k-sample log as a process, with the defaults. Target (issue
//     39): <= 0.2 s on 2 threads.
// The files are generated once into a temporary folder (removed at exit). Throughput is
// reported as bytes/s of CSV text. Target: >= 200 MB/s for the thermal log.
// Run: build/bench/lmcal_io_bench
#include <benchmark/benchmark.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <string>
#include <vector>

#include "lmcal/io/catalog.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/io/thermal_run.hpp"
#include "lmcal/rig/virtual_rig.hpp"
#include "scratch_dir.hpp"

namespace {

namespace fs = std::filesystem;
using lmcal::bench::write;

// A folder that lives as long as the benchmark binary.
const lmcal::bench::ScratchDir& scratch() {
  static const lmcal::bench::ScratchDir dir("lmcal_io_bench");
  return dir;
}

// Rail warming towards a plateau with a slow ambient drift and a little noise, like the
// paper's logger records.
const fs::path& thermal_log() {
  static const fs::path file = [] {
    constexpr int kRows = 6 * 3600 * 50;  // 6 h at 50 Hz
    std::string text = "# synthetic 6 h log at 50 Hz (io_bench)\ntime_s,ambient1_C,ambient2_C,tc1_C,tc2_C,tc3_C\n";
    text.reserve(56u << 20);
    char line[128];
    unsigned noise = 12345;
    const auto jitter = [&] {
      noise = noise * 1103515245u + 12345u;
      return static_cast<double>((noise >> 16) & 0x3ff) / 1024.0 * 0.02 - 0.01;
    };
    for (int i = 0; i < kRows; ++i) {
      const double t = i * 0.02;
      const double ambient = 24.0 + 0.5 * std::sin(t / 7200.0);
      const double rise = 1.0 - std::exp(-t / 4320.0);  // 72 min time constant (PHYSICS.md §4)
      const int n = std::snprintf(line, sizeof line, "%.3f,%.3f,%.3f,%.3f,%.3f,%.3f\n", t, ambient + jitter(),
                                  ambient + 0.1 + jitter(), ambient + 6.0 * rise + jitter(),
                                  ambient + 4.0 * rise + jitter(), ambient + 2.5 * rise + jitter());
      text.append(line, static_cast<std::size_t>(n));
    }
    const fs::path path = scratch().path() / "thermal_6h_50hz.csv";
    write(path, text);
    return path;
  }();
  return file;
}

const fs::path& friction_log() {
  static const fs::path file = [] {
    constexpr int kRows = 1000000;
    std::string text =
        "run,guide,time_s,velocity_m_s,load_N,preload_um,block_length_mm,temperature_C,friction_N,"
        "viscosity40_mm2_s,direction\n";
    char line[192];
    const double speeds[] = {0.066, 0.083, 0.11};
    for (int i = 0; i < kRows; ++i) {
      const int run = i / (kRows / 3);
      const double t = (i % (kRows / 3)) * 0.02;
      const double temperature = 26.0 + 8.0 * (1.0 - std::exp(-t / 4320.0));
      const int n =
          std::snprintf(line, sizeof line, "v%d,SRN 35C,%.3f,%.3f,3000,4,120.2,%.3f,%.3f,99,%d\n", run, t,
                        speeds[run % 3], temperature, 28.0 + 8.0 * run + 0.1 * std::sin(t), (i / 500) % 2 ? -1 : 1);
      text.append(line, static_cast<std::size_t>(n));
    }
    const fs::path path = scratch().path() / "friction_1m.csv";
    write(path, text);
    return path;
  }();
  return file;
}

void BM_LoadThermalTrace(benchmark::State& state) {
  const fs::path& file = thermal_log();
  for (auto _ : state) {
    lmcal::ThermalTrace trace = lmcal::load_thermal_trace(file);
    benchmark::DoNotOptimize(trace.time_s.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(fs::file_size(file)));
  state.counters["rows"] = static_cast<double>(lmcal::load_thermal_trace(file).size());
  state.counters["file_MB"] = static_cast<double>(fs::file_size(file)) / 1e6;
}
BENCHMARK(BM_LoadThermalTrace)->Unit(benchmark::kMillisecond)->MinTime(3.0);

void BM_LoadFrictionLog(benchmark::State& state) {
  const fs::path& file = friction_log();
  for (auto _ : state) {
    lmcal::FrictionLog log = lmcal::load_friction_log(file);
    benchmark::DoNotOptimize(log.friction_N.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(fs::file_size(file)));
  state.counters["rows"] = static_cast<double>(lmcal::load_friction_log(file).size());
  state.counters["file_MB"] = static_cast<double>(fs::file_size(file)) / 1e6;
}
BENCHMARK(BM_LoadFrictionLog)->Unit(benchmark::kMillisecond)->MinTime(3.0);

// The lmcal executable `argv` names run with OMP_NUM_THREADS=threads, its output discarded:
// its exit status, or -1 when it could not be started.
int run_process(const std::vector<std::string>& argv, int threads) {
  std::vector<std::string> env_text{"OMP_NUM_THREADS=" + std::to_string(threads)};
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "OMP_NUM_THREADS=", 16) != 0) env_text.emplace_back(*e);
  std::vector<char*> args, env;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  for (const std::string& e : env_text) env.push_back(const_cast<char*>(e.c_str()));
  args.push_back(nullptr);
  env.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int started = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), env.data());
  posix_spawn_file_actions_destroy(&actions);
  if (started != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

// `lmcal check friction` of the 1 M-row log, the whole process, wall time; its argument the
// threads. The file is in the page cache after the first run, as for a user who checks a log
// just written.
void BM_CheckFrictionLogProcess(benchmark::State& state) {
  const fs::path& file = friction_log();
  const std::vector<std::string> argv{LMCAL_CLI, "check", "friction", file.string()};
  for (auto _ : state) {
    if (run_process(argv, static_cast<int>(state.range(0))) != 0) {
      state.SkipWithError("lmcal check friction failed");
      return;
    }
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(fs::file_size(file)));
  state.counters["file_MB"] = static_cast<double>(fs::file_size(file)) / 1e6;
}
BENCHMARK(BM_CheckFrictionLogProcess)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

// `lmcal fit friction` of a 101,238-sample log from the virtual rig (47 runs of the default
// sweep: `lmcal generate friction --runs 47`) with the defaults, the whole process: start-up,
// loading, the fit with its covariance, bootstrap and per-run fits, the residual checks, writing
// the three outputs. Wall time; its argument the threads. Target (issue 39): <= 0.2 s on 2.
void BM_FitFrictionProcess100k(benchmark::State& state) {
  static const fs::path folder = [] {
    const fs::path out = scratch().path() / "friction_100k";
    return run_process({LMCAL_CLI, "generate", "friction", "--runs", "47", "-o", out.string()}, 2) == 0 ? out : fs::path();
  }();
  if (folder.empty()) {
    state.SkipWithError("lmcal generate friction failed");
    return;
  }
  const std::vector<std::string> argv{LMCAL_CLI, "fit", "friction", (folder / "friction.csv").string(), "-o",
                                      (scratch().path() / "fit_100k").string()};
  for (auto _ : state) {
    if (run_process(argv, static_cast<int>(state.range(0))) != 0) {
      state.SkipWithError("lmcal fit friction failed");
      return;
    }
  }
  state.counters["file_MB"] = static_cast<double>(fs::file_size(folder / "friction.csv")) / 1e6;
}
BENCHMARK(BM_FitFrictionProcess100k)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

// One setup moving back and forth at four speeds, 25 cycles each, logged at 1 kHz.
const fs::path& raw_friction_manifest() {
  static const fs::path file = [] {
    lmcal::FrictionRigConfig config;
    config.guides = {"SRN 35C"};
    config.preload_um = {2.5};
    config.load_N = {2000};
    config.temperature_C = {26};
    config.velocity_m_s = {0.01, 0.02, 0.05, 0.1};
    config.runs = 1;
    lmcal::RawFrictionRigConfig raw;
    raw.sample_rate_Hz = 1000;
    raw.cycles = 25;
    const lmcal::RawFrictionRigOutput made = lmcal::generate_raw_friction_logs(config, raw, {});
    fs::create_directories(scratch().path() / "friction");
    for (const auto& [name, text] : made.run_files) write(scratch().path() / name, text);
    const fs::path path = scratch().path() / "friction.toml";
    write(path, made.manifest_toml);
    return path;
  }();
  return file;
}

void BM_LoadRawFrictionLog(benchmark::State& state) {
  const fs::path& manifest = raw_friction_manifest();
  const fs::path csv = manifest.parent_path() / "friction" / "run01.csv";
  for (auto _ : state) {
    lmcal::FrictionDataSet set = lmcal::load_friction_dataset(manifest);
    benchmark::DoNotOptimize(set.log.friction_N.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(fs::file_size(csv)));
  const lmcal::FrictionDataSet set = lmcal::load_friction_dataset(manifest);
  state.counters["rows"] = static_cast<double>(set.log.segmentation.at(0).samples);
  state.counters["kept"] = static_cast<double>(set.log.size());
  state.counters["file_MB"] = static_cast<double>(fs::file_size(csv)) / 1e6;
}
BENCHMARK(BM_LoadRawFrictionLog)->Unit(benchmark::kMillisecond)->MinTime(3.0);

// A user catalog of N guides (five keys each, 88 bytes a guide), loaded from its file: the
// duplicate check must stay linear (issue 36: 10^5 guides took over 120 s when every model was
// compared with every earlier one). Target: 10^5 guides, the limit, in under 2 s.
void BM_LoadCatalog(benchmark::State& state) {
  const auto count = static_cast<std::size_t>(state.range(0));
  const fs::path file = scratch().path() / ("catalog_" + std::to_string(count) + ".toml");
  std::string text;
  for (std::size_t i = 0; i < count; ++i)
    text += "[[guide]]\nmodel = \"G" + std::to_string(i) + "\"\nblock_length_mm = 97\narea_m2 = 1.5e-4\nconductivity_W_mK = 18\n";
  write(file, text);
  for (auto _ : state) {
    const lmcal::GuideCatalog catalog = lmcal::load_catalog(file);
    benchmark::DoNotOptimize(catalog.guides.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(text.size()));
  state.counters["guides"] = static_cast<double>(count);
}
BENCHMARK(BM_LoadCatalog)->Arg(1000)->Arg(10'000)->Arg(100'000)->Unit(benchmark::kMillisecond);

}  // namespace
