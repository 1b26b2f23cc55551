// The polish's Levenberg-Marquardt on normal equations accumulated row by row (no Jacobian
// stored): the engine's solver for costs that are a NormalEquationsCost.
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "least_squares_steps.hpp"

namespace lmcal::detail::engine {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// H and g restricted to the free parameters.
void restrict_to_free(const Eigen::MatrixXd& H, const Eigen::VectorXd& g, const std::vector<Eigen::Index>& free,
                      Eigen::MatrixXd& Hf, Eigen::VectorXd& gf) {
  const auto m = static_cast<Eigen::Index>(free.size());
  for (Eigen::Index a = 0; a < m; ++a) {
    gf[a] = g[free[static_cast<std::size_t>(a)]];
    for (Eigen::Index b = 0; b < m; ++b) Hf(a, b) = H(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(b)]);
  }
}

// Converged when the projected gradient step is negligible: max |x - Π(x - g)|.
bool gradient_small(const std::vector<double>& theta, const Eigen::VectorXd& gf, const std::vector<Eigen::Index>& free,
                    const std::vector<ParameterSpec>& specs, bool bounded) {
  const auto m = static_cast<Eigen::Index>(free.size());
  double worst = 0;
  for (Eigen::Index k = 0; k < m; ++k) {
    const auto j = static_cast<std::size_t>(free[static_cast<std::size_t>(k)]);
    double moved = theta[j] - gf[k];
    if (bounded) moved = std::clamp(moved, specs[j].lower, specs[j].upper);
    worst = std::max(worst, std::abs(theta[j] - moved));
  }
  return worst <= kGradientTolerance;
}

// One step's system A δ = rhs: JᵀJ plus its damped, Jacobi-scaled diagonal (clamped to
// [1e-6, 1e32]) over the radius. A parameter on a bound that the gradient pushes outwards
// stays there this step (its row and column decoupled): the others' step is then not spoiled
// by the projection.
struct DampedSystem {
  Eigen::MatrixXd A;
  Eigen::VectorXd rhs;
};
DampedSystem damped_system(const Eigen::MatrixXd& Hf, const Eigen::VectorXd& gf, const Eigen::VectorXd& scale,
                           double radius, const std::vector<double>& theta, const std::vector<Eigen::Index>& free,
                           const std::vector<ParameterSpec>& specs, bool bounded) {
  const auto m = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd A = Hf;
  for (Eigen::Index k = 0; k < m; ++k)
    A(k, k) += std::clamp(Hf(k, k) * scale[k] * scale[k], 1e-6, 1e32) / (scale[k] * scale[k]) / radius;
  Eigen::VectorXd rhs = -gf;
  for (Eigen::Index k = 0; k < m && bounded; ++k) {
    const auto j = static_cast<std::size_t>(free[static_cast<std::size_t>(k)]);
    if ((theta[j] <= specs[j].lower && gf[k] > 0) || (theta[j] >= specs[j].upper && gf[k] < 0)) {
      const double d = A(k, k);
      A.row(k).setZero();
      A.col(k).setZero();
      A(k, k) = d;
      rhs[k] = 0;
    }
  }
  return {std::move(A), std::move(rhs)};
}

// θ + δ projected onto the bounds; δ becomes the step as projected, and ‖δ‖², ‖θ‖² (over the
// free parameters) are added to step_norm and x_norm.
std::vector<double> projected_candidate(const std::vector<double>& theta, Eigen::VectorXd& step,
                                        const std::vector<Eigen::Index>& free, const std::vector<ParameterSpec>& specs,
                                        bool bounded, double& step_norm, double& x_norm) {
  const auto m = static_cast<Eigen::Index>(free.size());
  std::vector<double> candidate = theta;
  for (Eigen::Index k = 0; k < m; ++k) candidate[static_cast<std::size_t>(free[static_cast<std::size_t>(k)])] += step[k];
  for (Eigen::Index k = 0; k < m && bounded; ++k) {
    const auto j = static_cast<std::size_t>(free[static_cast<std::size_t>(k)]);
    candidate[j] = std::clamp(candidate[j], specs[j].lower, specs[j].upper);
  }
  for (Eigen::Index k = 0; k < m; ++k) {
    const auto j = static_cast<std::size_t>(free[static_cast<std::size_t>(k)]);
    step[k] = candidate[j] - theta[j];  // as projected
    step_norm += step[k] * step[k];
    x_norm += theta[j] * theta[j];
  }
  return candidate;
}

}  // namespace

// Levenberg-Marquardt on normal equations accumulated row by row (NormalEquationsCost): no
// Jacobian is stored, so a 10⁵-row fit stays in cache. The same method and tolerances as the
// Ceres polish: the step solves (JᵀJ + diag(JᵀJ)/Δ) δ = -Jᵀr (the diagonal of the
// Jacobi-scaled JᵀJ clamped to [1e-6, 1e32]), the radius Δ grows by 1/max(1/3, 1 - (2ρ - 1)³) after a step whose gain
// ratio ρ exceeds 1e-3 and halves (then quarters, …) after a failed one; with bounds, the
// step is projected onto the box and its predicted gain computed for the projected step. A
// trial's cost is a residual pass, or, where the cost asks for it (normal_equations_at_trials),
// its normal equations, kept for the next iteration when the step is taken.
Polish solve_normal_equations(const NormalEquationsCost& normal, const ceres::CostFunction& cost,
                              const std::vector<ParameterSpec>& specs, const std::vector<bool>& held,
                              std::vector<double> theta, bool bounded, int max_iterations) {
  Polish out;
  ceres::Solver::Summary& summary = out.summary;
  std::vector<Eigen::Index> free;
  for (std::size_t j = 0; j < specs.size(); ++j)
    if (!held[j]) free.push_back(static_cast<Eigen::Index>(j));
  const auto m = static_cast<Eigen::Index>(free.size());
  Eigen::VectorXd r(cost.num_residuals());
  auto cost_at = [&](const std::vector<double>& x, double& value) {
    const double* parameters[] = {x.data()};
    if (!cost.Evaluate(parameters, r.data(), nullptr) || !r.allFinite()) return false;
    value = 0.5 * r.squaredNorm();
    return true;
  };
  auto finish = [&](ceres::TerminationType type, std::string message, int iterations) {
    summary.termination_type = type;
    summary.message = std::move(message);
    summary.iterations.resize(static_cast<std::size_t>(iterations) + 1);
    out.brief = fmt::format("Levenberg-Marquardt on the row-by-row normal equations: Iterations: {}, Initial cost: {:e}, "
                            "Final cost: {:e}, Termination: {}",
                            iterations, summary.initial_cost, summary.final_cost, ceres::TerminationTypeToString(type));
    out.theta = std::move(theta);
    return std::move(out);
  };
  Eigen::MatrixXd H, H_new;
  Eigen::VectorXd g, g_new;
  double f = 0;
  const bool at_trials = normal.normal_equations_at_trials();
  if (!normal.normal_equations(theta.data(), held, f, H, g)) {
    summary.initial_cost = summary.final_cost = kNaN;
    return finish(ceres::FAILURE, "the residuals are not finite at the start", 0);
  }
  summary.initial_cost = summary.final_cost = f;
  if (m == 0) return finish(ceres::CONVERGENCE, "no free parameters", 0);
  double radius = 1e4, decrease = 2;
  Eigen::MatrixXd Hf(m, m);
  Eigen::VectorXd gf(m);
  restrict_to_free(H, g, free, Hf, gf);
  if (gradient_small(theta, gf, free, specs, bounded)) return finish(ceres::CONVERGENCE, "gradient tolerance reached at the start", 0);
  // Ceres' Jacobi scaling, fixed at the start: s_j = 1 / (1 + ‖J_j‖); the diagonal's clamp
  // applies to the scaled columns.
  Eigen::VectorXd scale(m);
  for (Eigen::Index k = 0; k < m; ++k) scale[k] = 1.0 / (1.0 + std::sqrt(std::max(Hf(k, k), 0.0)));
  for (int iteration = 1; iteration <= max_iterations; ++iteration) {
    const DampedSystem system = damped_system(Hf, gf, scale, radius, theta, free, specs, bounded);
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(system.A);
    Eigen::VectorXd step = ldlt.solve(system.rhs);
    double step_norm = 0, x_norm = 0;
    std::vector<double> candidate = projected_candidate(theta, step, free, specs, bounded, step_norm, x_norm);
    if (ldlt.info() == Eigen::Success && std::sqrt(step_norm) <= kParameterTolerance * (std::sqrt(x_norm) + kParameterTolerance))
      return finish(ceres::CONVERGENCE, "parameter tolerance reached", iteration);
    const double predicted = -(gf.dot(step) + 0.5 * step.dot(Hf * step));
    double f_new = 0;
    const bool solved = ldlt.info() == Eigen::Success && step.allFinite();
    const bool finite = solved && (at_trials ? normal.normal_equations(candidate.data(), held, f_new, H_new, g_new)
                                             : cost_at(candidate, f_new));
    const double gain = finite ? f - f_new : -kInfinity;
    if (finite && std::abs(gain) <= kFunctionTolerance * f) {
      if (gain > 0) theta = std::move(candidate), summary.final_cost = f_new;
      return finish(ceres::CONVERGENCE, "function tolerance reached", iteration);
    }
    const double rho = predicted > 0 ? gain / predicted : -1;
    if (finite && rho > 1e-3) {
      theta = std::move(candidate);
      f = f_new;
      summary.final_cost = f;
      radius = std::min(radius / std::max(1.0 / 3.0, 1.0 - std::pow(2 * rho - 1, 3)), 1e16);
      decrease = 2;
      if (at_trials) {
        H.swap(H_new);
        g.swap(g_new);
      } else if (!normal.normal_equations(theta.data(), held, f, H, g)) {
        return finish(ceres::FAILURE, "the Jacobian is not finite", iteration);
      }
      summary.final_cost = f;
      restrict_to_free(H, g, free, Hf, gf);
      if (gradient_small(theta, gf, free, specs, bounded)) return finish(ceres::CONVERGENCE, "gradient tolerance reached", iteration);
    } else {
      radius /= decrease;
      decrease *= 2;
      if (radius < 1e-32) return finish(ceres::CONVERGENCE, "the trust region shrank below 1e-32", iteration);
    }
  }
  return finish(ceres::NO_CONVERGENCE, fmt::format("maximum number of iterations reached ({})", max_iterations),
                max_iterations);
}

}  // namespace lmcal::detail::engine
