// Spread of repeated results, as the paper reports it (shared/PHYSICS.md §6), and the
// quantiles that intervals need.
//
//   σ = sqrt( Σ (x_i - <x>)² / (N - 1) )              Eq. 1
//   difference = |E1 - E2| / ((E1 + E2) / 2) · 100 %   Eq. 2
//   95 % interval of the mean: <x> ± t(0.975, N - 1) · σ / √N
//
// Example: the paper's four α values 0.593, 0.61, 0.61, 0.586 give mean 0.5998,
// σ = 0.0122 and half-width 0.019: "0.600 ± 0.019".
// Trap: Eq. 2 is undefined when E1 + E2 = 0; it returns NaN there.
#pragma once

#include "lmcal/export.hpp"

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace LMCAL_API lmcal {

double sample_standard_deviation(std::span<const double> values);  // Eq. 1; NaN for N < 2
double percent_difference(double e1, double e2);                    // Eq. 2

// Quantiles (Boost.Math): Student t with `dof` degrees of freedom, F(d1, d2), χ²(dof).
double student_t_quantile(double probability, double dof);
double fisher_f_quantile(double probability, double d1, double d2);
double chi_squared_quantile(double probability, double dof);
// Upper tail probabilities P(X > x).
double student_t_two_sided_p(double t, double dof);
double fisher_f_upper_p(double f, double d1, double d2);
double chi_squared_upper_p(double x, double dof);

struct Spread {
  std::size_t n = 0;
  double mean = 0;
  double sd = 0;          // Eq. 1
  double half_width = 0;  // t(1 - (1 - confidence)/2, n - 1) · sd / √n
  double low = 0, high = 0;
  double min = 0, max = 0;
};

// Mean, Eq. 1 σ, Student-t interval of the mean, min and max. NaN values are left out.
Spread spread(std::span<const double> values, double confidence = 0.95);

// "across runs 0.601 ± 0.012" (mean ± t half-width, `digits` significant), or, with fewer than
// two runs, what is missing: "one run: no spread across runs" (never "0.000 ± 0.000").
std::string across_runs(const Spread& s, int digits = 3);

// A p-value as the outputs print it: 2 significant digits ("0.032"), or "< 1e-16" below what a
// double's tail resolves (never "0": a test that rejects beyond any doubt still has p > 0);
// p_is gives "p = 0.032" or "p < 1e-16". No p (NaN: a test that could not run) is "n/a".
std::string p_value_text(double p);
std::string p_is(double p);

// Holm's step-down adjustment of a family of p-values (each in [0, 1], InvalidParameter
// otherwise): the k-th smallest becomes max over j <= k of min(1, (m − j + 1) p_(j)). NaN entries
// stay NaN and do not count in the family m. Same order as the input.
std::vector<double> holm_adjust(std::span<const double> p);

}  // namespace lmcal
