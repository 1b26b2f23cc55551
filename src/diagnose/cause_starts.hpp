// Where a diagnosis starts a candidate cause whose shape (its parts, friction_effect.hpp) a
// local fit from the parts' neutral values would not find: a position ripple's period (the
// least-squares objective in the period has an optimum per period the travel holds) and a
// pre-sliding distance. Private to the diagnosis.
#pragma once

#include <string_view>
#include <vector>

#include "lmcal/io/friction_log.hpp"

namespace lmcal::detail {

// The start of `cause` and its parts (in with_effect_parts order) from the current model's
// residuals (measured − predicted, N, per sample):
//   position_ripple: the strongest sinusoid of the residuals' means in position bins over
//                    periods from the period's lower bound to a third of the travel (a
//                    least-squares periodogram: A, λ, φ at its peak);
//   presliding:      ΔF and s0 of −ΔF exp(−s/s0) by least squares over a log-spaced grid of s0.
// Empty for any other cause (its parts, if any, start at their neutral values).
std::vector<double> cause_start(std::string_view cause, const FrictionLog& log, const std::vector<double>& residual_N);

}  // namespace lmcal::detail
