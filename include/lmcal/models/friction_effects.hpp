// The library of friction effects (see friction_effect.hpp for what one is) and the
// published law with them applied. Register a new effect here: its include and one line
// in FrictionEffectLibrary.
//
//   F = F_law + Σ on_law corrections       (each from the law's own terms)
//   F ← F + Σ on_total corrections          (each from that F)
//
// FrictionEffects<T> holds one value per registered effect, neutral by default, so the
// published law is FrictionEffects<double>{}. Values are addressed by slot (the effect's
// place in the library), by type (`e.of<SealDrag>()`) or by name (friction_effect_slot).
#pragma once

#include "lmcal/export.hpp"

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>
#include <utility>

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"
#include "lmcal/models/friction_effects/axis_gravity.hpp"
#include "lmcal/models/friction_effects/coulomb_temperature.hpp"
#include "lmcal/models/friction_effects/direction_asymmetry.hpp"
#include "lmcal/models/friction_effects/moving_mass.hpp"
#include "lmcal/models/friction_effects/moving_mass_error.hpp"
#include "lmcal/models/friction_effects/position_ripple.hpp"
#include "lmcal/models/friction_effects/presliding.hpp"
#include "lmcal/models/friction_effects/seal_drag.hpp"
#include "lmcal/models/friction_effects/seal_drag_block.hpp"
#include "lmcal/models/friction_effects/signed_zero_offset.hpp"
#include "lmcal/models/friction_effects/stribeck_exponent.hpp"
#include "lmcal/models/friction_effects/viscous_direction.hpp"
#include "lmcal/models/friction_effects/viscous_load.hpp"

namespace LMCAL_API lmcal {

template <class... Effects>
struct FrictionEffectList {
  static constexpr std::size_t size = sizeof...(Effects);
  static constexpr std::array<FrictionEffectInfo, size> infos{Effects::info...};

  template <class Effect>
  static constexpr std::size_t slot_of() {
    constexpr bool match[] = {std::is_same_v<Effect, Effects>...};
    for (std::size_t i = 0; i < size; ++i)
      if (match[i]) return i;
    return size;
  }

  // f.template operator()<Effect, slot>() for each effect, in library order.
  template <class F>
  static constexpr void for_each(F&& f) {
    [&]<std::size_t... slot>(std::index_sequence<slot...>) {
      (f.template operator()<Effects, slot>(), ...);
    }(std::index_sequence_for<Effects...>{});
  }
};

using FrictionEffectLibrary = FrictionEffectList<
    StribeckExponent,
    ViscousLoad,
    DirectionAsymmetry,
    SealDrag,
    CoulombTemperature,
    SealDragBlock,
    SignedZeroOffset,
    MovingMass,
    AxisGravity,
    ViscousDirection,
    MovingMassError,
    PositionRipple,
    PositionRipplePeriod,
    PositionRipplePhase,
    Presliding,
    PreslidingDistance>;

inline constexpr std::size_t kFrictionEffectCount = FrictionEffectLibrary::size;

// The number of parts (shape parameters) of an effect: library entries right after it.
template <class Effect>
constexpr std::size_t friction_effect_parts() {
  if constexpr (requires { Effect::kParts; }) return Effect::kParts;
  else return 0;
}
constexpr bool is_friction_effect_part(const FrictionEffectInfo& info) { return info.part_of[0] != '\0'; }

namespace detail {
constexpr bool same_name(const char* a, const char* b) {
  for (; *a != '\0' && *a == *b; ++a, ++b) {
  }
  return *a == *b;
}
// Every part follows its effect, and every entry after an effect within its kParts is its part.
constexpr bool parts_follow_their_effects() {
  bool ok = true;
  FrictionEffectLibrary::for_each([&]<class Effect, std::size_t slot>() {
    for (std::size_t p = 1; p <= friction_effect_parts<Effect>(); ++p)
      ok = ok && slot + p < kFrictionEffectCount && same_name(FrictionEffectLibrary::infos[slot + p].part_of, Effect::info.name);
  });
  std::size_t claimed = 0;  // parts claimed by the effects before
  FrictionEffectLibrary::for_each([&]<class Effect, std::size_t slot>() {
    if (is_friction_effect_part(Effect::info)) ok = ok && claimed > 0, --claimed;
    else claimed = friction_effect_parts<Effect>();
  });
  return ok;
}
}  // namespace detail
static_assert(detail::parts_follow_their_effects(), "an effect's parts are registered right after it, naming it");

// The slot of a named effect, or none.
constexpr std::optional<std::size_t> find_friction_effect(std::string_view name) {
  for (std::size_t i = 0; i < kFrictionEffectCount; ++i)
    if (name == FrictionEffectLibrary::infos[i].name) return i;
  return std::nullopt;
}
// The slot of a named effect; InvalidParameter naming the known ones for an unknown name.
std::size_t friction_effect_slot(std::string_view name);

template <typename T>
struct FrictionEffects {
  std::array<T, kFrictionEffectCount> values;

  FrictionEffects() {
    for (std::size_t i = 0; i < kFrictionEffectCount; ++i) values[i] = T(FrictionEffectLibrary::infos[i].neutral);
  }
  T& operator[](std::size_t slot) { return values[slot]; }
  const T& operator[](std::size_t slot) const { return values[slot]; }
  template <class Effect>
  T& of() {
    return values[FrictionEffectLibrary::slot_of<Effect>()];
  }
  template <class Effect>
  const T& of() const {
    return values[FrictionEffectLibrary::slot_of<Effect>()];
  }
};

// `names` with every effect's parts right after it (those not already given), `starts` (a fit's
// effect_start, in the order of `names`) with the parts' neutral values inserted where it
// reaches. An effect is fitted with its shape (friction_effect.hpp).
void with_effect_parts(std::vector<std::string>& names, std::vector<double>* starts = nullptr);

// The law's parameter called `name`: a fittable constant of `k` or an effect of `e`; nullptr for
// another name.
template <typename T>
T* find_law_parameter(FrictionConstants<T>& k, FrictionEffects<T>& e, std::string_view name) {
  if (const auto j = find_friction_constant(name)) return &fittable_constant(k, *j);
  if (const auto slot = find_friction_effect(name)) return &e[*slot];
  return nullptr;
}
template <typename T>
const T* find_law_parameter(const FrictionConstants<T>& k, const FrictionEffects<T>& e, std::string_view name) {
  return find_law_parameter(const_cast<FrictionConstants<T>&>(k), const_cast<FrictionEffects<T>&>(e), name);
}

namespace detail {
// An effect at its neutral value that is not being fitted (a double, or a Jet without
// derivatives) adds exactly nothing, for every condition and every value of its parts
// (friction_effect.hpp's trap): it is skipped, so that the library's unused effects cost a fit
// nothing. A fitted one is evaluated even at its neutral start (its derivative is not zero).
template <typename T>
bool held_neutral(const T& value, double neutral) {
  if constexpr (requires { value.a; value.v.isZero(); }) return value.a == neutral && value.v.isZero();
  else return value == neutral;
}
}  // namespace detail

// The published law with every effect of `e` applied, N, from the law's terms at c
// (friction_breakdown(k, c), computed by the caller).
template <typename P, typename C, typename E, typename B>
auto friction_force_with_effects_N(const FrictionConstants<P>& k, const FrictionEffects<E>& e,
                                   const FrictionConditions<C>& c, const FrictionBreakdown<B>& b) {
  const auto law_N = b.total_N();
  using R = decltype(law_N * e[0]);
  R total(law_N);
  auto add_stage = [&](FrictionEffectStage stage, const auto& reference_N) {
    FrictionEffectLibrary::for_each([&]<class Effect, std::size_t slot>() {
      if constexpr (!is_friction_effect_part(Effect::info)) {
        if (Effect::stage == stage && !detail::held_neutral(e[slot], Effect::info.neutral))
          total = total + [&]<std::size_t... part>(std::index_sequence<part...>) {
            return Effect::correction_N(k, c, b, reference_N, e[slot], e[slot + 1 + part]...);
          }(std::make_index_sequence<friction_effect_parts<Effect>()>{});
      }
    });
  };
  add_stage(FrictionEffectStage::on_law, law_N);
  const R with_law_effects = total;
  add_stage(FrictionEffectStage::on_total, with_law_effects);
  return total;
}

// The published law with every effect of `e` applied, N.
template <typename P, typename C, typename E>
auto friction_force_with_effects_N(const FrictionConstants<P>& k, const FrictionEffects<E>& e,
                                   const FrictionConditions<C>& c) {
  return friction_force_with_effects_N(k, e, c, friction_breakdown(k, c));
}

// Eqs. 9-10 with the effects: Q_f = F · V, W.
template <typename P, typename C, typename E>
auto heat_rate_with_effects_W(const FrictionConstants<P>& k, const FrictionEffects<E>& e, const FrictionConditions<C>& c) {
  return friction_force_with_effects_N(k, e, c) * c.velocity_m_s;
}

}  // namespace lmcal
