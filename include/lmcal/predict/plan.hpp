// Plan the next measurements (`lmcal plan friction`): which conditions the rig should log next
// to shrink the uncertainty of the friction constants the user names, or of all of them.
//
// The information the data hold, JᵀJ/σ² (J: ∂F/∂θ at every logged sample, the friction law
// with the fit's effects, at its estimates; σ²: the fit's residual variance), plus what `n`
// samples at a candidate condition c would add, n j(c) j(c)ᵀ/σ². Sequential design: the
// candidate that most increases the information's determinant (D-optimal: all parameters, in
// units of themselves) or most decreases the sum of the named parameters' variances, each
// relative to its own (A-optimal), is taken, its information added, and again, until N
// distinct conditions are chosen. A direction the data do not determine (a constant held
// because one preload class leaves k1 and k2 tied) has a variance of 1/ε in the scaled
// information: the first pick is the condition that determines it.
//
// The expected SEs compare like with like. A fit holds what its data cannot determine (k2 with
// one preload class), and then quotes the others' SEs with it held: k1 "with k2 held" is the
// Coulomb coefficient at the logged preload, k1 − k2·pc, not k1. Once the planned conditions
// determine k2, a refit quotes k1 itself, another quantity with another (larger) SE. So each
// parameter's SE, now -> after, is the SE of the parameter as the refit of the logs and the
// planned conditions would quote it (the constants still undetermined held, as now): "now" is
// not determined (infinite) where the logs determine it only with a constant held that the plan
// frees (`held_now`); the SE of what the fit quoted, the parameter with those constants held at
// their values, is beside it, now -> after (`se_held_now`, `se_held_after`: it only shrinks).
// After = the quoted SE times √(variance after / variance now) of the same quantity, so a
// covariance that accounts for correlated residuals keeps its inflation; a constant determined
// for the first time, from the information alone. A constant counts as determined after when
// its SE is below half its size (the fit's identifiability threshold).
//
// The candidates a plan needs: friction_candidates(log, grid, fit) adds the levels the fit's held
// constants need where the grid leaves a variable to the log (one preload class: the guides'
// preload classes; one temperature: 15 K warmer; no speed below 0.03 m/s: four there), and each
// such candidate says what it is for (`proposed_for`); the plan's notes name the picks that use them.
#pragma once

#include "lmcal/export.hpp"

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/fit/model_file.hpp"
#include "lmcal/io/thermal_run.hpp"

namespace LMCAL_API lmcal {

struct FrictionCandidate {
  std::string guide;
  FrictionConditions<double> conditions;  // direction included
  double viscosity40_mm2_s = 99;
  // Empty, or why a level the log lacks is in it: "a second preload class, for k2".
  std::string proposed_for;
};

// Every combination of the values given (an empty list: the log's own values; guides with
// their block lengths as the log has them, or the catalog's for guides given).
struct FrictionCandidateGrid {
  std::vector<double> velocity_m_s, load_N, preload_um, temperature_C;
  std::vector<double> directions;
  std::vector<std::string> guides;
  const GuideCatalog* catalog = nullptr;  // a user catalog searched before the built-in one
};
std::vector<FrictionCandidate> friction_candidates(const FrictionLog& log, const FrictionCandidateGrid& grid);
// The same, with the levels `fit` needs to determine the constants it held, where the grid gives
// no list of that variable: one preload class with k2 held, THK's classes of the log's guides
// (preload_class_um: normal, C1, C0); one temperature with beta_per_K held, one 15 K warmer; no
// speed below 0.03 m/s with v_st_m_s held, 0.002, 0.005, 0.01 and 0.02 m/s. Those candidates'
// `proposed_for` says which constant they are for.
std::vector<FrictionCandidate> friction_candidates(const FrictionLog& log, const FrictionCandidateGrid& grid,
                                                   const FrictionFitResult& fit);

struct PlanOptions {
  std::size_t conditions = 5;           // N
  std::vector<std::string> parameters;  // empty: all (D-optimal); else A-optimal for these
  std::size_t samples_per_condition = 0;  // 0: the log's median per condition
  // Two effects the diagnosis could not tell apart (a tie), both in the fit: the conditions
  // that most shrink the determinant of their 2×2 covariance (Ds-optimal).
  std::vector<std::string> separate;
};

struct PlannedCondition {
  FrictionCandidate candidate;
  double gain = 0;  // of the criterion: log det ratio (D) or the relative variance removed (A)
};

struct PlannedParameter {
  std::string name, unit;
  double value = 0;
  // The parameter as the refit would quote it, now and after; infinite: not determined (now:
  // not yet, or only with `held_now` held; after: still not).
  double se_before = 0, se_after = 0;
  bool determined_before = true;  // se_before finite
  // The constants the fit holds now, which the plan determines, that this parameter's quoted
  // SE assumed held (its meaning changes once they are estimated); with the SE of that quoted
  // quantity (the parameter with them held at their values), now and after.
  std::vector<std::string> held_now;
  double se_held_now = NAN, se_held_after = NAN;
};

struct FrictionPlan {
  std::string criterion;  // "D-optimal (all parameters)", "A-optimal for k1, mu_st"
  std::size_t samples_per_condition = 0;
  double sigma_N = 0;
  std::vector<PlannedCondition> picks;
  std::vector<PlannedParameter> parameters;
  double correlation_before = 0, correlation_after = 0;  // of the separated pair (NaN without)
  std::vector<std::string> notes;
};

// `fit` is a fit of `log` (its estimates, residual RMSE, quoted SEs and conditions).
FrictionPlan plan_friction(const FrictionLog& log, const FrictionFitResult& fit, const std::vector<FrictionCandidate>& candidates,
                           const PlanOptions& plan);

// plan.json; the template of a friction log to fill on the rig (one row per planned condition,
// friction_N empty, runs "plan1", "plan2", … by setup); the table for a terminal.
std::string friction_plan_json(const FrictionPlan& plan, const std::vector<std::string>& command);
std::string friction_plan_template_csv(const FrictionPlan& plan);
std::string friction_plan_summary(const FrictionPlan& plan);

// ---- thermal runs (`lmcal plan thermal`) ----------------------------------------------------------
//
// The same design for the next thermal runs of a calibrated model: each run's sensitivity,
// ∂ reading/∂θ at the run's sensors every record_every_s (forward differences of the rail model
// with the model's mechanisms), with each sensor's mean taken out (a new run's thermocouple
// offsets are fitted too); the information of the data set's runs as they were logged (their
// speed, load, duration, sensors) plus that of the candidates. With `separate` (two mechanisms
// the diagnosis could not tell apart, a tie), both are in θ — the one not in the model at its
// neutral value — and the runs chosen are those that most shrink the determinant of their 2×2
// covariance (Ds-optimal): the conditions under which their effects differ.

struct ThermalCandidate {
  double velocity_m_s = 0, load_N = 0, duration_s = 0;
};
// Every combination (an empty list: the data set's own values; the duration: its longest run's).
struct ThermalCandidateGrid {
  std::vector<double> velocity_m_s, load_N, duration_s;
};
std::vector<ThermalCandidate> thermal_candidates(const ThermalDataSet& data, const ThermalCandidateGrid& grid);

struct ThermalPlanOptions {
  std::size_t runs = 2;
  std::vector<std::string> parameters;  // empty: all (D-optimal), unless `separate`
  std::vector<std::string> separate;    // two mechanisms of the library to tell apart
  double record_every_s = 60;
  double noise_K = 0;                   // 0: the runs' thermocouple noise (second differences)
};

struct PlannedRun {
  ThermalCandidate candidate;
  double gain = 0;
};

struct ThermalPlan {
  std::string criterion;
  double noise_K = 0;
  std::vector<PlannedRun> picks;
  std::vector<PlannedParameter> parameters;
  double correlation_before = 0, correlation_after = 0;  // of the two separated mechanisms (NaN without)
  std::vector<std::string> notes;
};

ThermalPlan plan_thermal(const ModelFile& model, const ThermalDataSet& data, const std::vector<ThermalCandidate>& candidates,
                         const ThermalPlanOptions& options);

// plan.json; a thermal manifest template of the planned runs (each run's file to log); the table.
std::string thermal_plan_json(const ThermalPlan& plan, const std::vector<std::string>& command);
std::string thermal_plan_manifest_toml(const ThermalPlan& plan, const ThermalDataSet& data);
std::string thermal_plan_summary(const ThermalPlan& plan);

}  // namespace lmcal
