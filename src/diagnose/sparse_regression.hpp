// Sparse regression of a model's residuals on a dictionary of candidate terms (private to the
// diagnosis): which few transforms of the covariates explain what the model misses, chosen by
// how well they predict runs they were not fitted to. SINDy's sequentially thresholded least
// squares (Brunton, Proctor & Kutz 2016, PNAS 113:3932), with the threshold picked by
// leave-one-group-out error instead of by hand.
//
//   y = F β + D_S γ + level intercepts + e
//
//   y      the residuals of the current model (n rows);
//   F      columns always in the regression, unpenalised: the model's own parameters,
//          linearised (its Jacobian), so a term is scored for what it adds beyond what the
//          model's parameters can absorb — one Gauss-Newton step of the joint fit;
//   D      the dictionary; S the selected subset;
//   levels one free intercept per level (a run's load-cell zero, a thermocouple's offset).
//
// Candidates of one family (the same transform at different scales ℓ) compete: at most one
// member enters, the one that alone predicts held-out groups best. Then, for a path of
// thresholds λ on the standardised coefficients (each column scaled to unit RMS after F and
// the levels are projected out, so |γ| is the term's RMS contribution in the residuals' unit),
// STLSQ: fit all, drop |γ| < λ, refit, until the support is stable; and forward steps (add the
// candidate that best predicts held-out groups, up to max_terms), because on a dictionary of
// correlated transforms the full fit STLSQ starts from can spread one term over its
// look-alikes and lose it. Every support on the path
// is scored by leave-one-group-out RMSE (the held-out group's levels refitted on it: its
// shape, not its zero); the sparsest support within `min_gain_percent` of the best is kept, and
// it is kept only if it gains at least `min_gain_percent` over F alone.
//
// Trap: the held-out RMSE here is linearised (the model's parameters move only along F). The
// caller refits the model jointly with the terms chosen and judges that fit.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace lmcal::detail {

struct SparseProblem {
  std::vector<double> y;                         // n residuals
  std::vector<std::size_t> group;                // per row: what is held out together (a run), 0..G-1
  std::vector<std::size_t> level;                // per row: its intercept (run, or run × sensor); empty: none
  std::vector<std::vector<double>> fixed;        // columns always in (n each), unpenalised
  std::vector<std::vector<double>> candidates;   // the dictionary (n each)
  std::vector<std::size_t> family;               // per candidate; empty: each its own family
};

struct SparseOptions {
  std::size_t max_terms = 3;
  double min_gain_percent = 2.0;  // over F alone, on held-out groups; and the sparsity tolerance
  std::vector<double> thresholds{0.5, 0.3, 0.2, 0.1, 0.05, 0.02, 0.01};  // λ as shares of the residual RMS
};

struct SparseStep {
  double threshold = 0;                 // λ, in the residuals' unit; NaN for a forward step
  std::vector<std::size_t> support;     // candidate indices
  double cv_rmse = 0;
};

struct SparseSelection {
  std::vector<std::size_t> selected;   // candidate indices, in dictionary order
  std::vector<double> coefficient;     // per selected, in the candidate column's own unit
  double cv_rmse_fixed = 0;            // leave-one-group-out RMSE with F (and levels) alone
  double cv_rmse = 0;                  // with the selected terms
  std::vector<std::size_t> family_representative;  // per family seen: the member kept
  std::vector<SparseStep> path;
};

SparseSelection select_sparse(const SparseProblem& problem, const SparseOptions& options);

// F (and the levels) plus each given support of candidates: its leave-one-group-out RMSE and
// its coefficients on all data (per candidate of the support, in order). For blocks that
// enter together, e.g. the basis functions of a smooth term.
struct SupportScore {
  double cv_rmse = 0;
  std::vector<double> coefficient;
};
std::vector<SupportScore> score_supports(const SparseProblem& problem, const std::vector<std::vector<std::size_t>>& supports);
// The same for F plus `columns` (n rows each) given apart from the problem's candidates (its
// candidates are not read): a block scored on a thread of its own.
SupportScore score_columns(const SparseProblem& problem, const std::vector<std::vector<double>>& columns);

}  // namespace lmcal::detail
