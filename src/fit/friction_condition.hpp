// The condition of a friction sample, shared by the fit (weights from the spread of repeats,
// per-condition residuals) and the diagnosis (condition means, pure error). Private; no Ceres.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <tuple>
#include <vector>

#include "lmcal/io/friction_log.hpp"

namespace lmcal::detail {

// A trajectory's speed varies continuously, sample by sample: its samples are grouped in speed
// bins 2 % wide (log-spaced, the key is the bin's centre), as a plateau log's samples share
// their set speed. Without bins every sample was a condition of its own (a 10⁶-row table, no
// repeats).
inline constexpr double kTrajectorySpeedBin = 0.02;

inline double condition_speed(const FrictionLog& log, std::size_t i) {
  const double v = log.velocity_m_s[i];
  if (!log.trajectory || !(v > 0)) return v;
  static const double step = std::log1p(kTrajectorySpeedBin);
  return std::exp(std::round(std::log(v) / step) * step);
}

// (guide, preload, load, temperature to 1 K, speed, direction). The temperature at its
// nominal value: grouping by the logged one would group by its noise.
using ConditionKey = std::tuple<std::uint32_t, double, double, double, double, double>;

inline ConditionKey condition_key(const FrictionLog& log, std::size_t i) {
  return {log.guide[i], log.preload_um[i], log.load_N[i], std::round(log.temperature_C[i]), condition_speed(log, i),
          static_cast<double>(log.direction[i])};
}

// Two values of a quantity that agree to its resolution: within `tolerance` relative to the
// larger magnitude.
inline bool same_to_resolution(double a, double b, double tolerance) {
  return std::abs(a - b) <= tolerance * std::max(std::abs(a), std::abs(b));
}

// Values that agree to a quantity's resolution, as one value: each is replaced by the smallest
// of its cluster, the values sorted and a cluster closed where the next lies more than
// `tolerance` (relative, of the larger magnitude) beyond its first. A raw log's plateau speeds
// (each the mean of its plateau: 0.10003 and 0.09998 for one set speed) or run means of one
// block length that differ in the last bit become one value; set values a design spaces by 20 %
// stay apart. Clusters span at most `tolerance`, so dense continuous values do not chain.
inline std::vector<double> snap_to_resolution(const std::vector<double>& values, double tolerance) {
  std::vector<double> sorted = values;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  std::vector<double> first(sorted.size());
  for (std::size_t k = 0; k < sorted.size(); ++k)
    first[k] = k > 0 && same_to_resolution(sorted[k], first[k - 1], tolerance) ? first[k - 1] : sorted[k];
  std::vector<double> out;
  out.reserve(values.size());
  for (double v : values) out.push_back(first[static_cast<std::size_t>(std::lower_bound(sorted.begin(), sorted.end(), v) - sorted.begin())]);
  return out;
}

// condition_key with speed, preload and load matched to `tolerance` (snap_to_resolution) instead
// of as exact doubles: the diagnosis's conditions, where repeats across runs are what counts. The
// fit keeps its exact keys.
inline std::vector<ConditionKey> tolerant_condition_keys(const FrictionLog& log, double tolerance) {
  std::vector<double> speed(log.size());
  for (std::size_t i = 0; i < log.size(); ++i) speed[i] = condition_speed(log, i);
  const std::vector<double> v = snap_to_resolution(speed, tolerance), pc = snap_to_resolution(log.preload_um, tolerance),
                            load = snap_to_resolution(log.load_N, tolerance);
  std::vector<ConditionKey> keys;
  keys.reserve(log.size());
  for (std::size_t i = 0; i < log.size(); ++i) {
    ConditionKey& key = keys.emplace_back(condition_key(log, i));
    std::get<1>(key) = pc[i], std::get<2>(key) = load[i], std::get<4>(key) = v[i];
  }
  return keys;
}

}  // namespace lmcal::detail
