// Step 2, the polish: Levenberg-Marquardt on all rows from the best start, with bounds and
// held parameters (the engine's own on the normal equations for a NormalEquationsCost, as the
// friction and thermal models' are; Ceres' for any other cost), or one exact Gauss-Newton step
// for a model linear in its parameters.
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>

#include "least_squares_steps.hpp"

namespace lmcal::detail::engine {

namespace {

// The residual block of `cost` on `theta` with its loss, bounds and held parameters.
void build_problem(ceres::Problem& problem, const ceres::CostFunction& cost, const std::vector<ParameterSpec>& specs,
                   const std::vector<bool>& held, double* theta, bool bounded) {
  const int p = static_cast<int>(specs.size());
  problem.AddResidualBlock(const_cast<ceres::CostFunction*>(&cost), nullptr, theta);
  std::vector<int> constant;
  for (int j = 0; j < p; ++j)
    if (held[j]) constant.push_back(j);
  if (static_cast<int>(constant.size()) == p) {
    problem.SetParameterBlockConstant(theta);
    return;
  }
  if (!constant.empty()) problem.SetManifold(theta, new ceres::SubsetManifold(p, constant));
  for (int j = 0; j < p && bounded; ++j) {
    if (held[j]) continue;
    problem.SetParameterLowerBound(theta, j, specs[j].lower);
    problem.SetParameterUpperBound(theta, j, specs[j].upper);
  }
}

ceres::Problem::Options problem_options() {
  ceres::Problem::Options o;
  o.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  return o;
}

Polish solve(const ceres::CostFunction& cost, const std::vector<ParameterSpec>& specs, const std::vector<bool>& held,
             std::vector<double> theta, bool bounded, int max_iterations) {
  if (const auto* normal = dynamic_cast<const NormalEquationsCost*>(&cost))
    return solve_normal_equations(*normal, cost, specs, held, std::move(theta), bounded, max_iterations);
  Polish out;
  ceres::Problem problem(problem_options());
  build_problem(problem, cost, specs, held, theta.data(), bounded);
  ceres::Solver::Options solver;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  // Tall problems (10⁵ rows, a handful of parameters): JᵀJ once per iteration is far cheaper
  // than a QR of J, and identifiability is settled before the covariance is trusted.
  solver.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver.max_num_iterations = max_iterations;
  solver.function_tolerance = kFunctionTolerance;
  solver.gradient_tolerance = kGradientTolerance;
  solver.parameter_tolerance = kParameterTolerance;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  ceres::Solve(solver, &problem, &out.summary);
  out.brief = out.summary.BriefReport();
  out.theta = std::move(theta);
  return out;
}

bool inside_bounds(const std::vector<ParameterSpec>& specs, const std::vector<bool>& held, const std::vector<double>& theta) {
  for (std::size_t j = 0; j < specs.size(); ++j)
    if (!held[j] && !(theta[j] >= specs[j].lower && theta[j] <= specs[j].upper)) return false;
  return true;
}

}  // namespace

// Bounds make Ceres project its steps (about twice the Jacobian evaluations), so the polish
// first runs without them and repeats with them only when the minimum lies outside.
Polish polish(const ceres::CostFunction& cost, const std::vector<ParameterSpec>& specs, const std::vector<bool>& held,
              const std::vector<double>& theta, int max_iterations) {
  if (inside_bounds(specs, held, theta)) {
    Polish free = solve(cost, specs, held, theta, false, max_iterations);
    if (free.summary.IsSolutionUsable() && inside_bounds(specs, held, free.theta)) return free;
  }
  std::vector<double> start = theta;
  for (std::size_t j = 0; j < specs.size(); ++j)
    if (!held[j]) start[j] = std::clamp(start[j], specs[j].lower, specs[j].upper);
  return solve(cost, specs, held, start, true, max_iterations);
}

// For a model linear in its free parameters: the exact least-squares solution in one
// Gauss-Newton step from `theta`, min ‖r(θ) + J Δ‖ by a rank-revealing QR. Fills J. Falls back
// to the Ceres polish when the solution leaves the bounds or J is rank deficient.
Polish linear_solve(const LeastSquaresModel& model, const ceres::CostFunction& cost,
                    const std::vector<ParameterSpec>& specs, const std::vector<bool>& held, std::vector<double> theta,
                    const RowLoss& loss, Eigen::MatrixXd& J) {
  const Eigen::VectorXd r0 = evaluate_residuals(model, theta, loss, &J, {}, held);
  std::vector<Eigen::Index> free;
  for (std::size_t j = 0; j < specs.size(); ++j)
    if (!held[j]) free.push_back(static_cast<Eigen::Index>(j));
  if (free.empty()) {  // nothing to solve for: a QR of no columns is not a decomposition
    Polish out;
    out.theta = theta;
    out.residuals = r0;
    out.summary.termination_type = ceres::CONVERGENCE;
    out.summary.initial_cost = out.summary.final_cost = 0.5 * r0.squaredNorm();
    out.summary.message = out.brief = "no free parameters: nothing to solve for";
    return out;
  }
  // The free columns: J itself when none is held (a tall J is not copied once more for nothing).
  const bool some_held = free.size() != static_cast<std::size_t>(J.cols());
  Eigen::MatrixXd held_out;
  if (some_held) {
    held_out.resize(J.rows(), static_cast<Eigen::Index>(free.size()));
    for (std::size_t k = 0; k < free.size(); ++k) held_out.col(static_cast<Eigen::Index>(k)) = J.col(free[k]);
  }
  const Eigen::MatrixXd& Jf = some_held ? held_out : J;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Jf);
  if (qr.rank() == Jf.cols()) {
    const Eigen::VectorXd step = qr.solve(-r0);
    std::vector<double> solved = theta;
    for (std::size_t k = 0; k < free.size(); ++k) solved[static_cast<std::size_t>(free[k])] += step[static_cast<Eigen::Index>(k)];
    if (inside_bounds(specs, held, solved)) {
      Polish out;
      out.theta = solved;
      const Eigen::VectorXd r = r0 + Jf * step;  // exact: the residuals are linear in the step
      out.residuals = r;
      out.summary.termination_type = ceres::CONVERGENCE;
      out.summary.initial_cost = 0.5 * r0.squaredNorm();
      out.summary.final_cost = 0.5 * r.squaredNorm();
      out.summary.iterations.resize(2);
      out.summary.message = "linear in the free parameters: exact in one Gauss-Newton step";
      out.brief = fmt::format("linear in the free parameters: one Gauss-Newton step, exact (rank-revealing QR): "
                              "Initial cost: {:e}, Final cost: {:e}, Termination: CONVERGENCE",
                              out.summary.initial_cost, out.summary.final_cost);
      return out;
    }
  }
  // (The residuals too: a rank-deficient J, say a parameter the data do not see, came here
  // without them and crashed the covariance that reads them.)
  Polish out = polish(cost, specs, held, theta);
  out.residuals = evaluate_residuals(model, out.theta, loss, &J, {}, held);
  return out;
}

}  // namespace lmcal::detail::engine
