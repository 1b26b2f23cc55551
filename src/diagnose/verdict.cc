// A diagnosis's verdict: the sentences that state it (make_verdict) and the JSON of the
// verdict, its candidates, steps, empirical term and tests.
#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <map>

#include "fit/fit_json.hpp"
#include "lmcal/fit/statistics.hpp"
#include "selection.hpp"

namespace lmcal::detail {

namespace {

// "a", "a or b", "a, b or c"
std::string one_of(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i)
    out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  return out;
}

std::string lack_of_fit_words(const LackOfFit& l, const std::string& unit) {
  return fmt::format("lack of fit against {}: F = {:.3g} on ({:.0f}, {:.0f}) dof, {}, {:.3g} {} beyond a noise of {:.3g} {}",
                     l.basis, l.statistic, l.df1, l.df2, p_is(l.p_value), l.lack_rms, unit, l.pure_error_rms, unit);
}

// "The published law" in the middle of a sentence.
std::string lower_first(std::string s) {
  if (!s.empty()) s[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(s[0])));
  return s;
}
std::string upper_first(std::string s) {
  if (!s.empty()) s[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(s[0])));
  return s;
}

// "12.3 % better", "4.5 % worse" (held_out_gain_percent: a loss against the RMSE after).
std::string gain_words(double gain) {
  return gain < 0 ? fmt::format("{:.1f} % worse", -gain) : fmt::format("{:.1f} % better", gain);
}

// "c1 = 0.12 (95 % [0.1, 0.14]), l1 = 1.3e3 m (95 % [...])"
std::string estimate_words(const ParameterEstimate& p) {
  return fmt::format("{} = {:.4g}{} (95 % [{:.4g}, {:.4g}])", p.name, p.value, p.unit.empty() || p.unit == "1" ? "" : " " + p.unit, p.ci_low,
                     p.ci_high);
}

// What the empirical term adds to a verdict: found (formula, coefficients, covariates, gain,
// resemblance), or searched in vain.
std::string empirical_words(const EmpiricalFinding& e, const std::string& unit) {
  if (!e.searched) return "";
  if (!e.found)
    return fmt::format(" Beyond the library, an empirical term was searched for ({} candidate terms of the covariates): {}.",
                       e.dictionary_size, e.reason);
  std::string parts, covariates;
  for (const auto& c : e.components) {
    parts += fmt::format("{}{} is {}, {}", parts.empty() ? "" : "; ", c.symbol, c.words, estimate_words(c.coefficient));
    if (c.has_scale) parts += ", " + estimate_words(c.scale);
    for (const auto& name : c.covariates)
      if (covariates.find(name) == std::string::npos) covariates += (covariates.empty() ? "" : ", ") + name;
  }
  return fmt::format(
      " Beyond the library, an empirical term (learned from the residuals, not a named cause; {} candidate terms "
      "searched) is added to {}: {}. It uses {}. {} {:.4g} {} -> {:.4g} {} ({}; LRT {}). {}",
      e.dictionary_size, e.where, e.components.size() > 1 ? e.formula + ", where " + parts : parts, covariates,
      upper_first(held_out_criterion_words(e.criterion)), e.cv_rmse_before, unit, e.cv_rmse_after, unit,
      gain_words(e.cv_gain_percent), p_is(e.lrt_p),
      e.resembles.empty() ? "It resembles no mechanism we know of." : "It resembles " + e.resembles + ".");
}

}  // namespace

Verdict make_verdict(const VerdictInput& in) {
  Verdict v;
  const CovariateTest none;
  const CovariateTest& baseline_top = in.baseline_covariates.empty() ? none : in.baseline_covariates.front();
  const CovariateTest& final_top = in.final_covariates.empty() ? none : in.final_covariates.front();
  const double cv_final = std::isfinite(in.cv_final) ? in.cv_final : in.cv_after;
  v.cv_gain_percent = held_out_gain_percent(in.cv_before, cv_final);
  const LackOfFit& lof = in.final_lack_of_fit;
  std::string remains;
  if (in.final_structured)
    remains = fmt::format("the residuals still follow {} ({})", final_top.covariate, p_is(final_top.p_value));
  if (lof.tested && !lof.fits)
    remains += (remains.empty() ? "structure remains, the residuals exceed the noise: "
                                : "; and structure remains, they exceed the noise: ") +
               lack_of_fit_words(lof, in.unit);
  if (remains.empty())
    remains = lof.tested ? "no structure left beyond the noise (" + lack_of_fit_words(lof, in.unit) + ")"
                         : "no structure left beyond the noise (" + lof.basis + ")";
  if (!in.accepted.empty()) {
    // Explained only when nothing is left: no covariate the residuals follow, no lack of fit.
    const bool complete = !in.final_structured && (!lof.tested || lof.fits);
    v.verdict = complete ? "explained" : "partly explained";
    std::string causes, ties;
    for (const auto& c : in.accepted) {
      causes += causes.empty() ? "" : "; ";
      causes += std::isfinite(c.value) ? fmt::format("{} = {:.4g}{} (95 % [{:.4g}, {:.4g}])", shown_name(c), c.value,
                                                     c.unit.empty() || c.unit == "1" ? "" : " " + c.unit, c.ci_low, c.ci_high)
                                       : shown_name(c);
      if (!c.precondition.empty()) {
        ties += fmt::format(" {}: {}, {}.{}", shown_name(c), one_of(c.tied_with), c.precondition,
                            c.measure.empty() ? "" : " To separate them, " + c.measure + ".");
      } else if (!c.tied_with.empty()) {
        std::vector<std::string> all{c.effect};
        all.insert(all.end(), c.tied_with.begin(), c.tied_with.end());
        ties += fmt::format(" {}: these data cannot tell them apart (they change the fit alike); {} is kept as the "
                            "representative.{}",
                            one_of(all), c.effect, c.measure.empty() ? "" : " To separate them, log " + c.measure + ".");
      }
    }
    std::string shift;
    for (const auto& s : in.shifts)
      if (s.free && std::abs(s.extended - s.baseline) > 0.02 * std::max(std::abs(s.baseline), 1e-12))
        shift += fmt::format("{}{} {:.4g} [{:.4g}, {:.4g}] -> {:.4g} [{:.4g}, {:.4g}]", shift.empty() ? "" : ", ", s.name,
                             s.baseline, s.baseline_low, s.baseline_high, s.extended, s.extended_low, s.extended_high);
    v.summary = fmt::format(
        "{} misses: {}.{} Modelled, the held-out (leave-one-run-out) RMSE goes from {:.4g} {} to {:.4g} {} ({}). "
        "Parameters that move: {}. What remains: {}.",
        in.model, causes, ties, in.cv_before, in.unit, in.cv_after, in.unit,
        gain_words(held_out_gain_percent(in.cv_before, in.cv_after)),
        shift.empty() ? "none by more than 2 %" : shift, remains);
    if (in.final_structured) v.unexplained_covariate = final_top.covariate;
  } else if (in.baseline_structured || (in.baseline_lack_of_fit.tested && !in.baseline_lack_of_fit.fits)) {
    v.verdict = "unexplained";
    if (in.baseline_structured) {
      v.unexplained_covariate = baseline_top.covariate;
      v.summary = fmt::format(
          "Unexplained: the residuals of {} follow {} ({}), but no mechanism of the library explains them on "
          "held-out runs. Held-out RMSE {:.4g} {}.",
          lower_first(in.model), v.unexplained_covariate, p_is(baseline_top.p_value), in.cv_before, in.unit);
      if (in.baseline_lack_of_fit.tested && !in.baseline_lack_of_fit.fits)
        v.summary += " Structure remains, the residuals also exceed the noise: " +
                     lack_of_fit_words(in.baseline_lack_of_fit, in.unit) + ".";
    } else {
      v.unexplained_covariate = "none identified";
      v.summary = fmt::format(
          "Unexplained: structure remains, the residuals of {} exceed the noise ({}) without following any one covariate or pair, and no "
          "mechanism of the library explains them on held-out runs. Held-out RMSE {:.4g} {}.",
          lower_first(in.model), lack_of_fit_words(in.baseline_lack_of_fit, in.unit), in.cv_before, in.unit);
    }
  } else {
    v.verdict = "no significant discrepancy";
    v.summary = fmt::format(
        "{} fits to the noise (residual RMSE {:.4g} {}, held-out {:.4g} {}; {}) and no mechanism of the library "
        "improves it.",
        in.model, in.baseline_rmse, in.unit, in.cv_before, in.unit,
        in.baseline_lack_of_fit.tested ? lack_of_fit_words(in.baseline_lack_of_fit, in.unit)
                                       : "lack of fit not tested: " + in.baseline_lack_of_fit.basis);
  }
  if (in.empirical) {
    if (in.empirical->found && v.verdict == "no significant discrepancy") {
      // The residual tests saw nothing, but a term predicts held-out runs: that is structure.
      v.verdict = "unexplained";
      v.summary = fmt::format(
          "Unexplained: no covariate or lack of fit stands out in the residual tests, but a term beyond the library "
          "predicts held-out runs better: {} misses something no mechanism of the library explains.",
          lower_first(in.model));
    }
    if (in.empirical->found && (v.verdict == "unexplained" || v.verdict == "partly explained"))
      v.verdict += " — empirical term found";
    v.summary += empirical_words(*in.empirical, in.unit);
  }
  // The final model's held-out RMSE, when the sentences above end elsewhere (the term after the causes).
  if (cv_final != in.cv_after || (in.accepted.empty() && cv_final != in.cv_before))
    v.summary += fmt::format(" The final model (the law{} and the term) has a held-out RMSE of {:.4g} {}, against {:.4g} {} "
                             "for {} alone ({}).",
                             in.accepted.empty() ? "" : ", its causes", cv_final, in.unit, in.cv_before, in.unit,
                             lower_first(in.model), gain_words(v.cv_gain_percent));
  return v;
}

nlohmann::json candidate_json(const CandidateScore& c, const std::string& unit) {
  return nlohmann::json{{"effect", c.effect},
                        {"shown_as", shown_name(c)},
                        {"precondition", c.precondition},
                        {"unit", c.unit},
                        {"value", number(c.value)},
                        {"se", number(c.se)},
                        {"ci95", {number(c.ci_low), number(c.ci_high)}},
                        {"interval", c.interval},
                        {"cv_shape_rmse_" + unit, number(c.cv_shape_rmse)},
                        {"added_parameters", c.added_parameters},
                        {"aicc", number(c.aicc)},
                        {"bic", number(c.bic)},
                        {"lrt", number(c.lrt_statistic)},
                        {"lrt_p", number(c.lrt_p)},
                        {"cv_rmse_" + unit, number(c.cv_rmse)},
                        {"cv_gain_percent", number(c.cv_gain_percent)},
                        {"cv_shape_gain_percent", number(c.cv_shape_gain_percent)},
                        {"accepted", c.accepted},
                        {"reason", c.reason},
                        {"tied_with", c.tied_with},
                        {"alpha", number(c.alpha)},
                        {"alpha_ci95", {number(c.alpha_low), number(c.alpha_high)}}};
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
                     {"extended_ci95", {number(s.extended_low), number(s.extended_high)}},
                     {"estimated_in_both", s.free}});
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

nlohmann::json steps_json(const std::vector<DiagnosisStep>& steps, const std::string& unit) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& s : steps)
    out.push_back({{"action", s.action},
                   {"name", s.name},
                   {"cv_rmse_before_" + unit, number(s.cv_rmse_before)},
                   {"cv_rmse_after_" + unit, number(s.cv_rmse_after)},
                   {"cv_shape_rmse_before_" + unit, number(s.cv_shape_rmse_before)},
                   {"cv_shape_rmse_after_" + unit, number(s.cv_shape_rmse_after)},
                   {"criterion", s.criterion},
                   {"gain_percent", number(s.gain_percent)}});
  return out;
}

nlohmann::json empirical_json(const EmpiricalFinding& e, const std::string& unit) {
  auto estimate = [](const ParameterEstimate& p) {
    return nlohmann::json{{"name", p.name}, {"unit", p.unit}, {"value", number(p.value)}, {"se", number(p.se)},
                          {"ci95", {number(p.ci_low), number(p.ci_high)}}, {"interval", p.interval}, {"at_bound", p.at_bound}};
  };
  nlohmann::json components = nlohmann::json::array();
  for (const auto& c : e.components) {
    nlohmann::json j{{"symbol", c.symbol}, {"words", c.words}, {"covariates", c.covariates},
                     {"coefficient", estimate(c.coefficient)}};
    if (c.has_scale) j["scale"] = estimate(c.scale);
    components.push_back(j);
  }
  nlohmann::json ranges = nlohmann::json::object();
  for (const auto& r : e.ranges) ranges[r.covariate] = {number(r.min), number(r.max)};
  return {{"searched", e.searched},
          {"found", e.found},
          {"kind", "empirical (learned from the residuals; not a named cause)"},
          {"form", e.form},
          {"added_to", e.where},
          {"formula", e.formula},
          {"components", components},
          {"dictionary_size", e.dictionary_size},
          {"criterion", e.criterion},
          {"cv_rmse_before_" + unit, number(e.cv_rmse_before)},
          {"cv_rmse_after_" + unit, number(e.cv_rmse_after)},
          {"cv_gain_percent", number(e.cv_gain_percent)},
          {"lrt_p", number(e.lrt_p)},
          {"delta_bic", number(e.delta_bic)},
          {"resembles", e.resembles},
          {"reason", e.reason},
          {"covariate_ranges", ranges}};
}

nlohmann::json lack_of_fit_json(const LackOfFit& l) {
  return {{"tested", l.tested}, {"basis", l.basis}, {"against", l.against}, {"F", number(l.statistic)},
          {"df", {number(l.df1), number(l.df2)}}, {"p", number(l.p_value)}, {"lack_rms", number(l.lack_rms)},
          {"pure_error_rms", number(l.pure_error_rms)}, {"margin", number(l.margin)},
          {"condition_tolerance", number(l.condition_tolerance)}, {"fits", l.fits}};
}

nlohmann::json covariates_json(const std::vector<CovariateTest>& tests) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& c : tests)
    out.push_back({{"covariate", c.covariate}, {"strength", number(c.correlation)}, {"p", number(c.p_value)}, {"p_holm", number(c.p_adjusted)}, {"size", number(c.size)}, {"n", c.n},
                   {"structured", c.structured}});
  return out;
}


}  // namespace lmcal::detail
