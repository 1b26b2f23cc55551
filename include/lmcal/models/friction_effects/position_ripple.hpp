// Friction that ripples along the travel: + A sin(2π x / λ + φ), x the carriage's position
// (FrictionConditions::position_m, the log's own origin), the same in both senses. Rolling
// elements entering and leaving the load zone repeat at the roller pitch (a few mm); rail
// waviness at its own wavelength (PHYSICS.md §8). A is the effect's value (N, neutral 0); the
// period λ and the phase φ are its parts (friction_effect.hpp): a diagnosis starts them from a
// periodogram of the residuals against position (src/diagnose/cause_starts.hpp), a plain fit
// from their neutral values (a 5 mm period): give a start near the period
// (`--effect-start`), or the fit stays in the local optimum nearest it.
// Trap: the phase is tied to the position's origin; logs whose origins differ ripple with
// different phases.
#pragma once

#include "lmcal/export.hpp"

#include <cmath>
#include <cstddef>
#include <numbers>

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"

namespace LMCAL_API lmcal {

struct PositionRipplePeriod {
  static constexpr FrictionEffectInfo info{"position_ripple_period_m", "m", "period λ of the ripple along the travel",
                                           0.005, 5e-4, 0.5, 0.005,
                                           "positions over several periods, both senses", false, "", "position_ripple"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;
};

struct PositionRipplePhase {
  static constexpr FrictionEffectInfo info{"position_ripple_phase_rad", "rad", "phase φ of the ripple at x = 0",
                                           0.0, -4 * std::numbers::pi, 4 * std::numbers::pi, 1.0,
                                           "positions over several periods, both senses", false, "", "position_ripple"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;
};

struct PositionRipple {
  static constexpr FrictionEffectInfo info{"position_ripple", "N", "ripple along the travel A sin(2π x/λ + φ)",
                                           0.0, -100.0, 100.0, 0.1,
                                           "the force along the whole travel in both senses at one slow speed (a "
                                           "ripple repeats at one position in both senses, a speed's effect does not)",
                                           false, "position_m"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;
  static constexpr std::size_t kParts = 2;  // PositionRipplePeriod, PositionRipplePhase

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>&, const FrictionConditions<C>& c, const B&, const Total&,
                           const E& amplitude_N, const E& period_m, const E& phase_rad) {
    using std::sin;
    return amplitude_N * sin(2 * std::numbers::pi * c.position_m / period_m + phase_rad);
  }
  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>& k, const FrictionConditions<C>& c, const B& b, const Total& total_N,
                           const E& amplitude_N) {
    return correction_N(k, c, b, total_N, amplitude_N, E(PositionRipplePeriod::info.neutral),
                        E(PositionRipplePhase::info.neutral));
  }
};

}  // namespace lmcal
