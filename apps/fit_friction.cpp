// lmcal fit friction LOG.csv…: the seven friction constants (any subset) and optional
// effects from load-cell logs, with uncertainty, identifiability and spread across runs.
//
// Writes DIR/NAME.json (parameters, SE, intervals, correlation, identifiability, solver,
// spread across runs, input hashes), DIR/NAME_samples.csv (measured / predicted /
// residual per sample), DIR/NAME_conditions.csv (residual summary per condition), and a
// one-screen summary on stdout.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>

#include "cli_common.hpp"
#include "progress.hpp"
#include "lmcal/diagnose/friction_diagnosis.hpp"
#include "lmcal/error.hpp"
#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/io/hash.hpp"
#include "lmcal/io/limits.hpp"

namespace lmcal::cli {

namespace {

namespace fs = std::filesystem;

struct FitFrictionOptions {
  std::vector<std::string> files;
  FrictionInputOptions input;
  std::string name = "friction";
  std::string output_dir = "fits";
  FrictionConstantOptions constants;
  std::vector<std::string> effects;
  std::string loss = "none";
  double loss_scale = 1.345;
  std::string weights = "none";
  int starts = 8;
  std::uint64_t seed = 1;
  bool run_fits = true;
  bool keep_unusable = false;
  FitOptions uncertainty;  // --covariance, --bootstrap, --profile
};

FrictionFitOptions to_fit_options(const FitFrictionOptions& o) {
  FrictionFitOptions f;
  apply_friction_constant_options(o.constants, f);
  f.effects = o.effects;
  f.fit.loss = parse_robust_loss(o.loss, "--loss");
  require_positive("--loss-scale", o.loss_scale);
  f.fit.loss_scale = o.loss_scale;
  f.weighting = parse_friction_weighting(o.weights, "--weights");
  if (o.starts < 1 || o.starts > io::kMaxStarts)
    throw InvalidParameter("--starts", o.starts, fmt::format("from 1 to {} (docs/formats.md#limits)", io::kMaxStarts));
  f.fit.covariance = o.uncertainty.covariance;
  f.fit.bootstrap = o.uncertainty.bootstrap;
  f.fit.profile = o.uncertainty.profile;
  f.fit.starts = o.starts;
  f.fit.seed = o.seed;
  f.per_run_fits = o.run_fits;
  return f;
}

void run_fit_friction(const FitFrictionOptions& o, const std::vector<std::string>& argv) {
  require_writable_output(o.output_dir);
  const FrictionFitOptions options = to_fit_options(o);
  const FrictionInput input = load_friction_input(o.files, o.input);
  const FrictionLog& log = input.log;
  const FitProvenance provenance{o.name, input.inputs, argv};
  FrictionFitResult result = with_progress("friction fit", [&](const Progress&) { return fit_friction(log, options); });
  if (!result.fit.solver.usable)
    require_usable(fmt::format("the friction fit is not usable: {}", result.fit.solver.unusable_reason), o.keep_unusable);
  warn_of_missed_structure(log, options, result);  // a fit cannot say what its law misses
  const std::string written = write_outputs(o.output_dir, friction_fit_files(result, log, options, provenance));
  std::cout << "friction fit '" << o.name << "': " << friction_fit_summary(result);
  std::cout << "wrote " << written << "\n";
}

}  // namespace

void setup_fit(CLI::App& app, const std::vector<std::string>& argv) {
  CLI::App* fit = app.add_subcommand("fit", "Fit model parameters to measurements");
  fit->require_subcommand(1);
  auto o = std::make_shared<FitFrictionOptions>();
  CLI::App* friction = fit->add_subcommand("friction", "Friction constants from load-cell logs");
  friction->add_option("files", o->files, "Friction log CSV files, or one friction manifest (.toml)")->required();
  o->input.add_to(*friction);
  friction->add_option("--name", o->name, "Name of the fit (output file names)")->capture_default_str();
  friction->add_option("-o,--output-dir", o->output_dir, "Output folder")->capture_default_str();
  add_friction_constant_options(*friction, o->constants);
  friction->add_option("--effect", o->effects, "Fit a named effect on top of the law (e.g. seal_drag)")->delimiter(',');
  completes(friction->add_option("--loss", o->loss, "Robust loss: none, huber or cauchy"), enum_names(kRobustLosses))
      ->capture_default_str();
  friction->add_option("--loss-scale", o->loss_scale, "Robust loss scale, in residual sigmas")->capture_default_str();
  completes(friction->add_option("--weights", o->weights, "Weights: none, per-run or per-condition (from the spread of repeats)"),
            enum_names(kFrictionWeightings))
      ->capture_default_str();
  friction->add_option("--starts", o->starts, "Multi-start local searches")->capture_default_str();
  friction->add_option("--seed", o->seed, "Seed of the multi-start sequence")->capture_default_str();
  friction->add_flag_callback("--no-run-fits", [o] { o->run_fits = false; }, "Skip the per-run fits (spread across runs)");
  add_uncertainty_options(*friction, o->uncertainty);
  add_keep_unusable(*friction, o->keep_unusable);
  friction->callback([o, &argv] { run_fit_friction(*o, argv); });
  setup_fit_thermal(*fit, argv);
}

}  // namespace lmcal::cli
