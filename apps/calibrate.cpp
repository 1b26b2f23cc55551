// lmcal calibrate SET: the main job on one measurement folder (calibration.hpp): load,
// friction fit, friction diagnosis, thermal fit, thermal diagnosis; writes every fit's
// files, calibration.json and report.html to DIR (default fits/<set name>), whole or not at
// all, and the verdicts on stdout. Progress on the terminal (stderr), none in a pipe.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>

#include "cli_common.hpp"
#include "lmcal/report/calibration.hpp"
#include "progress.hpp"

namespace lmcal::cli {

namespace {

struct CalibrateOptions {
  std::string set;
  std::string output_dir;  // empty: fits/<set name>
  bool diagnose = true;
  FitOptions uncertainty;  // --covariance, --bootstrap: for the fits of the calibrated model
};

void run_calibrate(const CalibrateOptions& o) {
  const CalibrationSet set = find_calibration_set(o.set);
  CalibrationOptions options;
  options.diagnose = o.diagnose;
  for (FitOptions* fit : {&options.friction.fit, &options.thermal.fit}) {
    fit->covariance = o.uncertainty.covariance;
    fit->bootstrap = o.uncertainty.bootstrap;
  }
  TerminalProgress progress;
  const Calibration c = calibrate(set, options,
                                  {.step = [&](std::size_t i, std::size_t n, const std::string& name) { progress.step(i, n, name); },
                                   .detail = progress.detail_callback()});
  const std::filesystem::path dir = o.output_dir.empty() ? std::filesystem::path("fits") / set.name : std::filesystem::path(o.output_dir);
  const std::string written = write_outputs(dir, calibration_outputs(c));
  progress.clear();
  std::cout << "calibration of " << set.dir.string() << "\n" << calibration_summary(c);
  std::cout << "wrote " << written << "\nreport: " << (dir / "report.html").string() << "\n";
}

}  // namespace

void setup_calibrate(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  CLI::App* calibrate = app.add_subcommand(
      "calibrate", "The whole calibration of a measurement folder: fits, spread, diagnoses, report.html");
  calibrate->add_option("set", o->set, "Measurement folder (friction*.csv logs, a thermal*.toml manifest)")->required();
  calibrate->add_option("-o,--output-dir", o->output_dir, "Output folder (default: fits/<folder name>)");
  calibrate->add_flag("!--no-diagnosis", o->diagnose, "Skip the two diagnoses (fits and report only)");
  add_uncertainty_options(*calibrate, o->uncertainty);
  calibrate->callback([o] { run_calibrate(*o); });
}

}  // namespace lmcal::cli
