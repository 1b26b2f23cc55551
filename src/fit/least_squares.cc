#include "least_squares.hpp"

#include <fmt/format.h>
#include <nlopt.hpp>
#include <ceres/version.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>

#include "batched_autodiff.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"
#include "lmcal/fit/statistics.hpp"
#include "parallel_slices.hpp"

namespace lmcal {

const ParameterEstimate& FitResult::parameter(const std::string& name) const {
  for (const auto& p : parameters)
    if (p.name == name) return p;
  throw InvalidParameter("parameter", "no parameter named '" + name + "' in this fit");
}

std::vector<double> FitResult::values() const {
  std::vector<double> v;
  for (const auto& p : parameters) v.push_back(p.value);
  return v;
}

namespace detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInfinity = std::numeric_limits<double>::infinity();

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

// One Ceres solve over a fixed cost function, held parameters constant.
struct Polish {
  std::vector<double> theta;
  ceres::Solver::Summary summary;
  std::string brief;          // one line: solver, iterations, costs, termination
  Eigen::VectorXd residuals;  // at theta, when known (linear solve)
};

// The tolerances of every polish (Ceres' and the normal equations' alike).
constexpr double kFunctionTolerance = 1e-10, kGradientTolerance = 1e-10, kParameterTolerance = 1e-9;

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

// Levenberg-Marquardt on normal equations accumulated row by row (NormalEquationsCost): no
// Jacobian is stored, so a 10⁵-row fit stays in cache. The same method and tolerances as the
// Ceres polish: the step solves (JᵀJ + diag(JᵀJ)/Δ) δ = -Jᵀr (the diagonal of the
// Jacobi-scaled JᵀJ clamped to [1e-6, 1e32]), the radius Δ grows by 1/max(1/3, 1 - (2ρ - 1)³) after a step whose gain
// ratio ρ exceeds 1e-3 and halves (then quarters, …) after a failed one; with bounds, the
// step is projected onto the box and its predicted gain computed for the projected step.
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
  Eigen::MatrixXd H;
  Eigen::VectorXd g;
  double f = 0;
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
    const bool finite = ldlt.info() == Eigen::Success && step.allFinite() && cost_at(candidate, f_new);
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
      if (!normal.normal_equations(theta.data(), held, f, H, g)) return finish(ceres::FAILURE, "the Jacobian is not finite", iteration);
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

// Bounds make Ceres project its steps (about twice the Jacobian evaluations), so the polish
// first runs without them and repeats with them only when the minimum lies outside.
Polish polish(const ceres::CostFunction& cost, const std::vector<ParameterSpec>& specs, const std::vector<bool>& held,
              const std::vector<double>& theta, int max_iterations = 200) {
  if (inside_bounds(specs, held, theta)) {
    Polish free = solve(cost, specs, held, theta, false, max_iterations);
    if (free.summary.IsSolutionUsable() && inside_bounds(specs, held, free.theta)) return free;
  }
  std::vector<double> start = theta;
  for (std::size_t j = 0; j < specs.size(); ++j)
    if (!held[j]) start[j] = std::clamp(start[j], specs[j].lower, specs[j].upper);
  return solve(cost, specs, held, start, true, max_iterations);
}

}  // namespace

// For a model linear in its free parameters: the exact least-squares solution in one
// Gauss-Newton step from `theta`, min ‖r(θ) + J Δ‖ by a rank-revealing QR. Fills J. Falls back
// to the Ceres polish when the solution leaves the bounds or J is rank deficient.
namespace {
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
  Eigen::MatrixXd Jf(J.rows(), static_cast<Eigen::Index>(free.size()));
  for (std::size_t k = 0; k < free.size(); ++k) Jf.col(static_cast<Eigen::Index>(k)) = J.col(free[k]);
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
}  // namespace

// (JᵀJ)⁻¹ over the free parameters (held rows and columns zero): from the eigenvalues of the
// column-scaled JᵀJ when it is well conditioned, else from a rank-revealing QR of J at the
// solution: J P = Q R, (JᵀJ)⁻¹ = P (RᵀR)⁻¹ Pᵀ. This is the
// quantity ceres::Covariance computes (a test checks they agree); Ceres' dense SVD of a
// 10⁵-row J cost most of the friction fit's time budget. Returns false, with a message, when
// J is rank deficient.
bool covariance_from_jacobian(const Eigen::MatrixXd& J, const std::vector<bool>& held, Eigen::MatrixXd& covariance,
                              std::string& message) {
  const auto p = J.cols();
  covariance = Eigen::MatrixXd::Zero(p, p);
  std::vector<Eigen::Index> free;
  for (Eigen::Index j = 0; j < p; ++j)
    if (!held[static_cast<std::size_t>(j)]) free.push_back(j);
  if (free.empty()) return true;
  const auto m = static_cast<Eigen::Index>(free.size());
  // Column scaling keeps the rank decision about directions, not about units.
  Eigen::MatrixXd all = Eigen::MatrixXd::Zero(p, p);
  all.selfadjointView<Eigen::Lower>().rankUpdate(J.transpose());
  Eigen::VectorXd norms(m);
  Eigen::MatrixXd information(m, m);
  for (Eigen::Index a = 0; a < m; ++a) {
    norms[a] = std::sqrt(all(free[a], free[a]));
    if (!(norms[a] > 0)) {
      message = "the Jacobian is rank deficient at the solution: a parameter has no effect on any residual";
      return false;
    }
  }
  for (Eigen::Index a = 0; a < m; ++a)
    for (Eigen::Index b = 0; b < m; ++b) {
      const Eigen::Index i = std::max(free[a], free[b]), j = std::min(free[a], free[b]);
      information(a, b) = all(i, j) / (norms[a] * norms[b]);
    }
  // Well conditioned (the scaled JᵀJ's condition number below 1e8, J's below 1e4): the
  // inverse of the small information matrix, accurate to about 1e-8 and far cheaper than a QR
  // of a 10⁵-row J. Otherwise the QR, whose rank decision sees directions JᵀJ would lose.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> spectrum(information);
  const Eigen::VectorXd eigenvalues = spectrum.eigenvalues();
  if (spectrum.info() == Eigen::Success && eigenvalues[0] > 1e-8 * eigenvalues[m - 1]) {
    const Eigen::MatrixXd scaled = spectrum.eigenvectors() * eigenvalues.cwiseInverse().asDiagonal() *
                                   spectrum.eigenvectors().transpose();
    for (Eigen::Index a = 0; a < m; ++a)
      for (Eigen::Index b = 0; b < m; ++b) covariance(free[a], free[b]) = scaled(a, b) / (norms[a] * norms[b]);
    return true;
  }
  Eigen::MatrixXd Jf(J.rows(), m);
  for (Eigen::Index k = 0; k < m; ++k) Jf.col(k) = J.col(free[k]) / norms[k];
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Jf);
  qr.setThreshold(1e-10);
  if (qr.rank() < m) {
    message = fmt::format("the Jacobian is rank deficient at the solution (rank {} of {})", qr.rank(), m);
    return false;
  }
  const Eigen::MatrixXd R = qr.matrixR().topLeftCorner(m, m).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd Rinv = R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(m, m));
  const Eigen::MatrixXd permuted = Rinv * Rinv.transpose();
  const Eigen::MatrixXd scaled = qr.colsPermutation() * permuted * qr.colsPermutation().transpose();
  for (Eigen::Index a = 0; a < m; ++a)
    for (Eigen::Index b = 0; b < m; ++b) covariance(free[a], free[b]) = scaled(a, b) / (norms[a] * norms[b]);
  return true;
}

namespace {

// NLopt objective ½ Σ r² over a (sub)set of rows, in scaled free coordinates u = θ / scale.
struct LocalSearch {
  const ceres::CostFunction* cost;
  std::vector<double> full;
  std::vector<int> free;
  std::vector<double> scale;
  Eigen::VectorXd r;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J;

  static double objective(unsigned n, const double* u, double* grad, void* data) {
    auto& s = *static_cast<LocalSearch*>(data);
    for (unsigned k = 0; k < n; ++k) s.full[s.free[k]] = u[k] * s.scale[k];
    const double* parameters[] = {s.full.data()};
    double* jacobians[] = {s.J.data()};
    if (!s.cost->Evaluate(parameters, s.r.data(), grad ? jacobians : nullptr) || !s.r.allFinite())
      return std::numeric_limits<double>::max();
    if (grad) {
      const Eigen::VectorXd g = s.J.transpose() * s.r;
      for (unsigned k = 0; k < n; ++k) grad[k] = g[s.free[k]] * s.scale[k];
    }
    return 0.5 * s.r.squaredNorm();
  }
};

double radical_inverse(std::uint64_t index, unsigned base) {
  double result = 0, f = 1.0 / base;
  while (index > 0) {
    result += f * static_cast<double>(index % base);
    index /= base;
    f /= base;
  }
  return result;
}

// The k-th start: Halton point over the bounds (log-uniform where the bounds span > 100x).
std::vector<double> halton_start(const std::vector<ParameterSpec>& specs, const std::vector<bool>& held,
                                 const std::vector<double>& base, std::uint64_t index) {
  static constexpr unsigned kPrimes[] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53};
  std::vector<double> theta = base;
  std::size_t dim = 0;
  for (std::size_t j = 0; j < specs.size(); ++j) {
    if (held[j]) continue;
    const double h = radical_inverse(index, kPrimes[dim++ % std::size(kPrimes)]);
    const double lo = specs[j].lower, hi = specs[j].upper;
    theta[j] = lo > 0 && hi / lo > 100 ? lo * std::pow(hi / lo, h) : lo + h * (hi - lo);
  }
  return theta;
}

double relative_scale(const ParameterSpec& spec, double value) {
  // A typical size (effects neutral at 0): relative to it, or to the value where that is
  // larger — an effect estimated at 8 typical sizes with an SE of 2 is determined.
  if (spec.scale > 0) return std::max(spec.scale, std::abs(value));
  const double s = std::max(std::abs(value), std::abs(spec.start));
  return s > 0 ? s : 0.1 * (spec.upper - spec.lower);
}

struct MultiStart {
  std::vector<double> best;
  int starts = 0, agreed = 0;
  std::vector<double> costs;               // where each start ended, in start order
  std::vector<std::vector<double>> ends;   // and at which parameters
  std::size_t rows = 0;                    // residuals the searches used
};

MultiStart multi_start(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs,
                       const std::vector<bool>& held, const std::vector<double>& start, const FitOptions& options) {
  if (options.starts > io::kMaxStarts)
    throw InvalidParameter("starts", options.starts, fmt::format("at most {} (docs/formats.md#limits)", io::kMaxStarts));
  MultiStart out{start, 0, 0, {}, {}, 0};
  std::vector<int> free;
  for (std::size_t j = 0; j < specs.size(); ++j)
    if (!held[j]) free.push_back(static_cast<int>(j));
  if (free.empty() || options.starts < 1) return out;

  const std::size_t n = model.num_residuals();
  std::vector<std::size_t> rows;
  const std::size_t m = std::min(n, std::max<std::size_t>(options.subsample, 1));
  for (std::size_t k = 0; k < m; ++k) rows.push_back(k * n / m);  // evenly spread
  const auto cost = model.cost_function(rows, RowLoss{options.loss, options.loss_scale});

  std::vector<double> scale, lower, upper;
  for (int j : free) {
    scale.push_back(relative_scale(specs[j], start[j]));
    lower.push_back(specs[j].lower / scale.back());
    upper.push_back(specs[j].upper / scale.back());
  }

  // Each start's search on its own (its own buffers, its own NLopt object): side by side where
  // the model allows, and the same ends in the same order either way.
  std::vector<std::pair<double, std::vector<double>>> ends(static_cast<std::size_t>(options.starts));
  auto search_from = [&](std::size_t k) {
    std::vector<double> theta = k == 0 ? start : halton_start(specs, held, start, options.seed * 7919 + k);
    LocalSearch search{cost.get(), theta, free, scale, Eigen::VectorXd(rows.size()), {}};
    search.J.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(specs.size()));
    std::vector<double> u;
    for (std::size_t i = 0; i < free.size(); ++i) u.push_back(std::clamp(theta[free[i]] / scale[i], lower[i], upper[i]));
    nlopt::opt opt(nlopt::LD_LBFGS, static_cast<unsigned>(free.size()));
    opt.set_lower_bounds(lower);
    opt.set_upper_bounds(upper);
    opt.set_min_objective(&LocalSearch::objective, &search);
    opt.set_ftol_rel(1e-10);
    opt.set_xtol_rel(1e-8);
    opt.set_maxeval(250);
    double f = std::numeric_limits<double>::max();
    try {
      opt.optimize(u, f);
    } catch (const std::exception&) {
      // NLopt gives up on roundoff-limited or failed searches; keep the point it reached.
      f = LocalSearch::objective(static_cast<unsigned>(u.size()), u.data(), nullptr, &search);
    }
    for (std::size_t i = 0; i < free.size(); ++i) theta[free[i]] = u[i] * scale[i];
    ends[k] = {f, std::move(theta)};
  };
  if (model.costs_evaluate_concurrently()) {
    for_each_index(ends.size(), search_from);
  } else {
    for (std::size_t k = 0; k < ends.size(); ++k) search_from(k);
  }
  const auto best = std::min_element(ends.begin(), ends.end(), [](auto& a, auto& b) { return a.first < b.first; });
  out.best = best->second;
  out.starts = options.starts;
  out.rows = rows.size();
  for (const auto& [f, theta] : ends) {
    out.costs.push_back(f);
    out.ends.push_back(theta);
    if (f - best->first <= 1e-3 * std::abs(best->first) + 1e-12) ++out.agreed;
  }
  return out;
}

bool at_bound(const ParameterSpec& s, double v) {
  const double tol = 1e-7 * (s.upper - s.lower);
  return v - s.lower <= tol || s.upper - v <= tol;
}

}  // namespace

Eigen::VectorXd evaluate_residuals(const LeastSquaresModel& model, const std::vector<double>& theta,
                                   const RowLoss& loss, Eigen::MatrixXd* jacobian, const std::vector<std::size_t>& rows,
                                   const std::vector<bool>& held) {
  const auto cost = model.cost_function(rows, loss);
  const std::size_t n = rows.empty() ? model.num_residuals() : rows.size();
  Eigen::VectorXd r(static_cast<Eigen::Index>(n));
  const auto check = [&](bool evaluated) {
    if (!evaluated) throw NonFiniteResiduals("the model could not be evaluated");
    for (Eigen::Index i = 0; i < r.size(); ++i)
      if (!std::isfinite(r[i])) throw NonFiniteResiduals(fmt::format("residual {} of {} is {}", i + 1, r.size(), r[i]));
  };
  if (const auto* columns = dynamic_cast<const NormalEquationsCost*>(cost.get()); columns && jacobian) {
    check(columns->residuals_and_jacobian(theta.data(), held, r, *jacobian));
    return r;
  }
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J(static_cast<Eigen::Index>(n),
                                                                           static_cast<Eigen::Index>(theta.size()));
  const double* parameters[] = {theta.data()};
  double* jacobians[] = {J.data()};
  check(cost->Evaluate(parameters, r.data(), jacobian ? jacobians : nullptr));
  if (jacobian) *jacobian = J;
  return r;
}

namespace {

// ---- the steps of a fit ------------------------------------------------------------------

void check_specs(const std::vector<ParameterSpec>& specs) {
  for (const auto& s : specs) {
    require_finite(s.name.c_str(), s.start);
    if (s.free && !(s.lower < s.upper && std::isfinite(s.lower) && std::isfinite(s.upper)))
      throw InvalidParameter(s.name, fmt::format("bounds [{}, {}] must be finite with lower < upper", s.lower, s.upper));
    if (s.free && (s.start < s.lower || s.start > s.upper))
      throw InvalidParameter(s.name, s.start, fmt::format("a start inside the bounds [{}, {}]", s.lower, s.upper));
  }
}

// Step 0: what the design of the data rules out, held from the start.
std::vector<bool> held_by_design(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs,
                                 Identifiability& identifiability) {
  const std::size_t p = specs.size();
  std::vector<bool> held(p);
  std::vector<std::string> free_names;
  for (std::size_t j = 0; j < p; ++j) {
    held[j] = !specs[j].free;
    if (!held[j]) free_names.push_back(specs[j].name);
  }
  for (IdentifiabilityIssue& issue : model.design_issues(free_names)) {
    for (const auto& name : issue.held)
      for (std::size_t j = 0; j < p; ++j)
        if (specs[j].name == name) held[j] = true;
    identifiability.identifiable = false;
    identifiability.issues.push_back(std::move(issue));
  }
  return held;
}

std::vector<std::size_t> free_indices(const std::vector<bool>& held) {
  std::vector<std::size_t> free;
  for (std::size_t j = 0; j < held.size(); ++j)
    if (!held[j]) free.push_back(j);
  return free;
}

// The weakest direction of the fit, if the data cannot determine it: the top eigenvector of
// the relatively scaled covariance, or (J rank deficient) the null vector of JᵀJ. Returns the
// issue with the parameter that dominates it in `held`, or nothing when every direction is
// determined to `identifiability_threshold`. Records the condition number on the first call.
std::optional<IdentifiabilityIssue> weakest_direction(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs,
                                                      const FinalState& state, double s2, const FitOptions& options,
                                                      std::optional<double>& condition_number) {
  const std::vector<std::size_t> free = free_indices(state.held);
  if (free.empty()) return std::nullopt;
  const auto m = static_cast<Eigen::Index>(free.size());
  Eigen::VectorXd scale(m);
  for (Eigen::Index k = 0; k < m; ++k) scale[k] = relative_scale(specs[free[k]], state.theta[free[k]]);
  Eigen::VectorXd variance;  // relative, along each eigen-direction, largest first
  Eigen::MatrixXd directions;
  if (state.covariance_ok) {
    Eigen::MatrixXd c(m, m);
    for (Eigen::Index a = 0; a < m; ++a)
      for (Eigen::Index b = 0; b < m; ++b)
        c(a, b) = state.bread(static_cast<Eigen::Index>(free[a]), static_cast<Eigen::Index>(free[b])) / (scale[a] * scale[b]);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(c);
    variance = eig.eigenvalues().reverse().cwiseMax(0.0);
    directions = eig.eigenvectors().rowwise().reverse();
  } else {
    Eigen::MatrixXd Js(state.jacobian.rows(), m);
    for (Eigen::Index k = 0; k < m; ++k) Js.col(k) = state.jacobian.col(static_cast<Eigen::Index>(free[k])) * scale[k];
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Js.transpose() * Js);
    variance = eig.eigenvalues().cwiseMax(0.0).cwiseInverse();  // 1/0 = inf: undetermined
    directions = eig.eigenvectors();
  }
  if (!condition_number) condition_number = std::sqrt(variance[0] / variance[m - 1]);
  const double worst_se = std::sqrt(s2 * variance[0]);
  if (!(worst_se > options.identifiability_threshold) || std::isnan(s2)) return std::nullopt;

  IdentifiabilityIssue issue;
  issue.relative_se = worst_se;
  Eigen::VectorXd v = directions.col(0);
  Eigen::Index dominant = 0;
  v.cwiseAbs().maxCoeff(&dominant);
  if (v[dominant] < 0) v = -v;
  for (Eigen::Index k = 0; k < m; ++k)
    if (std::abs(v[k]) >= 0.05) issue.combination.emplace_back(specs[free[k]].name, v[k]);
  model.explain(issue);
  issue.held.push_back(specs[free[static_cast<std::size_t>(dominant)]].name);
  return issue;
}

struct Estimate {
  FinalState state;
  Polish fit;
  MultiStart starts;
  double remaining_step = 0;   // at the end, in SEs: see remaining_step()
  bool stopped_short = false;  // and a step along it lowers the cost: no minimum
  bool restarted = false;      // the polish stopped short of a minimum and was run again from the best start
};

// How far from a minimum the solution is: the Gauss-Newton step still to go, (JᵀJ)⁻¹Jᵀr, in
// standard errors (s²(JᵀJ)⁻¹), the largest over the free parameters not pressing on a bound. At
// a minimum it is ~0; a polish that stops because the cost falls too slowly along a badly
// scaled valley (μv at 1e-7 beside k1 at 0.3) leaves it large, though Ceres reports
// CONVERGENCE. 0 where the covariance could not be formed (reported on its own).
double remaining_step(const std::vector<ParameterSpec>& specs, const FinalState& state, double cost, std::size_t n) {
  if (!state.covariance_ok || state.jacobian.rows() != state.residuals.size() || state.residuals.size() == 0) return 0;
  const Eigen::VectorXd g = state.jacobian.transpose() * state.residuals;
  const Eigen::VectorXd step = -state.bread * g;
  const double dof = static_cast<double>(n) - static_cast<double>(free_indices(state.held).size());
  if (!(dof > 0) || !(cost > 0)) return 0;
  const double s2 = 2 * cost / dof;
  double worst = 0;
  for (std::size_t j = 0; j < specs.size(); ++j) {
    const auto k = static_cast<Eigen::Index>(j);
    if (state.held[j] || !(state.bread(k, k) > 0)) continue;
    const double tol = 1e-7 * (specs[j].upper - specs[j].lower);
    if ((step[k] < 0 && state.theta[j] <= specs[j].lower + tol) || (step[k] > 0 && state.theta[j] >= specs[j].upper - tol)) continue;
    worst = std::max(worst, std::abs(step[k]) / std::sqrt(s2 * state.bread(k, k)));
  }
  return worst;
}

// A step still to go above this many standard errors is no minimum, if taking it (or half, or a
// quarter of it) lowers the cost by more than a hundredth of what one SE is worth (½ s²): where
// the model is strongly nonlinear the quadratic model's step may not, and the polish did stop
// at a minimum.
constexpr double kStationary = 0.1;

bool step_lowers_cost(const ceres::CostFunction& cost, const std::vector<ParameterSpec>& specs, const FinalState& state,
                      double final_cost, std::size_t n) {
  const Eigen::VectorXd step = -state.bread * (state.jacobian.transpose() * state.residuals);
  const double dof = static_cast<double>(n) - static_cast<double>(free_indices(state.held).size());
  const double worth = 0.01 * 0.5 * (2 * final_cost / dof);
  Eigen::VectorXd r(cost.num_residuals());
  for (double t : {1.0, 0.5, 0.25}) {
    std::vector<double> theta = state.theta;
    for (std::size_t j = 0; j < specs.size(); ++j)
      if (!state.held[j]) theta[j] = std::clamp(theta[j] + t * step[static_cast<Eigen::Index>(j)], specs[j].lower, specs[j].upper);
    const double* parameters[] = {theta.data()};
    if (cost.Evaluate(parameters, r.data(), nullptr) && r.allFinite() && final_cost - 0.5 * r.squaredNorm() > worth) return true;
  }
  return false;
}

// Steps 1-3: multi-start, polish, and the covariance at the solution; a direction the data
// cannot determine is held and the rest refitted, until every direction is determined.
Estimate estimate(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs, const FitOptions& options,
                  std::vector<bool> held, Identifiability& identifiability) {
  const std::size_t p = specs.size(), n = model.num_residuals();
  std::vector<double> start(p);
  for (std::size_t j = 0; j < p; ++j) start[j] = specs[j].start;
  const RowLoss loss{options.loss, options.loss_scale};
  const auto cost = model.cost_function({}, loss);
  try {
    evaluate_residuals(model, start, loss);
  } catch (const NonFiniteResiduals& e) {
    throw NonFiniteResiduals(std::string(e.what()) + " at the start values");
  }

  // A linear model has one minimum: neither multi-start nor iterations are needed.
  const bool linear = model.linear(held) && options.loss == RobustLoss::none;
  Estimate e;
  e.starts = linear ? MultiStart{start, 1, 1, {}, {}, 0} : multi_start(model, specs, held, start, options);
  std::vector<double> theta = e.starts.best;
  // Large problems: converge on a tenth of the residuals first, so that the polish over all
  // of them starts next to the minimum and needs only a step or two.
  if (n > 20000 && !linear && model.rows_evaluate_separately()) {
    std::vector<std::size_t> rows;
    for (std::size_t k = 0; k < n / 10; ++k) rows.push_back(k * 10);
    theta = polish(*model.cost_function(rows, loss), specs, held, theta, options.max_iterations).theta;
  }
  std::optional<double> condition_number;
  FinalState& state = e.state;
  const std::vector<bool> held_given = held;
  const Identifiability identifiability_given = identifiability;
  // Polish from `theta`, hold what the data cannot determine and refit, until all is determined.
  auto settle = [&](std::vector<double> from) {
    std::vector<double> theta = std::move(from);
    held = held_given;
    identifiability = identifiability_given;
    condition_number.reset();
    for (std::size_t round = 0; round <= p; ++round) {
      if (linear && model.linear(held)) {
        e.fit = linear_solve(model, *cost, specs, held, theta, loss, state.jacobian);
        state.residuals = e.fit.residuals;
      } else {
        e.fit = polish(*cost, specs, held, theta, options.max_iterations);
        // The held parameters' columns are read by nothing after: not differentiated (a narrower Jet).
        state.residuals = evaluate_residuals(model, e.fit.theta, loss, &state.jacobian, {}, held);
      }
      theta = state.theta = e.fit.theta;
      state.held = held;
      state.covariance_message.clear();
      state.covariance_ok = covariance_from_jacobian(state.jacobian, held, state.bread, state.covariance_message);
      const double dof = static_cast<double>(n) - static_cast<double>(free_indices(held).size());
      const double s2 = dof > 0 ? 2.0 * e.fit.summary.final_cost / dof : kNaN;
      auto issue = weakest_direction(model, specs, state, s2, options, condition_number);
      if (!issue) break;
      for (std::size_t j = 0; j < p; ++j)
        if (specs[j].name == issue->held.front()) {
          held[j] = true;
          theta[j] = specs[j].start;
        }
      identifiability.identifiable = false;
      identifiability.issues.push_back(std::move(*issue));
    }
    e.remaining_step = linear ? 0.0 : remaining_step(specs, state, e.fit.summary.final_cost, n);
    e.stopped_short = e.remaining_step > kStationary && step_lowers_cost(*cost, specs, state, e.fit.summary.final_cost, n);
  };
  settle(theta);
  // Stopped short of a minimum (the starts agreed on a subsample): every start's end on all the
  // data, the best polished again; kept if it is lower.
  if (!linear && e.stopped_short && e.starts.ends.size() > 1) {
    const Estimate first = e;
    const Identifiability first_identifiability = identifiability;
    const std::optional<double> first_condition = condition_number;
    std::vector<double> best = e.starts.ends.front();
    double best_cost = std::numeric_limits<double>::infinity();
    Eigen::VectorXd r(static_cast<Eigen::Index>(n));
    for (const auto& end : e.starts.ends) {
      const double* parameters[] = {end.data()};
      if (cost->Evaluate(parameters, r.data(), nullptr) && r.allFinite() && 0.5 * r.squaredNorm() < best_cost) {
        best_cost = 0.5 * r.squaredNorm();
        best = end;
      }
    }
    settle(best);
    e.restarted = true;
    if (!(e.fit.summary.final_cost < first.fit.summary.final_cost)) {
      e = first;
      e.restarted = true;
      identifiability = first_identifiability;
      condition_number = first_condition;
    }
  }
  identifiability.condition_number = condition_number.value_or(0.0);
  return e;
}

void report_solver(const Estimate& e, const FitOptions& options, FitResult& result) {
  const auto& summary = e.fit.summary;
  SolverReport& s = result.solver;
  s.converged = summary.termination_type == ceres::CONVERGENCE;
  s.usable = summary.IsSolutionUsable() && std::isfinite(summary.final_cost);
  if (!s.usable) {
    s.unusable_reason = fmt::format("the solver failed: {}", summary.message);
  } else if (result.residuals == 0) {
    s.usable = false;
    s.unusable_reason = "no residuals: no measured value to fit";
  } else if (result.free_parameters > 0 && !(result.dof > 0)) {
    s.usable = false;
    s.unusable_reason = fmt::format("no degree of freedom left: {} residuals for {} free parameters", result.residuals,
                                    result.free_parameters);
  }
  s.iterations = static_cast<int>(summary.iterations.size()) - 1;
  s.termination = ceres::TerminationTypeToString(summary.termination_type);
  s.brief = e.fit.brief;
  s.initial_cost = summary.initial_cost;
  s.final_cost = summary.final_cost;
  s.covariance_ok = e.state.covariance_ok;
  s.covariance_message = e.state.covariance_message;
  s.starts = e.starts.starts;
  s.starts_agreed = e.starts.agreed;
  s.start_costs = e.starts.costs;
  s.start_residuals = e.starts.rows;
  s.remaining_step_se = e.remaining_step;
  s.restarted = e.restarted;
  if (e.stopped_short) {
    s.converged = false;
    result.warnings.push_back(fmt::format("the solver stopped where the cost still falls (a step of {:.2g} standard errors "
                                          "to go, > {:g}): the estimate may not be a minimum",
                                          e.remaining_step, kStationary));
  }
  if (!s.converged) result.warnings.push_back("the solver stopped without converging: " + summary.message);
  if (!s.covariance_ok && result.free_parameters > 0) result.warnings.push_back(s.covariance_message);
  if (e.starts.starts > 1 && e.starts.agreed * 2 < e.starts.starts)
    result.warnings.push_back(fmt::format(
        "only {} of {} starts reached the best minimum (the others stopped in local minima of a higher cost; the result "
        "is the best one found; more starts (--starts) may find a lower one)",
        e.starts.agreed, e.starts.starts));
  (void)options;
}

std::vector<ParameterEstimate> estimates(const std::vector<ParameterSpec>& specs, const FinalState& state) {
  std::vector<ParameterEstimate> out;
  for (std::size_t j = 0; j < specs.size(); ++j) {
    ParameterEstimate e;
    e.name = specs[j].name;
    e.unit = specs[j].unit;
    e.value = state.theta[j];
    e.start = specs[j].start;
    e.lower = specs[j].lower;
    e.upper = specs[j].upper;
    e.free = specs[j].free;
    e.held_unidentifiable = specs[j].free && state.held[j];
    e.per_run = specs[j].per_run;
    e.at_bound = !state.held[j] && at_bound(specs[j], state.theta[j]);
    e.se = e.ci_low = e.ci_high = e.profile_low = e.profile_high = e.boot_low = e.boot_high = kNaN;
    e.interval = state.held[j] ? "none" : "linear";
    out.push_back(e);
  }
  return out;
}

// Refits a profile search may spend on one side of one parameter.
constexpr int kMaxProfileFits = 24;

// Step 5: profile-likelihood intervals where the linear interval is unreliable (or everywhere,
// if asked): {θ_j : S(θ_j) − S_min <= k_j · ½ s² F(conf; 1, dof)}, k_j = max(1, chosen / iid
// variance of θ_j), so that the profile widens as the chosen covariance does.
void profile_intervals(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs, const FitOptions& options,
                       const FinalState& state, double final_cost, FitResult& result) {
  if (options.profile == ProfileMode::none || !(result.dof > 0) || result.free_parameters <= 1) return;
  const auto cost = model.cost_function({}, RowLoss{options.loss, options.loss_scale});
  const double s2 = result.residual_variance;
  const double base_threshold = 0.5 * s2 * fisher_f_quantile(options.confidence, 1, result.dof);
  const double t = student_t_quantile(1 - (1 - options.confidence) / 2, std::min(result.dof, 1e7));
  const CovarianceSummary* iid = result.uncertainty.find("iid");
  // A model linear in its parameters has a profile that is the linear interval: only a bound
  // inside the interval makes it differ.
  const bool linear = model.linear(state.held) && options.loss == RobustLoss::none;
  for (std::size_t j = 0; j < specs.size(); ++j) {
    ParameterEstimate& e = result.parameters[j];
    if (state.held[j]) continue;
    const bool truncated = e.at_bound || e.ci_low < e.lower || e.ci_high > e.upper;
    const bool unreliable = truncated || (!linear && (!std::isfinite(e.se) || e.se > 0.3 * relative_scale(specs[j], e.value)));
    // A run's nuisance parameter (an offset, a start temperature) is not quoted: `auto` spends no
    // refits on its profile.
    if (options.profile == ProfileMode::automatic && (!unreliable || specs[j].per_run)) continue;
    const double iid_se = iid ? iid->se[j] : kNaN;
    const double inflation = std::isfinite(e.se) && iid_se > 0 ? std::max(1.0, std::pow(e.se / iid_se, 2)) : 1.0;
    const double threshold = base_threshold * inflation;
    std::vector<bool> held_j = state.held;
    held_j[j] = true;
    auto excess = [&](double value) {
      std::vector<double> th = state.theta;
      th[j] = value;
      const double x = polish(*cost, specs, held_j, th).summary.final_cost - final_cost;
      e.profile_curve.push_back({value, x / threshold});
      return x;
    };
    // Each side in at most kMaxProfileFits refits (each a whole fit: minutes for a large thermal
    // model otherwise): doubling steps out from the estimate until the cost rises past the
    // threshold, then bisection to 1e-3 of the bracket. NaN: the side did not close.
    auto bound_side = [&](double direction) {
      const double limit = direction > 0 ? specs[j].upper : specs[j].lower;
      double step = std::isfinite(e.se) && e.se > 0 ? t * e.se : 0.1 * (specs[j].upper - specs[j].lower);
      double inside = e.value;
      int fits = 0;
      while (fits < kMaxProfileFits) {
        const double trial = std::clamp(e.value + direction * step, specs[j].lower, specs[j].upper);
        ++fits;
        if (excess(trial) > threshold) {
          double a = inside, b = trial;  // a inside, b outside: bisect
          while (fits < kMaxProfileFits && std::abs(b - a) > 1e-3 * std::abs(trial - e.value)) {
            const double mid = 0.5 * (a + b);
            ++fits;
            (excess(mid) > threshold ? b : a) = mid;
          }
          return 0.5 * (a + b);
        }
        if (trial == limit) return limit;
        inside = trial;
        step *= 2;
      }
      return kNaN;
    };
    e.profile_curve = {{e.value, 0.0}};
    e.profile_low = bound_side(-1);
    e.profile_high = bound_side(+1);
    if (!std::isfinite(e.profile_low) || !std::isfinite(e.profile_high)) {
      result.warnings.push_back(fmt::format("the profile of {} did not close within {} refits a side: its {} interval is quoted",
                                            e.name, kMaxProfileFits, e.interval));
      e.profile_low = e.profile_high = kNaN;
      e.profile_curve.clear();
      continue;
    }
    // The search crowds its points at the edges; half-way in and a half beyond draw the shape.
    for (const double edge : {e.profile_low, e.profile_high}) {
      excess(e.value + 0.5 * (edge - e.value));
      const double beyond = std::clamp(e.value + 1.5 * (edge - e.value), specs[j].lower, specs[j].upper);
      if (beyond != edge) excess(beyond);
    }
    std::sort(e.profile_curve.begin(), e.profile_curve.end(), [](const ProfilePoint& a, const ProfilePoint& b) { return a.value < b.value; });
    e.interval = "profile";
  }
}

// A fit whose residuals could not be evaluated (`why`): the start values, no uncertainty, and
// usable = false with the reason.
FitResult unusable_fit(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs, const std::vector<bool>& held,
                       const std::string& why, FinalState* final_state) {
  const auto n = static_cast<Eigen::Index>(model.num_residuals());
  const auto p = static_cast<Eigen::Index>(specs.size());
  FinalState state;
  for (const auto& s : specs) state.theta.push_back(s.start);
  state.held = held;
  state.residuals = Eigen::VectorXd::Constant(n, kNaN);
  state.jacobian = Eigen::MatrixXd::Zero(n, p);
  state.bread = Eigen::MatrixXd::Zero(p, p);
  state.covariance_message = "no covariance: the residuals are not finite";
  FitResult result;
  result.residuals = model.num_residuals();
  result.free_parameters = free_indices(held).size();
  result.dof = static_cast<double>(result.residuals) - static_cast<double>(result.free_parameters);
  result.residual_variance = kNaN;
  result.parameters = estimates(specs, state);
  for (auto& e : result.parameters) e.interval = "none";
  result.covariance = Eigen::MatrixXd::Zero(p, p);
  result.correlation = Eigen::MatrixXd::Constant(p, p, kNaN);
  SolverReport& s = result.solver;
  s.converged = s.usable = false;
  s.termination = "FAILURE";
  s.initial_cost = s.final_cost = kNaN;
  s.remaining_step_se = kNaN;
  s.covariance_message = state.covariance_message;
  s.brief = fmt::format("not fitted: {}", why);
  s.unusable_reason = fmt::format("the residuals are not finite: {}", why);
  result.warnings.push_back(fmt::format("the fit failed: {} (an input far outside what the model was built for?)", why));
  if (final_state) *final_state = std::move(state);
  return result;
}

}  // namespace

// The fit as a sequence of named steps; each is a function above (uncertainty.cc for step 4).
FitResult solve_least_squares(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs,
                              const FitOptions& options, FinalState* final_state) {
  const auto clock_start = std::chrono::steady_clock::now();
  check_specs(specs);
  FitResult result;
  result.residuals = model.num_residuals();

  const std::vector<bool> held = held_by_design(model, specs, result.identifiability);       // 0
  Estimate e;
  try {
    e = estimate(model, specs, options, held, result.identifiability);                        // 1-3
    model.estimate_settled();
  } catch (const NonFiniteResiduals& failure) {
    model.estimate_settled();
    result = unusable_fit(model, specs, held, failure.what(), final_state);
    result.solver.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
    return result;
  }
  result.free_parameters = free_indices(e.state.held).size();
  result.dof = static_cast<double>(result.residuals) - static_cast<double>(result.free_parameters);
  result.residual_variance = result.dof > 0 ? 2.0 * e.fit.summary.final_cost / result.dof : kNaN;
  result.parameters = estimates(specs, e.state);
  report_solver(e, options, result);
  for (const auto& p : result.parameters)
    if (p.at_bound) result.warnings.push_back(fmt::format("{} = {} sits on a bound [{}, {}]", p.name, p.value, p.lower, p.upper));

  assess_uncertainty(model.row_structure(), options, e.state, result);                         // 4
  profile_intervals(model, specs, options, e.state, e.fit.summary.final_cost, result);         // 5

  if (final_state) *final_state = std::move(e.state);
  result.solver.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
  return result;
}

GroupNormalEquations group_normal_equations(const FinalState& state, const std::vector<std::size_t>& group_of_row) {
  const Eigen::MatrixXd& J = state.jacobian;
  const Eigen::VectorXd& r = state.residuals;
  const auto p = J.cols();
  const std::size_t groups = group_of_row.empty() ? 0 : *std::max_element(group_of_row.begin(), group_of_row.end()) + 1;
  GroupNormalEquations sums{std::vector<Eigen::MatrixXd>(groups, Eigen::MatrixXd::Zero(p, p)),
                            std::vector<Eigen::VectorXd>(groups, Eigen::VectorXd::Zero(p)), Eigen::MatrixXd::Zero(p, p)};
  // By stretches of consecutive rows of one group: a rank-k update each (BLAS-3 speed).
  for (std::size_t first = 0; first < group_of_row.size();) {
    std::size_t last = first + 1;
    while (last < group_of_row.size() && group_of_row[last] == group_of_row[first]) ++last;
    const auto start = static_cast<Eigen::Index>(first), length = static_cast<Eigen::Index>(last - first);
    const std::size_t g = group_of_row[first];
    sums.H[g].selfadjointView<Eigen::Lower>().rankUpdate(J.middleRows(start, length).transpose());
    sums.b[g].noalias() += J.middleRows(start, length).transpose() * r.segment(start, length);
    first = last;
  }
  for (auto& h : sums.H) {
    h = h.selfadjointView<Eigen::Lower>();
    sums.total += h;
  }
  return sums;
}

Eigen::VectorXd leave_group_out_step(const GroupNormalEquations& sums, std::size_t g, const std::vector<bool>& held,
                                     bool* undetermined) {
  std::vector<Eigen::Index> free;
  for (std::size_t j = 0; j < held.size(); ++j)
    if (!held[j]) free.push_back(static_cast<Eigen::Index>(j));
  const auto m = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd A(m, m);
  Eigen::VectorXd b(m);
  for (Eigen::Index a = 0; a < m; ++a) {
    b[a] = sums.b[g][free[static_cast<std::size_t>(a)]];
    for (Eigen::Index c = 0; c < m; ++c)
      A(a, c) = sums.total(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(c)]) -
                sums.H[g](free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(c)]);
  }
  // The other groups may leave a direction undetermined (a load only the held-out run has):
  // the matrix without g is then singular, and its solve an arbitrary step (10^5 N held-out
  // errors on 2 N data). With the columns scaled to unit diagonal of the whole, an eigenvalue
  // below kUndetermined of the largest is such a direction (legitimate designs measured here
  // stay above 1e-5; singular ones fall to rounding, 1e-15). The step is then taken in the
  // determined directions only: the undetermined ones stay at the full fit's estimate.
  constexpr double kUndetermined = 1e-9;
  Eigen::VectorXd scale(m);
  for (Eigen::Index a = 0; a < m; ++a) {
    const double d = sums.total(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(a)]);
    scale[a] = d > 0 ? 1 / std::sqrt(d) : 1.0;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scale.asDiagonal() * A * scale.asDiagonal());
  const Eigen::VectorXd& lambda = eigen.eigenvalues();  // ascending
  const bool singular = m > 0 && !(lambda[0] > kUndetermined * lambda[m - 1]);
  if (undetermined) *undetermined = singular;
  Eigen::VectorXd step;
  if (!singular) {
    step = A.ldlt().solve(b);
  } else {
    Eigen::VectorXd inverse = Eigen::VectorXd::Zero(m);
    for (Eigen::Index k = 0; k < m; ++k)
      if (lambda[k] > kUndetermined * lambda[m - 1]) inverse[k] = 1 / lambda[k];
    const Eigen::MatrixXd& V = eigen.eigenvectors();
    step = scale.asDiagonal() * (V * inverse.asDiagonal() * V.transpose() * (scale.asDiagonal() * b));
  }
  Eigen::VectorXd out = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(held.size()));
  for (Eigen::Index a = 0; a < m; ++a) out[free[static_cast<std::size_t>(a)]] = step[a];
  return out;
}

Eigen::VectorXd leave_group_out_residuals(const FinalState& state, const std::vector<std::size_t>& group_of_row,
                                          const std::vector<bool>& held, std::vector<std::size_t>* undetermined) {
  const GroupNormalEquations sums = group_normal_equations(state, group_of_row);
  Eigen::VectorXd out = state.residuals;
  std::vector<Eigen::VectorXd> step(sums.H.size());
  for (std::size_t g = 0; g < step.size(); ++g) {
    bool alone = false;
    step[g] = leave_group_out_step(sums, g, held, &alone);
    if (alone && undetermined) undetermined->push_back(g);
  }
  for (Eigen::Index i = 0; i < out.size(); ++i) out[i] += state.jacobian.row(i).dot(step[group_of_row[static_cast<std::size_t>(i)]]);
  return out;
}

}  // namespace detail
}  // namespace lmcal
