// The thermal fit's shared pieces (private to the fit layer, free of Ceres): a run ready to
// simulate (PreparedRun) and the steps its files hand each other. The fit is four files, one
// job each: thermal_prepare.cc (the runs and the friction fit read in), thermal_fit.cc (the
// parameters, the solve and what the fitted model shows), thermal_uncertainty.cc (the heat's
// uncertainty and the runs as replicates), thermal_output.cc (JSON, CSV and the summary).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effects.hpp"
#include "lmcal/models/rail_thermal.hpp"

namespace lmcal::detail {

// One run, ready to simulate: geometry, fixed physical parameters, ambient, and the
// measured temperatures at the fitted records.
struct PreparedRun {
  std::string id;
  RailGeometry geometry;
  RailParams<double> params;  // α, h and T0 are starting values; Q, k, ρ, c fixed
  AmbientTrace ambient;
  std::vector<double> times_s;                // fitted records
  std::vector<std::uint32_t> lines;           // their lines in the run's file (empty: not from a file)
  std::vector<std::string> sensor_names;
  std::vector<double> sensor_positions_m;
  std::vector<std::vector<double>> measured;  // [time][sensor], NaN = missing
  bool fit_offsets = false;                   // one offset per sensor (ThermalOffsets)
  // Behind the heat rate (the coupling extension evaluates the law at the rail temperature).
  FrictionConstants<double> friction = paper_friction_constants();
  FrictionEffects<double> friction_effects;
  FrictionConditions<double> conditions;  // at the temperature Q_f was evaluated at
  bool heat_is_run_mean = false;          // params.heat_rate_W is the run's mean (ThermalRunSetup)
  // With a fitted heat scale: the weight σ_T/σ_Q of its prior row (σ_T the thermocouple
  // noise, σ_Q the relative uncertainty of Q_f), r = weight · (scale - 1).
  double heat_prior_weight = 0;
  double heat_prior_sigma_K = 0;  // σ_T: the prior row's standard deviation, by construction
};

// RunInfo::heat_source of a heat from the manifest's friction force.
inline constexpr const char* kMeasuredMeanFriction = "measured mean friction";
inline constexpr const char* kMeasuredStartFriction = "measured friction at the start temperature";
// ... and of a heat the manifest gives (heat_rate_W, a schedule's heats, the CSV's column).
inline constexpr const char* kGivenHeat = "given heat rate";

// ---- thermal_prepare.cc ----------------------------------------------------------------------

// A run prepared, with what the result reports of it.
struct PreparedRunInfo {
  PreparedRun run;
  RunInfo info;
  std::vector<double> span_K;  // measured span of every sensor (the scale of its max error)
};
PreparedRunInfo prepare_run(const ThermalRun& run, const ThermalFitOptions& o);
std::vector<PreparedRun> prepared_runs(const ThermalDataSet& data, const ThermalFitOptions& o);
// The given heat its heat_rate_uncertainty_W is stated at: the run's, else the largest given.
double given_heat_reference_W(const ThermalRun& run);

// ---- thermal_fit.cc --------------------------------------------------------------------------

// The source model: the option's, unless an extension switches it.
SourceModel source_of(const ThermalFitOptions& o);

// ---- thermal_uncertainty.cc ------------------------------------------------------------------

// The heat's uncertainty (two-stage): the covariance of the runs' ln Q_f, and, when the
// friction fit brought bootstrap replicates, each replicate's ln Q* − ln Q̂.
struct HeatUncertainty {
  Eigen::MatrixXd covariance;          // runs × runs
  std::vector<Eigen::VectorXd> draws;
  std::string description;             // how it was counted; empty: not counted
  std::string missing;                 // what is not counted, and why
};
HeatUncertainty heat_uncertainty(const std::vector<PreparedRun>& runs, const std::vector<RunInfo>& infos,
                                 const ThermalDataSet& data, const ThermalFitOptions& o);
// A global parameter's SE from the runs as replicates, where larger than the quoted one.
void widen_to_the_runs(ThermalFitResult& result, double confidence);

}  // namespace lmcal::detail
