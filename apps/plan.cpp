// lmcal plan friction LOG.csv…|MANIFEST: the next conditions to log (plan.hpp), from a fit of
// the logs (with the calibrated model's causes with --model), over a candidate grid (the
// logs' own values, or the lists given).
//
// Writes DIR/plan.json and DIR/plan_friction_template.csv (to fill on the rig), all or none,
// and the table on stdout.
#include <iostream>

#include "cli_common.hpp"
#include "lmcal/error.hpp"
#include "lmcal/fit/model_file.hpp"
#include "lmcal/predict/plan.hpp"
#include "progress.hpp"

namespace lmcal::cli {

namespace {

struct PlanFrictionOptions {
  std::vector<std::string> files;
  FrictionInputOptions input;
  FrictionConstantOptions constants;
  std::vector<std::string> effects;
  ModelOptions model;
  FrictionCandidateGrid grid;
  PlanOptions plan;
  std::string output_dir = "fits/plan";
};

void run_plan_friction(const PlanFrictionOptions& o, const std::vector<std::string>& argv) {
  FrictionFitOptions fit_options;
  apply_friction_constant_options(o.constants, fit_options);
  fit_options.effects = o.effects;
  if (const auto model = LoadedModel::read(o.model, "friction")) {
    if (!o.effects.empty()) throw InvalidParameter("--effect", "the model's causes are the effects: give --model or --effect");
    fit_options.effects = model->model.friction_causes;
    if (o.constants.run_offsets.empty()) fit_options.run_offsets = RunOffsets::random;  // as the calibrated model was fitted
  }
  fit_options.per_run_fits = false;
  fit_options.fit.bootstrap = 0;
  const FrictionInput input = load_friction_input(o.files, o.input);
  const FrictionPlan plan = with_progress("friction plan", [&](const Progress&) {
    const FrictionFitResult fit = fit_friction(input.log, fit_options);
    return plan_friction(input.log, fit, friction_candidates(input.log, o.grid), o.plan);
  });
  const std::string written = write_outputs(o.output_dir, {{"plan.json", friction_plan_json(plan, argv)},
                                                           {"plan_friction_template.csv", friction_plan_template_csv(plan)}});
  std::cout << friction_plan_summary(plan) << "wrote " << written << "\n";
}

}  // namespace

void setup_plan(CLI::App& app, const std::vector<std::string>& argv) {
  CLI::App* plan = app.add_subcommand("plan", "The next measurements that most shrink the uncertainty");
  plan->require_subcommand(1);
  auto o = std::make_shared<PlanFrictionOptions>();
  CLI::App* friction = plan->add_subcommand("friction", "The next friction conditions to log (sequential optimal design)");
  friction->add_option("files", o->files, "Friction log CSV files, or one friction manifest (.toml)")->required();
  o->input.add_to(*friction);
  add_friction_constant_options(*friction, o->constants);
  friction->add_option("--effect", o->effects, "Fit a named effect on top of the law (e.g. seal_drag)")->delimiter(',');
  o->model.add_to(*friction, "The calibrated model (model.toml): its friction causes are the law's effects");
  friction->add_option("-n,--conditions", o->plan.conditions, "How many conditions to plan")->capture_default_str();
  friction->add_option("--parameters", o->plan.parameters,
                       "The parameters to determine better (A-optimal); default: all (D-optimal)")
      ->delimiter(',');
  friction->add_option("--samples", o->plan.samples_per_condition, "Samples per planned condition (default: the logs' median)");
  add_list(*friction, "--velocity", o->grid.velocity_m_s, "Candidate speeds, m/s (default: the logs')");
  add_list(*friction, "--load", o->grid.load_N, "Candidate loads, N (default: the logs')");
  add_list(*friction, "--preload", o->grid.preload_um, "Candidate preloads, um (default: the logs')");
  add_list(*friction, "--temperature", o->grid.temperature_C, "Candidate temperatures, C (default: the logs')");
  add_list(*friction, "--direction", o->grid.directions, "Candidate directions, +1/-1 (default: the logs')");
  friction->add_option("-o,--output-dir", o->output_dir, "Output folder")->capture_default_str();
  friction->callback([o, &argv] { run_plan_friction(*o, argv); });
}

}  // namespace lmcal::cli
