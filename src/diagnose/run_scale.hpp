// Does the friction differ from run to run by a factor, beyond the runs' zeros? (private to the
// diagnosis)
//
// A run whose friction is (1 + u_r)·F_model + b_r + e: the random run offsets b_r take its
// zero, nothing takes u_r. Within each run, the residual of the final model (its run offset
// left in) is regressed on the model's force with an intercept of its own, r = a_r + u_r·F + e,
// so the run's zero and its level never pass for a factor; u_r's SE from the run's residual
// variance, widened by (1 + ρ)/(1 − ρ) for the lag-1 autocorrelation ρ of its residuals (a load
// cell's noise has memory). The factors are then tested for heterogeneity (Cochran's Q on R − 1
// dof) and their spread beyond their SEs estimated (DerSimonian-Laird τ²):
//
//   Q = Σ w_r (u_r − ū)²,  w_r = 1/SE_r²,  τ² = max(0, (Q − (R − 1)) / (Σw − Σw²/Σw)).
//
// τ is what a new run's level cannot be predicted better than (no covariate of the log follows
// it, or the empirical search would have found it): the new-run level criterion's share of the
// friction that random intercepts, being additive, do not carry.
//
// The runs differ when Q is significant at the selection's LRT level and τ exceeds the share of
// the friction the runs' zeros spread over (the SD of the a_r over the mean force): a factor
// smaller than that moves a run's level less than its zero does.
//
// Needs 3 runs or more whose model force varies within the run (speeds, loads or temperatures
// change within it); runs of fewer than 4 rows or a constant force are left out.
#pragma once

#include <string>
#include <vector>

#include "lmcal/diagnose/friction_diagnosis.hpp"

namespace lmcal::detail {

// `residual_N`: data − model per row with the run offsets left in; `model_N`: the model's force.
RunScaleTest test_run_scale(const FrictionLog& log, const std::vector<double>& residual_N, const std::vector<double>& model_N,
                            double lrt_p);

}  // namespace lmcal::detail
