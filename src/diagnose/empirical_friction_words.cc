// A term of the empirical friction search in words: what it does, what it resembles, and
// the covariate the report draws it over.
#include <fmt/format.h>

#include <algorithm>
#include <optional>

#include "empirical_friction_parts.hpp"

namespace lmcal::detail {

namespace {

// A law part's name in words ("" for the law's force and for covariates).
const char* part_words(TermCovariate c) {
  switch (c) {
    case TermCovariate::coulomb_N: return "Coulomb term";
    case TermCovariate::stribeck_N: return "Stribeck term";
    case TermCovariate::viscous_N: return "viscous term";
    case TermCovariate::seal_N: return "seal offset Lb·f0";
    default: return "";
  }
}

}  // namespace

// What a term does, in words.
std::string term_words(const FrictionTerm& t) {
  if (t.lagged_temperature())
    return "the law evaluated at a temperature that trails the logged one through a first-order lag of time constant tau";
  std::string words, share;
  for (const auto& f : t.factors) {
    if (f.covariate == TermCovariate::law_force_N) {
      share = "a share of the law's force, ";
      continue;
    }
    if (is_law_covariate(f.covariate)) {
      share = fmt::format("a share of the law's {}, ", part_words(f.covariate));
      continue;
    }
    if (f.transform == TermTransform::input_shift) continue;
    const std::string x = term_covariate_name(f.covariate);
    words += words.empty() ? "" : " and ";
    switch (f.transform) {
      case TermTransform::linear: words += f.centre == 0 ? "in proportion to " + x : fmt::format("in proportion to {} - {:g}", x, f.centre); break;
      case TermTransform::square: words += f.centre == 0 ? "with the square of " + x : fmt::format("with the square of {} - {:g}", x, f.centre); break;
      case TermTransform::decay: words += "decaying exponentially with " + x; break;
      case TermTransform::spline: words += "a smooth function (cubic B-spline) of " + x; break;
      case TermTransform::step: words += fmt::format("where {} > {:g}", x, f.centre); break;
      case TermTransform::lagged_temperature:
      case TermTransform::input_shift: break;
    }
  }
  if (const auto input = t.shifted_input())
    return fmt::format("the law evaluated at the logged {} plus a correction ({}) {}",
                       *input == TermCovariate::velocity_m_s ? "speed" : "temperature", term_covariate_unit(*input),
                       words.empty() ? "that is constant" : words);
  return (share.empty() ? "a force " : share) + words;
}

bool has_spline(const FrictionTerm& t) {
  return std::any_of(t.factors.begin(), t.factors.end(), [](const TermFactor& f) { return f.transform == TermTransform::spline; });
}

namespace {

bool has(const FrictionTerm& t, TermCovariate c, TermTransform how) {
  return std::any_of(t.factors.begin(), t.factors.end(), [&](const TermFactor& f) { return f.covariate == c && f.transform == how; });
}

// The law part a term reweights, if it does.
std::optional<TermCovariate> reweighted_part(const FrictionTerm& t) {
  for (const auto& f : t.factors)
    if (is_law_covariate(f.covariate) && f.covariate != TermCovariate::law_force_N) return f.covariate;
  return std::nullopt;
}

// What an input correction resembles: the law sees a temperature off the logged one.
std::string input_resemblance(const FrictionTerm& t, const std::string& chronology) {
  using C = TermCovariate;
  using X = TermTransform;
  if (t.shifted_input() == C::velocity_m_s) return "the law seeing a speed off the logged one (an encoder's or a drive's scale)";
  if (has_spline(t))
    return fmt::format("the law seeing a temperature off the logged one by an amount that changes smoothly with {} "
                       "(the contacts' temperature is not the logged one)",
                       term_covariate_name(t.factors.back().covariate));
  for (const auto& f : t.factors)
    if (f.transform == X::step)
      return fmt::format("the law seeing a temperature {:+.3g} K off the logged one where T > {:g} C (a thermocouple that "
                         "reads off when hot, or oil whose viscosity falls otherwise than nu(T) above it)",
                         t.coefficient, f.centre);
  if (has(t, C::campaign_time_s, X::linear))
    return fmt::format("the law seeing a temperature drifting by {:+.3g} K per hour over the campaign that the logged one "
                       "does not show (a thermocouple drifting, the room or the oil changing over the day; the runs in "
                       "order of {})",
                       t.coefficient * 3600, chronology == "time_s" ? "their clocks" : "the file");
  if (has(t, C::run_index, X::linear))
    return fmt::format("the law seeing a temperature drifting by {:+.3g} K per run over the campaign that the logged one "
                       "does not show (runs in order of {})",
                       t.coefficient, chronology == "time_s" ? "their clocks" : "the file");
  if (has(t, C::time_in_run_s, X::decay))
    return fmt::format("the law seeing a temperature {:+.3g} K off the logged one at each run's start, settling over about "
                       "{:.3g} s (a warm-up the logged temperature does not show)",
                       t.coefficient, t.scale);
  return fmt::format("the law seeing a temperature {:+.3g} K off the logged one", t.coefficient);
}

}  // namespace

// The mechanisms a term resembles, in words ("" when none comes to mind); `chronology` says
// how the runs were put in order (TermSeries::chronology).
std::string resemblance(const FrictionTerm& t, const std::string& chronology) {
  using C = TermCovariate;
  using X = TermTransform;
  if (t.shifted_input()) return input_resemblance(t, chronology);
  if (const auto part = reweighted_part(t)) {
    const TermFactor& by = t.factors.back();
    return fmt::format("the law's {} following {} otherwise than the law has it{}", part_words(*part),
                       term_covariate_name(by.covariate),
                       *part == C::viscous_N && by.covariate == C::load_N ? " (its viscous term mu_v pc V nu Lb has no load in it)"
                       : *part == C::coulomb_N && by.covariate == C::velocity_m_s ? " (a Coulomb level that changes with speed)"
                       : by.covariate == C::run_index ? " (changing from run to run over the campaign)"
                                                     : "");
  }
  if (has_spline(t))
    return fmt::format("a dependence on {} of a shape none of the law's terms or the dictionary's simple forms has",
                       term_covariate_name(t.factors.front().covariate));
  if (t.lagged_temperature())
    return fmt::format("the lubricant's temperature trailing the logged one by tau = {:.3g} s (a thermocouple away "
                       "from the contacts, or oil that warms slower than what is logged)",
                       t.scale);
  if (has(t, C::run_index, X::decay) || has(t, C::run_index, X::linear))
    return fmt::format("friction changing from run to run over the campaign{} (running-in, seals bedding in, the lubricant "
                       "ageing; the runs in order of {})",
                       has(t, C::run_index, X::decay) ? fmt::format(", over about {:.3g} runs", t.scale) : "",
                       chronology == "time_s" ? "their clocks" : "the file");
  if (has(t, C::sliding_distance_m, X::decay))
    return fmt::format("running-in: friction falling as the contacts and seals wear in, over about {:.3g} m of sliding",
                       t.scale);
  if (has(t, C::time_in_run_s, X::decay))
    return fmt::format("a settling within each run over about {:.3g} s (lubricant redistributing after a stop, a "
                       "warm-up the logged temperature does not show)",
                       t.scale);
  if (has(t, C::velocity_m_s, X::linear) && has(t, C::temperature_C, X::linear))
    return "a speed-proportional (viscous) force whose temperature dependence differs from the law's "
           "nu(T) = nu_i exp(-beta (T - T_i))";
  if (has(t, C::velocity_m_s, X::square)) return "a speed dependence beyond the linear viscous term (churning of the lubricant)";
  if (has(t, C::load_N, X::square)) return "a Coulomb force not proportional to the load";
  if (t.factors.size() == 1 && has(t, C::temperature_C, X::linear))
    return "a Coulomb or seal force that changes with temperature";
  if (has(t, C::direction, X::linear)) return "a force that depends on the direction of travel";
  return "";
}

// The covariate a term is drawn over in the report.
TermCovariate main_covariate(const FrictionTerm& t) {
  if (t.lagged_temperature()) return TermCovariate::time_in_run_s;
  for (const auto& f : t.factors)
    if (f.transform == TermTransform::decay) return f.covariate;
  for (const auto& f : t.factors)
    if (!is_law_covariate(f.covariate) && f.transform != TermTransform::input_shift) return f.covariate;
  for (const auto& f : t.factors)
    if (f.transform == TermTransform::input_shift) return f.covariate;
  return TermCovariate::law_force_N;
}

}  // namespace lmcal::detail
