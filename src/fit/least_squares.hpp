// The least-squares engine behind every lmcal fit (private: Ceres and NLopt stay here).
//
//   1. multi-start: `starts` local searches with NLopt (bounded L-BFGS on a subsample of
//      the residuals, gradient from the model's own autodiff cost function), from the
//      given start and from a Halton sequence over the bounds;
//   2. polish: Ceres Levenberg-Marquardt on all residuals from the best start, with
//      bounds, held parameters (SubsetManifold) and an optional robust loss (row by row);
//   3. uncertainty: (JᵀJ)⁻¹ from a rank-revealing QR of the autodiff Jacobian (what
//      ceres::Covariance computes; tested against it), scaled by s², t intervals, correlation;
//   4. identifiability: the eigen-directions of the relatively scaled covariance (or the
//      null space of JᵀJ when Ceres finds the Jacobian rank deficient); a direction the
//      data cannot determine is named (via the model's explain()) and the parameter that
//      dominates it is held at its start, then 2-4 repeat;
//   5. profile-likelihood intervals where the linear interval is unreliable.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "batched_autodiff.hpp"
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
  // What the design of the data rules out before any fit (e.g. one temperature: no β); each
  // issue names in `held` the parameters to hold. `free` are the parameters asked free.
  virtual std::vector<IdentifiabilityIssue> design_issues(const std::vector<std::string>& free) const {
    (void)free;
    return {};
  }
};

// The residuals and Jacobian at the final estimate, for callers that derive more from them.
struct FinalState {
  Eigen::VectorXd residuals;
  Eigen::MatrixXd jacobian;
};

FitResult solve_least_squares(const LeastSquaresModel& model, const std::vector<ParameterSpec>& parameters,
                              const FitOptions& options, FinalState* final_state = nullptr);

// Leave-one-group-out residuals without refitting: with group g removed, one Gauss-Newton
// step from the full-data optimum, Δθ = (JᵀJ - J_gᵀJ_g)⁻¹ J_gᵀ r_g (the gradient of the rest
// is -J_gᵀ r_g there), and group g's residuals become r_g - J_g Δθ... with r = data - model,
// ∂r/∂θ = J: r_g + J_g Δθ. Returns every row's held-out residual. `held` parameters stay.
// Exact for models linear in θ; otherwise the usual one-step approximation of refitting.
Eigen::VectorXd leave_group_out_residuals(const FinalState& state, const std::vector<std::size_t>& group_of_row,
                                          const std::vector<bool>& held);

// (JᵀJ)⁻¹ over the parameters not held (rows/columns of held ones zero); false with a message
// when J is rank deficient.
bool covariance_from_jacobian(const Eigen::MatrixXd& J, const std::vector<bool>& held, Eigen::MatrixXd& covariance,
                              std::string& message);

// Residuals r(θ) and, if `jacobian` is given, ∂r/∂θ (rows x parameters), over `rows`.
Eigen::VectorXd evaluate_residuals(const LeastSquaresModel& model, const std::vector<double>& theta,
                                   const RowLoss& loss = {}, Eigen::MatrixXd* jacobian = nullptr,
                                   const std::vector<std::size_t>& rows = {});

}  // namespace lmcal::detail
