// Empirical terms of the friction force: what `lmcal diagnose friction` learns when the law
// and every named effect (friction_effects.hpp) leave structure in the residuals. Not a
// mechanism: a term says what the friction follows, not why (the diagnosis says what it
// resembles). Each term adds, in N,
//
//   c · f(x)   or   c · f(x) · g(x)
//
// with f, g transforms of one covariate of the sample:
//   linear   x − x0                 (x0: 40 °C for the temperature, the law's T_i; else 0 or
//                                   the middle of the data's range, as the term states)
//   square   (x − x0)²
//   decay    exp(−x / ℓ)            x the sliding distance since the log's start (m), the
//                                   time since the run's start (s) or the run index; ℓ fitted
//   step     1 where x > x0, else 0 (x0: a threshold between the data's levels, not fitted)
//   spline   B_k(x)                 a cubic B-spline basis function: a smooth term is several,
//                                   one coefficient each (where no sparse form fits)
// The law's own force F_law (with its named effects) is a covariate, for terms in proportion to
// the friction (c · exp(−s/ℓ) · F_law: running-in); so is each of its parts at the fit's
// constants (the published law's Coulomb, Stribeck and viscous terms and the seal offset Lb·f0,
// without the effects), for a term that reweights one of them (c · F_viscous · (P − P0)²: the
// viscous term's load dependence the law lacks).
//
// Campaign covariates: the run index k (0, 1, … in chronological order) and the time since the
// campaign's start; chronological order from time_s where the runs' clocks do not overlap
// (then time_s is a campaign clock), else the order the runs are written in, each run's clock
// restarting (then the campaign time adds the runs' durations). TermSeries::chronology says which.
//
// Two forms are not sums but corrections of the law's input (the law evaluated where the
// contact is, not where the logger says):
//   lagged_temperature:  F_law(T + c (lag_τ(T) − T)) − F_law(T)
// with lag_τ the first-order lag of the logged temperature over each run's time (starting at
// the run's first reading), τ fitted; c = 1 means the friction follows a temperature that
// trails the logged one by τ (the lubricant behind a thermocouple);
//   input_shift of T or V:  F_law(T + c·g(x)) − F_law(T)   (g the term's other factor, or 1)
// "the law sees a temperature c·g(x) K off the logged one": a step in T (the oil above some
// temperature is not what the law assumes), a drift over the campaign, a warm-up within runs.
// Every input correction of a sample adds to the one shifted input, and the law (with its
// effects) and its parts are evaluated there.
//
// Sliding distance: s_i = Σ_{j<i} V_j Δt_j over the log in row order (runs in the order
// written, samples in time order), Δt from time_s (the median step across a run boundary).
// Terms in time or distance need a time_s column.
//
// Trap: a term's coefficient is in N per unit of its factors (N/K for a linear temperature
// term, N/(K·m/s) for temperature × speed); a term in F_law or one of its parts is relative
// (1 = 100 %); an input shift's is in the input's unit (K, m/s) per unit of its other factor.
#pragma once

#include "lmcal/export.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <string_view>
#include <string>
#include <vector>

#include "lmcal/io/friction_log.hpp"
#include "lmcal/models/friction_effects.hpp"

namespace LMCAL_API lmcal {

enum class TermCovariate {
  velocity_m_s,
  load_N,
  preload_um,
  block_length_mm,
  temperature_C,
  direction,
  time_in_run_s,
  sliding_distance_m,
  law_force_N,
  // Campaign covariates (chronological: TermSeries::chronology).
  run_index,
  campaign_time_s,
  // The published law's parts at the fit's constants (at the sample's corrected input).
  coulomb_N,
  stribeck_N,
  viscous_N,
  seal_N,
};
enum class TermTransform { linear, square, decay, lagged_temperature, spline, step, input_shift };

// The law's force or one of its parts: a covariate the fit's constants move, not a column.
constexpr bool is_law_covariate(TermCovariate c) {
  return c == TermCovariate::law_force_N || c == TermCovariate::coulomb_N || c == TermCovariate::stribeck_N ||
         c == TermCovariate::viscous_N || c == TermCovariate::seal_N;
}
// What changes only from run to run or over the campaign, with no value at a steady condition.
constexpr bool is_campaign_covariate(TermCovariate c) {
  return c == TermCovariate::run_index || c == TermCovariate::campaign_time_s;
}

struct TermFactor {
  TermCovariate covariate = TermCovariate::velocity_m_s;
  TermTransform transform = TermTransform::linear;
  double centre = 0;  // x0 of linear, square and step
  // spline: the cubic B-spline `basis` over the knot vector `knots` (boundary knots repeated
  // four times); beyond the end knots it stays at its end value.
  int basis = 0;
  std::vector<double> knots;
};

// The cubic B-spline basis function k over `knots` at x (Cox-de Boor), x clamped to the knots' span.
double bspline(const std::vector<double>& knots, int k, double x);

struct TermRange {
  TermCovariate covariate;
  double min = 0, max = 0;
};

struct FrictionTerm {
  // One or two; at most one decay; a lagged temperature alone; an input shift first, with at
  // most one factor of covariates (not the law) after it.
  std::vector<TermFactor> factors;
  double coefficient = 0;           // c (a fit's start value)
  double scale = 0;                 // ℓ or τ of a decay or lag (a fit's start value)
  double scale_lower = 0, scale_upper = 0;  // bounds of a fit
  // The covariates' ranges in the data it was learned from: beyond them it is an extrapolation.
  std::vector<TermRange> seen;

  bool has_scale() const;
  bool lagged_temperature() const;
  // The input an input_shift term corrects (temperature_C or velocity_m_s), or none.
  std::optional<TermCovariate> shifted_input() const;
  // A term that corrects the law's input (a lagged temperature or an input shift).
  bool corrects_input() const { return lagged_temperature() || shifted_input().has_value(); }
  // A term that uses the law's force or one of its parts.
  bool uses_law() const;
  // "c1·exp(-s/l1)·F_law" for term number `k` (1-based); "" names are the parameters.
  std::string symbol(std::size_t k) const;
  std::string coefficient_unit() const;
  std::string scale_unit() const;
  // The covariates it uses, by name ("sliding_distance_m", "friction_law_N").
  std::vector<std::string> covariates() const;
};

// Parameters the terms add to a fit: c per term, and ℓ or τ where it has one.
inline std::size_t term_parameter_count(const std::vector<FrictionTerm>& terms) {
  std::size_t n = 0;
  for (const auto& t : terms) n += t.has_scale() ? 2 : 1;
  return n;
}

const char* term_covariate_name(TermCovariate c);
const char* term_covariate_unit(TermCovariate c);
std::optional<TermCovariate> find_term_covariate(std::string_view name);

// What is wrong with a term's form ("" when nothing): one or two factors, at most one with a
// scale, a lagged temperature alone, an input shift (of temperature_C or velocity_m_s) first
// and never with the law, the law and its parts as plain factors (linear, centre 0).
std::string term_form_problem(const FrictionTerm& term);

// A factor as text and back: "linear:temperature_C:40", "decay:sliding_distance_m",
// "linear:friction_law_N", "lagged_temperature:temperature_C" (the model file's form).
std::string factor_text(const TermFactor& f);
std::optional<TermFactor> parse_factor(std::string_view text);

// What a log gives the terms beyond each row: time in the run, sliding distance and the
// campaign's time (NaN without a time column), each run's chronological index, and each run's
// rows in order.
struct TermSeries {
  std::vector<double> time_in_run_s, sliding_distance_m, campaign_time_s;
  std::vector<double> run_index;                   // per run (log.run): 0, 1, … in chronological order
  std::vector<std::vector<std::size_t>> run_rows;  // per run index, its rows in log order
  bool timed = false;
  // How the runs were put in order: "time_s" (the runs' clocks do not overlap: a campaign
  // clock) or "file" (the order they are written in; each run's clock restarts).
  std::string chronology = "file";
};
TermSeries term_series(const FrictionLog& log);

// lag_τ(T) − T per row of the log: the first-order lag of the logged temperature over each
// run's time (exact for piecewise-constant steps), restarting at every run's first reading.
template <typename T>
std::vector<T> lagged_temperature_change(const FrictionLog& log, const TermSeries& series, const T& tau_s) {
  using std::exp;
  std::vector<T> change(log.size(), T(0.0));
  for (const auto& rows : series.run_rows) {
    if (rows.empty()) continue;
    T lagged = T(log.temperature_C[rows.front()]);
    for (std::size_t k = 1; k < rows.size(); ++k) {
      const std::size_t i = rows[k], before = rows[k - 1];
      const double dt = std::max(series.time_in_run_s[i] - series.time_in_run_s[before], 0.0);
      const T keep = exp(-dt / tau_s);
      lagged = log.temperature_C[before] + (lagged - log.temperature_C[before]) * keep;
      change[i] = lagged - log.temperature_C[i];
    }
  }
  return change;
}

// The value of a column covariate (not the law or its parts) at row i.
double term_covariate_value(const FrictionLog& log, const TermSeries& series, std::size_t i, TermCovariate c);

// A part of the published law (coulomb_N, stribeck_N, viscous_N without the seal, seal_N: the
// seal offset Lb·f0 that Eq. 4 puts inside the viscous term) from its breakdown at constants `k`;
// the law's total for law_force_N is the caller's (it carries the effects).
template <typename P, typename R>
R law_part_N(const FrictionConstants<P>& k, const FrictionBreakdown<R>& b, double block_length_mm, TermCovariate part) {
  const R seal_N = R(k.f0 * block_length_mm);
  switch (part) {
    case TermCovariate::coulomb_N: return b.coulomb_N;
    case TermCovariate::stribeck_N: return b.stribeck_N;
    case TermCovariate::viscous_N: return b.viscous_N - seal_N;
    case TermCovariate::seal_N: return seal_N;
    default: return R(0.0);
  }
}

namespace detail {

// The law with terms at one sample, the one evaluation behind the fit (friction_with_terms_N)
// and the steady state (steady_terms_N). `covariate(c)`: the sample's value of a column
// covariate; `decay(x, ℓ)`: exp(−x/ℓ), or 0 at a steady state; `lag_change`: lag_τ(T) − T at
// the sample (0 at a steady state).
template <typename T>
struct LawWithTerms {
  T law;    // the law with its effects at the corrected input
  T added;  // the terms that add to it, summed in order
  T total;  // law + each added term, in order
};
template <typename T, typename P, typename E, typename Covariate, typename Decay>
LawWithTerms<T> law_with_terms_N(const FrictionConstants<P>& k, const FrictionEffects<E>& e, const FrictionConditions<double>& c,
                   const std::vector<FrictionTerm>& terms, const T* theta, const Covariate& covariate,
                   const Decay& decay, const T& lag_change) {
  // The term's coefficient (theta_term[0]) times its factors, in their order, its scale at
  // theta_term[1]; the law and its parts from `law` and `b` (unused by an input shift's factors,
  // which never include them).
  const T law_unused(0.0);
  FrictionBreakdown<T> b{};
  auto term_value = [&](const FrictionTerm& term, const T* theta_term, const T& law) {
    T value = *theta_term;
    for (const auto& f : term.factors) {
      if (f.transform == TermTransform::input_shift) continue;
      if (f.covariate == TermCovariate::law_force_N) value = value * law;
      else if (is_law_covariate(f.covariate)) value = value * law_part_N(k, b, c.block_length_mm, f.covariate);
      else if (f.transform == TermTransform::decay) value = value * decay(covariate(f.covariate), theta_term[1]);
      else {
        const double x = covariate(f.covariate);
        switch (f.transform) {
          case TermTransform::spline: value = value * bspline(f.knots, f.basis, x); break;
          case TermTransform::step: value = value * (x > f.centre ? 1.0 : 0.0); break;
          case TermTransform::square: value = value * ((x - f.centre) * (x - f.centre)); break;
          default: value = value * (x - f.centre); break;
        }
      }
    }
    return value;
  };
  // The corrected input: every input correction adds to it.
  T shift_T(0.0), shift_V(0.0);
  bool shifted = false, parts = false;
  std::size_t at = 0;
  for (const auto& term : terms) {
    if (term.lagged_temperature()) {
      shift_T = shift_T + theta[at] * lag_change;
      shifted = true;
    } else if (const auto input = term.shifted_input()) {
      T& shift = *input == TermCovariate::velocity_m_s ? shift_V : shift_T;
      shift = shift + term_value(term, theta + at, law_unused);
      shifted = true;
    }
    for (const auto& f : term.factors) parts = parts || (is_law_covariate(f.covariate) && f.covariate != TermCovariate::law_force_N);
    at += term.has_scale() ? 2 : 1;
  }
  T law;
  auto take_parts = [&](const auto& full) {
    b = {T(full.viscosity_mm2_s), T(full.stribeck_decay), T(full.coulomb_N), T(full.stribeck_N), T(full.viscous_N)};
  };
  if (shifted) {
    FrictionConditions<T> input = c.template cast<T>();
    input.temperature_C = input.temperature_C + shift_T;
    input.velocity_m_s = input.velocity_m_s + shift_V;
    law = T(friction_force_with_effects_N(k, e, input));
    if (parts) take_parts(friction_breakdown(k, input));
  } else {
    law = T(friction_force_with_effects_N(k, e, c));
    if (parts) take_parts(friction_breakdown(k, c));
  }
  LawWithTerms<T> out{law, T(0.0), law};
  at = 0;
  for (const auto& term : terms) {
    if (!term.corrects_input()) {
      const T value = term_value(term, theta + at, law);
      out.added = out.added + value;
      out.total = out.total + value;
    }
    at += term.has_scale() ? 2 : 1;
  }
  return out;
}

}  // namespace detail

// What the terms add at steady conditions (a sweep without a time course, long after the
// start): decays and lags have settled to 0; a campaign covariate (run index, campaign time)
// stays where the campaign ended (the largest value the terms saw). `outside` is set when a
// covariate lies beyond the range the terms were learned on (an extrapolation).
template <typename E>
double steady_terms_N(const std::vector<FrictionTerm>& terms, const FrictionConstants<double>& k,
                      const FrictionEffects<E>& e, const FrictionConditions<double>& c, bool* outside = nullptr) {
  std::vector<double> theta;
  for (const auto& t : terms) {
    theta.push_back(t.coefficient);
    if (t.has_scale()) theta.push_back(t.scale);
  }
  auto last_seen = [&](TermCovariate covariate) {
    double last = std::numeric_limits<double>::quiet_NaN();
    for (const auto& t : terms)
      for (const auto& r : t.seen)
        if (r.covariate == covariate) last = std::isnan(last) ? r.max : std::max(last, r.max);
    return std::isnan(last) ? 0.0 : last;
  };
  auto covariate = [&](TermCovariate covariate) {
    switch (covariate) {
      case TermCovariate::velocity_m_s: return c.velocity_m_s;
      case TermCovariate::load_N: return c.load_N;
      case TermCovariate::preload_um: return c.preload_um;
      case TermCovariate::block_length_mm: return c.block_length_mm;
      case TermCovariate::temperature_C: return c.temperature_C;
      case TermCovariate::direction: return c.direction;
      default: return last_seen(covariate);  // campaign, time and distance: where the data ended
    }
  };
  if (outside)
    for (const auto& t : terms)
      for (const auto& r : t.seen) {
        if (is_law_covariate(r.covariate) || is_campaign_covariate(r.covariate) ||
            r.covariate == TermCovariate::time_in_run_s || r.covariate == TermCovariate::sliding_distance_m)
          continue;
        const double x = covariate(r.covariate);
        if (x < r.min || x > r.max) *outside = true;
      }
  const auto settled = [](double, double) { return 0.0; };
  const auto with = detail::law_with_terms_N<double>(k, e, c, terms, theta.data(), covariate, settled, 0.0);
  const bool corrected = std::any_of(terms.begin(), terms.end(), [](const FrictionTerm& t) { return t.corrects_input(); });
  return corrected ? with.law - friction_force_with_effects_N(k, e, c) + with.added : with.added;
}

// The friction force at row i of `log`: the law with named effects `e`, plus the terms with
// parameters `theta` (per term: c, then ℓ or τ if it has one). `lag_change` holds
// lagged_temperature_change at the lag term's τ (nullptr without one). Templated like the law:
// double predicts, Jets differentiate.
template <typename T, typename P, typename E>
T friction_with_terms_N(const FrictionConstants<P>& k, const FrictionEffects<E>& e, const FrictionLog& log,
                        const TermSeries& series, std::size_t i, const std::vector<FrictionTerm>& terms, const T* theta,
                        const std::vector<T>* lag_change) {
  using std::exp;
  const auto covariate = [&](TermCovariate c) { return term_covariate_value(log, series, i, c); };
  const auto decay = [](double x, const T& scale) { return T(exp(-x / scale)); };
  return detail::law_with_terms_N<T>(k, e, log.conditions(i), terms, theta, covariate, decay,
                                     lag_change ? (*lag_change)[i] : T(0.0))
      .total;
}

}  // namespace lmcal
