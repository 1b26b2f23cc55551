// A fleet of units (linear guides, machine axes) calibrated one by one: what the population of
// one constant is, which units lie outside it given their own uncertainty, and whether one
// unit's constant drifts over dates.
//
// Population (random-effects meta-analysis). Unit i reports y_i with standard error s_i:
//   y_i = μ + u_i + e_i,   u_i ~ N(0, τ²)  (real unit-to-unit difference),  e_i ~ N(0, s_i²)
//   w_i(τ²) = 1 / (s_i² + τ²),   μ(τ²) = Σ w_i y_i / Σ w_i
//   Q(τ²)   = Σ w_i(τ²) (y_i − μ(τ²))²      generalized Q, decreasing in τ²; Q(0) is Cochran's Q
//   τ²      REML, kept >= 0: Newton steps (Fisher scoring where the curvature is wrong) with step
//           halving, from DerSimonian-Laird τ²_DL = max(0, (Q(0) − (k − 1)) / (Σf − Σf²/Σf)),
//           f_i = 1/s_i², or from a coarse τ² grid's best point when that is higher (with SEs
//           that differ by orders of magnitude the restricted likelihood can have several maxima)
//   τ interval   Q-profile (Viechtbauer 2007): Q(τ²_low) = χ²_{k−1}((1 + c)/2),
//                Q(τ²_high) = χ²_{k−1}((1 − c)/2); a bound is 0 when Q(0) is already below
//   μ interval   Hartung-Knapp-Sidik-Jonkman: μ ± t_{k−1}((1 + c)/2) · mean_se,
//                mean_se² = max(1, Q(τ̂²)/(k − 1)) / Σ w_i(τ̂²)
//   I² = τ² / (τ² + s̃²),  s̃² = (k − 1) Σf / ((Σf)² − Σf²)  (Higgins-Thompson typical s_i²)
//   Cochran's Q = Q(0), tested against χ²(k − 1)
//
// Outliers (fit_population), an outward sequential test. Nobody is flagged at first; then,
// repeatedly: every unit not flagged gets its leave-one-out deviation
//   z_i = (y_i − μ₋ᵢ) / sqrt(s_i² + τ₋ᵢ² + mean_se₋ᵢ²)
// against the random-effects fit of the m other units not flagged, read as Student t with
// m − 1 dof (τ₋ᵢ² is estimated from those m: a normal reading flags 10 % of clean 40-unit fleets
// at a 5 % family-wise level when τ dominates the SEs). The largest |z| is flagged when its
// Bonferroni p, p_t(z) · (units not flagged) · family_size, is below alpha. It stops at the
// first unit that is not, at half the units flagged, or when fewer than 3 others would be left to
// fit (2 say nothing about τ). The reported z and p_adjusted of every unit (flagged or not) are
// then against the final population (of the others); p_adjusted = p_t(z) · units · family_size,
// capped at 1. The flags are the sequential test's; p_adjusted is for reading.
//
// Drift (drift_test), one unit's constant at dates t_i (days) with values y_i ± s_i, w = 1/s².
// Both tests trust the SEs while the scatter is within them (χ² <= dof: normal p, SE as stated)
// and widen the SE by sqrt(χ²/dof), read with Student t on dof = n − 2, when it is beyond them.
//   trend   weighted line y = a + b (t − t̄_w), χ² = Σ w (y − ŷ)², se0(b)² = 1 / Σ w (t − t̄_w)²
//   change  every split into dates [0, c) and [c, n) with >= 2 on each side: shift Δ = m_after −
//           m_before (weighted means), χ²_c = Σ w (y − m_side)², se0(Δ)² = 1/W_before + 1/W_after;
//           the best split has the largest |Δ|/se0(Δ) (the least χ²_c: maximum likelihood, and
//           the least p); change_p = its p times the n − 3 candidate splits, capped at 1
//   p       min(1, 2 · min(trend_p, change_p)), or trend_p when n < 4
// The change test scales by the scatter about the two-mean model, as the slope does about its
// line: the single-mean model's χ² would count the shift itself as noise and cap |Δ|/se(Δ)
// however large the step. With correct SEs the combined test rejects 2-3 % of clean series at
// 0.05 (8 to 20 dates; Bonferroni is conservative); a t on the floored SE would reject 0.2 %.
// With 4 dates and SEs understated 2× it rejects 9 %: few dates cannot tell scatter from SEs.
//
// Units: value and se in the constant's own unit (any, the same for all units); day in days
// since any epoch; slope_per_day in value unit per day; percentages in %; τ in value unit.
//
// Example: five guides' friction coefficients 0.0030, 0.0032, 0.0031, 0.0036, 0.0029, each
// ± 0.0001, give Cochran's Q = 29.2 on 4 dof (p = 7e-6), μ = 0.00316 ± 0.00034 (95 %, HKSJ),
// τ = 0.00025 [0.00013, 0.00077] and I² = 0.86: most of the spread is real unit-to-unit difference.
// The 0.0036 guide stands out (z = 3.8 against the other four) but is not flagged: read with t on
// 3 dof and tested as one of 5 units × 3 constants, its p_adjusted is 0.48.
//   const std::vector<lmcal::Estimate> mu = {{0.0030, 1e-4}, {0.0032, 1e-4}, ...};
//   const lmcal::PopulationFit f = lmcal::fit_population(mu, /*family_size=*/3);
//
// Trap: se must be the standard error of each unit's estimate, not the scatter of its raw data.
// The model trusts it: SEs that are too small turn into τ (and into flagged outliers), SEs that
// are too large hide real differences. With k = 2 the τ interval is very wide and its upper
// bound may be +inf (not bracketed below 1e6 × the data's variance): that is the honest answer.
#pragma once

#include "lmcal/export.hpp"

#include <cmath>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "lmcal/fit/statistics.hpp"  // holm_adjust, for the caller's family of drift tests

namespace LMCAL_API lmcal {

// One unit's estimate of a constant. se > 0 and finite, value finite (InvalidParameter naming
// the estimate otherwise).
struct Estimate {
  double value = 0;
  double se = 0;
};

struct RandomEffects {
  std::size_t k = 0;
  double mean = NAN, mean_se = NAN, mean_low = NAN, mean_high = NAN;  // HKSJ; k = 1: the estimate, normal interval
  double tau = NAN, tau_low = NAN, tau_high = NAN;  // REML between-unit SD and its Q-profile interval; NaN for k = 1
  double tau_dl = NAN;                              // the DerSimonian-Laird moment estimate (for comparison)
  double q = NAN, q_p = NAN;                        // Cochran's Q (weights 1/se²) and its χ²(k − 1) upper p
  double i2 = NAN;                                  // τ²/(τ² + s̃²) with the REML τ, in [0, 1)
  bool converged = false;                           // REML converged (false for k < 2)
  std::string method;                               // one line: the estimator and the intervals
};

// The population of `estimates` at `confidence` (in (0, 1)). k = 0 gives an empty result.
RandomEffects random_effects(std::span<const Estimate> estimates, double confidence = 0.95);

struct PopulationFit {
  RandomEffects population;             // fitted without the flagged outliers
  std::vector<std::size_t> outliers;    // indices into the input, ascending
  std::vector<double> z;                // per input: leave-one-out deviation against the final population
  std::vector<double> p_adjusted;       // per input: p_t(z) · units · family_size, capped at 1
  std::string note;                     // why the test stopped, or why no unit was tested
};

// Outliers by the outward sequential test above. family_size >= 1: how many constants the caller
// tests in the same family (Bonferroni across constants and units); alpha in (0, 1): the
// family-wise level.
PopulationFit fit_population(std::span<const Estimate> estimates, std::size_t family_size = 1, double alpha = 0.05);

// One unit's estimate at a date. day strictly increasing along a series, all fields finite,
// se > 0 (InvalidParameter naming the entry otherwise).
struct DatedEstimate {
  double day = 0;
  double value = 0;
  double se = 0;
};

struct Drift {
  std::size_t n = 0;
  double slope_per_day = NAN, slope_se = NAN, trend_p = NAN;  // n >= 3; slope_se widened by the scatter
  double trend_percent = NAN;               // (ŷ(last day) − ŷ(first day)) / |ŷ(first day)| · 100, from the line
  std::optional<std::size_t> change_index;  // first date after the most likely mean shift; n >= 4
  double shift = NAN;                       // m_after − m_before at that split
  double shift_percent = NAN;               // shift / |m_before| · 100
  double change_p = NAN;                    // Bonferroni over the n − 3 splits, capped at 1
  double p = NAN;                           // the drift test: min(1, 2 · min(trend_p, change_p)), or trend_p
  std::string note;                         // what could not be tested and why
};

Drift drift_test(std::span<const DatedEstimate> series);

}  // namespace lmcal
