#include "findings.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "lmcal/models/friction_effects.hpp"
#include "sections.hpp"

namespace lmcal::report {

namespace {

// "a", "a and b", "a, b and c".
std::string words_list(const std::vector<std::string>& items) {
  if (items.empty()) return "";
  if (items.size() == 1) return items.front();
  std::string s;
  for (std::size_t k = 0; k + 1 < items.size(); ++k) s += fmt::format("{}{}", k ? ", " : "", items[k]);
  return fmt::format("{} and {}", s, items.back());
}

std::string unit_suffix(const ParameterEstimate& p) { return p.unit.empty() || p.unit == "1" ? "" : fmt::format(" {}", p.unit); }

// "seal_drag 150 N s2/m2 [149.3, 150.7]".
std::string value_with_interval(const ParameterEstimate& p) {
  const std::string band = interval(p);
  return fmt::format("{} {}{} {}", p.name, num(p.value), unit_suffix(p), band == "–" ? "(no interval: not determined)" : band);
}

bool belongs_to(const std::string& parameter, const std::vector<std::string>& causes) {
  return std::any_of(causes.begin(), causes.end(),
                     [&](const std::string& c) { return parameter == c || parameter.starts_with(c + "_"); });
}

// A drive's own dynamics fitted with a trajectory log (moving_mass, axis_gravity): not friction.
bool drive_dynamics(const std::string& parameter) {
  const auto slot = find_friction_effect(parameter);
  return slot && FrictionEffectLibrary::infos[*slot].dynamics;
}

// The calibrated values with their intervals: the causes' first, then the model's own (`own`,
// "the law's constants"), then a drive's dynamics; per-run nuisance and held parameters left out.
std::string values_sentence(const FitResult& fit, const std::vector<std::string>& causes, std::string_view own) {
  std::vector<std::string> added, rest, drive;
  for (const auto& p : fit.parameters) {
    if (nuisance(p) || !p.free || p.held_unidentifiable) continue;
    (belongs_to(p.name, causes) ? added : drive_dynamics(p.name) ? drive : rest).push_back(value_with_interval(p));
  }
  std::vector<std::string> groups;
  if (!added.empty()) groups.push_back(fmt::format("{}", fmt::join(added, ", ")));
  if (!rest.empty()) groups.push_back(fmt::format("{}: {}", own, fmt::join(rest, ", ")));
  if (!drive.empty()) groups.push_back(fmt::format("the drive's dynamics: {}", fmt::join(drive, ", ")));
  return fmt::format("Calibrated values, with their 95 % intervals: {}.", fmt::join(groups, "; "));
}

// "seal_drag (quadratic seal drag c V²)".
std::vector<std::string> friction_causes_in_words(const std::vector<std::string>& causes) {
  std::vector<std::string> out;
  for (const auto& name : causes)
    if (const auto slot = find_friction_effect(name))
      out.push_back(fmt::format("{} ({})", name, FrictionEffectLibrary::infos[*slot].description));
    else
      out.push_back(name);
  return out;
}

std::vector<std::string> thermal_causes_in_words(const std::vector<std::string>& causes) {
  const std::vector<ThermalExtensionInfo> library = thermal_extension_library();
  std::vector<std::string> out;
  for (const auto& name : causes) {
    const auto it = std::find_if(library.begin(), library.end(), [&](const auto& e) { return e.name == name; });
    out.push_back(it == library.end() ? name : fmt::format("{} ({})", name, it->description));
  }
  return out;
}

// What one model's diagnosis and calibration found, in a few sentences.
struct ModelStory {
  std::string label;        // "Friction"
  std::string published;    // "the published law (Eqs. 3-7)"
  std::string short_name;   // "the published law", for its second mention
  std::string unit;         // of the residuals
  int decimals = 4;         // significant digits of the RMSEs
  bool diagnosed = false;
  std::string verdict;      // the diagnosis's
  std::vector<std::string> causes_in_words;
  bool empirical = false;   // an empirical term is part of the calibrated model
  std::string unexplained_covariate;
  double cv_published = NAN, cv_calibrated = NAN;
  const LackOfFit* noise = nullptr;  // the calibrated model's diagnosis's lack of fit
  std::string values;                // values_sentence
};

std::string noise_words(const LackOfFit* lof, const std::string& unit) {
  if (!lof || !lof->tested || !(lof->pure_error_rms > 0)) return "";
  return fmt::format("; {} {} {}", lof->against == "pure error" ? "the scatter between repeats of a condition" : "the sensors' noise",
                     num(lof->pure_error_rms, 3), unit);
}

std::string story_sentences(const ModelStory& s) {
  std::string text = fmt::format("{}: ", s.label);
  const std::string held_out = fmt::format("{} {}", num(s.cv_calibrated, s.decimals), s.unit);
  const bool unexplained = s.verdict.starts_with("unexplained") || s.verdict.starts_with("partly");
  if (!s.diagnosed) {
    text += fmt::format("{} was fitted without a diagnosis (nothing was tested against it)", s.published);
  } else if (!s.causes_in_words.empty()) {
    text += fmt::format("{} misses {}", s.published, words_list(s.causes_in_words));
  } else if (!unexplained) {
    text += fmt::format("{} fits: no cause of the library predicts a held-out run better, and nothing is left beyond the noise",
                        s.published);
  } else {
    text += fmt::format("{} misses something no cause of the library explains", s.published);
  }
  if (s.diagnosed && unexplained && !s.causes_in_words.empty()) text += "; something else remains that no named cause explains";
  if (unexplained && !s.unexplained_covariate.empty()) text += fmt::format(" (it follows {})", s.unexplained_covariate);
  if (s.empirical) text += "; an empirical term (not a named cause) stands in for it";
  text += ". ";
  if (std::isfinite(s.cv_calibrated)) {
    text += fmt::format("The calibrated model predicts a run it was not fitted to within {} (held-out RMSE", held_out);
    if (!s.causes_in_words.empty() || s.empirical)
      text += fmt::format("; {} alone: {} {}", s.short_name, num(s.cv_published, s.decimals), s.unit);
    text += noise_words(s.noise, s.unit) + "). ";
  }
  return text + s.values;
}

// The covariance method without its added input ("cluster + heat" -> "cluster").
std::string base_method(const std::string& method) { return method.substr(0, method.find(" + ")); }

// Where one fit's intervals come from, in words. `runs_are`: what each run brings (friction:
// its own zero offset), "" for nothing to say; `heat`: the heat's share of α's variance, in words.
std::string how_sure_sentence(const std::string& label, const FitResult& fit, const std::string& runs_are,
                              const std::string& heat) {
  const Uncertainty& u = fit.uncertainty;
  const std::string method = base_method(u.method);
  std::string text = fmt::format("{}: ", label);
  if (!runs_are.empty()) text += fmt::format("{}; ", runs_are);
  if (method == "none") return fmt::format("{}no intervals: {}.", text, u.reason);
  if (method == "cluster") {
    text += fmt::format("the {} runs are treated as repeats: their spread sets the intervals (t with {} degrees of freedom), "
                        "never narrower than the scatter within each run allows",
                        u.runs, num(u.dof, 3));
  } else if (method == "bootstrap") {
    text += fmt::format("the intervals come from refitting the model to the {} runs resampled as wholes", u.runs);
  } else if (method == "hac") {
    text += fmt::format("the intervals come from the scatter within the runs, allowing for its correlation from one sample to "
                        "the next (the {} residuals count as {:.0f} independent ones)",
                        fit.residuals, u.effective_sample_size);
  } else {
    text += "the residuals are taken as independent, each with the same scatter";
  }
  if (method != "cluster" && method != "bootstrap") {
    std::vector<std::string> differ;
    for (const auto& h : u.heterogeneity)
      if (h.significant) differ.push_back(h.parameter);
    if (!differ.empty())
      text += fmt::format("; but the runs disagree beyond that scatter on {}, so the intervals are too narrow for a new run",
                          words_list(differ));
    else if (!u.heterogeneity.empty())
      text += fmt::format("; the {} runs do not disagree beyond that scatter", u.runs);
  }
  if (!u.from_replicates.empty())
    text += fmt::format("; for {} the spread of the runs' own estimates sets the interval (wider than the joint fit's)",
                        words_list(u.from_replicates));
  if (!heat.empty()) text += fmt::format("; {}", heat);
  return text + ".";
}

// "the heat's uncertainty, carried from the friction fit, is 0.075 % of α's variance".
std::string heat_share_words(const ThermalFitResult& t) {
  const Uncertainty& u = t.joint.uncertainty;
  for (std::size_t j = 0; j < t.joint.parameters.size() && j < u.input_variance_share.size(); ++j)
    if (t.joint.parameters[j].name == "alpha" && std::isfinite(u.input_variance_share[j]))
      return fmt::format("the heat's uncertainty, carried from the friction fit, is {} % of α's variance",
                         num(100 * u.input_variance_share[j], 2));
  return "";
}

// The parameters whose runs disagree (Holm-significant Cochran's Q).
std::vector<std::string> disagreeing(const FitResult& fit) {
  std::vector<std::string> out;
  for (const auto& h : fit.uncertainty.heterogeneity)
    if (h.significant) out.push_back(h.parameter);
  return out;
}

// "the published model's runs disagree on α …; the calibrated model's do not …", when one
// fit's runs disagree and the other's do not.
void runs_contradiction(std::vector<std::string>& out, const std::string& model, const std::vector<std::string>& published,
                        const std::vector<std::string>& calibrated, const std::string& published_test,
                        const std::string& calibrated_test) {
  if (!published.empty() && calibrated.empty())
    out.push_back(fmt::format("The published {0}'s runs disagree on {1} beyond their own errors{2}; the calibrated {0}'s runs do "
                              "not{3}: the causes it adds explain what differed between the runs. The warnings about the "
                              "runs further down are about the published {0}.",
                              model, words_list(published), published_test, calibrated_test));
  else if (published.empty() && !calibrated.empty())
    out.push_back(fmt::format("The calibrated {0}'s runs disagree on {1} beyond their own errors{3}, though the published {0}'s "
                              "do not{2}: the causes it adds fit some runs better than others. Read its values as averages "
                              "over runs that differ.",
                              model, words_list(calibrated), published_test, calibrated_test));
}

std::string q_words(const RandomEffects& r) {
  return fmt::format(" (Cochran's Q = {} on {} runs, {})", num(r.q, 3), r.k, p_is(r.q_p));
}

bool alpha_runs_differ(const ThermalFitResult& t) { return t.alpha_runs.k >= 3 && t.alpha_runs.q_p < 0.05; }

// What a diagnosis says, into the story: its verdict and causes, the published model's held-out
// error (`cv_before`) and the noise the final model is judged against.
template <class Diagnosis>
void tell_diagnosis(ModelStory& s, const Diagnosis& d, std::vector<std::string> causes_in_words, double cv_before) {
  s.diagnosed = true;
  s.verdict = d.verdict;
  s.causes_in_words = std::move(causes_in_words);
  s.unexplained_covariate = d.unexplained_covariate;
  s.cv_published = cv_before;
  s.noise = &d.final.lack_of_fit;
}

// The interval method's statement and its notes, for the details.
void add_method_details(Findings& f, const std::string& label, const Uncertainty& u) {
  f.method_details.push_back({label, {intervals_statement(u)}});
  for (const auto& note : u.notes) f.method_details.back().second.push_back(note);
}

}  // namespace

Findings findings(const Calibration& c) {
  Findings f;
  const CalibratedModel& m = c.calibrated;
  if (const FrictionFitResult* fit = m.friction ? &*m.friction : c.friction ? &*c.friction : nullptr) {
    const auto& d = c.friction_diagnosis;
    ModelStory s{.label = "Friction", .published = "the published law (Eqs. 3-7)", .short_name = "the published law", .unit = "N",
                 .decimals = 3};
    if (d) tell_diagnosis(s, *d, friction_causes_in_words(m.friction_causes), d->cv_rmse_before_N);
    s.empirical = !fit->terms.empty();
    s.cv_calibrated = fit->cv_rmse_N;
    s.values = values_sentence(friction_fit_as_shown(*fit), m.friction_causes, "the law's constants");
    f.found.push_back(story_sentences(s));
    const std::string runs_are =
        fit->run_offsets == RunOffsets::random
            ? fmt::format("each of the {} runs has its own zero offset (a random run intercept, spread {} N)", fit->runs.size(),
                          num(fit->run_offset_sd_N, 3))
            : "";
    f.how_sure.push_back(how_sure_sentence("Friction", fit->fit, runs_are, ""));
    add_method_details(f, "Friction", fit->fit.uncertainty);
    if (m.friction && c.friction)
      runs_contradiction(f.contradictions, "law", disagreeing(c.friction->fit), disagreeing(m.friction->fit),
                         " (Cochran's Q, Holm-adjusted)", "");
  }
  if (const ThermalFitResult* fit = m.thermal ? &*m.thermal : c.thermal ? &*c.thermal : nullptr) {
    const auto& d = c.thermal_diagnosis;
    const ThermalFitOptions& options = m.thermal ? m.thermal_options : c.thermal_options;
    ModelStory s{.label = "Rail temperature",
                 .published = fmt::format("the published rail model (Eq. 11, {} source)", to_string(options.source)),
                 .short_name = "the published rail model",
                 .unit = "K", .decimals = 3};
    if (d) {
      tell_diagnosis(s, *d, thermal_causes_in_words(m.thermal_causes), d->cv_rmse_before_K);
      s.empirical = m.thermal.has_value() && d->empirical.found;
    }
    s.cv_calibrated = fit->cv_rmse_K;
    s.values = values_sentence(fit->joint, m.thermal_causes, "the rail model's own");
    f.found.push_back(story_sentences(s));
    f.how_sure.push_back(how_sure_sentence("Rail temperature", fit->joint, "", heat_share_words(*fit)));
    add_method_details(f, "Rail temperature", fit->joint.uncertainty);
    if (!fit->heat_uncertainty.empty()) f.method_details.back().second.push_back("Heat: " + fit->heat_uncertainty);
    if (m.thermal && c.thermal) {
      const std::vector<std::string> alpha{"α"}, none;
      runs_contradiction(f.contradictions, "rail model", alpha_runs_differ(*c.thermal) ? alpha : none,
                         alpha_runs_differ(*m.thermal) ? alpha : none, q_words(c.thermal->alpha_runs),
                         q_words(m.thermal->alpha_runs));
    }
  }
  return f;
}

const std::vector<std::pair<std::string, std::string>>& glossary() {
  static const std::vector<std::pair<std::string, std::string>> terms{
      {"held-out RMSE (leave-one-run-out)",
       "each run predicted by the model fitted to the other runs alone; the root-mean-square of those errors. What to expect "
       "of a new run on the same rig."},
      {"iid", "independent residuals with one scatter: the covariance s²(JᵀJ)⁻¹. Too narrow when neighbouring residuals are "
              "correlated or the runs differ."},
      {"hac (Newey-West)", "a sandwich covariance that counts the residuals' correlation within each run up to a number of lags "
                           "(the bandwidth); the runs are taken as independent of each other."},
      {"cluster (cluster-robust by run)",
       "a sandwich covariance with each run's summed score as one independent draw: whatever differs between runs, and not "
       "within them, is counted. Its t quantile has runs − 1 degrees of freedom."},
      {"bootstrap (cluster bootstrap)", "whole runs resampled with replacement and the fit repeated; the interval is the spread "
                                        "of the refits."},
      {"+ heat (delta method)",
       "the heat rate the rail model takes comes from the friction fit; that fit's covariance, carried through the friction "
       "law's derivatives (the delta method), is added to the rail model's."},
      {"runs as replicates",
       "SE = √(Σ c_r² (SE_r² + τ²)) plus any uncertainty common to all runs: c_r is each run's share of the joint fit's "
       "information, SE_r the run's own standard error, τ the spread between runs (below). Used where it is wider than the "
       "joint fit's."},
      {"τ (tau, REML)", "how much the runs' own values differ beyond their standard errors, by restricted maximum likelihood; "
                        "0 when they agree within their errors."},
      {"Cochran's Q", "Σ (x_r − x̄)²/SE_r² over the runs' own estimates, against χ² with runs − 1 degrees of freedom: a small "
                      "p says the runs disagree beyond their own errors. I² is the share of their spread that is real."},
      {"Holm", "p-values adjusted for testing several parameters at once."},
      {"profile interval", "the parameter held at each value and the others refitted; the interval is where the cost rises by "
                           "the 95 % F threshold. Quoted where a straight-line (linear) interval would be wrong."},
      {"t degrees of freedom", "how many independent pieces of information the interval's width rests on; few (a few runs) "
                               "widen the t quantile. Combined variances use Welch-Satterthwaite."},
      {"lack of fit", "the residuals' variance against what repeats of a condition (friction) or the sensors' own noise "
                      "(thermal) scatter by: an F test that says whether structure is left."},
  };
  return terms;
}

}  // namespace lmcal::report
