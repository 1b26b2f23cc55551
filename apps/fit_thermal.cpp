// lmcal fit thermal MANIFEST [--friction fits/friction.json]: the heat partition α (and
// optionally h, thermocouple offsets, initial temperatures) from rail thermocouple traces.
//
// Writes DIR/NAME.json (joint and per-run estimates with intervals, α across runs with
// Eq. 1 σ and t interval, Eq. 2 differences, goodness per sensor, source-model comparison),
// DIR/NAME_samples.csv (measured vs simulated per sensor and time), DIR/NAME_alpha_curve.csv
// (the error against α at spot 1, the paper's Fig. 11), and a summary on stdout.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>

#include "cli_common.hpp"
#include "progress.hpp"
#include "lmcal/error.hpp"
#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/io/hash.hpp"

namespace lmcal::cli {

namespace {

namespace fs = std::filesystem;

struct FitThermalOptions {
  std::string manifest;
  std::string name = "thermal";
  std::string output_dir = "fits";
  std::string catalog_file;  // wins over the manifest's `catalog`
  ThermalModelOptions model;
  ThermalFitOptions fit;
  bool keep_unusable = false;
};

void run_fit_thermal(FitThermalOptions& o, const std::vector<std::string>& argv) {
  require_writable_output(o.output_dir);
  ThermalFitOptions& f = o.fit;
  std::vector<std::pair<std::string, std::string>> inputs;
  o.model.apply(f, inputs);
  const std::optional<GuideCatalog> catalog = user_catalog(o.catalog_file);
  const ThermalDataSet data = load_thermal_dataset(o.manifest, catalog ? &*catalog : nullptr, input_scope());
  inputs.emplace_back(o.manifest, sha256_file(o.manifest));
  if (!data.catalog_file.empty()) inputs.emplace_back(data.catalog_file.string(), sha256_file(data.catalog_file));
  for (const auto& run : data.runs) inputs.emplace_back(run.file.string(), sha256_file(run.file));

  const ThermalFitResult result = with_progress("thermal fit", [&](const Progress&) { return fit_thermal(data, f); });
  if (!result.joint.solver.usable)
    require_usable(fmt::format("the thermal fit is not usable: {}", result.joint.solver.unusable_reason), o.keep_unusable);
  const std::string written = write_outputs(o.output_dir, thermal_fit_files(result, f, inputs, argv, o.name));
  std::cout << "thermal fit '" << o.name << "' (" << to_string(f.source) << " source): " << thermal_fit_summary(result);
  std::cout << "wrote " << written << "\n";
}

}  // namespace

void setup_fit_thermal(CLI::App& fit, const std::vector<std::string>& argv) {
  auto o = std::make_shared<FitThermalOptions>();
  CLI::App* app = fit.add_subcommand("thermal", "Heat partition alpha from rail thermocouple traces");
  app->add_option("manifest", o->manifest, "Thermal data set manifest (TOML)")->required();
  app->add_option("--name", o->name, "Name of the fit (output file names)")->capture_default_str();
  app->add_option("-o,--output-dir", o->output_dir, "Output folder")->capture_default_str();
  app->add_option("--catalog", o->catalog_file, kCatalogHelp);
  o->model.add_to(*app, o->fit);
  o->model.add_friction_file(*app);
  ThermalModelOptions::add_offsets(*app, o->fit);
  std::string known;
  for (const auto& e : thermal_extension_library()) known += fmt::format("\n    {}: {}", e.name, e.description);
  app->add_option("--extension", o->fit.extensions, "Add a mechanism of the extension library (repeatable):" + known);
  app->add_flag("--cross-validate", o->fit.cross_validate, "Also report the leave-one-run-out prediction RMSE");
  app->add_flag_callback("--no-run-fits", [o] { o->fit.per_run_fits = false; }, "Skip the per-run fits");
  app->add_flag_callback("--no-source-comparison", [o] { o->fit.compare_sources = false; }, "Skip the paper/averaged comparison");
  add_uncertainty_options(*app, o->fit.fit);
  add_keep_unusable(*app, o->keep_unusable);
  app->callback([o, &argv] { run_fit_thermal(*o, argv); });
}

}  // namespace lmcal::cli
