// Quadratic seal drag: + c_s · V², N with c_s in N per (m/s)². The end seals' lip drag grows
// faster than the lubricant's linear viscous term; shows at the highest speeds. A drag: c_s >= 0.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"

namespace LMCAL_API lmcal {

struct SealDrag {
  static constexpr FrictionEffectInfo info{"seal_drag", "N s2/m2", "quadratic seal drag c V²", 0.0, 0.0, 5000.0, 100.0,
                                           "guides with different block lengths (a drag growing with the block is seal_drag_block), and speeds above 0.1 m/s"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>&, const FrictionConditions<C>& c, const B&, const Total&,
                           const E& coefficient) {
    return coefficient * c.velocity_m_s * c.velocity_m_s;
  }
};

}  // namespace lmcal
