// The friction residual functor (private to the fit layer), shared by two translation units:
// friction_model.cc instantiates it for the law with its effects, friction_term_model.cc for
// the law with empirical terms. Kept apart because the hot row loop of the first must be
// compiled where the compiler still inlines the Jet arithmetic: with the terms' code in the
// same file, GCC stopped inlining Eigen's Jet assignments and the 100 k-sample diagnosis took
// 60 % longer.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <vector>

#include "batched_autodiff.hpp"
#include "friction_model.hpp"

namespace lmcal::detail {

// r_j = (F_measured - F_model(θ)) / σ for entry `rows[j]` of `data` (entry j when `rows` is
// empty). θ = [k1, k2, μSt, V_St, μv, β, f0, effects..., terms...]: the one friction law, with
// Jets; kTerms: with the empirical terms of data.terms.
template <bool kTerms>
struct FrictionResidual {
  const FrictionData* data;
  std::vector<std::size_t> rows;
  std::vector<std::size_t> effect_slots;

  template <typename T>
  struct Prepared {
    FrictionConstants<T> k;
    FrictionEffects<T> e;
    const T* terms = nullptr;    // the terms' parameters
    std::vector<T> lag_change;   // lag_τ(T) - T per log row, when a term lags the temperature
    // ν(T) (Eq. 6) at the oil and temperature of the last row that needed it: the rows of a run
    // or a set point share them, and an exp per row and pass was a tenth of a fit's time. The
    // same bits as computing it again (the same operations on the same values).
    std::uint64_t nu40_bits = 0, temperature_bits = 0;
    bool has_viscosity = false;
    T viscosity{};
    // Likewise the Stribeck decay at the speed of the last row: a log at set speeds holds each
    // for a stretch of samples.
    std::uint64_t velocity_bits = 0;
    bool has_decay = false;
    T decay{};

    // k with ν_ref = nu40 (the row's oil), and ν at temperature_C.
    const T& viscosity_at(double nu40, double temperature_C) {
      k.nu_ref_mm2_s = T(nu40);
      const auto nu40_now = std::bit_cast<std::uint64_t>(nu40), temperature_now = std::bit_cast<std::uint64_t>(temperature_C);
      if (!has_viscosity || nu40_now != nu40_bits || temperature_now != temperature_bits) {
        viscosity = viscosity_mm2_s(k, temperature_C);
        nu40_bits = nu40_now, temperature_bits = temperature_now, has_viscosity = true;
      }
      return viscosity;
    }

    // exp(−V/V_St) at velocity_m_s.
    const T& decay_at(double velocity_m_s) {
      const auto velocity_now = std::bit_cast<std::uint64_t>(velocity_m_s);
      if (!has_decay || velocity_now != velocity_bits) {
        decay = stribeck_decay(k, velocity_m_s);
        velocity_bits = velocity_now, has_decay = true;
      }
      return decay;
    }
  };

  template <typename T>
  Prepared<T> prepare(const T* th) const {
    Prepared<T> p{{th[0], th[1], th[2], th[3], th[4], th[5], th[6], T(99.0), T(data->T_ref_C)}, {}};
    for (std::size_t m = 0; m < effect_slots.size(); ++m) p.e[effect_slots[m]] = th[FrictionConstants<double>::kFittable + m];
    if constexpr (kTerms) {
      p.terms = th + FrictionConstants<double>::kFittable + effect_slots.size();
      std::size_t at = 0;
      for (const auto& term : *data->terms) {
        if (term.lagged_temperature()) p.lag_change = lagged_temperature_change(*data->log, *data->series, p.terms[at + 1]);
        at += term.has_scale() ? 2 : 1;
      }
    }
    return p;
  }

  // The published law alone (no effects, no terms) has a closed-form gradient.
  // So has the law with effects that add a force of their own parameters only, free of the
  // law's (closed_form_effect): the drive's terms of a trajectory (moving_mass, axis_gravity)
  // and the effects along its travel (position_ripple, presliding, with their parts). A 10⁶-sample
  // trajectory fit's normal-equation pass took 104 ms in Jet<8>, ~35 ms so; a diagnosis's ripple
  // and pre-sliding candidates (Jet<12>, 15 iterations on a tenth of the rows and 15 on all)
  // about a fifth less.
  bool analytic() const {
    return !kTerms && std::all_of(effect_slots.begin(), effect_slots.end(), closed_form_effect);
  }
  static bool closed_form_effect(std::size_t slot) {
    using L = FrictionEffectLibrary;
    for (const std::size_t s : {L::slot_of<MovingMass>(), L::slot_of<AxisGravity>(), L::slot_of<PositionRipple>(),
                                L::slot_of<PositionRipplePeriod>(), L::slot_of<PositionRipplePhase>(), L::slot_of<Presliding>(),
                                L::slot_of<PreslidingDistance>()})
      if (slot == s) return true;
    return false;
  }

  // ∂F/∂(each effect of `effect_slots`) at conditions c into g, for the closed-form effects (see
  // correction_N in each one's header): M a·direction; G·direction; with θ = 2πx/λ + φ, sin θ,
  // A cos θ · (−2πx/λ²) and A cos θ; with E = exp(−s/s0), −E and −ΔF E s/s0². The ripple's
  // angle and the pre-sliding decay once per row, only where fitted.
  void effect_gradient(const FrictionEffects<double>& e, const FrictionConditions<double>& c, double w, double* g) const {
    using L = FrictionEffectLibrary;
    const auto fitted = [&](std::size_t slot) { return std::find(effect_slots.begin(), effect_slots.end(), slot) != effect_slots.end(); };
    double sine = 0, cosine = 0, turns = 0, decay = 0;
    const double period = e.of<PositionRipplePeriod>(), distance = e.of<PreslidingDistance>();
    if (fitted(L::slot_of<PositionRipple>()) || fitted(L::slot_of<PositionRipplePeriod>()) ||
        fitted(L::slot_of<PositionRipplePhase>())) {
      turns = 2 * std::numbers::pi * c.position_m / period;
      const double angle = turns + e.of<PositionRipplePhase>();
      sine = std::sin(angle), cosine = std::cos(angle);
    }
    if (fitted(L::slot_of<Presliding>()) || fitted(L::slot_of<PreslidingDistance>()))
      decay = std::exp(-c.distance_since_reversal_m / distance);
    for (std::size_t m = 0; m < effect_slots.size(); ++m) {
      const std::size_t slot = effect_slots[m];
      double d = 0;
      if (slot == L::slot_of<MovingMass>()) d = c.acceleration_m_s2 * c.direction;
      else if (slot == L::slot_of<AxisGravity>()) d = c.direction;
      else if (slot == L::slot_of<PositionRipple>()) d = sine;
      else if (slot == L::slot_of<PositionRipplePeriod>()) d = e.of<PositionRipple>() * cosine * (-turns / period);
      else if (slot == L::slot_of<PositionRipplePhase>()) d = e.of<PositionRipple>() * cosine;
      else if (slot == L::slot_of<Presliding>()) d = -decay;
      else d = -e.of<Presliding>() * decay * c.distance_since_reversal_m / (distance * distance);  // PreslidingDistance
      g[FrictionConstants<double>::kFittable + m] = w * d;
    }
  }

  // Residual of entry j and its gradient over θ = [k1, k2, μSt, V_St, μv, β, f0] (Eqs. 3-7):
  // with x = T - T_ref, ν = ν_ref e^{-βx}, E = e^{-V/V_St}, S = μSt pc Lb E / ν (Stribeck),
  //   ∂F/∂k1 = P/1000, ∂F/∂k2 = -pc P/1000, ∂F/∂μSt = S/μSt, ∂F/∂V_St = S V/V_St²,
  //   ∂F/∂μv = Lb pc V ν, ∂F/∂β = x (S - μv Lb pc V ν), ∂F/∂f0 = Lb;
  // then the closed-form effects' (effect_gradient).
  double gradient(Prepared<double>& p, std::size_t j, double* g) const {
    const std::size_t entry = rows.empty() ? j : rows[j];
    const std::size_t i = data->samples[entry];
    const FrictionLog& log = *data->log;
    const FrictionConditions<double> c = log.conditions(i);
    const double nu_at_T = p.viscosity_at(log.viscosity40_mm2_s[i], c.temperature_C);
    const FrictionConstants<double>& k = p.k;
    // The law's value from its one definition (the residual-only evaluation computes the
    // same, to the last bit), the derivatives from its pieces.
    const FrictionBreakdown<double> b = friction_breakdown_given(k, c, nu_at_T, p.decay_at(c.velocity_m_s));
    const double x = c.temperature_C - k.T_ref_C, nu = b.viscosity_mm2_s;
    const double pc = c.preload_um, Lb = c.block_length_mm, V = c.velocity_m_s;
    const double viscous_per_mu = Lb * pc * V * nu, stribeck_per_mu = pc * Lb / nu * b.stribeck_decay;
    const double w = -data->inv_sigma[entry];  // r = (F_measured - F) / σ
    g[0] = w * c.load_N * 1e-3;
    g[1] = -w * pc * c.load_N * 1e-3;
    g[2] = w * stribeck_per_mu;
    g[3] = w * k.mu_st * stribeck_per_mu * V / (k.v_st_m_s * k.v_st_m_s);
    g[4] = w * viscous_per_mu;
    g[5] = w * x * (k.mu_st * stribeck_per_mu - k.mu_v * viscous_per_mu);
    g[6] = w * Lb;
    if (effect_slots.empty()) return (log.friction_N[i] - b.total_N()) * data->inv_sigma[entry];
    effect_gradient(p.e, c, w, g);
    // The value as the residual-only evaluation computes it, to the last bit.
    return (log.friction_N[i] - friction_force_with_effects_N(k, p.e, c, b)) * data->inv_sigma[entry];
  }

  template <typename T>
  T operator()(Prepared<T>& p, std::size_t j) const {
    const std::size_t entry = rows.empty() ? j : rows[j];
    const std::size_t i = data->samples[entry];
    const FrictionLog& log = *data->log;
    if constexpr (kTerms) {
      p.k.nu_ref_mm2_s = T(log.viscosity40_mm2_s[i]);
      const T predicted = friction_with_terms_N(p.k, p.e, log, *data->series, i, *data->terms, p.terms,
                                                p.lag_change.empty() ? nullptr : &p.lag_change);
      return (log.friction_N[i] - predicted) * data->inv_sigma[entry];
    } else {
      const FrictionConditions<double> c = log.conditions(i);
      const auto b = friction_breakdown_given(p.k, c, p.viscosity_at(log.viscosity40_mm2_s[i], c.temperature_C),
                                              p.decay_at(c.velocity_m_s));
      const T predicted = effect_slots.empty() ? T(b.total_N()) : T(friction_force_with_effects_N(p.k, p.e, c, b));
      return (log.friction_N[i] - predicted) * data->inv_sigma[entry];
    }
  }
};

// The cost function of the law with empirical terms (friction_term_model.cc).
std::unique_ptr<ceres::CostFunction> term_cost_function(const FrictionData& data, const std::vector<std::size_t>& rows,
                                                        const std::vector<std::size_t>& effect_slots, int parameters,
                                                        std::size_t n, const RowLoss& loss, std::vector<std::size_t> groups);

}  // namespace lmcal::detail
