// An error ΔM of the moving mass a log's force was corrected with: the reader took M·a off the
// force (moving_mass_kg given), or a plateau log's acceleration column shows a force ∝ a that
// nobody took off. Read in the motion's sense it is + ΔM·a·direction, the moving_mass term's own
// form. A cause only where the mass is not fitted anyway: a trajectory fits its moving mass
// with the law (moving_mass, a drive term), which then is the given mass's error itself.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"
#include "lmcal/models/friction_effects/moving_mass.hpp"

namespace LMCAL_API lmcal {

struct MovingMassError {
  static constexpr FrictionEffectInfo info{"moving_mass_error", "kg", "error of the mass taken off: + ΔM a direction",
                                           0.0, -1e3, 1e3, 1.0,
                                           "the moving parts weighed, and accelerations that differ at one speed",
                                           false, "acceleration_m_s2"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>& k, const FrictionConditions<C>& c, const B& b, const Total& total_N,
                           const E& error_kg) {
    return MovingMass::correction_N(k, c, b, total_N, error_kg);
  }
};

}  // namespace lmcal
