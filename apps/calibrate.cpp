// lmcal calibrate SET: the main job on one measurement folder (calibration.hpp): load,
// friction fit, friction diagnosis, thermal fit, thermal diagnosis; writes every fit's
// files, calibration.json and report.html to DIR (default fits/<set name>), whole or not at
// all, and the verdicts on stdout. Progress on the terminal (stderr), none in a pipe.
#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "calibration_options.hpp"
#include "output_mode.hpp"
#include "lmcal/calibrate/calibration.hpp"
#include "lmcal/report/calibration.hpp"
#include "progress.hpp"

namespace lmcal::cli {

namespace {

struct CalibrateOptions {
  std::string set;
  std::string output_dir;  // empty: fits/<set name>
  CalibrationCliOptions calibration;
  bool timings = false;  // --timings: each step's wall time on stderr
  bool keep_unusable = false;
};

// Wall time of each step, printed on stderr when asked (--timings): where a slow calibration
// spends its time, without a profiler.
class StepTimes {
 public:
  using Clock = std::chrono::steady_clock;
  void start(const std::string& name) {
    stop();
    steps_.emplace_back(name, 0.0);
    since_ = Clock::now();
    running_ = true;
  }
  void stop() {
    if (running_) steps_.back().second = std::chrono::duration<double>(Clock::now() - since_).count();
    running_ = false;
  }
  void print(std::FILE* out) const {
    double total = 0;
    for (const auto& [name, seconds] : steps_) {
      fmt::print(out, "{:>8.3f} s  {}\n", seconds, name);
      total += seconds;
    }
    fmt::print(out, "{:>8.3f} s  total\n", total);
  }

 private:
  std::vector<std::pair<std::string, double>> steps_;
  Clock::time_point since_ = Clock::now();
  bool running_ = false;
};

void run_calibrate(CalibrateOptions& o) {
  const CalibrationSet set = find_calibration_set(o.set);
  CalibrationOptions options = o.calibration.resolve();
  options.inputs.allow_outside = input_scope().allow_outside;
  const std::filesystem::path dir = o.output_dir.empty() ? std::filesystem::path("fits") / set.name : std::filesystem::path(o.output_dir);
  require_writable_output(dir);
  TerminalProgress progress;
  StepTimes times;
  const Calibration c = calibrate(set, options,
                                  {.step =
                                       [&](std::size_t i, std::size_t n, const std::string& name) {
                                         times.start(name);
                                         progress.step(i, n, name);
                                       },
                                   .detail = progress.detail_callback()});
  progress.clear();
  require_usable(unusable_headline(c), o.keep_unusable);
  times.start("writing the outputs");
  const std::string written = write_outputs(dir, calibration_outputs(c), calibration_output_names());
  times.stop();
  progress.clear();
  if (o.timings || output_mode().verbosity == Verbosity::verbose) times.print(stderr);
  std::cout << "calibration of " << set.dir.string() << "\n" << calibration_summary(c);
  std::cout << "wrote " << written << "\nreport: " << (dir / "report.html").string() << "\n";
}

}  // namespace

void setup_calibrate(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  CLI::App* calibrate = app.add_subcommand(
      "calibrate",
      "The whole calibration of a measurement folder: fits, spread, diagnoses, report.html. Every option may also "
      "come from a file: lmcal --config options.toml calibrate SET, with the options under [calibrate]");
  calibrate->add_option("set", o->set, "Measurement folder (friction*.csv logs or a friction*.toml manifest, a thermal*.toml manifest)")
      ->required();
  calibrate->add_option("-o,--output-dir", o->output_dir, "Output folder (default: fits/<folder name>)");
  calibrate->add_flag("--timings", o->timings, "Print each step's wall time on stderr");
  add_keep_unusable(*calibrate, o->keep_unusable);
  o->calibration.add_to(*calibrate);
  calibrate->callback([o] { run_calibrate(*o); });
}

}  // namespace lmcal::cli
