#include "selection.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <map>

#include <Eigen/Dense>
#include <numeric>

#include "fit/bounded_interval.hpp"
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

std::vector<std::size_t> value_bins(const std::vector<double>& covariate, std::size_t max_groups, std::size_t quantile_bins) {
  std::vector<double> sorted = covariate;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  std::vector<std::size_t> bins;
  for (double v : covariate) {
    const auto pos = static_cast<std::size_t>(std::lower_bound(sorted.begin(), sorted.end(), v) - sorted.begin());
    bins.push_back(sorted.size() <= max_groups ? pos : pos * quantile_bins / sorted.size());
  }
  return bins;
}

namespace {

// Residual sum of squares and rank of the least-squares fit of `y` on the columns of X.
std::pair<double, Eigen::Index> least_squares_ss(const Eigen::MatrixXd& X, const Eigen::VectorXd& y) {
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  qr.setThreshold(1e-10);
  const Eigen::VectorXd fitted = X * qr.solve(y);
  return {(y - fitted).squaredNorm(), qr.rank()};
}

// F test of the larger model against the smaller nested one (residual sums of squares and ranks).
CovariateTest f_test(const std::string& name, double ss0, Eigen::Index rank0, double ss1, Eigen::Index rank1, std::size_t n) {
  CovariateTest t{.covariate = name, .n = n};
  const auto N = static_cast<Eigen::Index>(n);
  if (rank1 <= rank0 || N <= rank1) {
    t.n = 0;
    return t;
  }
  const double d1 = static_cast<double>(rank1 - rank0), d2 = static_cast<double>(N - rank1);
  const double F = (std::max(ss0 - ss1, 0.0) / d1) / std::max(ss1 / d2, 1e-300);
  t.p_value = fisher_f_upper_p(F, d1, d2);
  t.correlation = std::sqrt(std::max(ss0 - ss1, 0.0) / std::max(ss0, 1e-300));
  t.size = std::sqrt(std::max(ss0 - ss1, 0.0) / static_cast<double>(n));
  return t;
}

}  // namespace

CovariateTest regression_test(const std::string& name, const std::vector<std::vector<double>>& base,
                              const std::vector<std::vector<double>>& extra, const std::vector<double>& values) {
  const auto n = static_cast<Eigen::Index>(values.size());
  const auto p0 = static_cast<Eigen::Index>(base.size() + 1), p1 = p0 + static_cast<Eigen::Index>(extra.size());
  if (n <= p1 + 1) return {.covariate = name, .n = 0};
  Eigen::MatrixXd X(n, p1);
  X.col(0).setOnes();
  for (Eigen::Index j = 1; j < p1; ++j) {
    const auto& column = j < p0 ? base[static_cast<std::size_t>(j - 1)] : extra[static_cast<std::size_t>(j - p0)];
    // Standardised, so the rank threshold does not depend on units.
    const double mean = std::accumulate(column.begin(), column.end(), 0.0) / static_cast<double>(n);
    double sd = 0;
    for (double v : column) sd += (v - mean) * (v - mean);
    sd = std::sqrt(sd / static_cast<double>(n));
    for (Eigen::Index i = 0; i < n; ++i) X(i, j) = sd > 0 ? (column[static_cast<std::size_t>(i)] - mean) / sd : 0.0;
  }
  const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(values.data(), n);
  const auto [ss0, rank0] = least_squares_ss(X.leftCols(p0), y);
  const auto [ss1, rank1] = least_squares_ss(X, y);
  return f_test(name, ss0, rank0, ss1, rank1, values.size());
}

CovariateTest interaction_anova(const std::string& name, const std::vector<double>& a, const std::vector<double>& b,
                                const std::vector<double>& values) {
  const std::vector<std::size_t> ga = value_bins(a, 4, 4), gb = value_bins(b, 4, 4);
  const std::size_t la = *std::max_element(ga.begin(), ga.end()) + 1, lb = *std::max_element(gb.begin(), gb.end()) + 1;
  const auto n = static_cast<Eigen::Index>(values.size());
  if (la < 2 || lb < 2) return {.covariate = name, .n = 0};
  // Additive: intercept + level dummies of each; full: one mean per occupied cell.
  Eigen::MatrixXd additive = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(la + lb - 1));
  std::map<std::size_t, Eigen::Index> cells;
  Eigen::MatrixXd full = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(la * lb));
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::size_t x = ga[static_cast<std::size_t>(i)], z = gb[static_cast<std::size_t>(i)];
    additive(i, 0) = 1;
    if (x > 0) additive(i, static_cast<Eigen::Index>(x)) = 1;
    if (z > 0) additive(i, static_cast<Eigen::Index>(la - 1 + z)) = 1;
    full(i, static_cast<Eigen::Index>(x * lb + z)) = 1;
  }
  const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(values.data(), n);
  const auto [ss0, rank0] = least_squares_ss(additive, y);
  const auto [ss1, rank1] = least_squares_ss(full, y);
  return f_test(name, ss0, rank0, ss1, rank1, values.size());
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

DiagnosisStep make_step(std::string action, std::string name, const ModelFit& before, const ModelFit& after) {
  DiagnosisStep s{.action = std::move(action),
                  .name = std::move(name),
                  .cv_rmse_before = before.cv_rmse,
                  .cv_rmse_after = after.cv_rmse,
                  .cv_shape_rmse_before = before.cv_shape_rmse,
                  .cv_shape_rmse_after = after.cv_shape_rmse};
  const double level = held_out_gain_percent(s.cv_rmse_before, s.cv_rmse_after);
  const double shape = held_out_gain_percent(s.cv_shape_rmse_before, s.cv_shape_rmse_after);
  s.criterion = std::isfinite(shape) && !(shape <= level) ? "shape" : "level";
  s.gain_percent = s.criterion == "shape" ? shape : level;
  return s;
}

void set_held_out(EmpiricalFinding& f, const ModelFit& before, const ModelFit& after) {
  const DiagnosisStep step = make_step("add empirical term", f.formula, before, after);
  f.criterion = step.criterion;
  f.cv_rmse_before = step.before();
  f.cv_rmse_after = step.after();
  f.cv_gain_percent = step.gain_percent;
}

double final_cv_rmse(const std::vector<DiagnosisStep>& steps, double baseline) {
  return steps.empty() ? baseline : steps.back().cv_rmse_after;
}

ParameterEstimate within_bounds(ParameterEstimate p) {
  if (p.interval != "linear" || !(p.se > 0) || !std::isfinite(p.ci_high - p.ci_low)) return p;
  const double t = (p.ci_high - p.ci_low) / (2 * p.se);
  const BoundedInterval b = bounded_interval(p.value, p.se, t, p.lower, p.upper);
  p.ci_low = b.low;
  p.ci_high = b.high;
  p.interval = b.method;
  return p;
}

double counted_gain(const CandidateScore& c) {
  if (!std::isfinite(c.cv_shape_gain_percent)) return c.cv_gain_percent;
  return std::max(c.cv_gain_percent, c.cv_shape_gain_percent);
}

bool interval_excludes_neutral(const CandidateScore& c) {
  return !is_cause(c) || !std::isfinite(c.ci_low) || !std::isfinite(c.ci_high) || c.neutral < c.ci_low ||
         c.neutral > c.ci_high;
}

double whole_model_loss(const CandidateScore& c) {
  if (!std::isfinite(c.cv_shape_gain_percent)) return 0;
  return std::max(0.0, -std::min(c.cv_gain_percent, c.cv_shape_gain_percent));
}

bool score_candidate(const ModelFit& current, const ModelFit& candidate, const SelectionRules& rules, CandidateScore& c) {
  const double n_eff = std::min(current.n_eff, candidate.n_eff);
  std::tie(c.aicc, c.bic) = information_criteria(candidate.ss, candidate.n, n_eff, candidate.k);
  const double bic0 = information_criteria(current.ss, current.n, n_eff, current.k).second;
  c.added_parameters = candidate.k >= current.k ? candidate.k - current.k : 0;
  c.cv_rmse = candidate.cv_rmse;
  c.cv_shape_rmse = candidate.cv_shape_rmse;
  c.cv_gain_percent = held_out_gain_percent(current.cv_rmse, candidate.cv_rmse);
  c.cv_shape_gain_percent = held_out_gain_percent(current.cv_shape_rmse, candidate.cv_shape_rmse);
  const double gain = counted_gain(c);
  const bool excludes_neutral = interval_excludes_neutral(c);
  bool significant;
  std::string why_not;
  if (c.added_parameters > 0) {
    c.lrt_statistic = n_eff * std::log(current.ss / candidate.ss);
    c.lrt_p = chi_squared_upper_p(std::max(c.lrt_statistic, 0.0), static_cast<double>(c.added_parameters));
    significant = c.lrt_p < rules.lrt_p && c.bic < bic0;
    why_not = fmt::format("not significant (LRT {}, BIC {:+.1f})", p_is(c.lrt_p), c.bic - bic0);
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
  // The whole model, level and shape together: a cause that gains on one criterion must not
  // lose on the other by more than a gain must bring.
  const bool whole = !is_cause(c) || whole_model_loss(c) <= rules.min_cv_gain_percent;
  const double effect = std::sqrt(std::max(current.cv_rmse * current.cv_rmse - candidate.cv_rmse * candidate.cv_rmse, 0.0));
  const bool above_floor = rules.min_effect <= 0 || effect >= rules.min_effect;
  const bool better = gain >= rules.min_cv_gain_percent && enough && whole && above_floor;
  if (!candidate.problem.empty()) c.reason = candidate.problem;
  else if (!significant) c.reason = why_not;
  else if (!excludes_neutral)
    c.reason = fmt::format("its 95 % interval [{:.4g}, {:.4g}] contains its neutral value {:g}", c.ci_low, c.ci_high, c.neutral);
  else if (gain < rules.min_cv_gain_percent)
    c.reason = fmt::format("held-out RMSE gain {:.2f} % < {:.2f} %", gain, rules.min_cv_gain_percent);
  else if (!whole)
    c.reason = fmt::format("the whole model loses on held-out runs: {:.2f} % better on one criterion but {:.2f} % worse on "
                           "the other (level {:+.2f} %, runs' shape {:+.2f} %; at most {:.2f} % may be lost)",
                           gain, whole_model_loss(c), c.cv_gain_percent, c.cv_shape_gain_percent, rules.min_cv_gain_percent);
  else if (!enough)
    c.reason = fmt::format("removes {:.0f} % of the held-out RMSE above the noise ({:.4g}), less than {:.0f} %", 100 * removed,
                           rules.noise_floor, 100 * rules.min_excess_removed);
  else if (!above_floor)
    c.reason = fmt::format("its effect, {:.3g} RMS on held-out runs, is within {} ({:.3g})", effect,
                           rules.effect_floor_basis, rules.min_effect);
  else c.reason = "significant and better on held-out runs";
  c.accepted = candidate.problem.empty() && significant && excludes_neutral && better;  // passes; forward_select picks one
  return c.accepted;
}

void set_estimate(CandidateScore& c, const ParameterEstimate& given) {
  const ParameterEstimate p = within_bounds(given);
  c.value = p.value;
  c.unit = p.unit;
  c.se = p.se;
  const bool profile = p.interval == "profile";
  c.ci_low = profile ? p.profile_low : p.ci_low;
  c.ci_high = profile ? p.profile_high : p.ci_high;
  c.interval = p.interval;
}

double change_correlation(const std::vector<double>& current, const std::vector<double>& a, const std::vector<double>& b) {
  if (current.empty() || a.size() != current.size() || b.size() != current.size()) return 0;
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < current.size(); ++i) {
    const double da = a[i] - current[i], db = b[i] - current[i];
    sab += da * db;
    saa += da * da;
    sbb += db * db;
  }
  return saa > 0 && sbb > 0 ? sab / std::sqrt(saa * sbb) : 0.0;
}

void holm_adjust(std::vector<CovariateTest>& tests) {
  std::vector<double> p;
  for (const CovariateTest& t : tests) p.push_back(t.p_value);
  const std::vector<double> adjusted = lmcal::holm_adjust(p);
  for (std::size_t k = 0; k < tests.size(); ++k) tests[k].p_adjusted = adjusted[k];
}

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

LackOfFit lack_of_fit_against_noise(double ss, double n, double n_eff, std::size_t k, const NoiseFloor& noise,
                                    double structure_p, double margin, std::string basis) {
  LackOfFit l;
  const auto K = static_cast<double>(k);
  if (!(noise.sigma > 0) || !(noise.dof > 0) || !(n > K + 1)) {
    l.basis = "not tested: no noise estimate from " + basis + ", or no residual degrees of freedom";
    return l;
  }
  l.tested = true;
  l.against = "noise";
  l.basis = std::move(basis);
  const double variance = ss / (n - K);
  l.pure_error_rms = noise.sigma;
  l.lack_rms = std::sqrt(std::max(variance - noise.sigma * noise.sigma, 0.0));
  l.statistic = variance / (noise.sigma * noise.sigma);
  l.df1 = std::max(n_eff * (n - K) / n, 1.0);
  l.df2 = noise.dof;
  l.p_value = fisher_f_upper_p(l.statistic, l.df1, l.df2);
  l.margin = margin;
  l.fits = !(l.p_value < structure_p && std::sqrt(variance) > margin * noise.sigma);
  return l;
}

nlohmann::json covariates_json(const std::vector<CovariateTest>& tests) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& c : tests)
    out.push_back({{"covariate", c.covariate}, {"strength", number(c.correlation)}, {"p", number(c.p_value)}, {"p_holm", number(c.p_adjusted)}, {"size", number(c.size)}, {"n", c.n},
                   {"structured", c.structured}});
  return out;
}

}  // namespace lmcal::detail

namespace lmcal {

double held_out_gain_percent(double before, double after) {
  if (!(before > 0) || !(after > 0) || !std::isfinite(before) || !std::isfinite(after))
    return std::numeric_limits<double>::quiet_NaN();
  return 100 * (before - after) / std::max(before, after);
}

std::string held_out_criterion_words(const std::string& criterion) {
  return criterion == "shape" ? "held-out RMSE of the runs' shape (each held-out run's own level out)"
                              : "held-out (leave-one-run-out) RMSE";
}

ParameterShift parameter_shift(const ParameterEstimate& given_baseline, const ParameterEstimate& given_extended) {
  const ParameterEstimate baseline = detail::within_bounds(given_baseline), extended = detail::within_bounds(given_extended);
  auto low = [](const ParameterEstimate& p) { return p.interval == "profile" ? p.profile_low : p.ci_low; };
  auto high = [](const ParameterEstimate& p) { return p.interval == "profile" ? p.profile_high : p.ci_high; };
  // A parameter held (by the user, or as unidentifiable) in either model has not moved for a
  // physical reason: it is reported, but not as a shift.
  const bool free = baseline.free && extended.free && !baseline.held_unidentifiable && !extended.held_unidentifiable;
  return {baseline.name, baseline.value, extended.value, low(baseline), high(baseline), low(extended), high(extended), free};
}

std::pair<double, double> candidate_alpha_range(const std::vector<std::vector<CandidateScore>>& rounds) {
  double low = std::numeric_limits<double>::infinity(), high = -low;
  for (const auto& round : rounds)
    for (const auto& c : round)
      if (std::isfinite(c.alpha)) low = std::min(low, c.alpha), high = std::max(high, c.alpha);
  if (low > high) return {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  return {low, high};
}

}  // namespace lmcal
