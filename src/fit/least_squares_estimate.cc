// Steps 1-3 of a fit: the multi-start, the polish and the identifiability rounds (a
// direction the data cannot determine held and the rest refitted), and whether the polish
// ended at a minimum.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "least_squares_steps.hpp"

namespace lmcal::detail::engine {

namespace {

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

}  // namespace

// Steps 1-3: multi-start, polish, and the covariance at the solution; a direction the data
// cannot determine is held and the rest refitted, until every direction is determined.
Estimate estimate(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs, const FitOptions& options,
                  std::vector<bool> held, Identifiability& identifiability) {
  const std::size_t p = specs.size(), n = model.num_residuals();
  std::vector<double> start(p);
  for (std::size_t j = 0; j < p; ++j) start[j] = specs[j].start;
  const RowLoss loss{options.loss, options.loss_scale};
  const auto cost = model.cost_function({}, loss);
  auto at_start = [](const NonFiniteResiduals& e) { return NonFiniteResiduals(std::string(e.what()) + " at the start values"); };
  // A linear model has one minimum: neither multi-start nor iterations are needed. Its
  // residuals at the start come with its Jacobian there (the first round below); any other's
  // are checked first.
  const bool linear = model.linear(held) && options.loss == RobustLoss::none;
  try {
    if (!linear) evaluate_residuals(model, start, loss);
  } catch (const NonFiniteResiduals& e) {
    throw at_start(e);
  }
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
        try {
          e.fit = linear_solve(model, *cost, specs, held, theta, loss, state.jacobian);
        } catch (const NonFiniteResiduals& failure) {
          if (round == 0 && theta == start) throw at_start(failure);
          throw;
        }
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

}  // namespace lmcal::detail::engine
