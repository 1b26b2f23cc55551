// Empirical terms of the friction force: what `lmcal diagnose friction` learns when the law
// and every named effect (friction_effects.hpp) leave structure in the residuals. Not a
// mechanism: a term says what the friction follows, not why (the diagnosis says what it
// resembles). Each term adds, in N,
//
//   c · f(x)   or   c · f(x) · g(x)
//
// with f, g transforms of one covariate of the sample:
//   linear   x − x0                 (x0: 40 °C for the temperature, the law's T_i; else 0)
//   square   (x − x0)²
//   decay    exp(−x / ℓ)            x the sliding distance since the log's start (m) or the
//                                   time since the run's start (s); ℓ fitted
//   spline   B_k(x)                 a cubic B-spline basis function of V, P or T: a smooth
//                                   term is several, one coefficient each (where no sparse
//                                   form fits)
// and the law's own force F_law (with its named effects) as a covariate, for terms in
// proportion to the friction (c · exp(−s/ℓ) · F_law: running-in).
//
// One form is not a sum: the law at a lagged temperature,
//   lagged_temperature:  F_law(T + c (lag_τ(T) − T)) − F_law(T)
// with lag_τ the first-order lag of the logged temperature over each run's time (starting at
// the run's first reading), τ fitted; c = 1 means the friction follows a temperature that
// trails the logged one by τ (the lubricant behind a thermocouple).
//
// Sliding distance: s_i = Σ_{j<i} V_j Δt_j over the log in row order (runs in the order
// written, samples in time order), Δt from time_s (the median step across a run boundary).
// Terms in time or distance need a time_s column.
//
// Trap: a term's coefficient is in N per unit of its factors (N/K for a linear temperature
// term, N/(K·m/s) for temperature × speed); a term in F_law is relative (1 = 100 %).
#pragma once

#include "lmcal/export.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
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
};
enum class TermTransform { linear, square, decay, lagged_temperature, spline };

struct TermFactor {
  TermCovariate covariate = TermCovariate::velocity_m_s;
  TermTransform transform = TermTransform::linear;
  double centre = 0;  // x0 of linear and square
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
  std::vector<TermFactor> factors;  // one or two; at most one decay, and a lagged temperature alone
  double coefficient = 0;           // c (a fit's start value)
  double scale = 0;                 // ℓ or τ of a decay or lag (a fit's start value)
  double scale_lower = 0, scale_upper = 0;  // bounds of a fit
  // The covariates' ranges in the data it was learned from: beyond them it is an extrapolation.
  std::vector<TermRange> seen;

  bool has_scale() const;
  bool lagged_temperature() const;
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

// A factor as text and back: "linear:temperature_C:40", "decay:sliding_distance_m",
// "linear:friction_law_N", "lagged_temperature:temperature_C" (the model file's form).
std::string factor_text(const TermFactor& f);
std::optional<TermFactor> parse_factor(std::string_view text);

// A term's value at steady conditions (a sweep without a time course, long after the start):
// decays and lags have settled to 0; `law_N` is the law's force there. `outside` is set when a
// covariate lies beyond the range the term was learned on (an extrapolation).
double steady_term_N(const FrictionTerm& term, const FrictionConditions<double>& c, double law_N, bool* outside = nullptr);

// What a log gives the terms beyond each row: time in the run and sliding distance (NaN
// without a time column), and each run's rows in order.
struct TermSeries {
  std::vector<double> time_in_run_s, sliding_distance_m;
  std::vector<std::vector<std::size_t>> run_rows;  // per run index, its rows in log order
  bool timed = false;
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

// The value of a factor (not decay, lag or law) at row i.
double term_covariate_value(const FrictionLog& log, const TermSeries& series, std::size_t i, TermCovariate c);

// The friction force at row i of `log`: the law with named effects `e`, plus the terms with
// parameters `theta` (per term: c, then ℓ or τ if it has one). `lag_change` holds
// lagged_temperature_change at the lag term's τ (nullptr without one). Templated like the law:
// double predicts, Jets differentiate.
template <typename T, typename P, typename E>
T friction_with_terms_N(const FrictionConstants<P>& k, const FrictionEffects<E>& e, const FrictionLog& log,
                        const TermSeries& series, std::size_t i, const std::vector<FrictionTerm>& terms, const T* theta,
                        const std::vector<T>* lag_change) {
  using std::exp;
  const FrictionConditions<double> c = log.conditions(i);
  T law;
  std::size_t at = 0;
  bool lag_applied = false;
  for (const auto& term : terms)
    if (term.lagged_temperature()) {
      FrictionConditions<T> shifted = c.template cast<T>();
      shifted.temperature_C = shifted.temperature_C + theta[at] * (*lag_change)[i];
      law = T(friction_force_with_effects_N(k, e, shifted));
      lag_applied = true;
      break;
    } else {
      at += term.has_scale() ? 2 : 1;
    }
  if (!lag_applied) law = T(friction_force_with_effects_N(k, e, c));
  T total = law;
  at = 0;
  for (const auto& term : terms) {
    const T& coefficient = theta[at];
    if (!term.lagged_temperature()) {
      T value = coefficient;
      for (const auto& f : term.factors) {
        if (f.covariate == TermCovariate::law_force_N) value = value * law;
        else if (f.transform == TermTransform::decay) value = value * exp(-term_covariate_value(log, series, i, f.covariate) / theta[at + 1]);
        else if (f.transform == TermTransform::spline) value = value * bspline(f.knots, f.basis, term_covariate_value(log, series, i, f.covariate));
        else {
          const double x = term_covariate_value(log, series, i, f.covariate) - f.centre;
          value = value * (f.transform == TermTransform::square ? x * x : x);
        }
      }
      total = total + value;
    }
    at += term.has_scale() ? 2 : 1;
  }
  return total;
}

}  // namespace lmcal
