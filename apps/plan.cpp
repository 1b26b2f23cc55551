// lmcal plan friction LOG.csv…|MANIFEST: the next conditions to log (plan.hpp), from a fit of
// the logs (with the calibrated model's causes with --model), over a candidate grid (the
// logs' own values, or the lists given).
//
// Writes DIR/plan.json, DIR/plan_friction_template.csv (to fill on the rig) or
// DIR/plan_thermal_manifest.toml, and DIR/plan.html (the picks, the SE table and its plot), all
// or none, and the table on stdout.
#include <algorithm>
#include <iostream>

#include "cli_common.hpp"
#include "output_mode.hpp"
#include "lmcal/io/hash.hpp"
#include "lmcal/io/output_record.hpp"
#include "lmcal/error.hpp"
#include "lmcal/fit/model_file.hpp"
#include "lmcal/predict/plan.hpp"
#include "lmcal/report/predict_pages.hpp"
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
  require_writable_output(o.output_dir);
  FrictionFitOptions fit_options;
  apply_friction_constant_options(o.constants, fit_options);
  fit_options.effects = o.effects;
  if (const auto model = LoadedModel::read(o.model, "friction")) {
    if (!o.effects.empty()) throw InvalidParameter("--effect", "the model's causes are the effects: give --model or --effect");
    fit_options.effects = model->model.friction_causes;
    if (o.constants.run_offsets.empty()) fit_options.run_offsets = RunOffsets::random;  // as the calibrated model was fitted
  }
  for (const auto& effect : o.plan.separate)  // a tie: both effects in the fit
    if (std::find(fit_options.effects.begin(), fit_options.effects.end(), effect) == fit_options.effects.end())
      fit_options.effects.push_back(effect);
  fit_options.per_run_fits = false;
  fit_options.fit.bootstrap = 0;
  const FrictionInput input = load_friction_input(o.files, o.input);
  const auto catalog = user_catalog(o.input.catalog_file);
  FrictionCandidateGrid grid = o.grid;
  grid.catalog = catalog ? &*catalog : nullptr;
  const FrictionPlan plan = with_progress("friction plan", [&](const Progress&) {
    const FrictionFitResult fit = fit_friction(input.log, fit_options);
    return plan_friction(input.log, fit, friction_candidates(input.log, grid, fit), o.plan);
  });
  std::vector<std::pair<std::string, std::string>> inputs = input.inputs;
  if (!o.model.file.empty()) inputs.emplace_back(o.model.file, sha256_file(o.model.file));
  const std::string written = write_outputs(o.output_dir, {{"plan.json", with_output_record(friction_plan_json(plan, argv), argv, &inputs, &output_mode().options)},
                                                           {"plan_friction_template.csv", friction_plan_template_csv(plan)},
                                                           {"plan.html", friction_plan_html(plan, argv)}});
  std::cout << friction_plan_summary(plan) << "wrote " << written << "\n";
}

struct PlanThermalOptions {
  std::string manifest, catalog_file, output_dir = "fits/plan";
  ModelOptions model;
  ThermalCandidateGrid grid;
  std::vector<double> duration_h;
  ThermalPlanOptions plan;
};

void run_plan_thermal(const PlanThermalOptions& o, const std::vector<std::string>& argv) {
  require_writable_output(o.output_dir);
  const auto model = LoadedModel::read(o.model, "thermal");
  if (!model) throw InvalidParameter("--model", "a thermal plan needs the calibrated model (model.toml of lmcal calibrate)");
  const auto catalog = user_catalog(o.catalog_file);
  const ThermalDataSet data = load_thermal_dataset(o.manifest, catalog ? &*catalog : nullptr, input_scope());
  ThermalCandidateGrid grid = o.grid;
  for (double h : o.duration_h) grid.duration_s.push_back(3600 * h);
  const ThermalPlan plan = with_progress("thermal plan", [&](const Progress&) {
    return plan_thermal(model->model, data, thermal_candidates(data, grid), o.plan);
  });
  std::vector<std::pair<std::string, std::string>> inputs = {{o.manifest, sha256_file(o.manifest)}, {model->file, model->sha256}};
  for (const auto& run : data.runs) inputs.emplace_back(run.file.string(), sha256_file(run.file));
  const std::string written = write_outputs(o.output_dir, {{"plan.json", with_output_record(thermal_plan_json(plan, argv), argv, &inputs, &output_mode().options)},
                                                           {"plan_thermal_manifest.toml", thermal_plan_manifest_toml(plan, data)},
                                                           {"plan.html", thermal_plan_html(plan, argv)}});
  std::cout << thermal_plan_summary(plan) << "wrote " << written << "\n";
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
  friction->add_option("--guide", o->grid.guides, "Candidate guides of the catalog (default: the logs')")->delimiter(',');
  friction->add_option("--separate", o->plan.separate,
                       "Two effects to tell apart (a tie of the diagnosis), e.g. seal_drag,seal_drag_block")
      ->delimiter(',');
  friction->add_option("-o,--output-dir", o->output_dir, "Output folder")->capture_default_str();
  friction->callback([o, &argv] { run_plan_friction(*o, argv); });

  auto t = std::make_shared<PlanThermalOptions>();
  CLI::App* thermal = plan->add_subcommand("thermal", "The next thermal runs for a calibrated rail model (sequential optimal design)");
  thermal->add_option("manifest", t->manifest, "The thermal manifest of the runs logged so far")->required();
  t->model.add_to(*thermal, "The calibrated model (model.toml): its rail model and friction law (required)");
  thermal->add_option("--catalog", t->catalog_file, kCatalogHelp);
  thermal->add_option("-n,--runs", t->plan.runs, "How many runs to plan")->capture_default_str();
  thermal->add_option("--parameters", t->plan.parameters, "The parameters to determine better (A-optimal); default: all")
      ->delimiter(',');
  thermal->add_option("--separate", t->plan.separate,
                      "Two mechanisms to tell apart (a tie of the diagnosis), e.g. base_loss,convection_velocity")
      ->delimiter(',');
  add_list(*thermal, "--velocity", t->grid.velocity_m_s, "Candidate speeds, m/s (default: the runs')");
  add_list(*thermal, "--load", t->grid.load_N, "Candidate loads, N (default: the runs')");
  add_list(*thermal, "--duration-h", t->duration_h, "Candidate durations, h (default: the longest run's)");
  thermal->add_option("--record-every", t->plan.record_every_s, "Seconds between the readings the design counts")->capture_default_str();
  thermal->add_option("--noise", t->plan.noise_K, "Thermocouple noise, K (default: from the runs' traces)");
  thermal->add_option("-o,--output-dir", t->output_dir, "Output folder")->capture_default_str();
  thermal->callback([t, &argv] { run_plan_thermal(*t, argv); });
}

}  // namespace lmcal::cli
