// Direction-dependent viscous slope: μv (1 + d · direction), i.e. the correction
// d · direction · Lb μv pc V ν of the viscous term's velocity part (Eq. 4 without f0). Seals and
// a preload relieved in one sense give a speed slope that differs forward and backward
// (PHYSICS.md §8): the difference grows with the speed, where direction_asymmetry's (a common
// scale of the whole law) is already there at the lowest speed and signed_zero_offset's is
// the same at every speed.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"

namespace LMCAL_API lmcal {

struct ViscousDirection {
  static constexpr FrictionEffectInfo info{"viscous_direction", "1", "viscous slope (1 + d) forward, (1 - d) backward",
                                           0.0, -0.9, 0.9, 0.05,
                                           "both directions at several speeds above 0.05 m/s (a slope that differs by "
                                           "direction, where an asymmetry of the whole force is there at every speed)",
                                           false, "direction"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>& k, const FrictionConditions<C>& c, const B& b, const Total&,
                           const E& difference) {
    const auto velocity_part = b.viscous_N - c.block_length_mm * k.f0;  // Lb μv pc V ν
    return difference * c.direction * velocity_part;
  }
};

}  // namespace lmcal
