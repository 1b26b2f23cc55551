// Direction asymmetry: the whole friction force × (1 + a · direction), direction = ±1
// (a tilted rail, an off-centre load, a seal that wipes one way). Acts on the total with
// every other effect applied; shows as forward and backward strokes that differ in proportion.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"

namespace LMCAL_API lmcal {

struct DirectionAsymmetry {
  static constexpr FrictionEffectInfo info{"direction_asymmetry", "1", "friction (1 + a) forward, (1 - a) backward",
                                           0.0, -0.5, 0.5, 0.05,
                                           "the force in both directions at several loads (an asymmetry grows with the force, a sensor offset does not)", false, "direction"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_total;

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>&, const FrictionConditions<C>& c, const B&, const Total& total_N,
                           const E& asymmetry) {
    return total_N * asymmetry * c.direction;
  }
};

}  // namespace lmcal
