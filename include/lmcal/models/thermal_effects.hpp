// Thermal mechanisms the published model leaves out (shared/PHYSICS.md §7), as small
// templated functions the virtual rig and the discrepancy analysis share. The others live
// in the solver itself: heat loss through the base (RailParams::base_loss_W_mK), two-way
// friction-temperature coupling (HeatRateModel), and the source model (SourceModel).
//
//   forced convection   h(V) = h0 + c_V · sqrt(V)     (laminar flat plate: Nu ∝ Re^0.5)
//   α(V)                α(V) = α0 + s_α · (V - V_ref)  V_ref = 0.1 m/s
//   thermocouple lag    τ dy/dt = x - y                (exact for x linear between samples)
#pragma once

#include "lmcal/export.hpp"

#include <cmath>
#include <cstddef>
#include <vector>

namespace LMCAL_API lmcal {

inline constexpr double kAlphaReferenceVelocity_m_s = 0.1;

template <typename T>
T convection_with_velocity(const T& h0_W_m2K, const T& coefficient_W_m2K_per_sqrt_m_s, double velocity_m_s) {
  return h0_W_m2K + coefficient_W_m2K_per_sqrt_m_s * std::sqrt(velocity_m_s);
}

template <typename T>
T alpha_with_velocity(const T& alpha0, const T& slope_per_m_s, double velocity_m_s) {
  return alpha0 + slope_per_m_s * (velocity_m_s - kAlphaReferenceVelocity_m_s);
}

// The reading of a first-order sensor with time constant τ (s) that starts in equilibrium
// with the first sample. τ = 0 returns the input.
template <typename T>
std::vector<T> first_order_lag(const std::vector<double>& time_s, const std::vector<T>& input, const T& tau_s) {
  using std::exp;
  std::vector<T> out(input.size());
  if (input.empty()) return out;
  out[0] = input[0];
  if (!(tau_s > 0.0)) return input;
  for (std::size_t n = 0; n + 1 < input.size(); ++n) {
    const double dt = time_s[n + 1] - time_s[n];
    const T slope = (input[n + 1] - input[n]) / dt;
    const T decay = exp(-dt / tau_s);
    // x(t) = x_n + s (t - t_n)  =>  y(t_n+1) = x_n+1 - s τ + (y_n - x_n + s τ) e^{-Δt/τ}
    out[n + 1] = input[n + 1] - slope * tau_s + (out[n] - input[n] + slope * tau_s) * decay;
  }
  return out;
}

}  // namespace lmcal
