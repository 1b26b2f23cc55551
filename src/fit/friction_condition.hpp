// The condition of a friction sample, shared by the fit (weights from the spread of repeats,
// per-condition residuals) and the diagnosis (condition means, pure error). Private; no Ceres.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <tuple>

#include "lmcal/io/friction_log.hpp"

namespace lmcal::detail {

// (guide, preload, load, temperature to 1 K, speed, direction). The temperature at its
// nominal value: grouping by the logged one would group by its noise.
using ConditionKey = std::tuple<std::uint32_t, double, double, double, double, double>;

inline ConditionKey condition_key(const FrictionLog& log, std::size_t i) {
  return {log.guide[i], log.preload_um[i], log.load_N[i], std::round(log.temperature_C[i]), log.velocity_m_s[i],
          static_cast<double>(log.direction[i])};
}

}  // namespace lmcal::detail
