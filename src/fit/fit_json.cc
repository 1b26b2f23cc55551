#include "fit_json.hpp"

#include <fmt/format.h>

#include <cmath>

namespace lmcal::detail {

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json uncertainty_json(const FitResult& fit) {
  const Uncertainty& u = fit.uncertainty;
  nlohmann::json methods = nlohmann::json::array();
  for (const auto& m : u.methods) {
    nlohmann::json se = nlohmann::json::object();
    for (std::size_t j = 0; j < m.se.size() && j < fit.parameters.size(); ++j)
      if (std::isfinite(m.se[j])) se[fit.parameters[j].name] = m.se[j];
    methods.push_back({{"method", m.method}, {"description", m.description}, {"ok", m.ok}, {"dof", number(m.dof)},
                       {"note", m.note}, {"se", se}});
  }
  nlohmann::json heterogeneity = nlohmann::json::array();
  for (const auto& h : u.heterogeneity)
    heterogeneity.push_back({{"parameter", h.parameter}, {"runs", h.runs}, {"q", number(h.q)}, {"p", number(h.p_value)},
                             {"p_holm", number(h.p_holm)}, {"i_squared", number(h.i_squared)}, {"significant", h.significant}});
  nlohmann::json j = {{"method", u.method},
                      {"reason", u.reason},
                      {"dof", number(u.dof)},
                      {"runs", u.runs},
                      {"lag1_autocorrelation", number(u.lag1_autocorrelation)},
                      {"effective_sample_size", number(u.effective_sample_size)},
                      {"hac_lags", number(u.hac_lags)},
                      {"methods", methods},
                      {"between_run_heterogeneity", heterogeneity},
                      {"notes", u.notes}};
  if (!u.input.empty()) {
    nlohmann::json share = nlohmann::json::object();
    for (std::size_t k = 0; k < u.input_variance_share.size() && k < fit.parameters.size(); ++k)
      if (std::isfinite(u.input_variance_share[k])) share[fit.parameters[k].name] = u.input_variance_share[k];
    j["input"] = {{"name", u.input}, {"variance_share", share}};
  }
  return j;
}

std::string uncertainty_summary(const FitResult& fit) {
  const Uncertainty& u = fit.uncertainty;
  std::string s = fmt::format("95 % intervals: {} (t with {:.3g} dof) — {}\n", u.method, u.dof, u.reason);
  std::string header = fmt::format("  {:<22}", "SE by method:");
  for (const auto& m : u.methods) header += fmt::format(" {:>12}", m.method);
  s += header + "\n";
  for (std::size_t j = 0; j < fit.parameters.size(); ++j) {
    const auto& p = fit.parameters[j];
    if (p.interval == "none" || p.per_run) continue;
    std::string row = fmt::format("    {:<20}", p.name);
    for (const auto& m : u.methods) row += fmt::format(" {:>12.4g}", m.se[j]);
    s += row + "\n";
  }
  for (const auto& note : u.notes) s += "  note: " + note + "\n";
  return s;
}

nlohmann::json parameter_json(const ParameterEstimate& p) {
  const bool profile = p.interval == "profile", none = p.interval == "none";
  nlohmann::json j = {{"name", p.name},
          {"unit", p.unit},
          {"value", number(p.value)},
          {"se", number(p.se)},
          {"dof", number(p.dof)},
          {"ci95", {number(none ? NAN : profile ? p.profile_low : p.ci_low), number(none ? NAN : profile ? p.profile_high : p.ci_high)}},
          {"interval", p.interval},
          {"linear_ci95", {number(p.ci_low), number(p.ci_high)}},
          {"profile_ci95", {number(p.profile_low), number(p.profile_high)}},
          {"bootstrap_ci95", {number(p.boot_low), number(p.boot_high)}},
          {"start", number(p.start)},
          {"bounds", {number(p.lower), number(p.upper)}},
          {"free", p.free},
          {"held", !p.free || p.held_unidentifiable},
          {"held_unidentifiable", p.held_unidentifiable},
          {"at_bound", p.at_bound},
          {"per_run", p.per_run}};
  if (!p.profile_curve.empty()) {
    nlohmann::json curve = nlohmann::json::array();
    for (const ProfilePoint& point : p.profile_curve) curve.push_back({number(point.value), number(point.excess)});
    j["profile_curve"] = curve;
  }
  return j;
}

nlohmann::json fit_json(const FitResult& fit) {
  nlohmann::json parameters = nlohmann::json::array();
  std::vector<std::string> names;
  for (const auto& p : fit.parameters) {
    names.push_back(p.name);
    parameters.push_back(parameter_json(p));
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
          {"uncertainty", uncertainty_json(fit)},
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
            {"unusable_reason", s.unusable_reason},
            {"iterations", s.iterations},
            {"termination", s.termination},
            {"initial_cost", s.initial_cost},
            {"final_cost", s.final_cost},
            {"starts", s.starts},
            {"starts_agreed", s.starts_agreed},
            {"start_costs", s.start_costs},
            {"start_residuals", s.start_residuals},
            {"remaining_step_se", number(s.remaining_step_se)},
            {"restarted", s.restarted},
            {"covariance_ok", s.covariance_ok},
            {"covariance_message", s.covariance_message},
            {"brief", s.brief}}},
          {"warnings", fit.warnings}};
}

}  // namespace lmcal::detail
