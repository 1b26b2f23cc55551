// Friction force of a roller LM block and the heat it generates.
// Cheng et al. (2017), Eqs. 3-10; see shared/PHYSICS.md §2-3.
//
//   ν(T)       = ν_i · exp(-β (T - T_i))                               (Eq. 6)
//   f_Coulomb  = (k1 - k2·pc) · P · 1e-3                                (Eq. 3)
//   f_Viscous  = Lb · (μv · pc · V · ν(T) + f0)                         (Eq. 4)
//   f_Stribeck = μSt · pc · Lb / ν(T) · exp(-V / V_St)                  (Eq. 5)
//   F_f        = f_Coulomb + f_Stribeck + f_Viscous                     (Eq. 7)
//   Q_f        = η · F_f · V,  η = 1                                    (Eqs. 9-10)
//
// Units are the paper's, because its constants are defined in them, and every
// field says which: P in N, pc in µm, Lb in mm, V in m/s, ν in mm²/s, T in °C,
// F in N, Q in W. The printed Eq. 8 repeats Lb inside the viscous term; that is
// a typo (it would give ~1.7 kN), and this file follows Eq. 4.
//
// Everything is templated on the scalar so that one copy of the law serves
// double (simulation) and ceres::Jet (fits). Parameters and conditions may use
// different scalars (fit the constants at measured conditions, or propagate a
// derivative through the temperature in a coupled thermal model).
//
// Example (PHYSICS.md sanity figure):
//   lmcal::FrictionConditions<double> c{.load_N = 3000, .preload_um = 4,
//       .block_length_mm = 120.2, .velocity_m_s = 0.11, .temperature_C = 26};
//   double F = lmcal::friction_force_N(lmcal::paper_friction_constants(), c);  // ≈ 44.2 N
//
// Trap: V is a speed (>= 0). Direction, if it matters, is a separate model term;
// a negative V here makes the viscous term negative and the Stribeck term blow up.
#pragma once

#include "lmcal/export.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "lmcal/io/friction_conditions.hpp"

namespace LMCAL_API lmcal {

// The seven friction constants of Eq. 8 plus the viscosity reference point of Eq. 6.
template <typename T>
struct FrictionConstants {
  T k1{};                  // Coulomb coefficient, (N per kN of load)
  T k2{};                  // preload reduction of k1, per µm
  T mu_st{};               // Stribeck coefficient, N·mm²/s per (µm·mm)
  T v_st_m_s{};            // Stribeck velocity, m/s
  T mu_v{};                // viscous coefficient, N per (mm·µm·m/s·mm²/s)
  T beta_per_K{};          // viscosity-temperature coefficient, 1/K
  T f0{};                  // seal/viscous offset, N per mm of block length
  T nu_ref_mm2_s{99.0};    // ν_i: viscosity at the reference temperature (ISO VG ~100)
  T T_ref_C{40.0};         // T_i: reference temperature

  // Number of constants that a fit may free (the first seven members, in order).
  static constexpr std::size_t kFittable = 7;

  template <typename U>
  FrictionConstants<U> cast() const {
    return {U(k1), U(k2), U(mu_st), U(v_st_m_s), U(mu_v), U(beta_per_K), U(f0), U(nu_ref_mm2_s),
            U(T_ref_C)};
  }
};

// Names of the seven fittable constants, in the order of FrictionConstants.
inline constexpr std::array<const char*, FrictionConstants<double>::kFittable> kFrictionConstantNames = {
    "k1", "k2", "mu_st", "v_st_m_s", "mu_v", "beta_per_K", "f0"};

// The index of a fittable constant by name (into kFrictionConstantNames), or none.
constexpr std::optional<std::size_t> find_friction_constant(std::string_view name) {
  for (std::size_t j = 0; j < kFrictionConstantNames.size(); ++j)
    if (name == kFrictionConstantNames[j]) return j;
  return std::nullopt;
}
// The same, or InvalidParameter naming `parameter` (the option or key it came from) and the constants.
std::size_t friction_constant_index(const std::string& parameter, std::string_view name);

// The j-th fittable constant, in the order of kFrictionConstantNames (j < kFittable).
template <typename T>
T& fittable_constant(FrictionConstants<T>& k, std::size_t j) {
  T* members[] = {&k.k1, &k.k2, &k.mu_st, &k.v_st_m_s, &k.mu_v, &k.beta_per_K, &k.f0};
  return *members[j];
}
template <typename T>
const T& fittable_constant(const FrictionConstants<T>& k, std::size_t j) {
  return fittable_constant(const_cast<FrictionConstants<T>&>(k), j);
}

// The identified constants of Eq. 8, with ν_i = 99 mm²/s at T_i = 40 °C.
inline FrictionConstants<double> paper_friction_constants() {
  return {.k1 = 0.315,
          .k2 = 0.03,
          .mu_st = 1.52,
          .v_st_m_s = 0.015,
          .mu_v = 0.003,
          .beta_per_K = 0.067,
          .f0 = 0.029,
          .nu_ref_mm2_s = 99.0,
          .T_ref_C = 40.0};
}

// The three terms of Eq. 7, kept apart for plots and diagnostics.
template <typename T>
struct FrictionBreakdown {
  T viscosity_mm2_s;
  T stribeck_decay;  // exp(-V / V_St)
  T coulomb_N;
  T stribeck_N;
  T viscous_N;
  T total_N() const { return coulomb_N + stribeck_N + viscous_N; }
};

// Eq. 6.
template <typename P, typename C>
auto viscosity_mm2_s(const FrictionConstants<P>& k, const C& temperature_C) {
  using std::exp;
  return k.nu_ref_mm2_s * exp(-k.beta_per_K * (temperature_C - k.T_ref_C));
}

// The Stribeck decay of Eq. 4, exp(−V/V_St).
template <typename P, typename C>
auto stribeck_decay(const FrictionConstants<P>& k, const C& velocity_m_s) {
  using std::exp;
  return exp(-velocity_m_s / k.v_st_m_s);
}

// Eqs. 3-5 and 7, term by term, at the viscosity `nu` = ν(T) that Eq. 6 gives at c's temperature
// and the Stribeck decay `decay` at c's speed (a fit computes each once for the rows that share
// a temperature or a speed). The scalar of the result is whatever P ⊗ C promotes to.
template <typename P, typename C, typename N, typename D>
auto friction_breakdown_given(const FrictionConstants<P>& k, const FrictionConditions<C>& c, const N& nu, const D& decay) {
  using R = decltype(std::declval<P>() * std::declval<C>());
  FrictionBreakdown<R> out;
  out.viscosity_mm2_s = nu;
  out.stribeck_decay = decay;
  out.coulomb_N = (k.k1 - k.k2 * c.preload_um) * c.load_N * 1e-3;
  out.viscous_N = c.block_length_mm * (k.mu_v * c.preload_um * c.velocity_m_s * nu + k.f0);
  out.stribeck_N = k.mu_st * c.preload_um * c.block_length_mm / nu * out.stribeck_decay;
  return out;
}

// The same at the viscosity `nu` alone.
template <typename P, typename C, typename N>
auto friction_breakdown_at_viscosity(const FrictionConstants<P>& k, const FrictionConditions<C>& c, const N& nu) {
  return friction_breakdown_given(k, c, nu, stribeck_decay(k, c.velocity_m_s));
}

// Eqs. 3-7, term by term.
template <typename P, typename C>
auto friction_breakdown(const FrictionConstants<P>& k, const FrictionConditions<C>& c) {
  return friction_breakdown_at_viscosity(k, c, viscosity_mm2_s(k, c.temperature_C));
}

// Eq. 7: total friction force, N.
template <typename P, typename C>
auto friction_force_N(const FrictionConstants<P>& k, const FrictionConditions<C>& c) {
  return friction_breakdown(k, c).total_N();
}

// Eqs. 9-10: frictional heat rate Q_f = η F_f V, W, with η = 1 (all friction becomes heat).
// The rail receives α·Q_f of it, the block the rest.
template <typename P, typename C>
auto heat_rate_W(const FrictionConstants<P>& k, const FrictionConditions<C>& c) {
  return friction_force_N(k, c) * c.velocity_m_s;
}

// Refuses non-physical values (NaN, negative load/preload/speed, non-positive block
// length, ν_ref or V_St) with lmcal::InvalidParameter naming the parameter and value.
void validate(const FrictionConstants<double>& k);
void validate(const FrictionConditions<double>& c);

}  // namespace lmcal
