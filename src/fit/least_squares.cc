// solve_least_squares as its named steps (the engine's other files take one step each), the
// fit's result assembled from them, and the residuals every step evaluates.
#include "least_squares.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>

#include "least_squares_steps.hpp"
#include "lmcal/error.hpp"

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

using engine::Estimate;
using engine::estimate;
using engine::free_indices;
using engine::kNaN;
using engine::kStationary;
using engine::profile_intervals;

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

// The fit as a sequence of named steps; each is a function above or in least_squares_*.cc
// (least_squares_steps.hpp; uncertainty.cc for step 4).
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

}  // namespace detail
}  // namespace lmcal
