// The friction diagnosis's search beyond the library: the law linearised at the current fit,
// the dictionary's sparse regression and the smooth alternative, each fitted jointly with the
// law and judged as a cause is, and the term kept described with its curve.
#include "empirical_friction.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>

#include "empirical_friction_parts.hpp"
#include "lmcal/fit/statistics.hpp"
#include "parallel_slices.hpp"
#include "sparse_regression.hpp"

namespace lmcal::detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kMaxFitParameters = 16;  // the batched cost's largest Jet

// The law with the fit's named effects for the parameter values `values` (the seven constants,
// then the effects, as in `params`), at row i of the log with the temperature `warmer_K`
// higher. The constants and effects are set once: by name per row, a 10⁵-row log's finite
// differences looked the effects up millions of times.
class LawAt {
 public:
  LawAt(const FrictionLog& log, const std::vector<ParameterEstimate>& params, const std::vector<double>& values,
        double reference_C)
      : log_(log) {
    for (std::size_t j = 0; j < FrictionConstants<double>::kFittable; ++j) fittable_constant(k_, j) = values[j];
    k_.T_ref_C = reference_C;
    for (std::size_t j = FrictionConstants<double>::kFittable; j < params.size(); ++j)
      if (const auto slot = find_friction_effect(params[j].name)) e_[*slot] = values[j];
  }
  double operator()(std::size_t i, double warmer_K = 0) const {
    FrictionConstants<double> k = k_;
    k.nu_ref_mm2_s = log_.viscosity40_mm2_s[i];
    FrictionConditions<double> c = log_.conditions(i);
    c.temperature_C += warmer_K;
    return friction_force_with_effects_N(k, e_, c);
  }

 private:
  const FrictionLog& log_;
  FrictionConstants<double> k_;
  FrictionEffects<double> e_;
};

// Up to `bins` groups of the values (one per distinct value when there are few), as labels
// and the centre of each group.
std::pair<std::vector<std::size_t>, std::vector<double>> binned(const std::vector<double>& x, std::size_t bins) {
  std::vector<double> sorted = x;
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> edges;
  std::set<double> distinct(sorted.begin(), sorted.end());
  if (distinct.size() <= bins) {
    edges.assign(distinct.begin(), distinct.end());
  } else {
    for (std::size_t b = 0; b < bins; ++b) edges.push_back(sorted[b * sorted.size() / bins]);
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  }
  std::vector<std::size_t> label(x.size());
  std::vector<double> sum(edges.size(), 0.0), count(edges.size(), 0.0);
  for (std::size_t i = 0; i < x.size(); ++i) {
    label[i] = static_cast<std::size_t>(std::upper_bound(edges.begin(), edges.end(), x[i]) - edges.begin()) - 1;
    sum[label[i]] += x[i];
    count[label[i]] += 1;
  }
  std::vector<double> centre(edges.size());
  for (std::size_t b = 0; b < edges.size(); ++b) centre[b] = count[b] > 0 ? sum[b] / count[b] : kNaN;
  return {label, centre};
}

// The term's contribution per row (the model with the terms minus without), at the fit's
// law and effects and the term parameters `theta`.
std::vector<double> contribution(const FrictionLog& log, const TermSeries& series, const FrictionFitResult& fit,
                                 const std::vector<double>& theta, double reference_C) {
  const FrictionConstants<double> k0 = fit.constants();
  const FrictionEffects<double> e = fit.effects();
  std::vector<double> lag;
  for (std::size_t t = 0, at = 0; t < fit.terms.size(); at += fit.terms[t].has_scale() ? 2 : 1, ++t)
    if (fit.terms[t].lagged_temperature()) lag = lagged_temperature_change(log, series, theta[at + 1]);
  std::vector<double> out(log.size());
  for (std::size_t i = 0; i < log.size(); ++i) {
    FrictionConstants<double> k = k0;
    k.nu_ref_mm2_s = log.viscosity40_mm2_s[i];
    k.T_ref_C = reference_C;
    out[i] = friction_with_terms_N(k, e, log, series, i, fit.terms, theta.data(), lag.empty() ? nullptr : &lag) -
             friction_force_with_effects_N(k, e, log.conditions(i));
  }
  return out;
}

EmpiricalCurve curve_of(const FrictionLog& log, const TermSeries& series, const FrictionFitResult& before,
                        const FrictionFitResult& after, double reference_C) {
  EmpiricalCurve c;
  const TermCovariate main = main_covariate(after.terms.front());
  c.covariate = term_covariate_name(main);
  c.unit = term_covariate_unit(main);
  std::vector<double> x(log.size());
  for (std::size_t i = 0; i < log.size(); ++i)
    x[i] = main == TermCovariate::law_force_N ? before.predicted_N[i] : term_covariate_value(log, series, i, main);
  const auto [label, centre] = binned(x, 20);
  const std::size_t bins = centre.size();
  // The term's parameters: after the constants and the effects.
  const std::size_t first = after.fit.parameters.size() - term_parameter_count(after.terms);
  std::vector<double> theta;
  for (std::size_t j = first; j < after.fit.parameters.size(); ++j) theta.push_back(after.fit.parameters[j].value);
  auto bin_means = [&](const std::vector<double>& v) {
    std::vector<double> sum(bins, 0.0), count(bins, 0.0);
    for (std::size_t i = 0; i < v.size(); ++i) sum[label[i]] += v[i], count[label[i]] += 1;
    for (std::size_t b = 0; b < bins; ++b) sum[b] = count[b] > 0 ? sum[b] / count[b] : kNaN;
    return sum;
  };
  const std::vector<double> contribution_N = contribution(log, series, after, theta, reference_C);
  const std::vector<double> value = bin_means(contribution_N);
  // Delta method over the term's parameters (central differences of the bin means).
  std::vector<std::vector<double>> gradient;
  for (std::size_t a = 0; a < theta.size(); ++a) {
    const double h = 1e-4 * std::max(std::abs(theta[a]), 1e-9);
    std::vector<double> up = theta, down = theta;
    up[a] += h;
    down[a] -= h;
    const std::vector<double> mu = bin_means(contribution(log, series, after, up, reference_C));
    const std::vector<double> md = bin_means(contribution(log, series, after, down, reference_C));
    std::vector<double> g(bins);
    for (std::size_t b = 0; b < bins; ++b) g[b] = (mu[b] - md[b]) / (2 * h);
    gradient.push_back(g);
  }
  const double t95 = student_t_quantile(0.975, std::max(after.fit.dof, 1.0));
  std::vector<double> before_residual(log.size()), after_residual(log.size());
  // Before: the partial residuals — the joint fit's residuals with the term added back, what
  // the term has to explain (the model without it absorbs part of it in its run offsets and
  // constants, in sample; the held-out gain is what it cannot absorb).
  for (std::size_t i = 0; i < log.size(); ++i) {
    after_residual[i] = log.friction_N[i] - after.predicted_N[i];
    before_residual[i] = after_residual[i] + contribution_N[i];
  }
  c.residual_before = bin_means(before_residual);
  c.residual_after = bin_means(after_residual);
  for (std::size_t b = 0; b < bins; ++b) {
    double variance = 0;
    for (std::size_t p = 0; p < theta.size(); ++p)
      for (std::size_t q = 0; q < theta.size(); ++q)
        variance += gradient[p][b] * after.fit.covariance(static_cast<Eigen::Index>(first + p), static_cast<Eigen::Index>(first + q)) *
                    gradient[q][b];
    const double half = t95 * std::sqrt(std::max(variance, 0.0));
    c.x.push_back(centre[b]);
    c.value.push_back(value[b]);
    c.low.push_back(value[b] - half);
    c.high.push_back(value[b] + half);
  }
  return c;
}

// The empirical term is judged as a cause is (score_candidate): its interval must exclude its
// neutral value, 0, and the whole model must not lose on held-out runs. Which coefficient
// speaks for the term: for a sparse form every term must be there, so the one nearest 0 in its
// standard errors decides; for a smooth term the curve must differ from 0 somewhere, so the basis
// coefficient farthest from 0 does (one B-spline's coefficient may sit at 0 where the curve
// does not). Returns that term's index, terms.size() when no coefficient has a finite SE (the
// interval unknown: not a rejection, the fit's own problem is reported instead).
bool is_smooth(const std::vector<FrictionTerm>& terms) {
  return !terms.empty() && has_spline(terms.front());
}

const ParameterEstimate& term_coefficient(const FrictionFitResult& fit, const std::vector<FrictionTerm>& terms, std::size_t k) {
  std::size_t at = fit.fit.parameters.size() - term_parameter_count(terms);
  for (std::size_t j = 0; j < k; ++j) at += terms[j].has_scale() ? 2 : 1;
  return fit.fit.parameters[at];
}

std::size_t decisive_term(const FrictionFitResult& fit, const std::vector<FrictionTerm>& terms) {
  const bool smooth = is_smooth(terms);
  std::size_t decisive = terms.size();
  double decisive_t = smooth ? -1.0 : std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < terms.size(); ++k) {
    const ParameterEstimate& c = term_coefficient(fit, terms, k);
    const double t = std::abs(c.value) / c.se;
    if (std::isfinite(t) && (smooth ? t > decisive_t : t < decisive_t)) decisive = k, decisive_t = t;
  }
  return decisive;
}

// The score's value and interval from the decisive coefficient, its neutral value 0.
void score_the_term(const FrictionFitResult& fit, const std::vector<FrictionTerm>& terms, CandidateScore& score) {
  score.neutral = 0;
  if (const std::size_t k = decisive_term(fit, terms); k < terms.size()) set_estimate(score, term_coefficient(fit, terms, k));
}

// The linear problem the sparse regression solves: the law's residuals (the run levels are the
// regression's levels) and its Jacobian in the parameters the fit moves.
SparseProblem linear_problem(const FrictionLog& log, const FrictionFitResult& current, const std::vector<double>& values,
                             std::vector<double> y, double reference_C) {
  const std::size_t n = log.size();
  const auto& params = current.fit.parameters;
  SparseProblem problem;
  problem.y = std::move(y);
  problem.group.assign(log.run.begin(), log.run.end());
  problem.level = problem.group;
  std::vector<std::size_t> moved;  // the parameters the fit moves
  for (std::size_t j = 0; j < params.size(); ++j)
    if (params[j].free && !params[j].held_unidentifiable && !params[j].at_bound) moved.push_back(j);
  problem.fixed.resize(moved.size());
  // Central differences, one column per parameter: independent, each on a free thread.
  for_each_index(moved.size(), [&](std::size_t m) {
    const std::size_t j = moved[m];
    const double h = 1e-6 * std::max(std::abs(params[j].value), 1e-3);
    std::vector<double> up = values, down = values, column(n);
    up[j] += h;
    down[j] -= h;
    const LawAt law_up(log, params, up, reference_C), law_down(log, params, down, reference_C);
    for (std::size_t i = 0; i < n; ++i) column[i] = (law_up(i) - law_down(i)) / (2 * h);
    problem.fixed[m] = std::move(column);
  });
  return problem;
}

using Refit = std::function<FrictionFitResult(const std::vector<FrictionTerm>&)>;
using Summarise = std::function<ModelFit(const FrictionFitResult&)>;

// A candidate set of terms, fitted jointly with the law, its causes and the run offsets,
// and judged as a cause is.
struct Trial {
  std::vector<FrictionTerm> terms;
  FrictionFitResult fit;
  CandidateScore score;
  bool passes = false;
};

// The terms' trial against `before` (the model without them, `parameters` in its fit).
Trial trial(std::vector<FrictionTerm> terms, std::size_t parameters, const Refit& refit, const Summarise& summarise,
            const ModelFit& before, const SelectionRules& rules) {
  Trial t;
  std::size_t count = parameters;
  for (auto& term : terms) {
    const std::size_t adds = term.has_scale() ? 2 : 1;
    if (count + adds > kMaxFitParameters) continue;  // within the fit's parameter limit
    count += adds;
    t.terms.push_back(std::move(term));
  }
  // A term the data cannot determine beside the law and the others (a spline's basis
  // function that the Stribeck term already draws) is dropped, and the rest refitted once.
  auto undetermined = [&](const FrictionFitResult& fit) {
    std::vector<std::size_t> out;
    const std::size_t first = fit.fit.parameters.size() - term_parameter_count(t.terms);
    for (std::size_t k = 0, at = first; k < t.terms.size(); at += t.terms[k].has_scale() ? 2 : 1, ++k)
      for (std::size_t j = at; j < at + (t.terms[k].has_scale() ? 2 : 1); ++j)
        if (fit.fit.parameters[j].held_unidentifiable || !std::isfinite(fit.fit.parameters[j].se)) {
          out.push_back(k);
          break;
        }
    return out;
  };
  if (t.terms.empty()) {
    t.score.reason = "no room for the term within the fit's 16 parameters";
    return t;
  }
  t.fit = refit(t.terms);
  if (const auto drop = undetermined(t.fit); !drop.empty() && drop.size() < t.terms.size()) {
    for (auto k = drop.rbegin(); k != drop.rend(); ++k) t.terms.erase(t.terms.begin() + static_cast<std::ptrdiff_t>(*k));
    t.fit = refit(t.terms);
  }
  // A sparse form keeps only the terms its fit can tell from 0, as a cause must be: the
  // weakest of the others is dropped and the rest refitted, one at a time.
  while (!is_smooth(t.terms) && t.terms.size() > 1) {
    CandidateScore weakest;
    score_the_term(t.fit, t.terms, weakest);
    if (interval_excludes_neutral(weakest)) break;
    t.terms.erase(t.terms.begin() + static_cast<std::ptrdiff_t>(decisive_term(t.fit, t.terms)));
    t.fit = refit(t.terms);
  }
  ModelFit after = summarise(t.fit);
  if (!undetermined(t.fit).empty()) after.problem = "a term the data cannot determine beside the law";
  t.score.effect = "empirical term";
  score_the_term(t.fit, t.terms, t.score);
  t.passes = score_candidate(before, after, rules, t.score);
  return t;
}

// The found term described in `f`: each component's symbol, words and estimate, the formula,
// what it resembles and every covariate's range in these data (the terms are extrapolations
// beyond); the ranges are kept in the terms of `joint` too.
void describe_term(EmpiricalFinding& f, const FrictionLog& log, const TermSeries& series, const TermColumns& columns,
                   FrictionFitResult& joint) {
  const std::size_t n = log.size();
  // Every covariate's range in these data: the terms are extrapolations beyond.
  auto range_of = [&](TermCovariate c) {
    TermRange r{c, std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    const std::vector<double> part = is_law_covariate(c) ? columns.factor(TermFactor{c}, 0) : std::vector<double>{};
    for (std::size_t i = 0; i < n; ++i) {
      const double x = is_law_covariate(c) ? part[i] : term_covariate_value(log, series, i, c);
      r.min = std::min(r.min, x);
      r.max = std::max(r.max, x);
    }
    return r;
  };
  std::string formula, resembles;
  std::map<std::string, TermRange> used;
  const std::size_t first = joint.fit.parameters.size() - term_parameter_count(joint.terms);
  for (std::size_t t = 0, at = first; t < joint.terms.size(); ++t) {
    FrictionTerm& term = joint.terms[t];
    for (const auto& factor : term.factors)
      if (std::none_of(term.seen.begin(), term.seen.end(), [&](const TermRange& r) { return r.covariate == factor.covariate; }))
        term.seen.push_back(range_of(factor.covariate));
    if (term.lagged_temperature()) term.seen.push_back(range_of(TermCovariate::time_in_run_s));
    for (const auto& r : term.seen) used.emplace(term_covariate_name(r.covariate), r);
    EmpiricalComponent c;
    c.symbol = term.symbol(t + 1);
    c.words = term_words(term);
    c.covariates = term.covariates();
    c.coefficient = within_bounds(joint.fit.parameters[at++]);
    if (term.has_scale()) {
      c.has_scale = true;
      c.scale = within_bounds(joint.fit.parameters[at++]);
    }
    formula += (formula.empty() ? "" : " + ") + c.symbol;
    const std::string r = resemblance(term, series.chronology);
    if (!r.empty() && resembles.find(r) == std::string::npos) resembles += (resembles.empty() ? "" : "; or ") + r;
    f.components.push_back(std::move(c));
  }
  f.form = is_smooth(joint.terms) ? "smooth" : "sparse";
  f.formula = formula;
  f.resembles = resembles;
  for (const auto& [name, r] : used) f.ranges.push_back({name, r.min, r.max});
}

}  // namespace

FrictionTermSearch learn_friction_term(const FrictionLog& log, const FrictionFitResult& current,
                                       const std::function<FrictionFitResult(const std::vector<FrictionTerm>&)>& refit,
                                       const std::function<ModelFit(const FrictionFitResult&)>& summarise,
                                       const SelectionRules& rules, double reference_C) {
  FrictionTermSearch out;
  EmpiricalFinding& f = out.finding;
  f.searched = true;
  f.where = "the friction force";
  const std::size_t n = log.size();
  const TermSeries series = term_series(log);

  // The residuals of the law (the run levels are the sparse regression's levels), the law, its
  // temperature slope, and its Jacobian in the parameters the fit moves.
  const auto& params = current.fit.parameters;
  std::vector<double> values;
  for (const auto& p : params) values.push_back(p.value);
  std::vector<double> law(n), y(n);
  for (std::size_t i = 0; i < n; ++i) {
    law[i] = current.predicted_N[i] - current.run_offset_N[log.run[i]];
    y[i] = log.friction_N[i] - law[i];
  }
  const LawAt current_law(log, params, values, reference_C);
  const auto law_warmer = [&](std::size_t i, double dT) { return current_law(i, dT); };
  const LawColumns law_columns = law_columns_at(log, values, law, law_warmer, reference_C);
  const TermColumns columns{log, series, law_columns};
  SparseProblem problem = linear_problem(log, current, values, y, reference_C);
  std::vector<DictionaryEntry> candidates = dictionary(log, series, law_columns, law_warmer, reference_C);
  f.dictionary_size = candidates.size();
  for (auto& c : candidates) {
    problem.candidates.push_back(std::move(c.column));
    problem.family.push_back(c.family);
  }
  SparseOptions sparse;
  sparse.min_gain_percent = rules.min_cv_gain_percent;
  const SparseSelection chosen = select_sparse(problem, sparse);

  const ModelFit before = summarise(current);
  auto try_terms = [&](std::vector<FrictionTerm> terms) {
    return trial(std::move(terms), params.size(), refit, summarise, before, rules);
  };
  std::optional<Trial> kept;
  std::string why_not;
  if (chosen.selected.empty()) {
    why_not = fmt::format("no sparse set predicts held-out runs at least {:.3g} % better than the model alone (linearised "
                          "leave-one-run-out RMSE of the runs' shape {:.4g} N)",
                          rules.min_cv_gain_percent, chosen.cv_rmse_fixed);
  } else {
    std::vector<FrictionTerm> terms;
    for (std::size_t a = 0; a < chosen.selected.size(); ++a) {
      terms.push_back(candidates[chosen.selected[a]].term);
      terms.back().coefficient = chosen.coefficient[a];  // a lag's is its start: the joint fit is exact
    }
    Trial t = try_terms(std::move(terms));
    if (t.passes) kept = std::move(t);
    else why_not = "the sparse form fitted jointly with the law was not kept: " + t.score.reason;
  }
  // Where no sparse form wins: a smooth term in the one covariate whose spline predicts
  // held-out runs best — tried when the sparse form failed, or when its linearised held-out
  // RMSE beats the sparse form's by the gain a term must bring; kept if it does so fitted.
  const SmoothChoice smooth = smooth_term(log, series, columns, problem, rules.min_cv_gain_percent);
  f.dictionary_size += smooth.tried;
  const bool smooth_better = !smooth.terms.empty() && kept &&
                             smooth.cv_rmse < chosen.cv_rmse * (1 - rules.min_cv_gain_percent / 100);
  if (smooth.terms.empty()) {
    if (!kept) why_not += "; " + smooth.why_not;
  } else if (!kept || smooth_better) {
    Trial t = try_terms(smooth.terms);
    const bool wins = t.passes && (!kept || counted_gain(t.score) >= counted_gain(kept->score) + rules.min_cv_gain_percent);
    if (wins) {
      if (kept) why_not = "a smooth term predicts held-out runs better than the sparse form (" +
                          kept->terms.front().symbol(1) + (kept->terms.size() > 1 ? " + …" : "") + ")";
      kept = std::move(t);
    } else if (!kept) {
      why_not += "; the smooth term fitted jointly was not kept: " + t.score.reason;
    }
  }
  if (!kept) {
    f.reason = why_not;
    return out;
  }
  FrictionFitResult& joint = kept->fit;
  const CandidateScore& score = kept->score;
  set_held_out(f, before, summarise(joint));
  f.lrt_p = score.lrt_p;
  f.delta_bic = score.bic - information_criteria(before.ss, before.n, std::min(before.n_eff, summarise(joint).n_eff), before.k).second;
  describe_term(f, log, series, columns, joint);
  f.found = true;
  f.reason = score.reason + (f.form == "smooth" ? " (no sparse form did as well: " + why_not + ")" : "");
  f.curve = curve_of(log, series, current, joint, reference_C);
  out.fit = std::move(joint);
  return out;
}

}  // namespace lmcal::detail
