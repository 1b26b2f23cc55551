// Fit the heat partition α (and optionally h, named extensions, per-sensor offsets and the
// initial rail temperature) to rail thermocouple traces, through the rail solver of rail_thermal.hpp:
//
//   r = (T_measured(t, x_s) - offset_s - T_model(t, x_s; α, h, T0)) / σ
//
// with T_model driven by the run's measured ambient (mean of the ambient sensors, or one
// named; the manifest's ambient_C for a run without ambient columns), Q_f from the friction
// law with fitted constants (a friction fit) or from the run's measured mean friction force —
// or, when the manifest gives it (heat_rate_W, a schedule's heats, a CSV heat_rate_W column),
// the given heat, whatever `heat` says — and the chosen source model. A [[run.schedule]] makes
// Q_f change during the run (friction × each phase's speed, or its given heat): every record
// is fitted, so a heater's off phase (cooling) informs α too. The `moving` source refuses a
// schedule of speeds (InvalidParameter: its block keeps one speed), the coupling extension any
// schedule or measured power. Derivatives come from
// the templated solver with ceres::Jet. Without free h (or coupling) the model is linear
// in α, the offsets and T0, and the fit is one exact Gauss-Newton step.
//
// Runs are fitted jointly (one α for all) and one by one; the per-run α give the spread
// across runs as the paper reports it (mean, Eq. 1 σ, 95 % t interval), and Eq. 2 compares
// the two ambient sensors and repeated runs at the same conditions. The runs are α's
// replicates: with three or more, the cluster covariance is quoted, and the variance of α (and
// of any other global parameter every run's own fit estimates) is at least Σ c_r² (SE_r² + τ²)
// over the per-run fits (c_r each run's share of the joint fit's information, τ their spread
// beyond their own SEs), t with runs − 1 dof.
//
// Trap: α belongs to the source model it was fitted with (`paper` puts L1/Lb1 times the
// power into the rail, so its α is about Lb1/L1 times the `averaged` one).
#pragma once

#include "lmcal/export.hpp"

#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "lmcal/enum_names.hpp"
#include "lmcal/fit/fit_result.hpp"
#include "lmcal/fit/population.hpp"
#include "lmcal/fit/statistics.hpp"
#include "lmcal/io/thermal_run.hpp"
#include "lmcal/models/friction_effects.hpp"
#include "lmcal/models/rail_thermal.hpp"

namespace LMCAL_API lmcal {

// Thermocouple offsets: fitted where the data determine them, or as asked.
enum class ThermalOffsets {
  automatic,  // fitted for a run that starts isothermal (every thermocouple's first minute
              // within isothermal_tolerance_K of the ambient): the rail then starts at the
              // ambient and each offset is the sensor's bias; held at 0 otherwise, and said so
  fitted,     // fitted for every run
  held        // never fitted (the thermocouples' readings are taken as true)
};
inline constexpr ThermalOffsets kThermalOffsets[] = {ThermalOffsets::automatic, ThermalOffsets::fitted, ThermalOffsets::held};
const char* to_string(ThermalOffsets offsets);  // "auto", "fit", "hold"
inline ThermalOffsets parse_thermal_offsets(std::string_view name, const std::string& parameter = "offsets") {
  return parse_enum(kThermalOffsets, name, parameter, "offsets mode");
}

enum class HeatInput {
  automatic,        // friction law when constants are given, else the measured mean friction
  friction_law,     // Q = F(constants, effects; run conditions at the ambient at the start) · V
  measured_friction // Q = start_friction_N · V from the manifest (Q_f at the start temperature), else
                    // mean_friction_N · V (the run's mean: a coupled heat keeps that mean)
};
inline constexpr HeatInput kHeatInputs[] = {HeatInput::automatic, HeatInput::friction_law, HeatInput::measured_friction};
constexpr const char* to_string(HeatInput heat) {
  switch (heat) {
    case HeatInput::automatic: return "auto";
    case HeatInput::friction_law: return "friction";
    case HeatInput::measured_friction: return "measured";
  }
  return "?";
}
inline HeatInput parse_heat_input(std::string_view name, const std::string& parameter = "heat") {
  return parse_enum(kHeatInputs, name, parameter, "heat input");
}

// An empirical sensor-side term (what the thermal diagnosis learns when no named mechanism
// explains the residuals; src/fit/thermal_terms.hpp has the regressors φ): c · φ(run, s, t)
// added to every thermocouple reading, c free, and the term's scale (the ambient's period P,
// a lag's τ) free too where it has one. Not a physical mechanism: it says what the readings
// follow, not why.
enum class ThermalTermKind {
  time,                // t / 1 h, t since the run's first record
  time_squared,        // (t / 1 h)²
  ambient_in_phase,    // a_P(t): the run's ambient's own swing at period P
  ambient_quadrature,  // b_P(t): the same a quarter period earlier (shares P with a_P)
  ambient_lag,         // lag_τ(T∞) − T∞
  ambient_change,      // T∞(t) − T∞(0)
  rise_time,           // (simulated rise) · t / 1 h
  velocity_time        // V · t / 1 h
};
const char* to_string(ThermalTermKind kind);         // "t", "t^2", "a_P", "b_P", "lag_tau(Tamb)-Tamb", …
bool term_has_scale(ThermalTermKind kind);           // period or τ
const char* term_coefficient_unit(ThermalTermKind kind);  // of c: "K/h", "K/h2", "1", "1/h", "K/(h m/s)"

struct ThermalSensorTerm {
  ThermalTermKind kind = ThermalTermKind::time;
  double coefficient = 0;                 // start value (K per unit of φ)
  double scale_s = 0;                     // P or τ (s), start value, for the kinds with a scale
  double scale_lower_s = 0, scale_upper_s = 0;
  bool fit_scale = true;
};

struct ThermalFitOptions {
  // α is bounded and (without h) linear: no multi-start needed. Each run's heat reaching the
  // rail has its own error (the logged friction, the law at the run's conditions), which no
  // record of the run sees: the runs are the replicates α's interval must come from.
  FitOptions fit{.starts = 0, .runs_replicate = true};
  SourceModel source = SourceModel::averaged;
  TimeScheme scheme = TimeScheme::crank_nicolson;
  int half_rail_segments = 100;
  double time_step_s = 30;
  std::size_t every = 1;                     // use every n-th record of the traces
  std::string ambient = "mean";              // "mean" of the ambient sensors, or a column name
  HeatInput heat = HeatInput::automatic;
  std::optional<FrictionConstants<double>> friction;  // from a friction fit
  FrictionEffects<double> friction_effects;
  // Two-stage uncertainty: the friction fit the constants come from. Its covariance (and
  // bootstrap replicates) carry through the heat rate Q_f into α's interval (the rail sees only
  // αQ, so Q's relative error is α's). With the measured mean friction instead, the manifest's
  // mean_friction_uncertainty_N does (taken as one systematic error of the load cell, common
  // to all runs). Neither: the heat's uncertainty is not counted, and the result says so.
  std::optional<FitResult> friction_fit;
  double alpha_start = 0.6, alpha_lower = 0.0, alpha_upper = 1.0;
  bool fit_h = false;                        // one h for all runs
  // h's start when fitted; the fixed h when not, except for a run whose manifest gives its own
  // h_W_m2K (that run's wins; a fitted h is one for all runs and ignores it).
  double h_W_m2K = 5.3, h_lower = 0.5, h_upper = 50.0;
  // One offset per thermocouple and run; the rail then starts at the ambient (at rest, in
  // equilibrium with the room), and the offsets take each thermocouple's bias against the
  // ambient sensors.
  ThermalOffsets offsets = ThermalOffsets::automatic;
  double isothermal_tolerance_K = 1.0;  // T-type class ±0.5 K on either side
  bool fit_initial_temperature = false;      // one T0 per run
  // One heat-rate scale per run ("heat_scale <run>"), tied to 1 by a Gaussian prior of the
  // heat rate's relative uncertainty σ_Q: the temperature the friction law is evaluated at is
  // known to ±heat_temperature_uncertainty_K (|d ln Q/dT| is about 5 %/K at 24 °C), the law
  // itself to ±heat_law_uncertainty. Without it, a 0.3 K error of the ambient sensors puts a
  // 1.5 % error into one run's heat, which no global parameter can absorb.
  bool fit_heat_scales = false;
  double heat_temperature_uncertainty_K = 0.3;
  double heat_law_uncertainty = 0.01;
  // Named mechanisms of the extension library added to the model (`lmcal fit thermal
  // --extension`, thermal_extension_names()), each with its own parameter(s).
  std::vector<std::string> extensions;
  // Start values by parameter name (name -> value, clamped to the bounds; names the model does
  // not have are ignored): a warm start from an earlier fit of the same data, every offset,
  // heat scale and mechanism where it was. Before alpha_start, h_W_m2K and the terms' own.
  std::vector<std::pair<std::string, double>> parameter_start;
  // Empirical sensor terms added to every reading (parameters "c<j> <symbol>"; one period
  // "P_s" ("P2_s", …) shared by the ambient-periodic terms of the same start period; "tau<j>_s"
  // per lag). Their parameters enter the
  // residuals directly, not the solver: they cost no Jet slot.
  std::vector<ThermalSensorTerm> sensor_terms;
  // Keep ∂ reading / ∂ θ at every sample for the global parameters (ThermalFitResult::sensitivities).
  bool sensitivities = false;
  // Leave-one-run-out prediction error (cv_rmse_K): each run predicted by the global
  // parameters (α, h, extensions) fitted to the others, one Gauss-Newton step from the
  // joint fit; its own offsets, T0 and heat scale (within its prior) re-estimated from its
  // own records.
  bool cross_validate = false;
  bool per_run_fits = true;
  bool compare_sources = true;               // also fit with `paper` (or `averaged`) and report the α ratio
  // α error curve (the paper's Fig. 11): RMSE at spot 1 (first sensor) for α on a grid.
  double curve_from = 0.1, curve_to = 1.0;
  int curve_points = 46;
};

// Temperature along the rail at one time (the model's nodes, from the rail centre).
struct RailProfile {
  double time_s = 0;
  std::vector<double> position_m, temperature_C;
};

struct SensorGoodness {
  std::string run, sensor;
  double position_m = 0;
  std::size_t n = 0;
  double rmse_K = 0;
  double max_error_K = 0;
  double max_error_percent = 0;  // max |error| / the sensor's measured span (its highest minus lowest 10-record mean, at least a tenth of the widest sensor's) · 100
};

struct RunInfo {
  std::string id;
  double velocity_m_s = 0, load_N = 0, initial_temperature_C = 0;
  double heat_rate_W = 0;  // Q_f; with a schedule or a measured power, its mean over the run
  std::string heat_source;  // "friction law …", "measured mean friction", "measured friction at the start temperature"
                            // or "given heat rate" (heat_rate_uncertainty_W then feeds heat_relative_se)
  double heat_relative_se = 0;  // of the heat rate, as counted in the intervals (NaN: not known)
  bool offsets_fitted = false;
  std::string offsets_note;     // why the offsets were held, when they were
  double ambient_difference_percent = 0;  // Eq. 2 between the first two ambient sensors' rise
  // The friction law's conditions behind heat_rate_W when it came from the law (the temperature:
  // the ambient at the start), and the oil's ν40 it used: a prediction redraws the heat there.
  std::optional<FrictionConditions<double>> heat_conditions;
  double heat_viscosity40_mm2_s = 0;
};

struct ThermalFitResult {
  FitResult joint;                  // α (and h, offsets, T0) over all runs
  std::vector<FitResult> per_run;   // each run alone
  std::vector<RunInfo> runs;
  Spread alpha_spread;              // over the per-run α
  // The per-run α as a random-effects population (population.hpp): each run's within-run SE,
  // and τ, how much the runs' α differ beyond them (REML, with Cochran's Q and I²). The heat
  // reaching each rail has its own error that no record of the run sees, so a run's α is known
  // to √(SE² + τ²), not to its own SE: a comparison of repeats must use the former.
  RandomEffects alpha_runs;
  struct RepeatDifference {
    std::string runs;         // "v110_r1/v110_r2"
    double percent = 0;       // Eq. 2 of their α
    double z = 0;             // their difference over √(SE₁² + SE₂² + 2τ²)
    double z_within = 0;      // the same over √(SE₁² + SE₂²): their own SEs only
  };
  std::vector<RepeatDifference> repeat_differences;  // between runs at the same conditions
  std::vector<SensorGoodness> goodness;
  double max_error_percent = 0;
  struct CurvePoint {
    std::string run;
    double alpha, rmse_K, max_error_K;
  };
  std::vector<CurvePoint> alpha_curve;
  struct Sample {
    std::size_t run, sensor;
    double time_s, measured_C, simulated_C;
    std::uint32_t line;  // of its record in the run's file (0: not from a file)
  };
  // The same data fitted with the other source model (paper <-> averaged): its α, and the
  // ratio α_paper / α_averaged, which PHYSICS.md §7 expects near Lb1/L1.
  std::string other_source;
  double other_source_alpha = std::numeric_limits<double>::quiet_NaN();
  double alpha_ratio_paper_over_averaged = std::numeric_limits<double>::quiet_NaN();
  double contact_over_stroke = std::numeric_limits<double>::quiet_NaN();  // Lb1 / L1 of the first run
  std::vector<Sample> samples;                         // joint fit, every fitted record
  // Each run at its last fitted record: the model along the rail, and each sensor's reading
  // less its fitted offset (the rail temperature it measured).
  struct EndState {
    RailProfile model;
    std::vector<double> sensor_position_m, measured_C;
  };
  std::vector<EndState> end_states;
  double cv_rmse_K = std::numeric_limits<double>::quiet_NaN();  // leave-one-run-out, when asked
  double sum_of_squares_K2 = 0;  // the fit's objective: data rows and the heat-scale priors
  std::string heat_uncertainty;  // how the heat's uncertainty entered α's interval, in words
  std::vector<std::vector<std::string>> sensor_names;  // [run][sensor]
  // When asked (ThermalFitOptions::sensitivities, no robust loss): ∂ simulated_C / ∂ θ at every
  // sample (in `samples` order) for each global parameter (α, h, the extensions', the sensor
  // terms') and each run's heat scale, by name.
  std::vector<std::pair<std::string, std::vector<double>>> sensitivities;
  // The sensor terms' parameters (coefficients, then the scale) per term, as fitted: indices into joint.parameters.
  std::vector<std::vector<std::size_t>> sensor_term_parameters;
};

ThermalFitResult fit_thermal(const ThermalDataSet& data, const ThermalFitOptions& options);

// The ambient each run's model is driven with (the mean of its ambient sensors, or the one
// named), from its first record (t = 0), as `fit_thermal` prepares it.
std::vector<AmbientTrace> thermal_fit_ambients(const ThermalDataSet& data, const ThermalFitOptions& options);
// The regressor φ of every term at every sample of `fit` (made from `data` with `options`),
// [term][sample]; rise_time from the fit's own simulation at its parameters.
std::vector<std::vector<double>> thermal_sensor_term_values(const ThermalDataSet& data, const ThermalFitOptions& options,
                                                            const ThermalFitResult& fit,
                                                            const std::vector<ThermalSensorTerm>& terms);
// The fitted sensor terms' sum at every sample of `fit` (options.sensor_terms), for the
// parameter values `theta` (all of fit.joint's, in order; the fit's own when empty).
std::vector<double> thermal_sensor_term_sum(const ThermalDataSet& data, const ThermalFitOptions& options,
                                            const ThermalFitResult& fit, const std::vector<double>& theta = {});

// The thermal extension library, in a fixed order (src/fit/thermal_extensions/).
struct ThermalExtensionInfo {
  std::string name, description;
  std::string measure;                       // what to log to see it
  std::vector<std::string> parameters;       // their names in FitResult; none for a switch
  std::optional<SourceModel> source;         // the source model a switch selects
  bool heat_follows_rail = false;            // Q_f follows the rail temperature (coupling)
  std::vector<double> parameter_scale;       // each parameter's typical size
  std::vector<std::pair<double, double>> parameter_bounds;  // each parameter's fit bounds
};
std::vector<ThermalExtensionInfo> thermal_extension_library();

// The rail model with mechanisms of the extension library switched on, at given parameter
// values (what `lmcal simulate thermal --model` runs with a calibrated model): `mechanisms`
// names them, `values` gives each of their parameters by name (thermal_extension_library()
// lists them). The heat comes from the friction law (constants, effects, the conditions at the
// start temperature) unless `params.heat_rate_W` > 0 is given; the coupling mechanism makes it
// follow the rail temperature. A thermocouple lag is a property of a sensor, not of the rail:
// the rail's own temperature is returned, without it. The source model comes from `numerics`
// unless a switch among the mechanisms selects one.
RailSolution<double> simulate_rail_with_mechanisms(const RailGeometry& geometry, RailNumerics numerics,
                                                   const RailOutputs& outputs, const RailParams<double>& params,
                                                   const AmbientTrace& ambient, const FrictionConstants<double>& friction,
                                                   const FrictionEffects<double>& effects,
                                                   const FrictionConditions<double>& conditions,
                                                   const std::vector<std::string>& mechanisms,
                                                   const std::vector<std::pair<std::string, double>>& values);

// The thermocouples' noise σ (K), from the second differences of the rail channels,
// x(t + k) − 2 x(t) + x(t − k) over k records, the most that fit in `spacing_s` (at least
// one): insensitive to the slow warm-up, exact for white noise; noise with memory shorter
// than the spacing counts in full, longer memory only in part. `differences`, when given,
// receives how many second differences went in.
double thermocouple_noise_K(const ThermalTrace& trace, double spacing_s = 0, std::size_t* differences = nullptr);

// Reads constants and effects from a friction fit JSON (`lmcal fit friction` output).
void read_friction_fit(const std::string& json_file, ThermalFitOptions& options);

std::string thermal_fit_json(const ThermalFitResult& result, const ThermalFitOptions& options,
                             const std::vector<std::pair<std::string, std::string>>& inputs,
                             const std::vector<std::string>& command, const std::string& name);
std::string thermal_fit_samples_csv(const ThermalFitResult& result);
std::string thermal_fit_curve_csv(const ThermalFitResult& result);
// Every file a thermal fit writes, file name -> contents: NAME.json, NAME_samples.csv and
// NAME_alpha_curve.csv.
std::vector<std::pair<std::string, std::string>> thermal_fit_files(const ThermalFitResult& result,
                                                                   const ThermalFitOptions& options,
                                                                   const std::vector<std::pair<std::string, std::string>>& inputs,
                                                                   const std::vector<std::string>& command,
                                                                   const std::string& name);
std::string thermal_fit_summary(const ThermalFitResult& result);

}  // namespace lmcal
