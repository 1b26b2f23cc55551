#include "fit_json.hpp"

#include <cmath>

namespace lmcal::detail {

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json fit_json(const FitResult& fit) {
  nlohmann::json parameters = nlohmann::json::array();
  std::vector<std::string> names;
  for (const auto& p : fit.parameters) {
    names.push_back(p.name);
    parameters.push_back({{"name", p.name},
                          {"unit", p.unit},
                          {"value", number(p.value)},
                          {"start", p.start},
                          {"bounds", {p.lower, p.upper}},
                          {"free", p.free},
                          {"held_unidentifiable", p.held_unidentifiable},
                          {"at_bound", p.at_bound},
                          {"se", number(p.se)},
                          {"ci95", {number(p.ci_low), number(p.ci_high)}},
                          {"profile_ci95", {number(p.profile_low), number(p.profile_high)}},
                          {"interval", p.interval}});
  }
  nlohmann::json correlation = nlohmann::json::array();
  for (Eigen::Index i = 0; i < fit.correlation.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index j = 0; j < fit.correlation.cols(); ++j) row.push_back(number(fit.correlation(i, j)));
    correlation.push_back(row);
  }
  nlohmann::json issues = nlohmann::json::array();
  for (const auto& issue : fit.identifiability.issues) {
    nlohmann::json combo = nlohmann::json::object();
    for (const auto& [name, w] : issue.combination) combo[name] = w;
    issues.push_back({{"combination", combo},
                      {"relative_se", number(issue.relative_se)},
                      {"why", issue.why},
                      {"measure", issue.measure},
                      {"held", issue.held}});
  }
  const auto& s = fit.solver;
  return {{"parameters", parameters},
          {"correlation", {{"names", names}, {"matrix", correlation}}},
          {"residuals", fit.residuals},
          {"free_parameters", fit.free_parameters},
          {"dof", fit.dof},
          {"residual_variance", number(fit.residual_variance)},
          {"identifiability",
           {{"identifiable", fit.identifiability.identifiable},
            {"condition_number", number(fit.identifiability.condition_number)},
            {"issues", issues}}},
          {"solver",
           {{"converged", s.converged},
            {"usable", s.usable},
            {"iterations", s.iterations},
            {"termination", s.termination},
            {"initial_cost", s.initial_cost},
            {"final_cost", s.final_cost},
            {"starts", s.starts},
            {"starts_agreed", s.starts_agreed},
            {"covariance_ok", s.covariance_ok},
            {"covariance_message", s.covariance_message},
            {"seconds", s.seconds},
            {"brief", s.brief}}},
          {"warnings", fit.warnings}};
}

}  // namespace lmcal::detail
