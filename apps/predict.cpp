// lmcal predict MODEL DUTY: the calibrated model (model.toml of `lmcal calibrate`) over a duty
// cycle (prediction.hpp): the rail's temperature, its elongation and a linear scale's
// positioning error over time, the block's friction and heat, each with its band.
//
// Writes DIR/prediction.json (the summary's moments, the method, the flags), DIR/prediction_time.csv
// (every output time) and DIR/prediction.html (the plots and the moments), all or none, and a summary.
#include <iostream>

#include "cli_common.hpp"
#include "output_mode.hpp"
#include "lmcal/io/hash.hpp"
#include "lmcal/io/output_record.hpp"
#include "lmcal/fit/model_file.hpp"
#include "lmcal/predict/prediction.hpp"
#include "lmcal/report/predict_pages.hpp"
#include "progress.hpp"

namespace lmcal::cli {

namespace {

struct PredictOptions {
  std::string model, duty, output_dir = "fits/prediction", catalog_file;
  PredictionOptions prediction;
};

void run_predict(const PredictOptions& o, const std::vector<std::string>& argv) {
  const ModelFile model = read_model_file(o.model);
  const auto catalog = user_catalog(o.catalog_file);
  const DutyCycle duty = load_duty_cycle(o.duty, catalog ? &*catalog : nullptr, input_scope());
  const Prediction p = with_progress("prediction", [&](const Progress&) { return predict(model, duty, o.prediction); });
  const std::vector<std::pair<std::string, std::string>> inputs = {{o.model, sha256_file(o.model)}, {o.duty, sha256_file(o.duty)}};
  const std::string written = write_outputs(o.output_dir, {{"prediction.json", with_output_record(prediction_json(p, duty, model, argv), argv, &inputs, &output_mode().options)},
                                                           {"prediction_time.csv", prediction_time_csv(p)},
                                                           {"prediction.html", prediction_html(p, duty, argv)}});
  std::cout << prediction_summary(p) << "wrote " << written << "\n";
}

}  // namespace

void setup_predict(CLI::App& app, const std::vector<std::string>& argv) {
  auto o = std::make_shared<PredictOptions>();
  CLI::App* predict = app.add_subcommand(
      "predict", "The calibrated model over a duty cycle: rail temperature, elongation and scale error with 95 % bands");
  predict->add_option("model", o->model, "The calibrated model (model.toml written by lmcal calibrate)")->required();
  predict->add_option("duty", o->duty, "The duty cycle (TOML: segments of speed, load, stroke and duration)")->required();
  predict->add_option("-o,--output-dir", o->output_dir, "Output folder")->capture_default_str();
  predict->add_option("--samples", o->prediction.samples, "Parameter draws for the bands")->capture_default_str();
  predict->add_option("--seed", o->prediction.seed, "Seed of the draws")->capture_default_str();
  predict->add_option("--confidence", o->prediction.confidence, "Coverage of the bands")->capture_default_str();
  predict->add_option("--segments", o->prediction.half_rail_segments, "Rail model segments (half rail)")->capture_default_str();
  // --dt as every other command names it; --time-step, its first name, still read (not shown).
  hidden_alias(predict->add_option("--dt,--time-step", o->prediction.time_step_s, "Rail model time step, s")->capture_default_str(),
               "time-step");
  predict->add_option("--catalog", o->catalog_file, kCatalogHelp);
  predict->add_flag("--any-guide", o->prediction.any_guide,
                    "Predict a duty on another guide than the model was calibrated on (refused otherwise; noted in the outputs)")
      ->capture_default_str();
  predict->callback([o, &argv] { run_predict(*o, argv); });
}

}  // namespace lmcal::cli
