// The state at a fit's final estimate and what its Jacobian gives without refitting: (JᵀJ)⁻¹
// over the free parameters and the leave-one-group-out steps (least_squares_state.cc).
// Ceres-free: for code that reads a fit's end, not the engine that reaches it.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

namespace lmcal::detail {

// The state at the final estimate, for callers that derive more from it.
struct FinalState {
  std::vector<double> theta;
  std::vector<bool> held;      // held parameters (given, or not identifiable)
  Eigen::VectorXd residuals;
  Eigen::MatrixXd jacobian;    // all parameters (a held one's column may be 0: evaluate_residuals)
  Eigen::MatrixXd bread;       // (JᵀJ)⁻¹ over the free parameters, rows/columns of held ones zero
  bool covariance_ok = false;
  std::string covariance_message;
};

// Leave-one-group-out residuals without refitting: with group g removed, one Gauss-Newton
// step from the full-data optimum, Δθ = (JᵀJ - J_gᵀJ_g)⁻¹ J_gᵀ r_g (the gradient of the rest
// is -J_gᵀ r_g there), and group g's residuals become r_g - J_g Δθ... with r = data - model,
// ∂r/∂θ = J: r_g + J_g Δθ. Returns every row's held-out residual. `held` parameters stay.
// Exact for models linear in θ; otherwise the usual one-step approximation of refitting.
// Where the other groups leave a direction of θ undetermined (only group g varies a condition
// the model needs), that direction keeps the full fit's estimate and g goes into `undetermined`
// (its held-out residuals are then optimistic there: say so).
Eigen::VectorXd leave_group_out_residuals(const FinalState& state, const std::vector<std::size_t>& group_of_row,
                                          const std::vector<bool>& held, std::vector<std::size_t>* undetermined = nullptr);

// The same in parts, for callers that hold out each group with its own parameters held:
// J_gᵀJ_g and J_gᵀr_g per group over all parameters (computed once, by blocks of consecutive
// rows), and the held-out step of one group.
struct GroupNormalEquations {
  std::vector<Eigen::MatrixXd> H;  // per group, all parameters
  std::vector<Eigen::VectorXd> b;
  Eigen::MatrixXd total;           // Σ_g H_g
};
GroupNormalEquations group_normal_equations(const FinalState& state, const std::vector<std::size_t>& group_of_row);
// Δθ with group g left out and `held` parameters kept (zero in the result); the directions the
// other groups leave undetermined kept too, and `*undetermined` set when there are any.
Eigen::VectorXd leave_group_out_step(const GroupNormalEquations& sums, std::size_t g, const std::vector<bool>& held,
                                     bool* undetermined = nullptr);

// (JᵀJ)⁻¹ over the parameters not held (rows/columns of held ones zero); false with a message
// when J is rank deficient.
bool covariance_from_jacobian(const Eigen::MatrixXd& J, const std::vector<bool>& held, Eigen::MatrixXd& covariance,
                              std::string& message);

}  // namespace lmcal::detail
