// The part of a diagnosis that does not depend on the physics (private): covariate ANOVA,
// the score of a candidate against the current model, forward selection and the verdict.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstddef>
#include <exception>
#include <tuple>
#include <string>
#include <utility>
#include <numeric>
#include <functional>
#include <vector>

#include <nlohmann/json.hpp>

#include "lmcal/diagnose/diagnosis.hpp"
#include "lmcal/fit/fit_result.hpp"
#include "parallel_slices.hpp"

namespace lmcal::detail {

// One-way ANOVA of `residual` grouped by the covariate's value (binned into ten quantile
// bins when it has more than twelve values): finds structure of any shape. η is stored in
// `correlation`.
CovariateTest anova(const std::string& name, const std::vector<double>& covariate, const std::vector<double>& residual);

// F test of the finer grouping against the coarser one it refines (group labels per value):
// does `fine` explain more of `values` than `coarse` already does? With all-equal `coarse`
// this is the one-way ANOVA of `fine`; with coarse = time bin and fine = (speed, time bin)
// it tests whether the residuals' course over time differs between speeds.
CovariateTest nested_anova(const std::string& name, const std::vector<std::size_t>& coarse,
                           const std::vector<std::size_t>& fine, const std::vector<double>& values);

// Holm's step-down adjustment over all `tests` (sets p_adjusted; the family-wise error of
// calling any of them structured stays at the level it is compared with).
void holm_adjust(std::vector<CovariateTest>& tests);

// Does the effect of one covariate on `values` depend on another? F test of the cells of
// (a, b) against the additive model a + b (dummy regression; up to four quantile bins of each
// covariate). Empty result (n = 0) when the cells leave no degrees of freedom.
CovariateTest interaction_anova(const std::string& name, const std::vector<double>& a, const std::vector<double>& b,
                                const std::vector<double>& values);

// Least-squares F test of adding the columns `extra` to the regression of `values` on `base`
// (an intercept is always in `base`): n = 0 when there are too few values.
CovariateTest regression_test(const std::string& name, const std::vector<std::vector<double>>& base,
                              const std::vector<std::vector<double>>& extra, const std::vector<double>& values);

// A covariate's values as group labels: one per distinct value, or ten quantile bins when
// there are more than twelve.
std::vector<std::size_t> value_bins(const std::vector<double>& covariate, std::size_t max_groups = 12, std::size_t bins = 10);

// What selection needs to know of one fitted model.
struct ModelFit {
  double ss = 0;          // residual sum of squares
  double n = 0;           // residuals
  double n_eff = 0;       // effective independent residuals (n when they are white)
  std::size_t k = 0;      // free parameters
  double cv_rmse = 0;     // leave-one-run-out
  // Leave-one-run-out with each held-out run's own level taken out (NaN: not scored). A
  // candidate may gain on either: on the level of new runs (a cause that changes only
  // between runs) or on their shape.
  double cv_shape_rmse = std::numeric_limits<double>::quiet_NaN();
  std::string problem;    // non-empty: the fit cannot be used (not identifiable, not converged)
  std::vector<double> fitted;  // the fitted values, in the same order for every model (for ties)
};

struct SelectionRules {
  double lrt_p = 1e-3;
  double min_cv_gain_percent = 2.0;
  double switch_bic = 10;  // a switch (no parameter) must lower the BIC by this much
  // When the measurement noise is known (> 0, in the held-out RMSE's unit) and the current
  // held-out RMSE is above it: a candidate must also remove this share of the excess
  // (RMSE² - noise²); a tiny gain on residuals far above the noise is not an explanation.
  double noise_floor = 0;
  double min_excess_removed = 0.1;
  // A candidate's effect, sqrt(held-out RMSE² before − after), must reach this (> 0: the size of
  // structure the measurement itself can make; `effect_floor_basis` names it in the reason).
  double min_effect = 0;
  std::string effect_floor_basis;
  double tie_correlation = 0.99;  // candidates whose fitted changes correlate above this are a tie
  std::size_t max_effects = 3;
  bool parallel = false;  // fit a round's candidates in parallel (fit_with and summarise thread-safe)
  Progress progress;  // told of every candidate fit (of every round when parallel)
  // In parallel, the candidates with the larger expected cost (none: all alike) are started
  // first, so that no thread is left with a long fit at the end of a round; only the order the
  // fits start in changes, not their results, which are kept in library order.
  std::function<double(const std::string& candidate)> expected_cost;
};

// AICc and BIC of a Gaussian least-squares fit with k parameters over n (effective) residuals.
std::pair<double, double> information_criteria(double ss, double n, double n_eff, std::size_t k);

// Scores `candidate` against `current` (LRT and BIC on the effective sample, held-out gain)
// and sets c.aicc … c.reason; true when it passes: significant, a cause's interval (as set in
// `c` before) excluding its neutral value, the counted gain at least min_cv_gain_percent and,
// for a cause, the whole model's loss on the other criterion (whole_model_loss) within it.
bool score_candidate(const ModelFit& current, const ModelFit& candidate, const SelectionRules& rules, CandidateScore& c);

template <class Fit>
struct Selection {
  std::vector<std::vector<CandidateScore>> rounds;  // the candidates of every forward step
  std::vector<std::string> accepted;
  Fit current;
  std::vector<DiagnosisStep> steps;  // one per accepted cause
  std::vector<Fit> path;             // path[k]: the model with the first k accepted causes (path[0]: the baseline)
  std::vector<ModelFit> path_scores; // and its summary
};

// The step from the model `before` to `after`, by their held-out RMSEs (each model's own,
// computed once), its gain on the criterion counted_gain counts.
DiagnosisStep make_step(std::string action, std::string name, const ModelFit& before, const ModelFit& after);

// The empirical term's held-out RMSEs before and after it, on the criterion its gain is counted
// on (make_step's), into `f`.
void set_held_out(EmpiricalFinding& f, const ModelFit& before, const ModelFit& after);

// `p` with its quoted interval within its bounds (bounded_interval.hpp): a linear interval that
// would cross a bound is formed on the log or logit scale instead, and `interval` says so.
ParameterEstimate within_bounds(ParameterEstimate p);

// A named cause with a neutral value (the library's), as opposed to a switch, a thermal
// extension without one, or the empirical term.
inline bool is_cause(const CandidateScore& c) { return std::isfinite(c.neutral); }
// A cause's 95 % interval (as quoted) excludes the value at which it is absent; true for
// anything else (and for an estimate without an interval).
bool interval_excludes_neutral(const CandidateScore& c);

// The held-out gain that counts for a candidate: on new runs' level (cv_gain_percent) or on
// their shape (cv_shape_gain_percent), whichever it improves more (the plain gain when the
// shape was not scored). The level of a held-out run rests on a few run means and its zero
// offset's variance, so a cause of the runs' shape may not show there, and a cause that
// changes only between runs shows nowhere else; the likelihood-ratio test guards both.
double counted_gain(const CandidateScore& c);
// What the candidate loses on the other criterion, in % (0 when it loses on neither, or the
// shape was not scored). A cause is judged on the whole model, level and shape together: its
// counted gain must clear the threshold and this loss stay within it.
double whole_model_loss(const CandidateScore& c);

// Correlation of the changes two candidate fits make to the current fitted values (0 when
// either makes none or the fitted values are missing).
double change_correlation(const std::vector<double>& current, const std::vector<double>& a, const std::vector<double>& b);

// Forward selection: every effect of `library` not yet accepted is added to the current
// model (fit_with(effects, current) -> Fit) and scored (summarise(fit, effect) -> the
// ModelFit and the effect's estimate in a CandidateScore); the passing candidate with the
// largest held-out gain is accepted, until none passes or max_effects are in.
template <class Fit, class FitWith, class Summarise>
Selection<Fit> forward_select(const std::vector<std::string>& library, Fit baseline, const FitWith& fit_with,
                              const Summarise& summarise, const SelectionRules& rules) {
  Selection<Fit> s{{}, {}, std::move(baseline), {}, {}, {}};
  ModelFit current = summarise(s.current, std::string()).first;
  s.path.push_back(s.current);
  s.path_scores.push_back(current);
  while (s.accepted.size() < rules.max_effects) {
    std::vector<std::string> effects_left;
    for (const auto& effect : library)
      if (std::find(s.accepted.begin(), s.accepted.end(), effect) == s.accepted.end()) effects_left.push_back(effect);
    const std::size_t candidates = effects_left.size();
    const std::string step = "round " + std::to_string(s.rounds.size() + 1);
    // The candidate fits are independent: in parallel when asked (each fit alone is
    // deterministic, and the results are kept in library order, so any thread count gives
    // the same selection). Progress is told from the calling thread only.
    std::vector<Fit> fits(candidates);
    std::vector<ModelFit> models(candidates);
    std::vector<CandidateScore> round(candidates);
    if (rules.parallel && rules.progress) rules.progress(step + ": " + std::to_string(candidates) + " candidates", 0, 1);
    std::vector<std::size_t> start_order(candidates);
    std::iota(start_order.begin(), start_order.end(), std::size_t{0});
    if (rules.parallel && rules.expected_cost)
      std::stable_sort(start_order.begin(), start_order.end(), [&](std::size_t a, std::size_t b) {
        return rules.expected_cost(effects_left[a]) > rules.expected_cost(effects_left[b]);
      });
    auto fit_candidate = [&](std::size_t started) {
      const std::size_t i = start_order[started];
      if (!rules.parallel && rules.progress) rules.progress(step + ", " + effects_left[i], i, candidates);
      std::vector<std::string> effects = s.accepted;
      effects.push_back(effects_left[i]);
      fits[i] = fit_with(effects, s.current);
      std::tie(models[i], round[i]) = summarise(fits[i], effects_left[i]);
      round[i].effect = effects_left[i];
    };
    if (rules.parallel) {
      for_each_index(candidates, fit_candidate);
    } else {
      for (std::size_t started = 0; started < candidates; ++started) fit_candidate(started);
    }
    for (std::size_t i = 0; i < candidates; ++i) score_candidate(current, models[i], rules, round[i]);
    std::size_t best = round.size();
    for (std::size_t i = 0; i < round.size(); ++i)
      if (round[i].accepted &&
          (best == round.size() || counted_gain(round[i]) > counted_gain(round[best])))
        best = i;
    for (auto& c : round) c.accepted = false;
    if (best == round.size()) {
      s.rounds.push_back(std::move(round));
      break;
    }
    // Candidates that change the fit as the best does, and fit about as well (BIC within
    // switch_bic), are indistinguishable from it on these data: a tie, named together,
    // represented by the one listed first in the library (the plainer form comes first). A
    // look-alike whose interval holds its neutral value is not named: it would be a cause named
    // with an interval that says it may be absent.
    std::vector<std::size_t> tie{best};
    for (std::size_t i = 0; i < round.size(); ++i)
      if (i != best && models[i].problem.empty() && std::isfinite(round[i].cv_rmse) && interval_excludes_neutral(round[i]) &&
          change_correlation(current.fitted, models[best].fitted, models[i].fitted) > rules.tie_correlation &&
          round[i].bic < round[best].bic + rules.switch_bic)  // and fit as well: a clearly worse form is no tie
        tie.push_back(i);
    best = *std::min_element(tie.begin(), tie.end());  // rounds list candidates in library order
    for (std::size_t i : tie)
      if (i != best) round[best].tied_with.push_back(round[i].effect);
    round[best].accepted = true;
    s.accepted.push_back(round[best].effect);
    s.steps.push_back(make_step("add cause", round[best].effect, current, models[best]));
    s.current = std::move(fits[best]);
    current = models[best];
    s.path.push_back(s.current);
    s.path_scores.push_back(current);
    s.rounds.push_back(std::move(round));
  }
  return s;
}

// The estimate and interval of `p` into the candidate's score.
void set_estimate(CandidateScore& c, const ParameterEstimate& p);

// The accepted candidates, each as scored in the round it was accepted in, with the final
// fit's estimate of its (first) parameter (`estimate(name)`; nullptr for a switch).
template <class Estimate>
std::vector<CandidateScore> accepted_scores(const std::vector<std::vector<CandidateScore>>& rounds,
                                            const std::vector<std::string>& accepted, const Estimate& estimate) {
  std::vector<CandidateScore> out;
  for (const auto& name : accepted) {
    CandidateScore c;
    for (const auto& round : rounds)
      for (const auto& candidate : round)
        if (candidate.effect == name && candidate.accepted) c = candidate;
    if (const ParameterEstimate* p = estimate(name)) set_estimate(c, *p);
    out.push_back(c);
  }
  return out;
}

// The verdict of a diagnosis in plain words.
struct VerdictInput {
  std::string model;  // "the published law", "the published rail model"
  std::string unit;   // of the residuals: "N", "K"
  std::vector<CandidateScore> accepted;  // with the final fit's estimates
  std::vector<ParameterShift> shifts;
  double cv_before = 0, cv_after = 0, baseline_rmse = 0;  // cv_after: the named causes' model
  double cv_final = std::numeric_limits<double>::quiet_NaN();  // the last step's after (with the empirical term)
  bool baseline_structured = false, final_structured = false;
  std::vector<CovariateTest> baseline_covariates, final_covariates;  // strongest first
  LackOfFit baseline_lack_of_fit, final_lack_of_fit;
  const EmpiricalFinding* empirical = nullptr;  // the term learned beyond the library, if searched
};
struct Verdict {
  // "explained", "partly explained" (causes found, but the residuals still exceed the noise),
  // "unexplained", "no significant discrepancy"; "unexplained — empirical term found" and
  // "partly explained — empirical term found" when a term beyond the library gains on held-out runs
  std::string verdict;
  std::string summary;
  std::string unexplained_covariate;
  double cv_gain_percent = 0;
};
Verdict make_verdict(const VerdictInput& in);
// The verdict of a diagnosis (FrictionDiagnosis, ThermalDiagnosis: accepted, shifts, baseline
// and final residuals set) into it; `model` and `unit` name the baseline and the residuals,
// the held-out RMSEs and the baseline RMSE are in that unit.
// The held-out RMSE a diagnosis ends with: the last step's after (the baseline's without steps).
double final_cv_rmse(const std::vector<DiagnosisStep>& steps, double baseline);
// `cv_after` is the named causes' model's; the final value is the last step's after (d.steps).
template <class Diagnosis>
void conclude(Diagnosis& d, std::string model, std::string unit, double cv_before, double cv_after, double baseline_rmse) {
  const Verdict v = make_verdict({.model = std::move(model),
                                  .unit = std::move(unit),
                                  .accepted = d.accepted,
                                  .shifts = d.shifts,
                                  .cv_before = cv_before,
                                  .cv_after = cv_after,
                                  .baseline_rmse = baseline_rmse,
                                  .cv_final = final_cv_rmse(d.steps, cv_before),
                                  .baseline_structured = d.baseline.structured,
                                  .final_structured = d.final.structured,
                                  .baseline_covariates = d.baseline.covariates,
                                  .final_covariates = d.final.covariates,
                                  .baseline_lack_of_fit = d.baseline.lack_of_fit,
                                  .final_lack_of_fit = d.final.lack_of_fit,
                                  .empirical = &d.empirical});
  d.verdict = v.verdict;
  d.summary = v.summary;
  d.unexplained_covariate = v.unexplained_covariate;
  d.cv_gain_percent = v.cv_gain_percent;
}

// JSON of candidate scores (the held-out RMSE as "cv_rmse_<unit>") and covariate tests.
nlohmann::json candidate_json(const CandidateScore& c, const std::string& unit);
nlohmann::json covariates_json(const std::vector<CovariateTest>& tests);
nlohmann::json lack_of_fit_json(const LackOfFit& l);

// A noise σ in the residuals' unit from differences of a series (the thermocouples' traces, a
// friction log's consecutive residuals), with the degrees of freedom of that estimate: for
// white noise, the mean square of m second differences is as good as 18/35 m independent
// squares (they overlap).
struct NoiseFloor {
  double sigma = 0, dof = 0;
};
inline constexpr double kSecondDifferenceDofShare = 18.0 / 35.0;

// Lack of fit against a noise floor: F = s² / σ², the residual variance per degree of freedom
// the fit leaves (n − k: every parameter and level counted) against the noise variance, the
// residuals' degrees of freedom counted on n_eff (serially correlated residuals carry less
// evidence than their number). Rejected (fits = false) when F is significant at structure_p
// and the residual RMS s exceeds `margin` σ: on thousands of records a hair above the noise is
// significant without mattering. `basis` names the noise in words.
LackOfFit lack_of_fit_against_noise(double ss, double n, double n_eff, std::size_t k, const NoiseFloor& noise,
                                    double structure_p, double margin, std::string basis);

// What both diagnoses write of their verdict: verdict, summary, causes, the held-out RMSE
// before and after ("cv_rmse_before_<unit>"), the gain, parameter shifts, the unexplained
// covariate and every forward step's candidates ("rounds").
nlohmann::json verdict_json(const std::string& verdict, const std::string& summary,
                            const std::vector<CandidateScore>& accepted, const std::vector<ParameterShift>& shifts,
                            const std::vector<std::vector<CandidateScore>>& rounds, double cv_before, double cv_after,
                            double cv_gain_percent, const std::string& unexplained_covariate, const std::string& unit);
// The empirical term (searched or not, found or not) as JSON; values in the residuals' unit.
nlohmann::json empirical_json(const EmpiricalFinding& e, const std::string& unit);
// The steps from the baseline to the final model, values in the residuals' unit.
nlohmann::json steps_json(const std::vector<DiagnosisStep>& steps, const std::string& unit);
template <class Diagnosis>
nlohmann::json verdict_json(const Diagnosis& d, double cv_before, double cv_after, const std::string& unit) {
  nlohmann::json j = verdict_json(d.verdict, d.summary, d.accepted, d.shifts, d.rounds, cv_before, cv_after, d.cv_gain_percent,
                      d.unexplained_covariate, unit);
  j["steps"] = steps_json(d.steps, unit);
  j["empirical_term"] = empirical_json(d.empirical, unit);
  return j;
}

}  // namespace lmcal::detail
