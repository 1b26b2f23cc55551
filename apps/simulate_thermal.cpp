// lmcal simulate thermal: rail temperature vs time at sensor positions and vs position
// (at the end of the run and at steady state), over sweeps of guide, velocity, load,
// preload, block length, contact length and stroke (the paper's Figs. 14-19).
//
// Writes PREFIX_time.csv, PREFIX_profile.csv and PREFIX.json (every input), and prints
// one line per case. With --reference each case is also run on a converged grid and
// step, and the difference is the numerical error of the chosen numerics.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "cli_common.hpp"
#include "progress.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/models/rail_thermal.hpp"

namespace lmcal::cli {

namespace {

struct ThermalSweepOptions {
  GuideOptions guide;
  FrictionOptions friction;
  std::vector<double> velocity_m_s{0.11};
  std::vector<double> load_N{3000};
  std::vector<double> preload_um;         // empty: the catalog's
  std::vector<double> block_length_mm;    // Lb for the friction law; empty: the catalog's
  std::vector<double> contact_length_mm;  // Lb1 for the heat input; empty: the catalog's
  std::vector<double> stroke_m{0.2};
  double heat_rate_W = NAN;               // set: skip the friction law
  double friction_temperature_C = NAN;    // unset: the initial temperature
  double alpha = 0.6;
  double h_W_m2K = 5.3;
  double rail_length_m = 0.6;
  std::vector<double> sensors_m{0.0, 0.05, 0.1};
  double ambient_C = 26.0;
  std::string ambient_trace;  // "t:T,t:T,..."
  double initial_C = NAN;     // unset: the ambient at t = 0
  std::string source = "averaged";
  std::string scheme = "crank-nicolson";
  int segments = 100;
  double time_step_s = 60;
  double duration_s = 21600;
  double output_every_s = 300;
  bool reference = false;
  std::string output;
};

struct Case {
  std::string guide;
  double velocity_m_s, load_N, preload_um, block_length_mm, contact_length_mm, stroke_m;
  double heat_rate_W;
  RailGeometry geometry;
  RailParams<double> params;
};

AmbientTrace make_ambient(const ThermalSweepOptions& o) {
  if (o.ambient_trace.empty()) return AmbientTrace::constant(o.ambient_C);
  AmbientTrace trace;
  for (auto [t, T] : parse_pairs("--ambient-trace", o.ambient_trace)) {
    trace.time_s.push_back(t);
    trace.temperature_C.push_back(T);
  }
  return trace;
}

std::vector<Case> enumerate_cases(const ThermalSweepOptions& o, double initial_C) {
  std::vector<Case> cases;
  for (const auto& model : o.guide.guides) {
    const GuideSpec spec = o.guide.resolve(model);
    const double area = require(spec, &GuideSpec::area_m2, "area_m2");
    const double perimeter = require(spec, &GuideSpec::perimeter_m, "perimeter_m");
    RailParams<double> params{.heat_partition = o.alpha,
                              .h_W_m2K = o.h_W_m2K,
                              .conductivity_W_mK = require(spec, &GuideSpec::conductivity_W_mK, "conductivity_W_mK"),
                              .density_kg_m3 = require(spec, &GuideSpec::density_kg_m3, "density_kg_m3"),
                              .specific_heat_J_kgK = require(spec, &GuideSpec::specific_heat_J_kgK, "specific_heat_J_kgK"),
                              .initial_temperature_C = initial_C};
    const std::vector<double> preloads = std::isnan(o.heat_rate_W)
                                             ? or_catalog(o.preload_um, spec, &GuideSpec::preload_um, "preload_um")
                                             : (o.preload_um.empty() ? std::vector<double>{NAN} : o.preload_um);
    for (double V : o.velocity_m_s)
      for (double P : o.load_N)
        for (double pc : preloads)
          for (double Lb : or_catalog(o.block_length_mm, spec, &GuideSpec::block_length_mm, "block_length_mm"))
            for (double Lb1 : or_catalog(o.contact_length_mm, spec, &GuideSpec::contact_length_mm, "contact_length_mm"))
              for (double L1 : o.stroke_m) {
                Case c{spec.model, V, P, pc, Lb, Lb1, L1, o.heat_rate_W, {}, params};
                if (std::isnan(c.heat_rate_W)) {
                  const FrictionConditions<double> fc{.load_N = P, .preload_um = pc, .block_length_mm = Lb,
                                                      .velocity_m_s = V,
                                                      .temperature_C = std::isnan(o.friction_temperature_C)
                                                                           ? initial_C
                                                                           : o.friction_temperature_C};
                  validate(fc);
                  c.heat_rate_W = heat_rate_W(o.friction.constants, fc);
                }
                c.params.heat_rate_W = c.heat_rate_W;
                c.geometry = {.rail_length_m = o.rail_length_m, .area_m2 = area, .perimeter_m = perimeter,
                              .stroke_m = L1, .contact_length_m = Lb1 * 1e-3, .velocity_m_s = V};
                cases.push_back(c);
              }
  }
  return cases;
}

// A grid and step fine enough that their error is far below the published setup's:
// at least 8x the segments (>= 400) and a step of at most 5 s, Crank-Nicolson.
RailNumerics converged(const RailNumerics& n) {
  return {.source = n.source,
          .scheme = TimeScheme::crank_nicolson,
          .half_rail_segments = std::max(8 * n.half_rail_segments, 400),
          .time_step_s = std::min(n.time_step_s, 5.0)};
}

void run_simulate_thermal(const ThermalSweepOptions& o, const std::vector<std::string>& argv) {
  // The options by the names the user typed; the library re-checks everything it is given.
  require_in_range("--alpha", o.alpha, 0.0, 1.0);
  require_positive("--h", o.h_W_m2K);
  require_positive("--rail-length", o.rail_length_m);
  if (o.segments < 1) throw InvalidParameter("--segments", o.segments, "at least 1");
  require_positive("--dt", o.time_step_s);
  require_positive("--duration", o.duration_s);
  require_positive("--output-every", o.output_every_s);
  if (!std::isnan(o.heat_rate_W)) require_non_negative("--heat-rate", o.heat_rate_W);
  validate(o.friction.constants);
  const AmbientTrace ambient = make_ambient(o);
  const double initial_C = std::isnan(o.initial_C) ? ambient.temperature_C.front() : o.initial_C;
  const RailNumerics numerics{.source = parse_source_model(o.source),
                              .scheme = parse_time_scheme(o.scheme),
                              .half_rail_segments = o.segments,
                              .time_step_s = o.time_step_s};
  RailOutputs outputs{.duration_s = o.duration_s, .sensor_positions_m = o.sensors_m};
  for (double t = 0; t < o.duration_s; t += o.output_every_s) outputs.output_times_s.push_back(t);
  outputs.output_times_s.push_back(o.duration_s);
  outputs.profile_times_s = {o.duration_s};

  const std::vector<std::string> case_columns = {"case", "guide", "velocity_m_s", "load_N", "preload_um",
                                                 "block_length_mm", "contact_length_mm", "stroke_m", "heat_rate_W"};
  auto columns = [&](std::vector<std::string> extra) {
    std::vector<std::string> all = case_columns;
    all.insert(all.end(), extra.begin(), extra.end());
    return all;
  };
  CsvText time_csv(columns(o.reference ? std::vector<std::string>{"time_s", "sensor_x_m", "temperature_C",
                                                                   "reference_temperature_C"}
                                       : std::vector<std::string>{"time_s", "sensor_x_m", "temperature_C"}));
  CsvText profile_csv(columns({"profile", "x_m", "temperature_C"}));

  std::cout << fmt::format("{:>4}  {:<8} {:>7} {:>6} {:>7} {:>6} {:>7}  {:>8}  {}\n", "case", "guide", "V_m/s", "P_N",
                           "Lb_mm", "L1_m", "Q_W", "peak_dT", "T at end per sensor (C)");
  const std::vector<Case> cases = enumerate_cases(o, initial_C);
  nlohmann::json errors = nlohmann::json::array();
  TerminalProgress progress;
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const Case& c = cases[k];
    progress.step(k, cases.size(), "simulating case " + std::to_string(k));
    const auto sol = simulate_rail(c.geometry, numerics, outputs, c.params, ambient);
    const auto steady = steady_rail(c.geometry, numerics, {}, c.params, ambient.at(o.duration_s));
    RailSolution<double> ref;
    if (o.reference) ref = simulate_rail(c.geometry, converged(numerics), outputs, c.params, ambient);

    auto case_cells = [&](CsvText& csv) {
      csv.cell(double(k)).cell(c.guide).cell(c.velocity_m_s).cell(c.load_N).cell(c.preload_um);
      csv.cell(c.block_length_mm).cell(c.contact_length_mm).cell(c.stroke_m).cell(c.heat_rate_W);
    };
    std::vector<double> max_error(o.sensors_m.size(), 0.0);
    for (std::size_t t = 0; t < outputs.output_times_s.size(); ++t)
      for (std::size_t s = 0; s < o.sensors_m.size(); ++s) {
        case_cells(time_csv);
        time_csv.cell(outputs.output_times_s[t]).cell(o.sensors_m[s]).cell(sol.temperature_C(t, s));
        if (o.reference) {
          time_csv.cell(ref.temperature_C(t, s));
          max_error[s] = std::max(max_error[s], std::abs(sol.temperature_C(t, s) - ref.temperature_C(t, s)));
        }
        time_csv.end_row();
      }
    auto write_profile = [&](const char* name, const std::vector<double>& x, const std::vector<double>& T) {
      for (std::size_t i = 0; i < x.size(); ++i) {
        case_cells(profile_csv);
        profile_csv.cell(name).cell(x[i]).cell(T[i]);
        profile_csv.end_row();
      }
    };
    write_profile("end_of_run", sol.node_positions_m, sol.profiles_C.front());
    write_profile("steady_state", steady.node_positions_m, steady.profiles_C.front());

    const auto& peak = *std::max_element(steady.profiles_C.front().begin(), steady.profiles_C.front().end());
    std::string at_end;
    for (std::size_t s = 0; s < o.sensors_m.size(); ++s)
      at_end += fmt::format("{}{:.2f}", s ? " " : "", sol.temperature_C(outputs.output_times_s.size() - 1, s));
    progress.clear();
    std::cout << fmt::format("{:>4}  {:<8} {:>7.3f} {:>6.0f} {:>7.1f} {:>6.3f} {:>7.3f}  {:>8.2f}  {}\n", k, c.guide,
                             c.velocity_m_s, c.load_N, c.block_length_mm, c.stroke_m, c.heat_rate_W,
                             peak - ambient.at(o.duration_s), at_end);
    if (o.reference) {
      std::string e;
      for (std::size_t s = 0; s < o.sensors_m.size(); ++s)
        e += fmt::format("{}x={} m: {:.4f} K", s ? ", " : "", o.sensors_m[s], max_error[s]);
      std::cout << "      numerical error (max over time) vs converged reference: " << e << "\n";
      errors.push_back({{"case", k}, {"max_abs_error_K", max_error}});
    }
  }

  nlohmann::json record = run_record(argv);
  record["guide"] = o.guide.record();
  record["friction_constants"] = o.friction.record();
  record["heat_rate_W"] = std::isnan(o.heat_rate_W) ? nlohmann::json("from the friction law") : nlohmann::json(o.heat_rate_W);
  record["friction_temperature_C"] = std::isnan(o.friction_temperature_C) ? initial_C : o.friction_temperature_C;
  record["alpha"] = o.alpha;
  record["h_W_m2K"] = o.h_W_m2K;
  record["rail_length_m"] = o.rail_length_m;
  record["sensor_positions_m"] = o.sensors_m;
  record["ambient"] = {{"time_s", ambient.time_s}, {"temperature_C", ambient.temperature_C}};
  record["initial_temperature_C"] = initial_C;
  record["numerics"] = {{"source", to_string(numerics.source)},
                        {"scheme", to_string(numerics.scheme)},
                        {"half_rail_segments", numerics.half_rail_segments},
                        {"time_step_s", numerics.time_step_s},
                        {"duration_s", o.duration_s}};
  if (o.reference) {
    const RailNumerics r = converged(numerics);
    record["reference_numerics"] = {{"scheme", to_string(r.scheme)},
                                    {"half_rail_segments", r.half_rail_segments},
                                    {"time_step_s", r.time_step_s}};
    record["numerical_error"] = errors;
  }
  OutputSet out;
  out.add(o.output + "_time.csv", time_csv.str());
  out.add(o.output + "_profile.csv", profile_csv.str());
  out.add(o.output + ".json", record.dump(2) + "\n");
  out.commit();
  std::cout << fmt::format("wrote {0}_time.csv, {0}_profile.csv and {0}.json\n", o.output);
}

}  // namespace

void setup_simulate_thermal(CLI::App& parent, const std::vector<std::string>& argv) {
  auto o = std::make_shared<ThermalSweepOptions>();
  CLI::App* app = parent.add_subcommand("thermal", "Rail temperature over time and position (Figs. 14-19)");
  o->guide.add_to(*app);
  o->friction.add_to(*app);
  add_list(*app, "--velocity", o->velocity_m_s, "Speeds, m/s (default 0.11)");
  add_list(*app, "--load", o->load_N, "Block loads, N (default 3000)");
  add_list(*app, "--preload", o->preload_um, "Preload amounts, um (default: the catalog's)");
  add_list(*app, "--block-length", o->block_length_mm, "Block lengths Lb (friction), mm (default: the catalog's)");
  add_list(*app, "--contact-length", o->contact_length_mm, "Contact lengths Lb1 (heat input), mm (default: the catalog's)");
  add_list(*app, "--stroke", o->stroke_m, "Strokes L1, m (default 0.2)");
  app->add_option("--heat-rate", o->heat_rate_W, "Frictional heat Q_f, W (default: from the friction law)");
  app->add_option("--friction-temperature", o->friction_temperature_C,
                  "Temperature at which the friction law gives Q_f, C (default: the initial temperature)");
  app->add_option("--alpha", o->alpha, "Heat partition coefficient alpha")->capture_default_str();
  app->add_option("--h", o->h_W_m2K, "Convection coefficient, W/m2K")->capture_default_str();
  app->add_option("--rail-length", o->rail_length_m, "Rail length L, m (the paper does not report it)")
      ->capture_default_str();
  add_list(*app, "--sensors", o->sensors_m, "Sensor positions from the rail centre, m (default 0,0.05,0.1)");
  app->add_option("--ambient", o->ambient_C, "Constant ambient temperature, C")->capture_default_str();
  app->add_option("--ambient-trace", o->ambient_trace, "Ambient trace as time_s:temperature_C pairs, e.g. 0:26,21600:27");
  app->add_option("--initial", o->initial_C, "Initial rail temperature, C (default: the ambient at t = 0)");
  app->add_option("--source", o->source, "Heat source model: paper, averaged or moving")->capture_default_str();
  app->add_option("--scheme", o->scheme, "Time scheme: backward-euler (be) or crank-nicolson (cn)")->capture_default_str();
  app->add_option("--segments", o->segments, "Segments on the half rail")->capture_default_str();
  app->add_option("--dt", o->time_step_s, "Time step, s")->capture_default_str();
  app->add_option("--duration", o->duration_s, "Simulated time, s")->capture_default_str();
  app->add_option("--output-every", o->output_every_s, "Output interval, s")->capture_default_str();
  app->add_flag("--reference", o->reference, "Also run a converged reference and report the numerical error");
  app->add_option("-o,--output", o->output, "Output prefix: PREFIX_time.csv, PREFIX_profile.csv, PREFIX.json")
      ->required();
  app->callback([o, &argv] { run_simulate_thermal(*o, argv); });
}

}  // namespace lmcal::cli
