// The least-squares engine behind every lmcal fit (private: Ceres and NLopt stay here).
//
//   1. multi-start: `starts` local searches on a subsample of the residuals, from the given
//      start and from a Halton sequence over the bounds: Levenberg-Marquardt on the
//      subsample's normal equations where the cost accumulates them (the friction and
//      thermal models), else NLopt's bounded L-BFGS with the gradient of the model's autodiff
//      cost function;
//   2. polish: Levenberg-Marquardt on all residuals from the best start, with bounds, held
//      parameters and an optional robust loss (row by row): the engine's own on the normal
//      equations where the cost accumulates them, else Ceres' (SubsetManifold for the held);
//   3. identifiability: (JᵀJ)⁻¹ from a rank-revealing QR of the autodiff Jacobian (what
//      ceres::Covariance computes; tested against it); the eigen-directions of the relatively
//      scaled covariance (or the null space of JᵀJ when the Jacobian is rank deficient); a
//      direction the data cannot determine is named (via the model's explain()) and the
//      parameter that dominates it is held at its start, then 2-3 repeat;
//   4. uncertainty (uncertainty.cc): the covariance by every method the rows' structure
//      allows (covariance/: iid, hac, cluster, bootstrap), the one that fits the data chosen,
//      t intervals and the correlation from it;
//   5. profile-likelihood intervals where the linear interval is unreliable.
//
// solve_least_squares (least_squares.cc) reads as these steps; each lives in its own
// least_squares_*.cc (least_squares_steps.hpp), the state at the end in the Ceres-free
// least_squares_state.hpp.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "batched_autodiff.hpp"
#include "covariance/covariance.hpp"
#include "least_squares_state.hpp"
#include "lmcal/fit/fit_result.hpp"

namespace lmcal::detail {

struct ParameterSpec {
  std::string name;
  std::string unit;
  double start = 0;
  double lower = 0, upper = 0;
  bool free = true;
  // Typical size, for judging what the data determine (SE / scale). 0: the larger of |value|
  // and |start|. Give it for parameters whose natural value is near zero (offsets, effects).
  double scale = 0;
  bool per_run = false;  // a nuisance parameter of one run (see ParameterEstimate::per_run)
};

// A whitened residual vector r(θ) over one parameter block holding all parameters.
class LeastSquaresModel {
 public:
  virtual ~LeastSquaresModel() = default;
  virtual std::size_t num_residuals() const = 0;
  // A cost function over the residual rows given (all rows when `rows` is empty), each row
  // passed through the robust loss.
  virtual std::unique_ptr<ceres::CostFunction> cost_function(const std::vector<std::size_t>& rows,
                                                             const RowLoss& loss) const = 0;
  // Why the data cannot determine `issue.combination`, and what to measure; fills why/measure.
  virtual void explain(IdentifiabilityIssue& issue) const { (void)issue; }
  // True when the residuals are linear in the parameters not held (so one Gauss-Newton step
  // is exact): the engine then skips the multi-start and the iterations.
  virtual bool linear(const std::vector<bool>& held) const {
    (void)held;
    return false;
  }
  // True when a cost over a tenth of the rows costs about a tenth (a row is evaluated on its
  // own). False when every row needs the whole computation (a simulation): then a fit over a
  // subset of rows saves nothing, and the engine's first pass over a tenth of the rows is
  // skipped (it would only move the start away from the optimum of all rows).
  virtual bool rows_evaluate_separately() const { return true; }
  // True when one cost function may be evaluated on several threads at once (it keeps no
  // state between evaluations): the engine then runs the multi-start's searches side by side.
  // False (the default) where the model remembers its last evaluation (the thermal model's
  // end profiles).
  virtual bool costs_evaluate_concurrently() const { return false; }
  // What the design of the data rules out before any fit (e.g. one temperature: no β); each
  // issue names in `held` the parameters to hold. `free` are the parameters asked free.
  virtual std::vector<IdentifiabilityIssue> design_issues(const std::vector<std::string>& free) const {
    (void)free;
    return {};
  }
  // The run and time step of every residual row, for covariances that do not assume
  // independent rows; empty (the default) when the model knows none.
  virtual RowStructure row_structure() const { return {}; }
  // Called once the estimate is settled (after the polish and the identifiability rounds,
  // before the uncertainty and the profiles): a model whose whitening followed the estimate
  // during the polish (a random intercept's variance, profiled) holds it from here on, so
  // that the covariance, the bootstrap and the profiles see one objective.
  virtual void estimate_settled() const {}
};

// Step 4: fills result.uncertainty, result.covariance, result.correlation and every free
// parameter's se, ci and bootstrap interval, from the covariance chosen for the rows'
// structure (see fit_result.hpp).
void assess_uncertainty(const RowStructure& rows, const FitOptions& options, const FinalState& state, FitResult& result);

// Adds the uncertainty of an input the fit took as given (two-stage, Murphy-Topel in its
// delta-method form): with E = ∂r/∂u (rows × q) at θ̂ and u's covariance Σ_u, the estimate
// moves by D = ∂θ̂/∂u = −(JᵀJ)⁻¹JᵀE, and D Σ_u Dᵀ joins the chosen covariance (t dof by
// Welch-Satterthwaite). With `draws` (u* − û per bootstrap replicate) the bootstrap is rerun
// over both stages. `label` names the input ("heat").
void add_input_uncertainty(const RowStructure& rows, const FitOptions& options, const FinalState& state,
                           const Eigen::MatrixXd& input_jacobian, const Eigen::MatrixXd& input_covariance,
                           const std::vector<Eigen::VectorXd>* draws, const std::string& label, FitResult& result);

FitResult solve_least_squares(const LeastSquaresModel& model, const std::vector<ParameterSpec>& parameters,
                              const FitOptions& options, FinalState* final_state = nullptr);

// Thrown by evaluate_residuals when the model cannot be evaluated at θ or a residual is not
// finite there; solve_least_squares reports it as an unusable fit (never an abort).
class NonFiniteResiduals : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Residuals r(θ) and, if `jacobian` is given, ∂r/∂θ (rows x parameters), over `rows`.
// `held` (one flag per parameter, or empty): parameters whose columns the caller does not read;
// a cost that accumulates its rows (NormalEquationsCost) may leave them 0 and differentiate in
// the others only (the same bits in theirs). NonFiniteResiduals when they cannot be evaluated
// or one is not finite.
Eigen::VectorXd evaluate_residuals(const LeastSquaresModel& model, const std::vector<double>& theta,
                                   const RowLoss& loss = {}, Eigen::MatrixXd* jacobian = nullptr,
                                   const std::vector<std::size_t>& rows = {}, const std::vector<bool>& held = {});

}  // namespace lmcal::detail
