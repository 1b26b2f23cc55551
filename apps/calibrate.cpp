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

#include "cli_common.hpp"
#include "lmcal/report/calibration.hpp"
#include "progress.hpp"

namespace lmcal::cli {

namespace {

struct CalibrateOptions {
  std::string set;
  std::string output_dir;  // empty: fits/<set name>
  CalibrationOptions calibration;
  FitOptions uncertainty;  // --covariance, --bootstrap: for every fit
  FrictionConstantOptions constants;
  ThermalModelOptions thermal_model;
  FrictionInputOptions input;  // --catalog and the raw logs' segmentation
  const CLI::Option* lrt_p = nullptr;
  const CLI::Option* starts = nullptr;
  const CLI::Option* seed = nullptr;
  bool timings = false;  // --timings: each step's wall time on stderr
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
  CalibrationOptions& options = o.calibration;
  options.catalog_file = o.input.catalog_file;
  options.raw = o.input.parsed();
  options.raw_given = o.input.raw_given();
  // One setting, every step that has it: the published fits, the diagnoses' baselines and
  // the calibrated model's fits.
  apply_friction_constant_options(o.constants, options.friction);
  apply_friction_constant_options(o.constants, options.friction_diagnosis.fit);
  std::vector<std::pair<std::string, std::string>> no_inputs;
  o.thermal_model.apply(options.thermal, no_inputs);
  o.thermal_model.apply(options.thermal_diagnosis.fit, no_inputs);
  o.thermal_model.copy_given(options.thermal, options.thermal_diagnosis.fit);
  if (o.lrt_p->count() > 0) options.thermal_diagnosis.lrt_p = options.friction_diagnosis.lrt_p;
  for (FitOptions* fit : {&options.friction.fit, &options.friction_diagnosis.fit.fit, &options.thermal.fit,
                          &options.thermal_diagnosis.fit.fit}) {
    fit->covariance = o.uncertainty.covariance;
    fit->bootstrap = o.uncertainty.bootstrap;
  }
  for (FitOptions* fit : {&options.friction_diagnosis.fit.fit}) {
    if (o.starts->count() > 0) fit->starts = options.friction.fit.starts;
    if (o.seed->count() > 0) fit->seed = options.friction.fit.seed;
  }
  TerminalProgress progress;
  StepTimes times;
  const Calibration c = calibrate(set, options,
                                  {.step =
                                       [&](std::size_t i, std::size_t n, const std::string& name) {
                                         times.start(name);
                                         progress.step(i, n, name);
                                       },
                                   .detail = progress.detail_callback()});
  times.start("writing the outputs");
  const std::filesystem::path dir = o.output_dir.empty() ? std::filesystem::path("fits") / set.name : std::filesystem::path(o.output_dir);
  const std::string written = write_outputs(dir, calibration_outputs(c));
  times.stop();
  progress.clear();
  if (o.timings) times.print(stderr);
  std::cout << "calibration of " << set.dir.string() << "\n" << calibration_summary(c);
  std::cout << "wrote " << written << "\nreport: " << (dir / "report.html").string() << "\n";
}

}  // namespace

void setup_calibrate(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  CalibrationOptions& c = o->calibration;
  CLI::App* calibrate = app.add_subcommand(
      "calibrate",
      "The whole calibration of a measurement folder: fits, spread, diagnoses, report.html. Every option may also "
      "come from a file: lmcal --config options.toml calibrate SET, with the options under [calibrate]");
  calibrate->add_option("set", o->set, "Measurement folder (friction*.csv logs or a friction*.toml manifest, a thermal*.toml manifest)")
      ->required();
  calibrate->add_option("-o,--output-dir", o->output_dir, "Output folder (default: fits/<folder name>)");
  calibrate->add_flag("!--no-diagnosis", c.diagnose, "Skip the two diagnoses (fits and report only)");
  calibrate->add_flag("--timings", o->timings, "Print each step's wall time on stderr");
  add_uncertainty_options(*calibrate, o->uncertainty);
  // The friction fits: constants held, freed, started and bounded; the load cell's zero; the
  // multi-start search.
  add_friction_constant_options(*calibrate, o->constants);
  o->starts = calibrate->add_option("--starts", c.friction.fit.starts, "Multi-start local searches of the friction fits")
                  ->capture_default_str();
  o->seed = calibrate->add_option("--seed", c.friction.fit.seed, "Seed of the multi-start sequence")->capture_default_str();
  // The guides' catalog and the raw load-cell logs' segmentation.
  o->input.add_to(*calibrate);
  // The rail model: heat, source, numerics, h, offsets.
  o->thermal_model.add_to(*calibrate, c.thermal);
  ThermalModelOptions::add_offsets(*calibrate, c.thermal);
  // The diagnoses' thresholds.
  calibrate->add_option("--friction-min-gain", c.friction_diagnosis.min_cv_gain_percent,
                        "Least held-out RMSE gain to accept a friction cause, %")
      ->capture_default_str();
  calibrate->add_option("--thermal-min-gain", c.thermal_diagnosis.min_cv_gain_percent,
                        "Least held-out RMSE gain to accept a thermal mechanism, %")
      ->capture_default_str();
  o->lrt_p = calibrate->add_option("--lrt-p", c.friction_diagnosis.lrt_p, "Significance level of the diagnoses' likelihood-ratio tests")
                 ->capture_default_str();
  calibrate->callback([o] { run_calibrate(*o); });
}

}  // namespace lmcal::cli
