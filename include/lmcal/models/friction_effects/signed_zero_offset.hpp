// The load cell's zero in its signed convention (a sensor offset, not friction): the cell
// reads force + o with the force's sign following the motion, so a log of magnitudes reads
// F + direction · o. Unlike a direction asymmetry it does not grow with the friction force.
// A per-run zero that is the same in both directions is the run offset of the fit instead.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"

namespace LMCAL_API lmcal {

struct SignedZeroOffset {
  static constexpr FrictionEffectInfo info{"signed_zero_offset", "N", "load-cell zero o in the signed force: + direction o",
                                           0.0, -10.0, 10.0, 0.1,
                                           "the load cell at rest before each run (its zero), and both directions at several loads", false, "direction"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>&, const FrictionConditions<C>& c, const B&, const Total&,
                           const E& offset) {
    return offset * c.direction;
  }
};

}  // namespace lmcal
