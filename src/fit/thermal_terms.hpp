// The regressors of the thermal model's sensor-side terms (private to the fit and the
// diagnosis; templated so that a term's scale — the ambient's period P, a lag's τ — gets its
// derivative from a Jet). A sensor term is added to every thermocouple reading of a run:
//
//   reading(run, s, t) = simulated(run, s, t) + offset(run, s) + Σ_j c_j φ_j(run, s, t)
//
//   time                 φ = t / 1 h                       (t since the run's first record)
//   time_squared         φ = (t / 1 h)²
//   ambient_in_phase     φ = a_P(t) = A sin ωt + B cos ωt  (ω = 2π/P; A, B: least squares of the
//   ambient_quadrature   φ = b_P(t) = A cos ωt − B sin ωt   run's ambient on [1, t, sin ωt, cos ωt])
//   ambient_lag          φ = lag_τ(T∞)(t) − T∞(t)          (first-order lag, thermal_effects.hpp)
//   ambient_change       φ = T∞(t) − T∞(0)
//   rise_time            φ = (T_sim(s, t) − T0) · t / 1 h  (here t / 1 h: the caller multiplies by the
//                                                       simulated rise, thermal_model.cc)
//   velocity_time        φ = V · t / 1 h
//
// a_P is the ambient's own swing at P; b_P the same a quarter period earlier. A rail that sees
// a larger or later swing than the ambient sensors shows as c_a a_P + c_b b_P.
//
// Trap: ambient_in_phase and ambient_quadrature share one period (one parameter in a fit).
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <type_traits>
#include <vector>

#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/models/rail_thermal.hpp"
#include "lmcal/models/thermal_effects.hpp"

namespace lmcal::detail {

inline constexpr double kSecondsPerHour = 3600.0;

template <typename T>
double value_of_jet(const T& x) {
  if constexpr (std::is_same_v<T, double>) return x;
  else return x.a;
}

// The ambient's component at period P: A, B of T∞ ≈ c0 + c1 t + A sin ωt + B cos ωt (least
// squares over the ambient's records, t from its first), and the sum of squares the sine
// explains beyond the line (for the period search; in double only).
template <typename T>
struct PeriodicComponent {
  T in_phase{0.0}, quadrature{0.0};  // A, B
  double explained = 0;
};

template <typename T>
PeriodicComponent<T> periodic_component(const AmbientTrace& ambient, const T& period_s) {
  using std::sin, std::cos;
  const std::size_t n = ambient.time_s.size();
  PeriodicComponent<T> out;
  if (n < 5) return out;
  const double t0 = ambient.time_s.front(), span = std::max(ambient.time_s.back() - t0, 1.0);
  const T omega = 2 * std::numbers::pi / period_s;
  // Normal equations of [1, t/span, sin, cos] (t scaled for conditioning).
  T M[4][5];
  for (auto& row : M)
    for (auto& v : row) v = T(0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = ambient.time_s[i] - t0;
    const T x[4] = {T(1.0), T(t / span), sin(omega * t), cos(omega * t)};
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) M[a][b] += x[a] * x[b];
      M[a][4] += x[a] * ambient.temperature_C[i];
    }
  }
  // Gaussian elimination with partial pivoting (on the values).
  for (int c = 0; c < 4; ++c) {
    int pivot = c;
    for (int r = c + 1; r < 4; ++r)
      if (std::abs(value_of_jet(M[r][c])) > std::abs(value_of_jet(M[pivot][c]))) pivot = r;
    if (!(std::abs(value_of_jet(M[pivot][c])) > 1e-12 * static_cast<double>(n))) return out;  // P too long for the run
    if (pivot != c)
      for (int k = 0; k < 5; ++k) std::swap(M[c][k], M[pivot][k]);
    for (int r = c + 1; r < 4; ++r) {
      const T f = M[r][c] / M[c][c];
      for (int k = c; k < 5; ++k) M[r][k] -= f * M[c][k];
    }
  }
  T beta[4];
  for (int c = 3; c >= 0; --c) {
    T s = M[c][4];
    for (int k = c + 1; k < 4; ++k) s -= M[c][k] * beta[k];
    beta[c] = s / M[c][c];
  }
  out.in_phase = beta[2];
  out.quadrature = beta[3];
  if constexpr (std::is_same_v<T, double>) {
    // Explained beyond the line: SS(line) − SS(line + sine), from the fitted values.
    double line_ss = 0, full_ss = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double t = (ambient.time_s[i] - t0) / span, y = ambient.temperature_C[i];
      sx += t, sy += y, sxx += t * t, sxy += t * y;
    }
    const double N = static_cast<double>(n), slope = (N * sxy - sx * sy) / (N * sxx - sx * sx), icept = (sy - slope * sx) / N;
    for (std::size_t i = 0; i < n; ++i) {
      const double t = ambient.time_s[i] - t0, y = ambient.temperature_C[i];
      line_ss += std::pow(y - icept - slope * t / span, 2);
      full_ss += std::pow(y - beta[0] - beta[1] * t / span - beta[2] * std::sin(omega * t) - beta[3] * std::cos(omega * t), 2);
    }
    out.explained = std::max(line_ss - full_ss, 0.0);
  }
  return out;
}

// The ambient linearly interpolated at `times_s` (both from the run's start), as T.
template <typename T>
std::vector<T> at_times(const std::vector<double>& from_s, const std::vector<T>& values, const std::vector<double>& times_s) {
  std::vector<T> out(times_s.size(), T(0.0));
  std::size_t k = 0;
  for (std::size_t i = 0; i < times_s.size(); ++i) {
    while (k + 2 < from_s.size() && from_s[k + 1] <= times_s[i]) ++k;
    if (from_s.size() == 1) {
      out[i] = values[0];
      continue;
    }
    const double w = std::clamp((times_s[i] - from_s[k]) / (from_s[k + 1] - from_s[k]), 0.0, 1.0);
    out[i] = values[k] * (1 - w) + values[k + 1] * w;
  }
  return out;
}

// φ of a term at the run's times (rise_time: t / 1 h, which the caller multiplies by the
// simulated rise), for the scale `scale_s` (P or τ; ignored by the kinds without one).
template <typename T>
std::vector<T> sensor_term_regressor(ThermalTermKind kind, const T& scale_s, const std::vector<double>& times_s,
                                     const AmbientTrace& ambient, double velocity_m_s) {
  using std::sin, std::cos;
  std::vector<T> phi(times_s.size(), T(0.0));
  const double t0 = ambient.time_s.empty() ? 0.0 : ambient.time_s.front();
  switch (kind) {
    case ThermalTermKind::time:
    case ThermalTermKind::rise_time:
    case ThermalTermKind::time_squared:
    case ThermalTermKind::velocity_time:
      for (std::size_t i = 0; i < times_s.size(); ++i) {
        const double h = times_s[i] / kSecondsPerHour;
        phi[i] = T(kind == ThermalTermKind::time_squared ? h * h : kind == ThermalTermKind::velocity_time ? velocity_m_s * h : h);
      }
      break;
    case ThermalTermKind::ambient_in_phase:
    case ThermalTermKind::ambient_quadrature: {
      const PeriodicComponent<T> c = periodic_component(ambient, scale_s);
      const T omega = 2 * std::numbers::pi / scale_s;
      const bool in_phase = kind == ThermalTermKind::ambient_in_phase;
      for (std::size_t i = 0; i < times_s.size(); ++i) {
        const T s = sin(omega * (times_s[i] - t0)), k = cos(omega * (times_s[i] - t0));
        phi[i] = in_phase ? c.in_phase * s + c.quadrature * k : c.in_phase * k - c.quadrature * s;
      }
      break;
    }
    case ThermalTermKind::ambient_lag: {
      std::vector<T> series(ambient.temperature_C.begin(), ambient.temperature_C.end());
      std::vector<T> lagged = first_order_lag(ambient.time_s, series, scale_s);
      for (std::size_t i = 0; i < series.size(); ++i) lagged[i] -= series[i];
      phi = at_times(ambient.time_s, lagged, times_s);
      break;
    }
    case ThermalTermKind::ambient_change: {
      std::vector<T> series(ambient.temperature_C.size());
      for (std::size_t i = 0; i < series.size(); ++i) series[i] = T(ambient.temperature_C[i] - ambient.temperature_C.front());
      phi = at_times(ambient.time_s, series, times_s);
      break;
    }
  }
  return phi;
}

}  // namespace lmcal::detail
