// A t interval that respects its parameter's bounds (private to the fit and diagnosis layers).
//
//   value ± t·SE where that lies within [lower, upper]; where it would cross a bound, the same
//   interval on a scale on which the bound is infinitely far: φ = log(θ − lower) (or
//   log(upper − θ)) with one finite bound, φ = logit((θ − lower)/(upper − lower)) with two,
//   SE_φ = SE·|dφ/dθ| (the delta method), φ ± t·SE_φ mapped back. Near a bound it is
//   asymmetric (short towards the bound), far from it the linear one. An estimate on its bound
//   has no such scale: its interval is the linear one clipped at the bound ("clipped").
//
//   bounded_interval(0.2, 0.15, 2.0, 0, 1) -> [0.0369, 0.620], "logit" (linear: [-0.1, 0.5])
//
// Trap: the interval is only as good as the SE; a parameter whose likelihood is far from
// quadratic still wants its profile.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

namespace lmcal::detail {

struct BoundedInterval {
  double low = 0, high = 0;
  std::string method;  // "linear", "log", "logit" or "clipped"
};

inline BoundedInterval bounded_interval(double value, double se, double t, double lower, double upper) {
  const double half = t * se;
  BoundedInterval out{value - half, value + half, "linear"};
  if (!std::isfinite(value) || !std::isfinite(half) || !(half > 0)) return out;
  const bool has_low = std::isfinite(lower), has_high = std::isfinite(upper);
  if ((!has_low || out.low >= lower) && (!has_high || out.high <= upper)) return out;
  if ((has_low && value <= lower) || (has_high && value >= upper)) {
    if (has_low) out.low = std::max(out.low, lower);
    if (has_high) out.high = std::min(out.high, upper);
    out.method = "clipped";
    return out;
  }
  if (has_low && has_high) {
    const double width = upper - lower, u = (value - lower) / width;
    const double phi = std::log(u / (1 - u)), se_phi = se * width / ((value - lower) * (upper - value));
    auto back = [&](double x) { return lower + width / (1 + std::exp(-x)); };
    out = {back(phi - t * se_phi), back(phi + t * se_phi), "logit"};
  } else if (has_low) {
    const double d = value - lower, se_phi = se / d;
    out = {lower + d * std::exp(-t * se_phi), lower + d * std::exp(t * se_phi), "log"};
  } else {
    const double d = upper - value, se_phi = se / d;
    out = {upper - d * std::exp(t * se_phi), upper - d * std::exp(-t * se_phi), "log"};
  }
  return out;
}

}  // namespace lmcal::detail
