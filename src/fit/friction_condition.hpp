// The condition of a friction sample, shared by the fit (weights from the spread of repeats,
// per-condition residuals) and the diagnosis (condition means, pure error). Private; no Ceres.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <tuple>

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

}  // namespace lmcal::detail
