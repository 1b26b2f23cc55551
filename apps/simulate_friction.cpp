// lmcal simulate friction: friction force and heat rate over sweeps of V, P, pc, T, Lb and
// the direction (the paper's Figs. 4-7), one tidy CSV row per condition. With --model, the
// calibrated law of `lmcal calibrate` (model.toml): its constants and the effects it found.
#include <fmt/format.h>

#include <iostream>

#include "output_mode.hpp"
#include "cli_common.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/models/friction_effects.hpp"

namespace lmcal::cli {

namespace {

struct FrictionSweepOptions {
  GuideOptions guide;
  FrictionOptions friction;
  ModelOptions model;
  std::vector<double> velocity_m_s = parse_list("--velocity", "0.005:0.2:0.005");
  std::vector<double> load_N{3000};
  std::vector<double> preload_um;       // empty: the catalog's
  std::vector<double> temperature_C{26};
  std::vector<double> block_length_mm;  // empty: the catalog's
  std::vector<double> direction{1};     // +1 forward, -1 backward (only an effect tells them apart)
  std::string output;
};

void run_simulate_friction(const FrictionSweepOptions& o, const std::vector<std::string>& argv) {
  const std::optional<LoadedModel> model = LoadedModel::read(o.model, "friction");
  const FrictionLaw law = o.friction.law(model ? &*model : nullptr);
  validate(law.constants);
  for (double d : o.direction)
    if (d != 1 && d != -1) throw InvalidParameter("--direction", d, "+1 or -1");
  // The published law's three terms; effects_N is what the effects add to them.
  // With a model's empirical terms: what they add (at steady state: decays and lags settled)
  // and whether a condition lies beyond the data they were learned on.
  std::vector<std::string> columns{"guide", "velocity_m_s", "load_N", "preload_um", "block_length_mm", "temperature_C",
                                   "direction", "viscosity_mm2_s", "coulomb_N", "stribeck_N", "viscous_N", "effects_N"};
  if (!law.terms.empty()) columns.insert(columns.end(), {"empirical_N", "extrapolated"});
  columns.insert(columns.end(), {"friction_N", "heat_W"});
  CsvText csv(columns);
  std::size_t extrapolated = 0;
  std::size_t rows = 0;
  for (const auto& guide : o.guide.guides) {
    const GuideSpec spec = o.guide.resolve(guide);
    for (double Lb : or_catalog(o.block_length_mm, spec, &GuideSpec::block_length_mm, "block_length_mm"))
      for (double pc : or_catalog(o.preload_um, spec, &GuideSpec::preload_um, "preload_um"))
        for (double P : o.load_N)
          for (double T : o.temperature_C)
            for (double direction : o.direction)
              for (double V : o.velocity_m_s) {
                const FrictionConditions<double> c{.load_N = P, .preload_um = pc, .block_length_mm = Lb,
                                                   .velocity_m_s = V, .temperature_C = T, .direction = direction};
                validate(c);
                const auto f = friction_breakdown(law.constants, c);
                const double with_effects_N = friction_force_with_effects_N(law.constants, law.effects, c);
                double empirical_N = 0;
                bool outside = false;
                if (!law.terms.empty()) empirical_N = steady_terms_N(law.terms, law.constants, law.effects, c, &outside);
                const double friction_N = with_effects_N + empirical_N;
                // The last check before the row leaves: validate() keeps the conditions in a rig's
                // ranges, but a model's constants may still take the law out of the doubles.
                for (double x : {f.viscosity_mm2_s, f.total_N(), with_effects_N, friction_N, friction_N * V})
                  if (!std::isfinite(x))
                    throw InvalidParameter("--velocity", V,
                                           fmt::format("a condition where the friction law is finite (at load {} N, {} °C, "
                                                       "preload {} um, block {} mm it gives {} N)",
                                                       P, T, pc, Lb, friction_N));
                csv.cell(spec.model).cell(V).cell(P).cell(pc).cell(Lb).cell(T).cell(direction).cell(f.viscosity_mm2_s);
                csv.cell(f.coulomb_N).cell(f.stribeck_N).cell(f.viscous_N).cell(with_effects_N - f.total_N());
                if (!law.terms.empty()) csv.cell(empirical_N).cell(outside ? 1 : 0);
                extrapolated += outside ? 1 : 0;
                csv.cell(friction_N).cell(friction_N * V);
                csv.end_row();
                ++rows;
              }
  }
  nlohmann::json record = run_record(argv);
  record["guide"] = o.guide.record();
  law.record_into(record);
  if (model) model->record_into(record);
  if (!law.terms.empty()) {
    std::vector<std::string> symbols;
    for (std::size_t t = 0; t < law.terms.size(); ++t) symbols.push_back(law.terms[t].symbol(t + 1));
    record["empirical_terms"] = {
        {"symbols", symbols},
        {"note", "learned from the residuals, not named causes; at steady state (terms in time, sliding distance "
                 "or a lagged temperature have settled to 0, the run index and the campaign's time stay where the "
                 "campaign ended); rows with extrapolated = 1 lie beyond the data they were learned on"},
        {"extrapolated_rows", extrapolated}};
  }
  OutputSet out;
  out.add(o.output, csv.str());
  out.add(o.output + ".json", record.dump(2) + "\n");
  offer_machine_output(o.output + ".json", true);
  out.commit();
  if (model)
    std::cout << fmt::format("the calibrated friction law of {} (set {}, lmcal {}); effects: {}\n", model->file,
                             model->model.set, model->model.lmcal_version, law.effects_text());
  if (!law.terms.empty())
    std::cout << fmt::format("with {} empirical term(s) (not named causes, at steady state); {} of {} conditions lie beyond "
                             "the data they were learned on (extrapolated = 1)\n",
                             law.terms.size(), extrapolated, rows);
  std::cout << fmt::format("wrote {} conditions to {} (inputs in {}.json)\n", rows, o.output, o.output);
}

}  // namespace

void setup_simulate_friction(CLI::App& parent, const std::vector<std::string>& argv) {
  auto options = std::make_shared<FrictionSweepOptions>();
  CLI::App* app = parent.add_subcommand("friction", "Friction force and heat rate over sweeps (Figs. 4-7)");
  options->guide.add_to(*app);
  options->friction.add_to(*app);
  options->model.add_to(*app, "Calibrated model (model.toml of lmcal calibrate): the friction law with its effects");
  add_list(*app, "--velocity", options->velocity_m_s, "Speeds, m/s (default 0.005:0.2:0.005)");
  add_list(*app, "--load", options->load_N, "Block loads, N (default 3000)");
  add_list(*app, "--preload", options->preload_um, "Preload amounts, um (default: the catalog's)");
  add_list(*app, "--temperature", options->temperature_C, "Lubricant temperatures, C (default 26)");
  add_list(*app, "--block-length", options->block_length_mm, "Block lengths Lb, mm (default: the catalog's)");
  add_list(*app, "--direction", options->direction, "Directions of travel, +1 and/or -1 (default 1)");
  app->add_option("-o,--output", options->output, "Output CSV (a .json with the inputs is written beside it)")
      ->required();
  app->callback([options, &argv] { run_simulate_friction(*options, argv); });
}

}  // namespace lmcal::cli
