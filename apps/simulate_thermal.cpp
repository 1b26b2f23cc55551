// lmcal simulate thermal: rail temperature vs time at sensor positions and vs position
// (at the end of the run and at steady state), over sweeps of guide, velocity, load,
// preload, block length, contact length and stroke (the paper's Figs. 14-19).
//
// Writes PREFIX_time.csv, PREFIX_profile.csv and PREFIX.json (every input), and prints
// one line per case. With --reference each case is also run on a converged grid and
// step, and the difference is the numerical error of the chosen numerics. With --model, the
// calibrated model of `lmcal calibrate` (model.toml): α, h, the source model and the
// mechanisms of its [thermal], the heat rate from the friction law of its [friction].
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>

#include "output_mode.hpp"
#include "cli_common.hpp"
#include "progress.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/io/units.hpp"
#include "lmcal/models/friction_effects.hpp"
#include "lmcal/models/rail_thermal.hpp"
#include "lmcal/predict/prediction.hpp"

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
  double stop_s = NAN;                    // set: the block stops (no heat) from then on
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
  ModelOptions model;
  std::vector<const CLI::Option*> rail_options;  // --alpha, --h, --source: what a model's [thermal] gives
};

// The rail model simulated: from the options, or a calibrated model's [thermal].
struct RailModel {
  double alpha = 0.6, h_W_m2K = 5.3;
  SourceModel source = SourceModel::averaged;
  std::vector<std::string> mechanisms;                    // of the thermal extension library
  std::vector<std::pair<std::string, double>> values;     // their parameters, name -> value
  bool h_from_model = false;
};

RailModel rail_model(const ThermalSweepOptions& o, const LoadedModel* model) {
  if (!model) return {.alpha = o.alpha, .h_W_m2K = o.h_W_m2K, .source = parse_source_model(o.source)};
  model->refuse(given(o.rail_options), "the rail model (alpha, h and the source model, with its mechanisms)");
  const ModelFile& m = model->model;
  return {.alpha = m.alpha, .h_W_m2K = m.h_W_m2K.value_or(o.h_W_m2K), .source = m.source, .mechanisms = m.mechanisms,
          .values = m.mechanism_parameters, .h_from_model = m.h_W_m2K.has_value()};
}

bool has_mechanism(const RailModel& rail, const char* name) {
  return std::find(rail.mechanisms.begin(), rail.mechanisms.end(), name) != rail.mechanisms.end();
}

double value_of(const RailModel& rail, const char* name) {
  for (const auto& [n, v] : rail.values)
    if (n == name) return v;
  return NAN;
}

struct Case {
  std::string guide;
  double velocity_m_s, load_N, preload_um, block_length_mm, contact_length_mm, stroke_m;
  double heat_rate_W;  // at the start
  RailGeometry geometry;
  RailParams<double> params;
  FrictionConditions<double> conditions;  // behind the heat rate (a coupled heat rate follows the rail)
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

std::vector<Case> enumerate_cases(const ThermalSweepOptions& o, double initial_C, const RailModel& rail,
                                  const FrictionLaw& law) {
  std::vector<Case> cases;
  for (const auto& model : o.guide.guides) {
    const GuideSpec spec = o.guide.resolve(model);
    RailParams<double> params = rail_material_of(spec);
    params.heat_partition = rail.alpha;
    params.h_W_m2K = rail.h_W_m2K;
    params.initial_temperature_C = initial_C;
    // A given heat rate needs no friction conditions, unless a mechanism makes it follow the law.
    const bool law_needed = std::isnan(o.heat_rate_W) || !rail.mechanisms.empty();
    const auto law_input = [&](const std::vector<double>& given, std::optional<double> GuideSpec::*field, const char* name) {
      return law_needed ? or_catalog(given, spec, field, name) : (given.empty() ? std::vector<double>{NAN} : given);
    };
    const std::vector<double> preloads = law_input(o.preload_um, &GuideSpec::preload_um, "preload_um");
    const std::vector<double> block_lengths = law_input(o.block_length_mm, &GuideSpec::block_length_mm, "block_length_mm");
    for (double V : o.velocity_m_s)
      for (double P : o.load_N)
        for (double pc : preloads)
          for (double Lb : block_lengths)
            for (double Lb1 : or_catalog(o.contact_length_mm, spec, &GuideSpec::contact_length_mm, "contact_length_mm"))
              for (double L1 : o.stroke_m) {
                Case c{spec.model, V, P, pc, Lb, Lb1, L1, o.heat_rate_W, {}, params, {}};
                c.conditions = {.load_N = P, .preload_um = pc, .block_length_mm = Lb, .velocity_m_s = V,
                                .temperature_C = std::isnan(o.friction_temperature_C) ? initial_C : o.friction_temperature_C};
                if (law_needed) validate(c.conditions);
                if (std::isnan(c.heat_rate_W)) c.heat_rate_W = heat_rate_with_effects_W(law.constants, law.effects, c.conditions);
                c.params.heat_rate_W = c.heat_rate_W;
                if (!std::isnan(o.stop_s))
                  c.params.heat_schedule = HeatRateSchedule<double>::steps({0.0, o.stop_s}, {c.heat_rate_W, 0.0});
                c.geometry = rail_geometry_of(spec, o.rail_length_m, L1, Lb1 * 1e-3, V);
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

// One case's transient: the plain rail model, or with the mechanisms of a calibrated model.
RailSolution<double> simulate_case(const Case& c, const RailNumerics& numerics, const RailOutputs& outputs,
                                   const RailParams<double>& params, const AmbientTrace& ambient, const RailModel& rail,
                                   const FrictionLaw& law) {
  if (rail.mechanisms.empty()) return simulate_rail(c.geometry, numerics, outputs, params, ambient);
  return simulate_rail_with_mechanisms(c.geometry, numerics, outputs, params, ambient, law.constants, law.effects,
                                       c.conditions, rail.mechanisms, rail.values);
}

// Every case's transient. Cases on one rail whose source is static (the block's speed does
// not enter) and whose heat is constant run together, four in SIMD lanes (simulate_rails:
// the same numbers as one by one); the rest one by one.
std::vector<RailSolution<double>> simulate_cases(const std::vector<Case>& cases, const RailNumerics& numerics,
                                                 const RailOutputs& outputs, const AmbientTrace& ambient,
                                                 const RailModel& rail, const FrictionLaw& law) {
  std::vector<RailSolution<double>> out(cases.size());
  const bool lanes = rail.mechanisms.empty() && numerics.source != SourceModel::moving && !outputs.energy_balance;
  auto same_rail = [](const RailGeometry& a, const RailGeometry& b) {
    return a.rail_length_m == b.rail_length_m && a.area_m2 == b.area_m2 && a.perimeter_m == b.perimeter_m &&
           a.stroke_m == b.stroke_m && a.contact_length_m == b.contact_length_m;
  };
  std::vector<bool> done(cases.size(), false);
  for (std::size_t k = 0; k < cases.size() && lanes; ++k) {
    if (done[k] || !cases[k].params.heat_schedule.empty()) continue;
    std::vector<std::size_t> group;
    for (std::size_t j = k; j < cases.size(); ++j)
      if (!done[j] && cases[j].params.heat_schedule.empty() && same_rail(cases[j].geometry, cases[k].geometry))
        group.push_back(j);
    if (group.size() < 2) continue;
    std::vector<RailParams<double>> params;
    for (std::size_t j : group) params.push_back(cases[j].params);
    auto solutions = simulate_rails(cases[k].geometry, numerics, outputs, params,
                                    std::vector<AmbientTrace>(group.size(), ambient));
    for (std::size_t i = 0; i < group.size(); ++i) {
      out[group[i]] = std::move(solutions[i]);
      done[group[i]] = true;
    }
  }
  for (std::size_t k = 0; k < cases.size(); ++k)
    if (!done[k]) out[k] = simulate_case(cases[k], numerics, outputs, cases[k].params, ambient, rail, law);
  return out;
}

// The steady state under the ambient at the end, along the rail, with its heat rate.
struct SteadyState {
  std::vector<double> x_m, temperature_C;
  double heat_rate_W = 0;
  double last_change_K = 0;  // with mechanisms: the largest change over the last 2 of the 40 time constants
};

// Exact for the plain model (steady_rail). A mechanism may make the heat follow the rail
// (coupling), so with mechanisms it is the long-time limit: backward Euler over 40 time
// constants ρcA/(hp) of the rail, in steps of 1/20 of one, from the ambient.
SteadyState steady_state(const Case& c, const RailNumerics& numerics, double ambient_C, const RailModel& rail,
                         const FrictionLaw& law) {
  if (rail.mechanisms.empty()) {
    const auto steady = steady_rail(c.geometry, numerics, {}, c.params, ambient_C);
    return {steady.node_positions_m, steady.profiles_C.front(), c.heat_rate_W};
  }
  const double tau_s =
      c.params.density_kg_m3 * c.params.specific_heat_J_kgK * c.geometry.area_m2 / (c.params.h_W_m2K * c.geometry.perimeter_m);
  RailNumerics long_run = numerics;
  long_run.scheme = TimeScheme::backward_euler;
  long_run.time_step_s = tau_s / 20;
  const RailOutputs outputs{.duration_s = 40 * tau_s, .output_times_s = {40 * tau_s}, .profile_times_s = {38 * tau_s, 40 * tau_s}};
  RailParams<double> params = c.params;
  params.initial_temperature_C = ambient_C;
  const auto sol = simulate_case(c, long_run, outputs, params, AmbientTrace::constant(ambient_C), rail, law);
  SteadyState out{sol.node_positions_m, sol.profiles_C.back(), sol.heat_rate_W.back()};
  for (std::size_t i = 0; i < out.x_m.size(); ++i)
    out.last_change_K = std::max(out.last_change_K, std::abs(sol.profiles_C[1][i] - sol.profiles_C[0][i]));
  return out;
}

// What the calibrated model brings, in words (stdout) and in the record.
void describe_model(const LoadedModel& model, const RailModel& rail, const FrictionLaw& law, nlohmann::json& record) {
  const ModelFile& m = model.model;
  const std::string mechanisms = fmt::format("{}", fmt::join(rail.mechanisms, ", "));
  std::string values;
  for (const auto& [name, value] : rail.values) values += fmt::format("{}{} = {:.4g}", values.empty() ? "" : ", ", name, value);
  std::cout << fmt::format("model {} (set {}, lmcal {}): alpha = {:.4g}, h = {:.4g} W/m2K{}, source {}; mechanisms: {}{}\n",
                           model.file, m.set, m.lmcal_version, rail.alpha, rail.h_W_m2K,
                           rail.h_from_model ? "" : " (not in the model: the default)", to_string(rail.source),
                           mechanisms.empty() ? "none" : mechanisms, values.empty() ? "" : " (" + values + ")");
  std::cout << "heat rate: "
            << (m.has_friction ? "the model's friction law, effects: " + law.effects_text()
                               : std::string("the model has no [friction]: the friction constants given (default the paper's)"))
            << "\n";
  record["mechanisms"] = rail.mechanisms;
  record["mechanism_parameters"] = nlohmann::json::object();
  for (const auto& [name, value] : rail.values) record["mechanism_parameters"][name] = value;
  record["h_W_m2K_from"] = rail.h_from_model ? "the model" : "the default (the model file has no h_W_m2K)";
  if (has_mechanism(rail, "tc_lag")) {
    const std::string note = fmt::format(
        "tc_lag (tau = {:.4g} s) is a property of the thermocouples, not of the rail: the simulated temperature is the "
        "rail's own; a thermocouple would read it through a first-order lag of tau",
        value_of(rail, "tc_lag"));
    record["sensor_note"] = note;
    std::cout << "note: " << note << "\n";
  }
}

// The options by the names the user typed; the library re-checks everything it is given.
void check_sweep_options(const ThermalSweepOptions& o) {
  require_in_range("--alpha", o.alpha, 0.0, 1.0);
  require_positive("--h", o.h_W_m2K);
  require_positive("--rail-length", o.rail_length_m);
  if (o.segments < 1) throw InvalidParameter("--segments", o.segments, "at least 1");
  require_positive("--dt", o.time_step_s);
  require_positive("--duration", o.duration_s);
  require_positive("--output-every", o.output_every_s);
  if (!std::isnan(o.heat_rate_W)) require_in_range("--heat-rate", o.heat_rate_W, 0.0, kHeatRateRange.high);
  for (double V : o.velocity_m_s) require_in_range("--velocity", V, 0.0, physical_range(Quantity::velocity).high);
  if (!std::isnan(o.stop_s) && !(o.stop_s > 0 && o.stop_s < o.duration_s))
    throw InvalidParameter("--stop", o.stop_s, "a time within the run (0 < stop < --duration)");
}

// The sweep's two tables: every case's temperatures over time at the sensors (and the
// reference's), and its profiles along the rail; each row starts with the case's cells.
struct SweepTables {
  CsvText time_csv, profile_csv;
};

SweepTables sweep_tables(bool reference) {
  const std::vector<std::string> case_columns = {"case", "guide", "velocity_m_s", "load_N", "preload_um",
                                                 "block_length_mm", "contact_length_mm", "stroke_m", "heat_rate_W"};
  auto columns = [&](std::vector<std::string> extra) {
    std::vector<std::string> all = case_columns;
    all.insert(all.end(), extra.begin(), extra.end());
    return all;
  };
  return {CsvText(columns(reference ? std::vector<std::string>{"time_s", "sensor_x_m", "temperature_C", "reference_temperature_C"}
                                    : std::vector<std::string>{"time_s", "sensor_x_m", "temperature_C"})),
          CsvText(columns({"profile", "x_m", "temperature_C"}))};
}

// The case's cells of a row; heat_rate_W: Q_f at that time (it follows the rail with a coupled
// heat rate).
void case_cells(CsvText& csv, std::size_t k, const Case& c, double heat_rate_W) {
  // A given heat rate needs no preload or block length: their cells are empty (not NaN).
  const auto used = [&](double v) -> CsvText& { return std::isnan(v) ? csv.cell("") : csv.cell(v); };
  csv.cell(double(k)).cell(c.guide).cell(c.velocity_m_s).cell(c.load_N);
  used(c.preload_um);
  used(c.block_length_mm);
  csv.cell(c.contact_length_mm).cell(c.stroke_m).cell(heat_rate_W);
}

// The last check before case k's numbers leave: the run, its steady state and the reference.
void require_physical(std::size_t k, const Case& c, const RailSolution<double>& sol, const SteadyState& steady,
                      const RailSolution<double>& ref) {
  RailSolution<double> steady_as_run;
  steady_as_run.profiles_C = {steady.temperature_C};
  steady_as_run.heat_rate_W = {steady.heat_rate_W};
  for (const RailSolution<double>* run : std::array<const RailSolution<double>*, 3>{&sol, &steady_as_run, &ref}) {
    const std::string runaway =
        runaway_of(*run, fmt::format("velocity_m_s = {}, load_N = {}, stroke_m = {}, heat_rate_W = {}", c.velocity_m_s,
                                     c.load_N, c.stroke_m, c.heat_rate_W));
    if (!runaway.empty()) throw InvalidParameter(fmt::format("case {}", k), runaway);
  }
}

// Case k's rows of both tables; the largest difference from the reference at each sensor.
std::vector<double> write_case_rows(const ThermalSweepOptions& o, std::size_t k, const Case& c, const RailOutputs& outputs,
                                    const RailSolution<double>& sol, const SteadyState& steady, const RailSolution<double>& ref,
                                    SweepTables& tables) {
  std::vector<double> max_error(o.sensors_m.size(), 0.0);
  for (std::size_t t = 0; t < outputs.output_times_s.size(); ++t)
    for (std::size_t s = 0; s < o.sensors_m.size(); ++s) {
      case_cells(tables.time_csv, k, c, sol.heat_rate_W[t]);
      tables.time_csv.cell(outputs.output_times_s[t]).cell(o.sensors_m[s]).cell(sol.temperature_C(t, s));
      if (o.reference) {
        tables.time_csv.cell(ref.temperature_C(t, s));
        max_error[s] = std::max(max_error[s], std::abs(sol.temperature_C(t, s) - ref.temperature_C(t, s)));
      }
      tables.time_csv.end_row();
    }
  auto write_profile = [&](const char* name, double heat_rate_W, const std::vector<double>& x, const std::vector<double>& T) {
    for (std::size_t i = 0; i < x.size(); ++i) {
      case_cells(tables.profile_csv, k, c, heat_rate_W);
      tables.profile_csv.cell(name).cell(x[i]).cell(T[i]);
      tables.profile_csv.end_row();
    }
  };
  write_profile("end_of_run", sol.heat_rate_W.back(), sol.node_positions_m, sol.profiles_C.front());
  write_profile("steady_state", steady.heat_rate_W, steady.x_m, steady.temperature_C);
  return max_error;
}

// Case k's line (and its notes) under the header run_simulate_thermal prints.
void print_case(const ThermalSweepOptions& o, std::size_t k, const Case& c, const RailOutputs& outputs,
                const RailSolution<double>& sol, const SteadyState& steady, double ambient_at_end_C,
                const std::vector<double>& max_error) {
  const double peak = *std::max_element(steady.temperature_C.begin(), steady.temperature_C.end());
  std::string at_end;
  for (std::size_t s = 0; s < o.sensors_m.size(); ++s)
    at_end += fmt::format("{}{:.2f}", s ? " " : "", sol.temperature_C(outputs.output_times_s.size() - 1, s));
  std::cout << fmt::format("{:>4}  {:<8} {:>7.3f} {:>6.0f} {:>7} {:>6.3f} {:>7.3f}  {:>8.2f}  {}\n", k, c.guide,
                           c.velocity_m_s, c.load_N,
                           std::isnan(c.block_length_mm) ? std::string("-") : fmt::format("{:.1f}", c.block_length_mm),
                           c.stroke_m, c.heat_rate_W,
                           peak - ambient_at_end_C, at_end);
  if (!std::isnan(o.stop_s))
    std::cout << fmt::format("      the block stops at {:g} s: no heat from then on; the steady state is the running block's\n",
                             o.stop_s);
  else if (sol.heat_rate_W.back() != sol.heat_rate_W.front())
    std::cout << fmt::format("      Q_f follows the rail: {:.3f} W at the end of the run, {:.3f} W at steady state\n",
                             sol.heat_rate_W.back(), steady.heat_rate_W);
  if (o.reference) {
    std::string e;
    for (std::size_t s = 0; s < o.sensors_m.size(); ++s)
      e += fmt::format("{}x={} m: {:.4f} K", s ? ", " : "", o.sensors_m[s], max_error[s]);
    std::cout << "      numerical error (max over time) vs converged reference: " << e << "\n";
  }
}

// The sweep's inputs and numerics into its record (the cases' steady-state changes and numerical
// errors: `steady_changes`, `errors`).
void record_sweep(const ThermalSweepOptions& o, const RailModel& rail, const FrictionLaw& law, const AmbientTrace& ambient,
                  double initial_C, const RailNumerics& numerics, const nlohmann::json& steady_changes,
                  const nlohmann::json& errors, nlohmann::json& record) {
  record["guide"] = o.guide.record();
  law.record_into(record);
  record["heat_rate_W"] = std::isnan(o.heat_rate_W) ? nlohmann::json("from the friction law") : nlohmann::json(o.heat_rate_W);
  record["friction_temperature_C"] = std::isnan(o.friction_temperature_C) ? initial_C : o.friction_temperature_C;
  record["alpha"] = rail.alpha;
  record["h_W_m2K"] = rail.h_W_m2K;
  record["rail_length_m"] = o.rail_length_m;
  record["sensor_positions_m"] = o.sensors_m;
  record["ambient"] = {{"time_s", ambient.time_s}, {"temperature_C", ambient.temperature_C}};
  record["initial_temperature_C"] = initial_C;
  record["numerics"] = {{"source", to_string(numerics.source)},
                        {"scheme", to_string(numerics.scheme)},
                        {"half_rail_segments", numerics.half_rail_segments},
                        {"time_step_s", numerics.time_step_s},
                        {"duration_s", o.duration_s}};
  if (!rail.mechanisms.empty())
    record["steady_state"] = {{"method", "long-time limit: backward Euler over 40 rail time constants rho c A / (h p), "
                                         "steps of 1/20 of one, at the ambient at the end"},
                              {"cases", steady_changes}};
  if (o.reference) {
    const RailNumerics r = converged(numerics);
    record["reference_numerics"] = {{"scheme", to_string(r.scheme)},
                                    {"half_rail_segments", r.half_rail_segments},
                                    {"time_step_s", r.time_step_s}};
    record["numerical_error"] = errors;
  }
}

void run_simulate_thermal(const ThermalSweepOptions& o, const std::vector<std::string>& argv) {
  check_sweep_options(o);
  const std::optional<LoadedModel> model = LoadedModel::read(o.model, "thermal");
  const RailModel rail = rail_model(o, model ? &*model : nullptr);
  const FrictionLaw law = o.friction.law(model ? &*model : nullptr);
  validate(law.constants);
  // simulate_rail_with_mechanisms takes a heat rate <= 0 as "from the law".
  if (!rail.mechanisms.empty() && !std::isnan(o.heat_rate_W) && !(o.heat_rate_W > 0))
    throw InvalidParameter("--heat-rate", o.heat_rate_W, "a value > 0 with a model's mechanisms");
  const AmbientTrace ambient = make_ambient(o);
  const double initial_C = std::isnan(o.initial_C) ? ambient.temperature_C.front() : o.initial_C;
  const RailNumerics numerics{.source = rail.source,
                              .scheme = parse_time_scheme(o.scheme),
                              .half_rail_segments = o.segments,
                              .time_step_s = o.time_step_s};
  RailOutputs outputs{.duration_s = o.duration_s, .sensor_positions_m = o.sensors_m};
  for (double t = 0; t < o.duration_s; t += o.output_every_s) outputs.output_times_s.push_back(t);
  outputs.output_times_s.push_back(o.duration_s);
  outputs.profile_times_s = {o.duration_s};
  SweepTables tables = sweep_tables(o.reference);

  nlohmann::json record = run_record(argv);
  if (model) {
    model->record_into(record);
    describe_model(*model, rail, law, record);
  }
  std::cout << fmt::format("{:>4}  {:<8} {:>7} {:>6} {:>7} {:>6} {:>7}  {:>8}  {}\n", "case", "guide", "V_m/s", "P_N",
                           "Lb_mm", "L1_m", "Q_W", "peak_dT", "T at end per sensor (C)");
  const std::vector<Case> cases = enumerate_cases(o, initial_C, rail, law);
  nlohmann::json errors = nlohmann::json::array(), steady_changes = nlohmann::json::array();
  TerminalProgress progress;
  progress.step(0, 2, "simulating " + std::to_string(cases.size()) + " cases");
  const std::vector<RailSolution<double>> solutions = simulate_cases(cases, numerics, outputs, ambient, rail, law);
  const std::vector<RailSolution<double>> references =
      o.reference ? simulate_cases(cases, converged(numerics), outputs, ambient, rail, law) : std::vector<RailSolution<double>>{};
  progress.step(1, 2, "steady states and outputs");
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const SteadyState steady = steady_state(cases[k], numerics, ambient.at(o.duration_s), rail, law);
    const RailSolution<double> ref = o.reference ? references[k] : RailSolution<double>{};
    require_physical(k, cases[k], solutions[k], steady, ref);
    const std::vector<double> max_error = write_case_rows(o, k, cases[k], outputs, solutions[k], steady, ref, tables);
    progress.clear();
    print_case(o, k, cases[k], outputs, solutions[k], steady, ambient.at(o.duration_s), max_error);
    if (!rail.mechanisms.empty()) steady_changes.push_back({{"case", k}, {"last_change_K", steady.last_change_K}});
    if (o.reference) errors.push_back({{"case", k}, {"max_abs_error_K", max_error}});
  }

  record_sweep(o, rail, law, ambient, initial_C, numerics, steady_changes, errors, record);
  OutputSet out;
  out.add(o.output + "_time.csv", tables.time_csv.str());
  out.add(o.output + "_profile.csv", tables.profile_csv.str());
  out.add(o.output + ".json", record.dump(2) + "\n");
  offer_machine_output(o.output + ".json", true);
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
  app->add_option("--stop", o->stop_s,
                  "The block stops at this time, s: no heat from then on, the rail cools (the steady state "
                  "stays the running block's)");
  app->add_option("--friction-temperature", o->friction_temperature_C,
                  "Temperature at which the friction law gives Q_f, C (default: the initial temperature)");
  o->rail_options = {app->add_option("--alpha", o->alpha, "Heat partition coefficient alpha")->capture_default_str(),
                     app->add_option("--h", o->h_W_m2K, "Convection coefficient, W/m2K")->capture_default_str()};
  app->add_option("--rail-length", o->rail_length_m, "Rail length L, m (the paper does not report it)")
      ->capture_default_str();
  add_list(*app, "--sensors", o->sensors_m, "Sensor positions from the rail centre, m (default 0,0.05,0.1)");
  app->add_option("--ambient", o->ambient_C, "Constant ambient temperature, C")->capture_default_str();
  app->add_option("--ambient-trace", o->ambient_trace, "Ambient trace as time_s:temperature_C pairs, e.g. 0:26,21600:27");
  app->add_option("--initial", o->initial_C, "Initial rail temperature, C (default: the ambient at t = 0)");
  o->rail_options.push_back(
      completes(app->add_option("--source", o->source, "Heat source model: paper, averaged or moving"),
                {"paper", "averaged", "moving"})
          ->capture_default_str());
  o->model.add_to(*app, "Calibrated model (model.toml of lmcal calibrate): alpha, h, source and mechanisms of its "
                        "[thermal], the friction law of its [friction]");
  completes(app->add_option("--scheme", o->scheme, "Time scheme: backward-euler (be) or crank-nicolson (cn)"),
            {"backward-euler", "be", "crank-nicolson", "cn"})
      ->capture_default_str();
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
