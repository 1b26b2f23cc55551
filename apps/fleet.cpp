// lmcal fleet ROOT: every measurement set under ROOT calibrated as `lmcal calibrate` would
// (fleet.hpp), resumably, on --jobs threads, a --shard of a job array, or MPI ranks; then the
// population, outliers, drift and causes across the fleet (fleet_summary.hpp) in
// OUT/fleet.json, fleet.csv and fleet.html.
//
//   lmcal fleet logs --jobs 8                     one machine
//   lmcal fleet logs --shard 3/16 ; … ; lmcal fleet logs --summarize    a job array
//   mpirun -np 64 lmcal fleet logs                a cluster
#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <tuple>
#include <string>
#include <vector>

#include "calibration_options.hpp"
#include "lmcal/error.hpp"
#include "lmcal/fleet/fleet_summary.hpp"
#include "progress.hpp"
#ifdef LMCAL_WITH_MPI
#include "fleet_mpi.hpp"
#endif

namespace lmcal::cli {

namespace {

namespace fs = std::filesystem;

struct FleetCliOptions {
  std::string root;
  std::string output_dir;  // empty: fits/<root's name>
  std::size_t jobs = 1;
  std::string shard;       // "i/n", empty: all
  bool summarize = false;
  CalibrationCliOptions calibration;
};

// "i/n" with 0 <= i < n.
std::pair<std::size_t, std::size_t> parse_shard(const std::string& text) {
  std::size_t i = 0, n = 0;
  char slash = 0;
  std::istringstream in(text);
  if (!(in >> i >> slash >> n) || slash != '/' || !in.eof() || n == 0 || i >= n)
    throw InvalidParameter("--shard", fmt::format("'{}': expected i/n with 0 <= i < n, e.g. 0/16", text));
  return {i, n};
}

void write_summary(const Fleet& fleet, const FleetOptions& options, const std::vector<std::string>& records,
                   const std::string& root) {
  const FleetSummary summary = summarize_fleet(fleet, records, {"lmcal", "fleet", root});
  const std::string written = write_outputs(options.output_dir, fleet_summary_outputs(summary));
  std::cout << "fleet " << root << ": " << fleet_summary_text(summary);
  std::cout << "wrote " << written << "\n";
}

void run_fleet_command(FleetCliOptions& o) {
  FleetOptions options{.calibration = o.calibration.resolve(), .jobs = o.jobs};
  if (o.jobs == 0) throw InvalidParameter("--jobs", "expected at least 1");
  if (!o.shard.empty()) std::tie(options.shard, options.shards) = parse_shard(o.shard);
  if (o.summarize && !o.shard.empty()) throw InvalidParameter("--summarize", "summarizes every shard: give it without --shard");
  options.output_dir = o.output_dir.empty() ? fs::path("fits") / fs::weakly_canonical(o.root).filename() : fs::path(o.output_dir);
  options.calibration.inputs.allow_outside = input_scope().allow_outside;
  require_writable_output(options.output_dir);
#ifdef LMCAL_WITH_MPI
  // Under mpirun every rank runs this: MPI starts first, and only rank 0 writes the summary.
  std::optional<MpiSession> mpi;
  if (launched_by_mpi()) mpi.emplace();
  const bool distributed = mpi && mpi->size() > 1;
  if (distributed && o.summarize && mpi->rank() != 0) return;
#endif
  const Fleet fleet = discover_fleet(o.root, options.output_dir, input_scope().allow_outside);
  if (o.summarize) {
    write_summary(fleet, options, read_fleet_records(fleet, options), o.root);
    return;
  }

  TerminalProgress progress;
  const FleetProgress report = [&](std::size_t done, std::size_t total, const std::string& id, const FleetSetOutcome& outcome) {
    progress.step(done - 1, total, fmt::format("{} {}", id, outcome.computed ? "calibrated" : "up to date"));
  };
  FleetRun run;
#ifdef LMCAL_WITH_MPI
  if (distributed) {
    run = run_fleet_mpi(*mpi, fleet, options, report);
    if (mpi->rank() != 0) return;  // rank 0 writes the summary
  } else {
    run = run_fleet(fleet, options, report);
  }
#else
  run = run_fleet(fleet, options, report);
#endif
  progress.clear();
  std::cout << fmt::format("{} sets{}: {} calibrated, {} up to date (skipped), {} failed\n",
                           run.computed + run.skipped, options.shards > 1 ? fmt::format(" of shard {}", o.shard) : "",
                           run.computed, run.skipped, run.failed);
  if (options.shards > 1) {
    std::cout << fmt::format("when every shard is done: lmcal fleet {} --summarize (with the same options)\n", o.root);
    return;
  }
  std::vector<std::string> records;
  for (auto& r : run.records) records.push_back(std::move(*r));
  write_summary(fleet, options, records, o.root);
}

}  // namespace

void setup_fleet(CLI::App& app) {
  auto o = std::make_shared<FleetCliOptions>();
  CLI::App* fleet = app.add_subcommand(
      "fleet",
      "Calibrate every measurement folder under ROOT (a folder per unit, or per unit/date; or a fleet.toml listing "
      "them) and report the population, outliers, drift and causes. Resumable: up-to-date sets are skipped. "
      "Parallel: --jobs N, --shard i/n with --summarize, or mpirun -np N lmcal fleet ROOT");
  fleet->add_option("root", o->root, "The fleet's folder")->required();
  fleet->add_option("-o,--output-dir", o->output_dir, "Output folder: each set's outputs in OUT/<set>, the summary in OUT (default: fits/<root name>)");
  fleet->add_option("-j,--jobs", o->jobs, "Sets calibrated at once on this machine")->capture_default_str();
  fleet->add_option("--shard", o->shard, "Calibrate only shard i of n (sets i, i+n, …), for a job array; then --summarize");
  fleet->add_flag("--summarize", o->summarize, "Only write the summary, from the sets' results on disk (after the shards)");
  o->calibration.add_to(*fleet);
  fleet->callback([o] { run_fleet_command(*o); });
}

}  // namespace lmcal::cli
