// Plan the next measurements (`lmcal plan friction`): which conditions the rig should log next
// to shrink the uncertainty of the friction constants the user names, or of all of them.
//
// The information the data hold, JᵀJ/σ² (J: ∂F/∂θ at every logged sample, the friction law
// with the fit's effects, at its estimates; σ²: the fit's residual variance), plus what `n`
// samples at a candidate condition c would add, n j(c) j(c)ᵀ/σ². Sequential design: the
// candidate that most increases the information's determinant (D-optimal: all parameters, in
// units of themselves) or most decreases the sum of the named parameters' variances, each
// relative to its own (A-optimal), is taken, its information added, and again, until N
// distinct conditions are chosen. The expected SE after: the quoted SE times
// √(variance after / variance before), so a covariance that accounts for correlated residuals
// keeps its inflation; "before" with the undetermined parameters held, as the fit quoted it, so
// a parameter that was determined only with another held can grow once both are estimated. A direction the data do not
// determine (a constant held because one preload class leaves k1 and k2 tied) has a variance
// of 1/ε in the scaled information: the first pick is the condition that determines it.
#pragma once

#include "lmcal/export.hpp"

#include <cstddef>
#include <string>
#include <vector>

#include "lmcal/fit/friction_fit.hpp"

namespace LMCAL_API lmcal {

struct FrictionCandidate {
  std::string guide;
  FrictionConditions<double> conditions;  // direction included
  double viscosity40_mm2_s = 99;
};

// Every combination of the values given (an empty list: the log's own values; guides with
// their block lengths as the log has them).
struct FrictionCandidateGrid {
  std::vector<double> velocity_m_s, load_N, preload_um, temperature_C;
  std::vector<double> directions;
};
std::vector<FrictionCandidate> friction_candidates(const FrictionLog& log, const FrictionCandidateGrid& grid);

struct PlanOptions {
  std::size_t conditions = 5;           // N
  std::vector<std::string> parameters;  // empty: all (D-optimal); else A-optimal for these
  std::size_t samples_per_condition = 0;  // 0: the log's median per condition
};

struct PlannedCondition {
  FrictionCandidate candidate;
  double gain = 0;  // of the criterion: log det ratio (D) or the relative variance removed (A)
};

struct PlannedParameter {
  std::string name, unit;
  double value = 0;
  double se_before = 0, se_after = 0;  // se_before infinite: not determined by the data yet
  bool determined_before = true;
};

struct FrictionPlan {
  std::string criterion;  // "D-optimal (all parameters)", "A-optimal for k1, mu_st"
  std::size_t samples_per_condition = 0;
  double sigma_N = 0;
  std::vector<PlannedCondition> picks;
  std::vector<PlannedParameter> parameters;
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

}  // namespace lmcal
