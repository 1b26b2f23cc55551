// The friction diagnosis: the law's residuals tested (friction_residual_tests.cc), the library's
// causes whose precondition the log holds tried forward against held-out runs, an empirical
// term beyond them, and the verdict with what the design hides; and its JSON.
#include "lmcal/diagnose/friction_diagnosis.hpp"

#include "lmcal/version.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <future>
#include <mutex>
#include <set>
#include <optional>
#include <string>
#include <vector>

#include "lmcal/error.hpp"
#include "lmcal/fit/statistics.hpp"
#include "fit/fit_json.hpp"
#include "fit/friction_condition.hpp"
#include "fit/friction_steps.hpp"
#include "cause_starts.hpp"
#include "empirical_friction.hpp"
#include "friction_residual_tests.hpp"
#include "run_scale.hpp"
#include "selection.hpp"

namespace lmcal {

namespace {

using detail::Covariate;
using detail::covariates_of;
using detail::diagnose_residuals;
using detail::kMinCauseAcceleration_m_s2;
using detail::varies_in;

constexpr int kCandidateIterations = 15;

// A cause is named only where its precondition holds. A constant force signed with the motion
// (signed_zero_offset's signature) is a load cell's or torque sensor's zero only where one
// measured the force on an axis whose mounting is known; otherwise it may as well be the weight
// on an inclined axis or a drive's current offset, and it is reported as what the data show,
// under a neutral name, with those candidates.

// Why a cause's precondition is absent, in words.
std::string absent_because(const FrictionLog& log, std::string_view column) {
  if (column == "direction") return "has one sense only";
  if (column == "acceleration_m_s2")
    return log.trajectory ? "a trajectory: its moving mass is fitted with the law (moving_mass)"
                          : fmt::format("RMS under {} m/s2 or not logged", kMinCauseAcceleration_m_s2);
  if (column == "position_m" || column == "distance_since_reversal_m") return "spans under 1 mm or not logged (a raw log's)";
  return "constant or not logged";
}

// The library's causes a log can show; the others, with why, into `not_tried`.
std::vector<std::string> causes_that_can_show(const FrictionLog& log, std::vector<std::string>& not_tried) {
  std::vector<std::string> out;
  for (const std::string& name : friction_cause_names()) {
    const FrictionEffectInfo& info = FrictionEffectLibrary::infos[*find_friction_effect(name)];
    if (varies_in(log, info.varies)) out.push_back(name);
    else not_tried.push_back(fmt::format("{} ({} {})", name, info.varies, absent_because(log, info.varies)));
  }
  return out;
}

void read_precondition(CandidateScore& c, const FrictionLog& log) {
  if (c.effect != SignedZeroOffset::info.name) return;
  const ForceSensor sensor = log.force_sensor;
  const bool has_zero = sensor == ForceSensor::load_cell || sensor == ForceSensor::torque_sensor;
  if (has_zero && log.incline_stated) return;
  std::vector<std::string> candidates, unstated;
  if (sensor != ForceSensor::motor_current)
    candidates.push_back(sensor == ForceSensor::torque_sensor ? "a torque sensor's zero" : "a load cell's zero");
  if (!log.incline_stated) candidates.push_back("the weight on an inclined axis");
  if (!has_zero) candidates.push_back("a drive's current offset");
  if (sensor == ForceSensor::unknown) unstated.push_back("what measured the force (force_sensor)");
  if (!log.incline_stated) unstated.push_back("the axis's mounting (axis_incline_deg)");
  candidates.insert(candidates.end(), c.tied_with.begin(), c.tied_with.end());
  c.shown = "signed_constant_force";
  c.tied_with = std::move(candidates);
  c.precondition = unstated.empty()
                       ? std::string("a constant force signed with the motion, which a motor's current cannot tell from "
                                     "the friction's level")
                       : fmt::format("a constant force signed with the motion; not stated: {}", fmt::join(unstated, ", "));
  c.measure = "state force_sensor and axis_incline_deg in the friction manifest's [raw] table (--force-sensor, "
              "--axis-incline), and log the force at rest before each run";
}

// What a candidate cause's fit is expected to cost, for the order the fits start in: a cause
// with parts (a ripple's period and phase, a pre-sliding distance) is nonlinear in them and
// takes several times the iterations of the others (the 100k-sample axis: 0.5 s against 0.15 s);
// listed last in the library, they were started last and left one thread alone at the end.
double expected_fit_cost(const std::string& cause) {
  const std::size_t slot = friction_effect_slot(cause);
  double parts = 0;
  for (std::size_t s = slot + 1; s < kFrictionEffectCount && std::string_view(FrictionEffectLibrary::infos[s].part_of) == cause; ++s)
    parts += 1;
  return 1 + parts;
}

// A fit of the law plus `effects`, started at `start` (one start: the diagnosis refits many times).
FrictionFitResult fit_with(const FrictionLog& log, const FrictionDiagnosisOptions& o, const std::vector<std::string>& effects,
                           const FrictionConstants<double>& start, const std::vector<double>& effect_start,
                           double run_offset_ratio, const std::vector<FrictionTerm>& terms = {}, bool hold_ratio = false) {
  FrictionFitOptions f = o.fit;
  f.terms = terms;
  f.run_offset_ratio_start = run_offset_ratio;  // the current model's: its variance settles in fewer fits
  if (hold_ratio) f.max_variance_passes = 1;    // and stays there
  f.effects = effects;
  f.effect_start = effect_start;
  f.start = start;
  for (std::size_t j = 0; j < FrictionConstants<double>::kFittable; ++j)
    fittable_constant(f.start, j) = std::clamp(fittable_constant(f.start, j), f.bounds[j].first, f.bounds[j].second);
  f.per_run_fits = false;
  f.cross_validate = true;
  f.fit.starts = 0;  // warm-started from the previous model's estimate: no multi-start
  f.fit.profile = ProfileMode::none;
  f.fit.bootstrap = 0;  // the diagnosis quotes no bootstrap intervals
  // Warm-started, a candidate converges in a few iterations; one that crawls along a bound
  // (a drag pinned at 0 beside its twin) adds nothing and is reported as not converged.
  // A term starts from a linearised estimate, further away: it gets the iterations a fit needs.
  f.fit.max_iterations = terms.empty() ? kCandidateIterations : o.fit.fit.max_iterations;
  return fit_friction(log, f);
}

constexpr const char* kResolutionFloorWords =
    "the force the position's resolution makes through the moving mass (M σ_a; a repeating move repeats the encoder's "
    "quantization)";

// What the design hides or makes costly, in words; and what the final residuals' tests found
// significant but left unexplained because of its size.
std::vector<std::string> design_notes(const FrictionLog& log, const FrictionFitResult& baseline, const LackOfFit& lack,
                                      const ResidualDiagnostics& final, const FrictionDiagnosisOptions& o) {
  std::vector<std::string> notes;
  std::string between, single;
  const std::vector<std::string> not_given = log.law.not_logged();  // their columns hold neutral stand-ins
  for (const Covariate& c : covariates_of(log, o.condition_tolerance)) {
    const std::vector<double> snapped = detail::snap_to_resolution(c.value, o.condition_tolerance);
    const std::set<double> values(snapped.begin(), snapped.end());
    if (std::string(c.name) == "time_s") continue;
    if (std::string(c.name) == "direction") {
      // Each run moves one way: a force signed with the motion is seen only between runs,
      // against the spread of their zero offsets.
      if (values.size() > 1 && c.run_level)
        notes.push_back(fmt::format(
            "direction changes only between runs (each run moves one way): direction is confounded with the runs, so a "
            "force signed with the motion (a zero offset, a direction asymmetry) is judged on the {} run means against "
            "the spread of the runs' zero offsets (tau = {:.3g} N); log both senses in each run to see it within runs",
            log.run_names.size(), baseline.run_offset_sd_N));
      continue;
    }
    if (std::find(not_given.begin(), not_given.end(), c.name) != not_given.end()) continue;
    if (values.size() == 1) single += fmt::format("{}{} ({:g})", single.empty() ? "" : ", ", c.name, *values.begin());
    else if (c.run_level) between += (between.empty() ? "" : ", ") + std::string(c.name);
  }
  if (!between.empty())
    notes.push_back(fmt::format(
        "{} change only between runs (each run holds one value): their effects are judged on the {} run means against "
        "the spread of the runs' zero offsets (tau = {:.3g} N), not on the samples; to see them within runs, log two "
        "setups per run or repeat setups",
        between, log.run_names.size(), baseline.run_offset_sd_N));
  if (!single.empty())
    notes.push_back(fmt::format("one value only of {}: no effect of these can be seen in these data", single));
  if (!not_given.empty())
    notes.push_back(fmt::format("not given: {}: no effect of these can be seen in these data", fmt::join(not_given, ", ")));
  if (!lack.tested) notes.push_back("lack of fit not tested (" + lack.basis + "): repeat a setup in a second run to get it");
  else if (lack.against == "noise")
    notes.push_back("lack of fit judged against the noise of consecutive residuals, not against pure error (too few "
                    "conditions recur in another run): repeat setups in a second run for a test against pure error");
  // Significant, but under the size that counts: said, not dropped silently.
  std::vector<std::string> small;
  for (const CovariateTest& t : final.covariates)
    if (t.p_adjusted < o.structure_p && !t.structured)
      small.push_back(fmt::format("{} ({}, Holm {}; size {:.3g} N)", t.covariate, p_is(t.p_value), p_value_text(t.p_adjusted), t.size));
  if (!small.empty()) {
    const bool floor_binds = final.resolution_floor_N > o.min_structure_fraction * final.rmse_N;
    notes.push_back(fmt::format(
        "left unexplained, significant but each of a size {}: {}",
        floor_binds ? fmt::format("within {}, {:.3g} N", kResolutionFloorWords, final.resolution_floor_N)
                    : fmt::format("under {:g} % of the sample RMSE ({:.3g} N)", 100 * o.min_structure_fraction, final.rmse_N),
        fmt::join(small, "; ")));
  }
  return notes;
}

// A candidate's fit as the selection compares it: the likelihood of the random run offsets'
// fit (their variance included), and the law's own predictions (without the offsets) to tell
// ties; with `effect`, the cause's estimate.
std::pair<detail::ModelFit, CandidateScore> summarise_fit(const FrictionLog& log, const FrictionFitResult& fit,
                                                           const std::string& effect) {
  const std::size_t n = log.size();
  detail::ModelFit m{.ss = fit.deviance_ss,
                     .n = static_cast<double>(n),
                     .n_eff = static_cast<double>(n),
                     .k = fit.fit.free_parameters + 1,
                     .cv_rmse = fit.cv_rmse_N,
                     .cv_shape_rmse = fit.cv_shape_rmse_N};
  m.fitted = fit.predicted_N;
  for (std::size_t i = 0; i < n; ++i) m.fitted[i] -= fit.run_offset_N[log.run[i]];
  CandidateScore c;
  if (!effect.empty()) {
    const auto& p = fit.fit.parameter(effect);
    detail::set_estimate(c, p);
    c.measure = FrictionEffectLibrary::infos[friction_effect_slot(effect)].measure;
    c.neutral = FrictionEffectLibrary::infos[friction_effect_slot(effect)].neutral;
    if (p.held_unidentifiable) m.problem = "not identifiable from these data";
  }
  if (!fit.fit.solver.converged)
    m.problem = fmt::format("the fit did not converge ({}, {} iterations)", fit.fit.solver.termination,
                            fit.fit.solver.iterations);
  return std::make_pair(m, c);
}

detail::ModelFit model_fit(const FrictionLog& log, const FrictionFitResult& fit) { return summarise_fit(log, fit, std::string()).first; }

// 1. The law alone, cross-validated: what every cause is measured against.
FrictionFitResult baseline_fit(const FrictionLog& log, const FrictionDiagnosisOptions& o) {
  FrictionFitOptions base_options = o.fit;
  base_options.per_run_fits = false;
  base_options.cross_validate = true;
  base_options.fit.profile = ProfileMode::none;
  base_options.fit.bootstrap = 0;
  return fit_friction(log, base_options);
}

// Where a candidate's fit starts.
struct CandidateStart {
  std::vector<std::string> effects;
  std::vector<double> effect_start;
  FrictionConstants<double> start;
};

// The causes with their parts and the drive's terms, each from the current model's value
// where it has one; a new cause from its neutral value, or where it says so from the
// current residuals (cause_starts.hpp).
CandidateStart candidate_start(const FrictionLog& log, const FrictionDiagnosisOptions& o,
                               const std::vector<std::string>& causes, const FrictionFitResult& current) {
  const std::size_t n = log.size();
  std::vector<std::string> effects = causes;
  with_effect_parts(effects);
  for (const std::string& name : drive_effects(log))
    if (std::find(effects.begin(), effects.end(), name) == effects.end()) effects.push_back(name);
  std::vector<double> effect_start;
  for (const std::string& name : effects) {
    const auto at = std::find_if(current.fit.parameters.begin() + FrictionConstants<double>::kFittable, current.fit.parameters.end(),
                                 [&](const ParameterEstimate& p) { return p.name == name; });
    effect_start.push_back(at != current.fit.parameters.end() ? at->value
                                                              : FrictionEffectLibrary::infos[friction_effect_slot(name)].neutral);
  }
  const std::string& added = causes.empty() ? std::string() : causes.back();
  if (!added.empty() && std::none_of(current.fit.parameters.begin(), current.fit.parameters.end(),
                                     [&](const ParameterEstimate& p) { return p.name == added; })) {
    std::vector<double> residual_N(n);
    for (std::size_t i = 0; i < n; ++i) residual_N[i] = log.friction_N[i] - current.predicted_N[i];
    const std::vector<double> start = detail::cause_start(added, log, residual_N);
    const auto at = std::find(effects.begin(), effects.end(), added) - effects.begin();
    for (std::size_t p = 0; p < start.size(); ++p) effect_start[static_cast<std::size_t>(at) + p] = start[p];
  }
  // From the current estimate where it is inside its bounds (fewer iterations), else from
  // the given start (a misspecified fit may sit on a bound).
  FrictionConstants<double> start = o.fit.start;
  for (std::size_t j = 0; j < FrictionConstants<double>::kFittable; ++j) {
    const ParameterEstimate& p = current.fit.parameters[j];
    if (p.free && !p.held_unidentifiable && p.value > o.fit.bounds[j].first && p.value < o.fit.bounds[j].second &&
        !p.at_bound)
      fittable_constant(start, j) = p.value;
  }
  return {std::move(effects), std::move(effect_start), start};
}

// The log the diagnosis's fits take, and the options they take it with: where a fit would
// smooth the logged temperatures to their set points' means (FrictionTemperature::block_mean),
// they are smoothed here once, not in each of the diagnosis's dozens of fits (a tenth of each
// fit's time on 10⁵ samples), and the fits take them as logged: the same fits, bit for bit.
class FitLog {
 public:
  FitLog(const FrictionLog& log, const FrictionDiagnosisOptions& o) : options_(o) {
    if (detail::smooths_temperature(log, o.fit)) {
      smoothed_ = with_block_mean_temperature(log);
      options_.fit.temperature = FrictionTemperature::logged;
    }
    log_ = smoothed_ ? &*smoothed_ : &log;
  }
  FitLog(const FitLog&) = delete;
  FitLog& operator=(const FitLog&) = delete;

  const FrictionLog& log() const { return *log_; }
  const FrictionDiagnosisOptions& options() const { return options_; }

 private:
  std::optional<FrictionLog> smoothed_;
  const FrictionLog* log_ = nullptr;
  FrictionDiagnosisOptions options_;
};

// The candidates' fits, from several threads at once (the forward selection fits a round's
// candidates in parallel), and which of them needed the zeros' variance held.
class CandidateFits {
 public:
  CandidateFits(const FrictionLog& log, const FitLog& fits, const FrictionDiagnosisOptions& o) : log_(log), fits_(fits), o_(o) {}

  // The law with `causes` (and `terms`), started from `current`.
  FrictionFitResult fit(const std::vector<std::string>& causes, const FrictionFitResult& current,
                        const std::vector<FrictionTerm>& terms = {}) {
    const CandidateStart s = candidate_start(log_, o_, causes, current);
    const std::string& added = causes.empty() ? std::string() : causes.back();
    FrictionFitResult fit = fit_with(fits_.log(), fits_.options(), s.effects, s.start, s.effect_start, current.run_offset_ratio, terms);
    // The random zeros are a spread about 0 added outside the law and its effects. A candidate
    // whose fit needs them to spread far wider than the model before it trades the law's level
    // against a zero common to the runs: outside an effect on the total, (F + c)(1 + a·dir) - c
    // is a signed force c·a·dir, and the candidate's held-out runs (predicted at the zeros'
    // mean, 0) miss by c. Such a candidate is fitted with the zeros' variance held at the
    // current model's: it must explain the data with the law's level where the law puts it.
    if (fit.run_offsets == RunOffsets::random &&
        fit.run_offset_sd_N > 2 * current.run_offset_sd_N + 0.5 * current.rmse_N) {
      fit = fit_with(fits_.log(), fits_.options(), s.effects, s.start, s.effect_start, current.run_offset_ratio, terms, true);
      const std::lock_guard<std::mutex> lock(held_zeros_mutex_);
      held_zeros_.insert(terms.empty() ? added : "the empirical term");
    }
    return fit;
  }

  // An empirical term learned on top of `named` (the law with `causes`).
  detail::FrictionTermSearch learn_term(const std::vector<std::string>& causes, const FrictionFitResult& named,
                                        const detail::SelectionRules& rules) {
    return detail::learn_friction_term(
        log_, named, [&](const std::vector<FrictionTerm>& terms) { return fit(causes, named, terms); },
        [&](const FrictionFitResult& f) { return model_fit(log_, f); }, rules, o_.fit.start.T_ref_C);
  }

  const std::set<std::string>& held_zeros() const { return held_zeros_; }

 private:
  const FrictionLog& log_;
  const FitLog& fits_;
  const FrictionDiagnosisOptions& o_;
  std::set<std::string> held_zeros_;  // candidates fitted with the zeros' variance held
  std::mutex held_zeros_mutex_;
};

// The model so far: the causes accepted and its fit.
struct CurrentModel {
  std::vector<std::string> accepted;
  FrictionFitResult fit;
};

// 4. What remains; beyond the library, an empirical term when structure remains.
// Searched unless named causes were found and nothing is left: structure the residual tests
// miss (running-in, shared between the runs' levels and their pure error) shows only as a
// term that predicts held-out runs, and the term must pass the rules a cause passes.
// Fills d.final.
std::optional<detail::FrictionTermSearch> search_term(const FrictionLog& log, const FrictionDiagnosisOptions& o,
                                                      CandidateFits& candidates, const detail::SelectionRules& rules,
                                                      const CurrentModel& model, FrictionDiagnosis& d) {
  std::optional<detail::FrictionTermSearch> search;
  auto search_term = [&] {
    if (o.progress) o.progress("empirical term", 0, 1);
    search = candidates.learn_term(model.accepted, model.fit, rules);
  };
  if (o.learn_term && model.accepted.empty()) {
    // Searched whatever the residuals' tests say: they run on a thread of their own meanwhile
    // (they only read the log and the fit).
    auto tests = std::async(std::launch::async, [&] { return diagnose_residuals(log, model.fit, o); });
    search_term();
    d.final = tests.get();
  } else {
    d.final = diagnose_residuals(log, model.fit, o);
    const bool left = d.final.structured || (d.final.lack_of_fit.tested && !d.final.lack_of_fit.fits);
    if (o.learn_term && left) search_term();
  }
  return search;
}

// A cause accepted before the term may only have stood in for what the term models (a
// Coulomb level changing with temperature for the law seeing another temperature above
// 35 C): each must still pass, as a candidate, on top of the others and the term (learned
// anew without it), or it is dropped — its own step, the model refitted without it.
void drop_stand_ins(const FrictionLog& log, const FrictionDiagnosisOptions& o, CandidateFits& candidates,
                    const detail::SelectionRules& rules, const detail::Selection<FrictionFitResult>& selection,
                    CurrentModel& model, std::optional<detail::FrictionTermSearch>& search, FrictionDiagnosis& d) {
  std::vector<std::string>& accepted = model.accepted;
  FrictionFitResult& current = model.fit;
  for (std::size_t i = accepted.size(); search && search->fit && i-- > 0;) {
    std::vector<std::string> others = accepted;
    others.erase(others.begin() + static_cast<std::ptrdiff_t>(i));
    // The model without it: the forward selection's own where it passed through it.
    const bool on_path = others.size() < selection.path.size() &&
                         std::equal(others.begin(), others.end(), selection.accepted.begin());
    FrictionFitResult named = on_path ? selection.path[others.size()] : candidates.fit(others, current);
    detail::FrictionTermSearch without = candidates.learn_term(others, named, rules);
    if (!without.fit) continue;
    CandidateScore c;
    if (detail::score_candidate(model_fit(log, *without.fit), model_fit(log, *search->fit), rules, c)) continue;
    d.dropped.push_back(fmt::format("{} (accepted in round {}, it adds nothing once the empirical term is in: {})",
                                    accepted[i], i + 1, c.reason));
    d.steps.push_back(detail::make_step("drop cause", accepted[i], model_fit(log, current), model_fit(log, named)));
    accepted = std::move(others);
    current = std::move(named);
    d.final = diagnose_residuals(log, current, o);
    search = std::move(without);
  }
}

// 5. Verdict. The steps carry each model's held-out RMSE: the causes, then the term.
void conclude_friction(const FrictionLog& log, const FrictionDiagnosisOptions& o, const FrictionFitResult& baseline,
                       const CurrentModel& model, FrictionDiagnosis& d) {
  const std::size_t n = log.size();
  const FrictionFitResult& current = model.fit;
  if (d.empirical.found)
    d.steps.push_back(detail::make_step("add empirical term", d.empirical.formula, model_fit(log, current),
                                        model_fit(log, d.empirical_fit)));
  d.cv_rmse_before_N = baseline.cv_rmse_N;
  d.cv_rmse_after_N = detail::final_cv_rmse(d.steps, d.cv_rmse_before_N);
  d.accepted = detail::accepted_scores(d.rounds, model.accepted,
                                       [&](const std::string& name) { return &current.fit.parameter(name); });
  for (auto& round : d.rounds)
    for (CandidateScore& c : round) read_precondition(c, log);
  for (CandidateScore& c : d.accepted) read_precondition(c, log);
  for (std::size_t j = 0; j < FrictionConstants<double>::kFittable; ++j)
    d.shifts.push_back(parameter_shift(baseline.fit.parameters[j], current.fit.parameters[j]));

  detail::conclude(d, "The published law", "N", d.cv_rmse_before_N, current.cv_rmse_N, d.baseline.rmse_N);
  for (const auto& why : d.dropped) d.summary += " Dropped: " + why + ".";
  {
    const FrictionFitResult& last = d.empirical.found ? d.empirical_fit : current;
    std::vector<double> residual_N(n), model_N(n);
    for (std::size_t i = 0; i < n; ++i) {
      model_N[i] = last.predicted_N[i] - last.run_offset_N[log.run[i]];
      residual_N[i] = log.friction_N[i] - model_N[i];
    }
    d.run_scale = detail::test_run_scale(log, residual_N, model_N, o.lrt_p);
    if (d.run_scale.differ)
      d.summary += fmt::format(" The runs' friction also differs by a factor from run to run beyond their zeros: about "
                               "{:.2g} % ({}); nothing logged predicts it, so a new run's level is uncertain by that share.",
                               d.run_scale.tau_percent, d.run_scale.reason);
  }
}

}  // namespace

FrictionDiagnosis diagnose_friction(const FrictionLog& log, const FrictionDiagnosisOptions& o) {
  if (log.run_names.size() < kMinDiagnosisRuns)
    throw InvalidParameter("runs", fmt::format("a diagnosis needs at least {} runs (it holds one out at a time)",
                                               kMinDiagnosisRuns));
  FrictionDiagnosis d;

  // 1. The baseline and its residuals.
  const FitLog fits(log, o);
  const FrictionFitResult baseline = baseline_fit(fits.log(), fits.options());
  d.baseline = diagnose_residuals(log, baseline, o);

  // 2-3. Candidates, forward.
  CandidateFits candidates(log, fits, o);
  auto fit_candidate = [&](const std::vector<std::string>& causes, const FrictionFitResult& current) {
    return candidates.fit(causes, current);
  };
  auto summarise = [&](const FrictionFitResult& fit, const std::string& effect) { return summarise_fit(log, fit, effect); };
  const detail::SelectionRules rules{.lrt_p = o.lrt_p,
                                     .min_cv_gain_percent = o.min_cv_gain_percent,
                                     .min_effect = d.baseline.resolution_floor_N,
                                     .effect_floor_basis = kResolutionFloorWords,
                                     .max_effects = o.max_effects,
                                     .parallel = true,
                                     .progress = o.progress,
                                     .expected_cost = expected_fit_cost};
  std::vector<std::string> not_tried;
  auto selection =
      detail::forward_select(causes_that_can_show(log, not_tried), baseline, fit_candidate, summarise, rules);
  CurrentModel model{selection.accepted, selection.current};
  d.rounds = std::move(selection.rounds);
  d.steps = std::move(selection.steps);

  // 4. Beyond the library, and the causes the term makes redundant.
  std::optional<detail::FrictionTermSearch> search = search_term(log, o, candidates, rules, model, d);
  drop_stand_ins(log, o, candidates, rules, selection, model, search, d);
  if (search) {
    d.empirical = std::move(search->finding);
    if (search->fit) d.empirical_fit = std::move(*search->fit);
  }

  // 5. Verdict, and what the design hides.
  conclude_friction(log, o, baseline, model, d);
  d.design_notes = design_notes(log, baseline, d.baseline.lack_of_fit, d.final, o);
  if (!not_tried.empty())
    d.design_notes.push_back(fmt::format("not tried, their precondition absent: {}", fmt::join(not_tried, "; ")));
  if (!candidates.held_zeros().empty())
    d.design_notes.push_back(fmt::format(
        "{} fitted with the spread of the runs' zeros held at the model's before it: fitted freely, the zeros spread "
        "far wider and the law's level moved against them (a zero common to the runs, outside an effect on the total "
        "force, acts as a signed force), which held-out runs cannot follow",
        fmt::join(candidates.held_zeros(), ", ")));
  d.final_fit = model.fit;
  d.baseline_fit = baseline;
  return d;
}

std::string friction_diagnosis_json(const FrictionDiagnosis& d) {
  using detail::number;
  auto diagnostics = [&](const ResidualDiagnostics& r) {
    nlohmann::json runs = nlohmann::json::object();
    for (const auto& [run, bias] : r.run_bias_N) runs[run] = number(bias);
    return nlohmann::json{{"rmse_N", number(r.rmse_N)},         {"sigma", number(r.sigma)},
                          {"durbin_watson", number(r.durbin_watson)}, {"resolution_floor_N", number(r.resolution_floor_N)}, {"run_bias_N", runs},
                          {"covariates", detail::covariates_json(r.covariates)}, {"structured", r.structured},
                          {"lack_of_fit", detail::lack_of_fit_json(r.lack_of_fit)}};
  };
  nlohmann::json j = detail::verdict_json(d, d.cv_rmse_before_N, d.cv_rmse_after_N, "N");
  j["kind"] = "friction diagnosis";
  j["design_notes"] = d.design_notes;
  j["lmcal_version"] = LMCAL_VERSION;
  j["schema_version"] = kOutputSchemaVersion;
  j["baseline_residuals"] = diagnostics(d.baseline);
  j["final_residuals"] = diagnostics(d.final);
  j["dropped_for_the_empirical_term"] = d.dropped;
  {
    const RunScaleTest& t = d.run_scale;
    nlohmann::json runs = nlohmann::json::array();
    for (std::size_t r = 0; r < t.run.size(); ++r)
      runs.push_back({{"run", t.run[r]}, {"factor_percent", number(t.factor_percent[r])}, {"se_percent", number(t.se_percent[r])}});
    j["run_scale"] = {{"tested", t.tested}, {"differ", t.differ},     {"q", number(t.q)},
                      {"dof", number(t.dof)}, {"p", number(t.p)},     {"tau_percent", number(t.tau_percent)}, {"floor_percent", number(t.floor_percent)},
                      {"runs", runs},         {"reason", t.reason},
                      {"method", "within each run, the final model's residual (its zero left in) on its force with an "
                                 "intercept; Cochran's Q over the runs' factors, SEs widened for lag-1 autocorrelation; "
                                 "tau by DerSimonian-Laird; the runs differ when p < the LRT level and tau exceeds the "
                                 "runs' zeros' spread as a share of the mean force"}};
  }
  return j.dump(2) +
         "\n";
}

}  // namespace lmcal
