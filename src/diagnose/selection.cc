#include "selection.hpp"

#include <fmt/format.h>

#include <cmath>
#include <map>

#include "fit/fit_json.hpp"
#include "lmcal/fit/statistics.hpp"

namespace lmcal::detail {

CovariateTest nested_anova(const std::string& name, const std::vector<std::size_t>& coarse,
                           const std::vector<std::size_t>& fine, const std::vector<double>& values) {
  CovariateTest t{.covariate = name, .n = values.size()};
  auto fit_means = [&](const std::vector<std::size_t>& group, std::size_t& groups) {
    std::map<std::size_t, std::pair<double, double>> sums;  // group -> (sum, count)
    for (std::size_t i = 0; i < values.size(); ++i) {
      sums[group[i]].first += values[i];
      sums[group[i]].second += 1;
    }
    groups = sums.size();
    double ss = 0;
    for (std::size_t i = 0; i < values.size(); ++i) {
      const auto& [sum, count] = sums[group[i]];
      ss += std::pow(values[i] - sum / count, 2);
    }
    return ss;
  };
  std::size_t g0 = 0, g1 = 0;
  const double ss0 = fit_means(coarse, g0), ss1 = fit_means(fine, g1);
  if (g1 <= g0 || values.size() <= g1) return t;
  const double d1 = static_cast<double>(g1 - g0), d2 = static_cast<double>(values.size() - g1);
  const double F = ((ss0 - ss1) / d1) / std::max(ss1 / d2, 1e-300);
  t.p_value = fisher_f_upper_p(std::max(F, 0.0), d1, d2);
  t.correlation = std::sqrt(std::max(ss0 - ss1, 0.0) / std::max(ss0, 1e-300));
  t.size = std::sqrt(std::max(ss0 - ss1, 0.0) / static_cast<double>(values.size()));
  return t;
}

std::vector<std::size_t> value_bins(const std::vector<double>& covariate) {
  std::vector<double> sorted = covariate;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  std::vector<std::size_t> bins;
  for (double v : covariate) {
    const auto pos = static_cast<std::size_t>(std::lower_bound(sorted.begin(), sorted.end(), v) - sorted.begin());
    bins.push_back(sorted.size() <= 12 ? pos : pos * 10 / sorted.size());
  }
  return bins;
}

CovariateTest anova(const std::string& name, const std::vector<double>& covariate, const std::vector<double>& residual) {
  return nested_anova(name, std::vector<std::size_t>(residual.size(), 0), value_bins(covariate), residual);
}

std::pair<double, double> information_criteria(double ss, double n, double n_eff, std::size_t k) {
  // The Gaussian log-likelihood of n residuals carries n_eff independent ones' evidence.
  const double K = static_cast<double>(k), fit = n_eff * std::log(ss / n);
  const double aic = fit + 2 * K;
  return {aic + 2 * K * (K + 1) / std::max(n_eff - K - 1, 1.0), fit + K * std::log(n_eff)};
}

bool score_candidate(const ModelFit& current, const ModelFit& candidate, const SelectionRules& rules, CandidateScore& c) {
  const double n_eff = std::min(current.n_eff, candidate.n_eff);
  std::tie(c.aicc, c.bic) = information_criteria(candidate.ss, candidate.n, n_eff, candidate.k);
  const double bic0 = information_criteria(current.ss, current.n, n_eff, current.k).second;
  c.added_parameters = candidate.k >= current.k ? candidate.k - current.k : 0;
  c.cv_rmse = candidate.cv_rmse;
  c.cv_gain_percent = 100 * (1 - candidate.cv_rmse / current.cv_rmse);
  bool significant;
  std::string why_not;
  if (c.added_parameters > 0) {
    c.lrt_statistic = n_eff * std::log(current.ss / candidate.ss);
    c.lrt_p = chi_squared_upper_p(std::max(c.lrt_statistic, 0.0), static_cast<double>(c.added_parameters));
    significant = c.lrt_p < rules.lrt_p && c.bic < bic0;
    why_not = fmt::format("not significant (LRT p = {:.2g}, BIC {:+.1f})", c.lrt_p, c.bic - bic0);
  } else {
    c.lrt_statistic = c.lrt_p = std::numeric_limits<double>::quiet_NaN();
    significant = c.bic < bic0 - rules.switch_bic;
    why_not = fmt::format("not significant (BIC {:+.1f}; a switch needs {:+.0f})", c.bic - bic0, -rules.switch_bic);
  }
  // The excess over the noise in variance; a current model within 2 % of the noise has none
  // left to speak of, and the plain gain decides.
  const double excess = current.cv_rmse * current.cv_rmse - rules.noise_floor * rules.noise_floor;
  const bool at_noise = rules.noise_floor <= 0 || current.cv_rmse <= 1.02 * rules.noise_floor;
  const double removed = at_noise ? 1.0 : (current.cv_rmse * current.cv_rmse - candidate.cv_rmse * candidate.cv_rmse) / excess;
  const bool enough = removed >= rules.min_excess_removed;
  const bool better = c.cv_gain_percent >= rules.min_cv_gain_percent && enough;
  if (!candidate.problem.empty()) c.reason = candidate.problem;
  else if (!significant) c.reason = why_not;
  else if (c.cv_gain_percent < rules.min_cv_gain_percent)
    c.reason = fmt::format("held-out RMSE gain {:.2f} % < {:.2f} %", c.cv_gain_percent, rules.min_cv_gain_percent);
  else if (!better)
    c.reason = fmt::format("removes {:.0f} % of the held-out RMSE above the noise ({:.4g}), less than {:.0f} %", 100 * removed,
                           rules.noise_floor, 100 * rules.min_excess_removed);
  else c.reason = "significant and better on held-out runs";
  c.accepted = candidate.problem.empty() && significant && better;  // passes; forward_select picks one
  return c.accepted;
}

void set_estimate(CandidateScore& c, const ParameterEstimate& p) {
  c.value = p.value;
  c.se = p.se;
  c.ci_low = p.ci_low;
  c.ci_high = p.ci_high;
}

Verdict make_verdict(const VerdictInput& in) {
  Verdict v;
  const CovariateTest none;
  const CovariateTest& baseline_top = in.baseline_covariates.empty() ? none : in.baseline_covariates.front();
  const CovariateTest& final_top = in.final_covariates.empty() ? none : in.final_covariates.front();
  v.cv_gain_percent = 100 * (1 - in.cv_after / in.cv_before);
  const std::string remains = in.final_structured ? fmt::format("the residuals still follow {} (p = {:.2g})",
                                                                final_top.covariate, final_top.p_value)
                                                  : "no structure left beyond the noise";
  if (!in.accepted.empty()) {
    v.verdict = "explained";
    std::string causes;
    for (const auto& c : in.accepted) {
      causes += causes.empty() ? "" : "; ";
      causes += std::isfinite(c.value) ? fmt::format("{} = {:.4g} (95 % [{:.4g}, {:.4g}])", c.effect, c.value, c.ci_low, c.ci_high)
                                       : c.effect;
    }
    std::string shift;
    for (const auto& s : in.shifts)
      if (std::abs(s.extended - s.baseline) > 0.02 * std::max(std::abs(s.baseline), 1e-12))
        shift += fmt::format("{}{} {:.4g} -> {:.4g}", shift.empty() ? "" : ", ", s.name, s.baseline, s.extended);
    v.summary = fmt::format(
        "{} misses: {}. Modelled, the held-out (leave-one-run-out) RMSE goes from {:.4g} {} to {:.4g} {} ({:.1f} % better). "
        "Parameters that move: {}. What remains: {}.",
        in.model, causes, in.cv_before, in.unit, in.cv_after, in.unit, v.cv_gain_percent,
        shift.empty() ? "none by more than 2 %" : shift, remains);
    if (in.final_structured) v.unexplained_covariate = final_top.covariate;
  } else if (in.baseline_structured) {
    v.verdict = "unexplained";
    v.unexplained_covariate = baseline_top.covariate;
    v.summary = fmt::format(
        "Unexplained: the residuals of {} follow {} (p = {:.2g}), but no mechanism of the library explains them on "
        "held-out runs. Held-out RMSE {:.4g} {}.",
        in.model, v.unexplained_covariate, baseline_top.p_value, in.cv_before, in.unit);
  } else {
    v.verdict = "no significant discrepancy";
    v.summary = fmt::format(
        "No significant discrepancy: {} fits to the noise (residual RMSE {:.4g} {}, held-out {:.4g} {}) and no mechanism "
        "of the library improves it.",
        in.model, in.baseline_rmse, in.unit, in.cv_before, in.unit);
  }
  return v;
}

nlohmann::json candidate_json(const CandidateScore& c, const std::string& unit) {
  return nlohmann::json{{"effect", c.effect},
                        {"value", number(c.value)},
                        {"se", number(c.se)},
                        {"ci95", {number(c.ci_low), number(c.ci_high)}},
                        {"added_parameters", c.added_parameters},
                        {"aicc", number(c.aicc)},
                        {"bic", number(c.bic)},
                        {"lrt", number(c.lrt_statistic)},
                        {"lrt_p", number(c.lrt_p)},
                        {"cv_rmse_" + unit, number(c.cv_rmse)},
                        {"cv_gain_percent", number(c.cv_gain_percent)},
                        {"accepted", c.accepted},
                        {"reason", c.reason}};
}

nlohmann::json verdict_json(const std::string& verdict, const std::string& summary,
                            const std::vector<CandidateScore>& accepted, const std::vector<ParameterShift>& shifts,
                            const std::vector<std::vector<CandidateScore>>& rounds, double cv_before, double cv_after,
                            double cv_gain_percent, const std::string& unexplained_covariate, const std::string& unit) {
  nlohmann::json steps = nlohmann::json::array();
  for (const auto& round : rounds) {
    nlohmann::json r = nlohmann::json::array();
    for (const auto& c : round) r.push_back(candidate_json(c, unit));
    steps.push_back(r);
  }
  nlohmann::json causes = nlohmann::json::array();
  for (const auto& c : accepted) causes.push_back(candidate_json(c, unit));
  nlohmann::json moves = nlohmann::json::array();
  for (const auto& s : shifts)
    moves.push_back({{"parameter", s.name},
                     {"baseline", s.baseline},
                     {"baseline_ci95", {number(s.baseline_low), number(s.baseline_high)}},
                     {"extended", s.extended},
                     {"extended_ci95", {number(s.extended_low), number(s.extended_high)}}});
  return {{"verdict", verdict},
          {"summary", summary},
          {"causes", causes},
          {"cv_rmse_before_" + unit, number(cv_before)},
          {"cv_rmse_after_" + unit, number(cv_after)},
          {"cv_gain_percent", number(cv_gain_percent)},
          {"parameter_shifts", moves},
          {"unexplained_covariate", unexplained_covariate},
          {"rounds", steps}};
}

nlohmann::json covariates_json(const std::vector<CovariateTest>& tests) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& c : tests)
    out.push_back({{"covariate", c.covariate}, {"strength", number(c.correlation)}, {"p", number(c.p_value)}, {"size", number(c.size)}, {"n", c.n},
                   {"structured", c.structured}});
  return out;
}

}  // namespace lmcal::detail

namespace lmcal {

ParameterShift parameter_shift(const ParameterEstimate& baseline, const ParameterEstimate& extended) {
  auto low = [](const ParameterEstimate& p) { return p.interval == "profile" ? p.profile_low : p.ci_low; };
  auto high = [](const ParameterEstimate& p) { return p.interval == "profile" ? p.profile_high : p.ci_high; };
  return {baseline.name, baseline.value, extended.value, low(baseline), high(baseline), low(extended), high(extended)};
}

}  // namespace lmcal
