// Friction mechanisms the published law (friction.hpp) leaves out, each a correction to
// the terms of Eq. 7 with its own parameter, neutral at zero (or one). The virtual rig
// switches them on to make data with a known truth; the discrepancy analysis fits them.
// See shared/PHYSICS.md §1a and §7.
//
//   Stribeck shape     f_St · exp(r - r^δ),  r = V / V_St      (δ = 1: Eq. 5)
//   load-dependent μv  + c_P · (P / 1 kN) · Lb μv pc V ν       (μv grows with load)
//   direction          F · (1 + a · direction)                  (a = asymmetry, ±)
//   seal drag          + c_s · V²                               (N per (m/s)²)
//   Coulomb(T)         + f_C · c_T · (T - T_i)                  (1/K)
//
// All templated like the law itself, so the same code serves data generation and fits.
// Trap: the Stribeck exponent is evaluated as exp(δ ln r); at V = 0 the correction is
// exactly 1 and its derivative with respect to δ is taken as 0.
#pragma once

#include <cmath>

#include "lmcal/models/friction.hpp"

namespace lmcal {

template <typename T>
struct FrictionEffects {
  T stribeck_exponent{1.0};           // δ
  T viscous_load_per_kN{0.0};         // c_P
  T direction_asymmetry{0.0};         // a
  T seal_drag_N_s2_m2{0.0};           // c_s
  T coulomb_temperature_per_K{0.0};   // c_T
};

// Each correction returns the force it adds (N) to the published law's breakdown `b`.
template <typename P, typename C, typename B, typename E>
auto stribeck_shape_correction_N(const FrictionConstants<P>& k, const FrictionConditions<C>& c, const B& b,
                                 const E& exponent) {
  using std::exp;
  using std::log;
  const auto r = c.velocity_m_s / k.v_st_m_s;
  if (!(r > 0.0)) return b.stribeck_N * 0.0 * exponent;
  return b.stribeck_N * (exp(r - exp(exponent * log(r))) - 1.0);
}

template <typename P, typename C, typename B, typename E>
auto viscous_load_correction_N(const FrictionConstants<P>& k, const FrictionConditions<C>& c, const B& b,
                               const E& per_kN) {
  const auto velocity_part = b.viscous_N - c.block_length_mm * k.f0;  // Lb μv pc V ν
  return per_kN * (c.load_N * 1e-3) * velocity_part;
}

template <typename C, typename Total, typename E>
auto direction_correction_N(const FrictionConditions<C>& c, const Total& total_N, const E& asymmetry) {
  return total_N * asymmetry * c.direction;
}

template <typename C, typename E>
auto seal_drag_correction_N(const FrictionConditions<C>& c, const E& coefficient) {
  return coefficient * c.velocity_m_s * c.velocity_m_s;
}

template <typename P, typename C, typename B, typename E>
auto coulomb_temperature_correction_N(const FrictionConstants<P>& k, const FrictionConditions<C>& c, const B& b,
                                      const E& per_K) {
  return b.coulomb_N * per_K * (c.temperature_C - k.T_ref_C);
}

// The published law with every effect of `e` applied (the direction factor last, on the total).
template <typename P, typename C, typename E>
auto friction_force_with_effects_N(const FrictionConstants<P>& k, const FrictionEffects<E>& e,
                                   const FrictionConditions<C>& c) {
  const auto b = friction_breakdown(k, c);
  const auto without_direction = b.total_N() + stribeck_shape_correction_N(k, c, b, e.stribeck_exponent) +
                                 viscous_load_correction_N(k, c, b, e.viscous_load_per_kN) +
                                 seal_drag_correction_N(c, e.seal_drag_N_s2_m2) +
                                 coulomb_temperature_correction_N(k, c, b, e.coulomb_temperature_per_K);
  return without_direction + direction_correction_N(c, without_direction, e.direction_asymmetry);
}

// Eqs. 9-10 with the effects: Q_f = F · V, W.
template <typename P, typename C, typename E>
auto heat_rate_with_effects_W(const FrictionConstants<P>& k, const FrictionEffects<E>& e, const FrictionConditions<C>& c) {
  return friction_force_with_effects_N(k, e, c) * c.velocity_m_s;
}

}  // namespace lmcal
