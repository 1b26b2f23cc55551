// Pre-sliding after a reversal: F ← F − ΔF exp(−s / s0), s the travel since the carriage last
// reversed or rested (FrictionConditions::distance_since_reversal_m). A one-state, first-order
// form of the Dahl / generalised Maxwell-slip behaviour of rolling guides: over the first
// micrometres to millimetres after a reversal the rolling elements act as a spring and the
// friction rises by ΔF towards its sliding level with a characteristic distance s0 (PHYSICS.md
// §8; Dahl from −F_c to +F_c is ΔF = 2 F_c). ΔF is the effect's value (N, neutral 0); s0 its part
// (friction_effect.hpp). Shows on trajectories with reversals, in the first few s0 beyond what
// the reader drops (RawFrictionOptions::presliding_m, 0.5 mm).
// ΔF is a force, not a share of the friction: a share of the law's level trades against the
// runs' zeros (the law's constant part and a run's zero are one constant within a run), so a
// fit with random run zeros could not tell a small share of a large level from a large share.
// Trap: a trajectory's first millimetres after a reversal are also its slowest and most
// accelerated: the Stribeck term and the moving mass compete there; moves at several speeds and
// accelerations separate them (the travel since a reversal at a given speed then differs).
#pragma once

#include "lmcal/export.hpp"

#include <cmath>
#include <cstddef>

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"

namespace LMCAL_API lmcal {

struct PreslidingDistance {
  static constexpr FrictionEffectInfo info{"presliding_distance_m", "m", "distance s0 over which friction rises after a reversal",
                                           1e-3, 1e-5, 0.05, 1e-3,
                                           "trajectories with reversals at several speeds", false, "", "presliding"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;
};

struct Presliding {
  static constexpr FrictionEffectInfo info{"presliding", "N", "friction F - dF exp(-s/s0), s the travel since a reversal",
                                           0.0, -1000.0, 1000.0, 0.5,
                                           "reversals at several speeds and accelerations (the force over the first "
                                           "millimetres after each; a Stribeck or mass effect depends on the speed or "
                                           "the acceleration, not on the travel)",
                                           false, "distance_since_reversal_m"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;
  static constexpr std::size_t kParts = 1;  // PreslidingDistance

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>&, const FrictionConditions<C>& c, const B&, const Total&,
                           const E& deficit_N, const E& distance_m) {
    using std::exp;
    return -deficit_N * exp(-c.distance_since_reversal_m / distance_m);
  }
  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>& k, const FrictionConditions<C>& c, const B& b, const Total& total_N,
                           const E& deficit_N) {
    return correction_N(k, c, b, total_N, deficit_N, E(PreslidingDistance::info.neutral));
  }
};

}  // namespace lmcal
