// lmcal check: load measurement files the way the fits will, and say what was found
// (rows, runs, conversions, skipped rows, gaps) or exactly what is wrong with them.
// lmcal resample: a thermal trace at a coarser step (keep every n-th record, or average
// blocks of n).
#include <fmt/format.h>

#include <filesystem>
#include <iostream>

#include "cli_common.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/io/resample.hpp"
#include "lmcal/io/thermal_run.hpp"

namespace lmcal::cli {

namespace {

namespace fs = std::filesystem;

void print_report(const LoadReport& r) {
  std::cout << fmt::format("  {}: {} rows read, {} kept\n", r.file, r.rows_read, r.rows_kept);
  for (const auto& [column, conversion] : r.conversions) std::cout << fmt::format("    converted {}: {}\n", column, conversion);
  for (const auto& [reason, count] : r.skipped) std::cout << fmt::format("    skipped {} rows: {}\n", count, reason);
  for (const auto& [column, count] : r.missing) std::cout << fmt::format("    {} missing samples in {}\n", count, column);
  for (const auto& column : r.ignored_columns) std::cout << fmt::format("    ignored column {}\n", column);
  if (r.time_gaps) std::cout << fmt::format("    {} gaps in time (> 1.5x the median step)\n", r.time_gaps);
  for (const auto& note : r.notes) std::cout << fmt::format("    note: {}\n", note);
  for (const auto& warning : r.warnings) std::cout << fmt::format("    warning: {}\n", warning);
}

void print_trace(const ThermalTrace& trace) {
  if (trace.size() == 0) return;
  std::cout << fmt::format("    {} records over {:.0f} s; ambient:", trace.size(), trace.time_s.back() - trace.time_s.front());
  for (const auto& c : trace.ambient) std::cout << " " << c.name;
  std::cout << "; rail:";
  for (const auto& c : trace.rail) std::cout << " " << c.name;
  std::cout << "\n";
}

// What segmentation kept and dropped of each raw run.
void print_segmentation(const RunSegmentation& s) {
  if (s.filter_window != 0) {  // read as a trajectory
    std::cout << fmt::format("    run {}: {} samples, {} kept as a trajectory (filter window {} samples, {:.3g} s: noise "
                             "{:.2g} m/s, {:.2g} m/s²); dropped {} at rest, reversing or at the log's ends, {} pre-sliding, {} at steps of "
                             "the force",
                             s.run, s.samples, s.kept, s.filter_window, s.filter_window_s, s.velocity_noise_m_s,
                             s.acceleration_noise_m_s2, s.dropped_stationary, s.dropped_settling, s.dropped_acceleration);
    if (s.averaged_duplicates) std::cout << fmt::format("; {} repeated times averaged", s.averaged_duplicates);
    std::cout << "\n";
    return;
  }
  std::cout << fmt::format("    run {}: {} samples, {} kept in {} plateaus; dropped {} accelerating, {} settling, {} at "
                           "rest, {} in short plateaus",
                           s.run, s.samples, s.kept, s.plateaus.size(), s.dropped_acceleration, s.dropped_settling,
                           s.dropped_stationary, s.dropped_short);
  if (s.averaged_duplicates) std::cout << fmt::format("; {} repeated times averaged", s.averaged_duplicates);
  std::cout << "\n";
  for (const Plateau& p : s.plateaus)
    std::cout << fmt::format("      {:>10.3f} s to {:>10.3f} s  {:+.5g} m/s  {} samples\n", p.start_s, p.end_s,
                             p.velocity_m_s, p.samples);
}

void check_friction(const std::vector<std::string>& files, const FrictionInputOptions& options) {
  const FrictionLog log = read_friction_input(files, options).log;
  // A log without a guide column or key has one unnamed guide: not counted as a guide.
  const bool guides = !(log.guide_names.size() == 1 && log.guide_names.front().empty());
  std::cout << fmt::format("friction log: {}, {}{}\n", plural(log.size(), "sample"), plural(log.run_names.size(), "run"),
                           guides ? ", " + plural(log.guide_names.size(), "guide") : ", no guide named");
  for (const auto& r : log.reports) {
    print_report(r);
    for (const auto& s : log.segmentation)
      if (s.file == r.file) print_segmentation(s);
  }
}

void check_thermal(const std::vector<std::string>& files, const std::string& catalog_file, std::size_t skip_lines) {
  for (const auto& file : files) {
    if (fs::path(file).extension() == ".csv") {
      const ThermalTrace trace = load_thermal_trace(file, skip_lines);
      std::cout << "thermal trace:\n";
      print_report(trace.report);
      print_trace(trace);
      continue;
    }
    const std::optional<GuideCatalog> catalog = user_catalog(catalog_file);
    const ThermalDataSet set = load_thermal_dataset(file, catalog ? &*catalog : nullptr, input_scope());
    std::cout << fmt::format("thermal data set '{}': {}\n", set.name, plural(set.runs.size(), "run"));
    for (const auto& run : set.runs) {
      const GuideSpec spec = resolved_guide(run);
      std::cout << fmt::format("  run {}: {} ({}, {}) at {} m/s, {} N\n", run.id, spec.model, spec.kind,
                               spec.source.empty() ? "<built-in>" : spec.source, run.velocity_m_s, run.load_N);
      print_report(run.trace.report);
      print_trace(run.trace);
    }
  }
}

struct ResampleOptions {
  std::string input, output;
  std::size_t every = 0, average = 0, skip_lines = 0;
};

void run_resample(const ResampleOptions& o) {
  if ((o.every == 0) == (o.average == 0))
    throw InvalidParameter("--every/--average", "give exactly one of --every N or --average N (N >= 1)");
  const ThermalTrace trace = load_thermal_trace(o.input, o.skip_lines);
  const ThermalTrace coarse = o.every ? decimate(trace, o.every) : block_average(trace, o.average);
  write_file_atomically(o.output, thermal_trace_csv(coarse, {fmt::format("resampled from {} ({} {})", o.input,
                                                                          o.every ? "every" : "average of",
                                                                          o.every ? o.every : o.average)}));
  std::cout << fmt::format("{} records -> {} records in {}\n", trace.size(), coarse.size(), o.output);
}

}  // namespace

void setup_check(CLI::App& app) {
  CLI::App* check = app.add_subcommand("check", "Load measurement files and report what was found or what is wrong");
  check->require_subcommand(1);
  auto friction_files = std::make_shared<std::vector<std::string>>();
  auto friction_input = std::make_shared<FrictionInputOptions>();
  CLI::App* friction = check->add_subcommand("friction", "Friction log CSV file(s) or a friction manifest (.toml)");
  friction->add_option("files", *friction_files, "Friction log CSV files, or one friction manifest")->required();
  friction_input->add_to(*friction);
  friction->callback([friction_files, friction_input] { check_friction(*friction_files, *friction_input); });
  auto thermal_files = std::make_shared<std::vector<std::string>>();
  auto thermal_catalog = std::make_shared<std::string>();
  CLI::App* thermal = check->add_subcommand("thermal", "Thermal manifest(s) (.toml) or run CSV file(s)");
  thermal->add_option("files", *thermal_files, "Manifests or thermal run CSVs")->required();
  thermal->add_option("--catalog", *thermal_catalog,
                      kCatalogHelp);
  auto thermal_skip = std::make_shared<std::size_t>(0);
  thermal->add_option("--skip-lines", *thermal_skip, kSkipLinesHelp);
  thermal->callback([thermal_files, thermal_catalog, thermal_skip] {
    check_thermal(*thermal_files, *thermal_catalog, *thermal_skip);
  });

  auto o = std::make_shared<ResampleOptions>();
  CLI::App* resample = app.add_subcommand("resample", "Coarsen a thermal run CSV (the paper kept every 120th record)");
  resample->add_option("input", o->input, "Thermal run CSV")->required();
  resample->add_option("-o,--output", o->output, "Output CSV")->required();
  resample->add_option("--every", o->every, "Keep records 0, N, 2N, ...");
  resample->add_option("--average", o->average, "Average consecutive blocks of N records");
  resample->add_option("--skip-lines", o->skip_lines, kSkipLinesHelp);
  resample->callback([o] { run_resample(*o); });
}

}  // namespace lmcal::cli
