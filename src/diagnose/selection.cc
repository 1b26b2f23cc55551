// The part of a diagnosis that does not depend on the physics: the covariate tests (ANOVA,
// regression F tests, Holm), the score of a candidate against the current model, and the
// held-out and information criteria (the verdict's words and JSON: verdict.cc).
#include "selection.hpp"

#include <fmt/format.h>

#include <cmath>
#include <map>

#include <Eigen/Dense>
#include <numeric>

#include "fit/bounded_interval.hpp"
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

