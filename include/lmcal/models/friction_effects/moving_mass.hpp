// The moving mass M of a trajectory log: the drive's force carries M·a besides friction, so
// read in the motion's sense (F·direction) it is F_fric + M·a·direction. Identified jointly with
// the friction constants on the whole trajectory (the inverse-dynamic model, PHYSICS.md §8);
// with moving_mass_kg given and taken off by the reader, it is that mass's error. Separable
// from friction only where the acceleration varies independently of the speed.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"

namespace LMCAL_API lmcal {

struct MovingMass {
  static constexpr FrictionEffectInfo info{"moving_mass", "kg", "moving mass M of a trajectory: + M a direction (inertia)",
                                           0.0, -1e4, 1e5, 10.0,
                                           "accelerations that differ at one speed (moves of several accelerations)",
                                           true};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>&, const FrictionConditions<C>& c, const B&, const Total&,
                           const E& mass_kg) {
    return mass_kg * c.acceleration_m_s2 * c.direction;
  }
};

}  // namespace lmcal
