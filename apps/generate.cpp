// lmcal generate: the virtual rig. Friction logs and thermal data sets with a known
// truth, realistic imperfections and optional named effects (virtual_rig.hpp).
//
//   lmcal generate friction -o DIR   -> DIR/friction.csv, DIR/friction_truth.json
//   lmcal generate friction --raw -o DIR -> DIR/friction.toml, DIR/friction/<run>.csv (raw
//                                       load-cell time series), DIR/friction_truth.json
//   lmcal generate axis -o DIR       -> DIR/friction.toml, DIR/friction/<run>.csv (a closed-loop
//                                       axis's drive log: position and drive force at 1 kHz),
//                                       DIR/friction_truth.json
//   lmcal generate thermal  -o DIR   -> DIR/thermal.toml, DIR/thermal/<run>.csv,
//                                       DIR/thermal_truth.json
#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>

#include "cli_common.hpp"
#include "progress.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/rig/axis_rig.hpp"
#include "lmcal/rig/fleet_rig.hpp"
#include "lmcal/rig/virtual_rig.hpp"

namespace lmcal::cli {

namespace {

namespace fs = std::filesystem;

struct GenerateOptions {
  std::map<std::string, double> effects;
  std::uint64_t seed = 1;
  std::string output;
  FrictionRigConfig friction;
  bool raw = false;  // raw load-cell time series
  RawFrictionRigConfig raw_rig;
  std::string raw_force_sign = "follows-motion";
  // generate axis: one trajectory per setup (its own defaults: one setup, one run)
  FrictionRigConfig axis_setup = [] {
    FrictionRigConfig c;
    c.guides = {"SRN 35C"};
    c.preload_um = {2.5};
    c.load_N = {1000};
    c.temperature_C = {26};
    c.runs = 1;
    return c;
  }();
  AxisRigConfig axis;
  std::string axis_controller{to_string(AxisRigConfig{}.controller)};
  std::string axis_reference{to_string(AxisRigConfig{}.reference)};
  bool axis_no_trajectory_keys = false;
  ThermalRigConfig thermal;
  std::string catalog_file;  // the user's catalog (its guides and bars)
  std::optional<GuideCatalog> catalog;
  std::string name = "synthetic";
  FleetRigConfig fleet;
  std::map<std::string, double> spread;  // --spread: replaces the default spreads when given
  std::vector<std::string> outliers, drifts;  // "U:NAME=VALUE"
};

RigEffects resolve_effects(const std::map<std::string, double>& given) {
  RigEffects effects;
  for (const auto& [name, value] : given) set_rig_effect(effects, name, value);
  return effects;
}

std::string command_line(const std::vector<std::string>& argv) {
  std::string line = "lmcal";
  for (std::size_t i = 1; i < argv.size(); ++i)
    line += argv[i].find_first_of(" \"'") == std::string::npos ? " " + argv[i] : " '" + argv[i] + "'";
  return line;
}

std::string active_effects(const RigEffects& effects) {
  std::string list;
  for (const auto& info : rig_effects()) {
    const double value = rig_effect(effects, info.name);
    if (value != info.neutral) list += fmt::format("{}{}={}", list.empty() ? "" : ", ", info.name, value);
  }
  return list.empty() ? "none" : list;
}

void run_generate_friction(GenerateOptions& o, const std::vector<std::string>& argv) {
  // The options by the names the user typed; the library re-checks everything it is given.
  require_autocorrelation("--noise-ar1", o.friction.noise_ar1);
  o.friction.seed = o.seed;
  o.catalog = user_catalog(o.catalog_file);
  if (o.catalog) o.friction.catalog = &*o.catalog;
  const RigEffects effects = resolve_effects(o.effects);
  const fs::path dir = o.output;
  const std::vector<std::string> comments = {
      "SYNTHETIC friction log made by the lmcal virtual rig, not measured.",
      "Command: " + command_line(argv),
      "Effects: " + active_effects(effects) + "; every true value is in friction_truth.json"};
  if (o.raw) {
    o.raw_rig.force_sign = parse_force_sign(o.raw_force_sign);
    const RawFrictionRigOutput made = with_progress("logging the raw runs", [&](const Progress&) {
      return generate_raw_friction_logs(o.friction, o.raw_rig, effects, comments);
    });
    OutputSet out;
    for (const auto& [file, text] : made.run_files) out.add(dir / file, text);
    out.add(dir / "friction.toml", made.manifest_toml);
    out.add(dir / "friction_truth.json", made.truth_json);
    out.commit();
    std::cout << fmt::format("wrote {} raw runs to {} (manifest {}, truth {})\n", made.run_names.size(),
                             (dir / "friction").string(), (dir / "friction.toml").string(),
                             (dir / "friction_truth.json").string());
    return;
  }
  const FrictionRigOutput made = generate_friction_log(o.friction, effects);
  OutputSet out;
  out.add(dir / "friction.csv", friction_log_csv(made.log, comments));
  out.add(dir / "friction_truth.json", made.truth_json);
  out.commit();
  std::cout << fmt::format("wrote {} in {} to {} (truth: {})\n", plural(made.log.size(), "sample"),
                           plural(made.log.run_names.size(), "run"), (dir / "friction.csv").string(),
                           (dir / "friction_truth.json").string());
}

void run_generate_axis(GenerateOptions& o, const std::vector<std::string>& argv) {
  require_autocorrelation("--current-noise-ar1", o.axis.current_noise_ar1);
  o.axis.controller = parse_axis_controller(o.axis_controller);
  o.axis.reference = parse_axis_reference(o.axis_reference);
  o.axis.trajectory_keys = !o.axis_no_trajectory_keys;
  o.axis_setup.seed = o.seed;
  o.catalog = user_catalog(o.catalog_file);
  if (o.catalog) o.axis_setup.catalog = &*o.catalog;
  const RigEffects effects = resolve_effects(o.effects);
  const fs::path dir = o.output;
  const std::vector<std::string> comments = {
      "SYNTHETIC closed-loop axis log made by the lmcal virtual rig, not measured.",
      "Command: " + command_line(argv),
      "Effects: " + active_effects(effects) + "; every true value is in friction_truth.json"};
  const AxisRigOutput made = with_progress("driving the axis", [&](const Progress&) {
    return generate_axis_logs(o.axis_setup, o.axis, effects, comments);
  });
  OutputSet out;
  for (const auto& [file, text] : made.run_files) out.add(dir / file, text);
  out.add(dir / "friction.toml", made.manifest_toml);
  out.add(dir / "friction_truth.json", made.truth_json);
  out.commit();
  std::cout << fmt::format("wrote {} of {} to {} (manifest {}, truth {})\n", plural(made.run_names.size(), "axis run"),
                           plural(made.traces.empty() ? 0 : made.traces.front().time_s.size(), "sample"),
                           (dir / "friction").string(), (dir / "friction.toml").string(),
                           (dir / "friction_truth.json").string());
}

void run_generate_thermal(GenerateOptions& o, const std::vector<std::string>& argv) {
  require_autocorrelation("--noise-ar1", o.thermal.noise_ar1);
  require_non_negative("--heat-variation", o.thermal.heat_variation);
  require_non_negative("--friction-gain-error", o.thermal.friction_gain_error);
  require_non_negative("--stated-friction-uncertainty", o.thermal.stated_friction_uncertainty);
  o.thermal.seed = o.seed;
  o.catalog = user_catalog(o.catalog_file);
  if (o.catalog) o.thermal.catalog = &*o.catalog;
  const RigEffects effects = resolve_effects(o.effects);
  const ThermalRigOutput made = with_progress("simulating the thermal runs", [&](const Progress&) {
    return generate_thermal_dataset(o.thermal, effects, o.name);
  });
  const fs::path dir = o.output;
  const std::vector<std::string> comments = {"SYNTHETIC thermal run made by the lmcal virtual rig, not measured.",
                                             "Command: " + command_line(argv),
                                             "Effects: " + active_effects(effects) +
                                                 "; every true value is in thermal_truth.json"};
  OutputSet out;
  ThermalDataSet placed = made.set;  // run files are relative to the data set's folder
  for (ThermalRun& run : placed.runs) {
    run.file = dir / run.file;
    out.add(run.file, thermal_trace_csv(run.trace, comments));
  }
  // A self-contained set: the user's catalog travels with it as catalog.toml (a manifest reads
  // only files inside its own folder).
  if (!placed.catalog_file.empty()) {
    std::ifstream in(o.catalog_file, std::ios::binary);
    placed.catalog_file = dir / "catalog.toml";
    out.add(placed.catalog_file, std::string(std::istreambuf_iterator<char>(in), {}));
  }
  out.add(dir / "thermal.toml", thermal_manifest_toml(placed, dir));
  out.add(dir / "thermal_truth.json", made.truth_json);
  out.commit();
  std::cout << fmt::format("wrote {} thermal runs of {} records to {} (manifest {}, truth {})\n", made.set.runs.size(),
                           made.set.runs.empty() ? 0 : made.set.runs.front().trace.size(), (dir / "thermal").string(),
                           (dir / "thermal.toml").string(), (dir / "thermal_truth.json").string());
}

// "U:NAME=VALUE" (unit 1-based): an outlier's factor or a drift's relative change.
FleetRigChange parse_change(const char* option, const std::string& text) {
  const auto colon = text.find(':'), equals = text.find('=');
  FleetRigChange c;
  try {
    if (colon == std::string::npos || equals == std::string::npos || equals < colon) throw std::invalid_argument(text);
    c.unit = std::stoul(text.substr(0, colon));
    c.parameter = text.substr(colon + 1, equals - colon - 1);
    c.value = std::stod(text.substr(equals + 1));
  } catch (const std::logic_error&) {
    throw InvalidParameter(option, fmt::format("'{}': expected UNIT:NAME=VALUE, e.g. 7:mu_v=1.4", text));
  }
  return c;
}

void run_generate_fleet(GenerateOptions& o) {
  FleetRigConfig& c = o.fleet;
  c.seed = o.seed;
  if (!o.spread.empty()) c.spread = o.spread;
  for (const auto& text : o.outliers) c.outliers.push_back(parse_change("--outlier", text));
  for (const auto& text : o.drifts) c.drifts.push_back(parse_change("--drift", text));
  const FleetRigOutput made = with_progress("generating the fleet", [&](const Progress&) { return generate_fleet(c); });
  OutputSet out;
  for (const auto& [file, text] : made.files) out.add(fs::path(o.output) / file, text);
  out.commit();
  std::cout << fmt::format("wrote {} sets of {} units to {} (fleet.toml; truth: fleet_truth.json)\n", made.sets, c.units,
                           o.output);
}

void add_common(CLI::App& app, GenerateOptions& o) {
  add_assignments(app, "--effect", o.effects,
                  "Switch on a named effect: --effect seal_drag=200 (repeatable; see lmcal generate effects)");
  app.add_option("--seed", o.seed, "Random seed (same seed, same data)")->capture_default_str();
  app.add_option("-o,--output-dir,--output", o.output, "Output folder")->required();
}

// lmcal generate friction: the sweep, the load cell's imperfections and the raw time series (--raw).
void setup_generate_friction(CLI::App& generate, const std::shared_ptr<GenerateOptions>& o, const std::vector<std::string>& argv) {
  CLI::App* friction = generate.add_subcommand("friction", "A friction log (load-cell CSV) and its truth");
  add_common(*friction, *o);
  FrictionRigConfig& f = o->friction;
  friction->add_option("--guide,--guides", f.guides, "Guide models (of the built-in catalog or --catalog), a list sweeps them")
      ->delimiter(',')
      ->capture_default_str();
  friction->add_option("--catalog", o->catalog_file, kCatalogHelp);
  add_list(*friction, "--preload", f.preload_um, "Preload amounts, um (default 1.5,2.5,4)");
  add_list(*friction, "--load", f.load_N, "Loads, N (default 1000,2000,3000)");
  add_list(*friction, "--velocity", f.velocity_m_s, "Speeds, m/s (default 0.002 ... 0.15)");
  add_list(*friction, "--temperature", f.temperature_C, "Temperatures, C (default 22,26,32,40)");
  friction->add_option("--runs", f.runs, "Repeats of the whole sweep")->capture_default_str();
  friction->add_flag("--one-setup-per-run", f.one_setup_per_run,
                     "Each setup (guide, preload, load, temperature) a run of its own, swept over speed and direction");
  friction->add_flag("--temperature-outermost", f.temperature_outermost,
                     "The temperature changes slowest: every other setup at one temperature before the next");
  friction->add_flag("--shuffle-runs", f.shuffle_runs,
                     "Make the runs in a random (seeded) order, not the design's: a run's place in the campaign then "
                     "does not follow its setup");

  friction->add_option("--noise", f.noise_N, "Load-cell noise per sample (sigma), N")->capture_default_str();
  friction->add_option("--run-offset", f.run_offset_N, "Zero offset per run (sigma), N")->capture_default_str();
  friction->add_option("--noise-ar1", f.noise_ar1, "Lag-1 autocorrelation of the load-cell noise within a run, [0, 1)")
      ->capture_default_str();
  auto* raw = friction->add_option_group("Raw load-cell logs", "--raw: time series of a rig moving back and forth");
  raw->add_flag("--raw", o->raw,
                "Raw load-cell time series, one run per setup, with a friction.toml manifest of the runs' conditions");
  raw->add_option("--sample-rate", o->raw_rig.sample_rate_Hz, "Samples per second, Hz")->capture_default_str();
  raw->add_option("--acceleration", o->raw_rig.acceleration_m_s2, "Acceleration of every move, m/s2")->capture_default_str();
  raw->add_option("--stroke", o->raw_rig.stroke_m, "Stroke, m")->capture_default_str();
  raw->add_option("--cycles", o->raw_rig.cycles, "Back-and-forth moves per speed")->capture_default_str();
  raw->add_option("--dwell", o->raw_rig.dwell_s, "Rest at each end, s")->capture_default_str();
  raw->add_option("--encoder-resolution", o->raw_rig.encoder_resolution_m, "Encoder step, m")->capture_default_str();
  raw->add_option("--moving-mass", o->raw_rig.moving_mass_kg, "Moving mass, kg (the force carries m*a)")->capture_default_str();
  raw->add_option("--drift", o->raw_rig.drift_N_per_h, "Load-cell zero drift, N/h")->capture_default_str();
  raw->add_flag("--log-velocity", o->raw_rig.log_velocity, "Log velocity_m_s instead of position_mm");
  raw->add_option("--force-sign", o->raw_force_sign, "How the logged force is signed: follows-motion, opposes-motion, magnitude")
      ->capture_default_str();
  friction->callback([o, &argv] { run_generate_friction(*o, argv); });
}

// lmcal generate axis: the setups, the axis's mechanics and controller, its reference and its log.
void setup_generate_axis(CLI::App& generate, const std::shared_ptr<GenerateOptions>& o, const std::vector<std::string>& argv) {
  CLI::App* axis = generate.add_subcommand(
      "axis", "A closed-loop positioning axis's own log (time, encoder position, drive force), a manifest and its truth");
  add_common(*axis, *o);
  FrictionRigConfig& as = o->axis_setup;
  AxisRigConfig& a = o->axis;
  axis->add_option("--guide,--guides", as.guides, "Guide models (of the built-in catalog or --catalog); a run per setup")
      ->delimiter(',')
      ->capture_default_str();
  axis->add_option("--catalog", o->catalog_file, kCatalogHelp);
  add_list(*axis, "--preload", as.preload_um, "Preload amounts, um (default 2.5)");
  add_list(*axis, "--load", as.load_N, "Loads, N (default 1000)");
  add_list(*axis, "--temperature", as.temperature_C, "Temperatures, C (default 26)");
  axis->add_option("--runs", as.runs, "Repeats of every setup")->capture_default_str();
  add_list(*axis, "--velocity", as.velocity_m_s, "Trapezoidal: the moves' top speeds, m/s (default 0.002 ... 0.15)");
  axis->add_option("--mass", a.moving_mass_kg, "Moving mass, kg")->capture_default_str();
  axis->add_option("--incline", a.incline_deg, "Axis incline, deg (0 horizontal, 90 vertical, +x up)")->capture_default_str();
  axis->add_option("--force-constant", a.force_constant_N_A, "Motor force constant K_f, N/A")->capture_default_str();
  completes(axis->add_option("--controller", o->axis_controller, "pd or p-pi (cascaded P position, PI velocity)"), {"pd", "p-pi"})
      ->capture_default_str();
  axis->add_option("--pd-bandwidth", a.pd_bandwidth_Hz, "pd: natural frequency, Hz")->capture_default_str();
  axis->add_option("--pd-damping", a.pd_damping, "pd: damping ratio")->capture_default_str();
  axis->add_option("--position-gain", a.position_gain_1_s, "p-pi: position gain, 1/s")->capture_default_str();
  axis->add_option("--velocity-bandwidth", a.velocity_bandwidth_Hz, "p-pi: velocity loop bandwidth, Hz")->capture_default_str();
  axis->add_option("--velocity-integral", a.velocity_integral_Hz, "p-pi: velocity loop integral corner, Hz")
      ->capture_default_str();
  axis->add_option("--feedforward", a.acceleration_feedforward, "Share of M*a_ref fed forward")->capture_default_str();
  completes(axis->add_option("--reference", o->axis_reference, "trapezoidal or sinusoid"), {"trapezoidal", "sinusoid"})
      ->capture_default_str();
  axis->add_option("--acceleration", a.acceleration_m_s2, "Trapezoidal: acceleration, m/s2")->capture_default_str();
  axis->add_option("--cruise", a.cruise_s, "Trapezoidal: cruise of every move, s (unless --stroke is shorter)")
      ->capture_default_str();
  axis->add_option("--stroke", a.stroke_m, "Trapezoidal: longest move, m")->capture_default_str();
  axis->add_option("--cycles", a.cycles, "Trapezoidal: out-and-back moves per speed")->capture_default_str();
  axis->add_option("--dwell", a.dwell_s, "Trapezoidal: pause at each end of a move, s")->capture_default_str();
  axis->add_option("--amplitude", a.sine_amplitude_m, "Sinusoid: amplitude, m")->capture_default_str();
  axis->add_option("--frequency", a.sine_frequency_Hz, "Sinusoid: frequency, Hz")->capture_default_str();
  axis->add_option("--duration", a.duration_s, "Sinusoid: length of a run, s")->capture_default_str();
  axis->add_option("--sample-rate", a.log_rate_Hz, "Log rate, Hz")->capture_default_str();
  axis->add_option("--substeps", a.substeps, "Control and integration steps per logged sample")->capture_default_str();
  axis->add_option("--encoder-resolution", a.encoder_resolution_m, "Encoder step, m")->capture_default_str();
  axis->add_option("--current-noise", a.current_noise_A, "Noise of the logged current (sigma), A")->capture_default_str();
  axis->add_option("--current-noise-ar1", a.current_noise_ar1, "Lag-1 autocorrelation of that noise, [0, 1)")
      ->capture_default_str();
  axis->add_option("--current-offset", a.current_offset_A, "Constant offset of the logged current, A")->capture_default_str();
  axis->add_flag("--no-trajectory-keys", o->axis_no_trajectory_keys,
                 "Leave segmentation and axis_incline_deg out of the manifest's [raw] table (for a plateau-only reader)");
  axis->callback([o, &argv] { run_generate_axis(*o, argv); });
}

// lmcal generate thermal: the rail, the runs' schedule, the sensors and their imperfections.
void setup_generate_thermal(CLI::App& generate, const std::shared_ptr<GenerateOptions>& o, const std::vector<std::string>& argv) {
  CLI::App* thermal = generate.add_subcommand("thermal", "A thermal data set (manifest + runs) and its truth");
  add_common(*thermal, *o);
  ThermalRigConfig& t = o->thermal;
  thermal->add_option("--name", o->name, "Data set name")->capture_default_str();
  thermal->add_option("--guide", t.guide, "Guide model (or a bar of --catalog)")->capture_default_str();
  thermal->add_option("--catalog", o->catalog_file, kCatalogHelp);
  add_assignments(*thermal, "--set", t.guide_overrides, "Override a catalog value: --set conductivity_W_mK=36");
  add_list(*thermal, "--velocity", t.velocity_m_s, "Speeds, m/s (default 0.066,0.083,0.11)");
  thermal->add_option("--repeats", t.repeats, "Runs per speed")->capture_default_str();
  thermal->add_option("--load", t.load_N, "Load, N")->capture_default_str();
  thermal->add_option("--alpha", t.alpha, "True heat partition alpha")->capture_default_str();
  thermal->add_option("--h", t.h_W_m2K, "True convection coefficient at rest, W/m2K")->capture_default_str();
  thermal->add_option("--rail-length", t.rail_length_m, "Rail length, m")->capture_default_str();
  thermal->add_option("--stroke", t.stroke_m, "Stroke, m")->capture_default_str();
  add_list(*thermal, "--sensors", t.sensor_position_m, "Thermocouple positions from the rail centre, m");
  thermal->add_option("--duration", t.duration_s, "Run length, s")->capture_default_str();
  thermal->add_option("--record-every", t.record_every_s, "Logger interval, s")->capture_default_str();
  thermal->add_option("--ambient", t.ambient_C, "Ambient at the start, C")->capture_default_str();
  thermal->add_option("--ambient-drift", t.ambient_drift_K_per_h, "Ambient drift, K/h")->capture_default_str();
  thermal->add_option("--noise", t.noise_K, "Temperature noise (sigma), K")->capture_default_str();
  thermal->add_option("--noise-ar1", t.noise_ar1, "Lag-1 autocorrelation of every temperature channel's noise, [0, 1)")
      ->capture_default_str();
  thermal->add_option("--heat-variation", t.heat_variation,
                      "Run-to-run variation of the heat reaching the rail (relative sigma; no logged value sees it)")
      ->capture_default_str();
  thermal->add_option("--friction-gain-error", t.friction_gain_error,
                      "Gain error of the load cell logging mean_friction_N (relative sigma, one per data set)")
      ->capture_default_str();
  thermal->add_option("--stated-friction-uncertainty", t.stated_friction_uncertainty,
                      "Write mean_friction_uncertainty_N = this x mean_friction_N for every run (0: not written)")
      ->capture_default_str();
  thermal->add_option("--tc-bias", t.tc_bias_K, "Thermocouple bias bound (uniform +-), K")->capture_default_str();
  thermal->add_option_function<double>("--heater", [&t](double W) { t.heat_rate_W = W; },
                                       "A heater run of this heat rate, W (heat_rate_W; no friction, no --velocity)");
  thermal->add_option_function<double>("--heater-off", [&t](double s) { t.heater_off_s = s; },
                                       "The heater switches off at this time, s; the run goes on cooling");
  thermal->add_option_function<double>("--stop", [&t](double s) { t.stop_s = s; },
                                       "The block stops at this time, s (a schedule phase with velocity 0)");
  thermal->add_option("--stated-heat-uncertainty", t.stated_heat_uncertainty,
                      "Write heat_rate_uncertainty_W = this x the heater's heat_rate_W (0: not written)")
      ->capture_default_str();
  thermal->add_flag_function("--no-ambient-columns", [&t](std::int64_t) { t.ambient_columns = false; },
                             "No ambient columns: the manifest's ambient_C (--ambient) instead");
  thermal->add_option("--ambient-wave", t.ambient_wave_K, "Amplitude of the ambient's 2 h wave, K")->capture_default_str();
  thermal->callback([o, &argv] { run_generate_thermal(*o, argv); });
}

// lmcal generate fleet: the units, their dates and their spread, outliers and drifts.
void setup_generate_fleet(CLI::App& generate, const std::shared_ptr<GenerateOptions>& o) {
  CLI::App* fleet = generate.add_subcommand(
      "fleet", "A fleet of units (a folder per unit, or per unit and date) with a known unit-to-unit spread, for lmcal fleet");
  fleet->add_option("--seed", o->seed, "Random seed (same seed, same data)")->capture_default_str();
  fleet->add_option("-o,--output-dir,--output", o->output, "Output folder (the fleet's root)")->required();
  FleetRigConfig& fl = o->fleet;
  fleet->add_option("--units", fl.units, "Units")->capture_default_str();
  fleet->add_option("--dated-units", fl.dated_units, "Units 1 … N are logged on --dates dates, the others once")->capture_default_str();
  fleet->add_option("--dates", fl.dates, "Dates of the dated units")->capture_default_str();
  fleet->add_option("--first-date", fl.first_date, "First date, YYYY-MM-DD")->capture_default_str();
  fleet->add_option("--days-between", fl.days_between, "Days between dates")->capture_default_str();
  add_assignments(*fleet, "--spread", o->spread,
                  "Relative unit-to-unit SD of a constant (or alpha): --spread mu_v=0.08 (repeatable; default mu_v=0.08, "
                  "mu_st=0.05, alpha=0.05)");
  fleet->add_option("--outlier", o->outliers, "A unit's constant times a factor: --outlier 5:mu_st=1.4 (repeatable)");
  fleet->add_option("--drift", o->drifts, "A dated unit's constant changing linearly over its dates: --drift 2:mu_v=0.25 (repeatable)");
  fleet->add_option("--corrupt", fl.corrupt, "Units whose first set has a corrupt friction log")->delimiter(',');
  fleet->add_flag_callback("--no-thermal", [o] { o->fleet.thermal = false; }, "Friction logs only");
  fleet->callback([o] { run_generate_fleet(*o); });
}

}  // namespace

void setup_generate(CLI::App& app, const std::vector<std::string>& argv) {
  auto o = std::make_shared<GenerateOptions>();
  CLI::App* generate = app.add_subcommand("generate", "Virtual rig: synthetic data with a known truth");
  generate->require_subcommand(1);
  setup_generate_friction(*generate, o, argv);
  setup_generate_axis(*generate, o, argv);
  setup_generate_thermal(*generate, o, argv);
  setup_generate_fleet(*generate, o);
  CLI::App* list = generate->add_subcommand("effects", "List the named effects");
  list->callback([] {
    std::cout << fmt::format("{:<22} {:<18} {:>8}  {}\n", "effect", "unit", "neutral", "what it does");
    for (const auto& e : rig_effects())
      std::cout << fmt::format("{:<22} {:<18} {:>8}  {}\n", e.name, e.unit, e.neutral, e.description);
  });
}

}  // namespace lmcal::cli
