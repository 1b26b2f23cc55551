// Seal drag that scales with the block: + c_b · (L_b / 100 mm) · V², N with c_b in N per
// (m/s)² per 100 mm of block. Larger blocks carry larger end seals (and some carry extra
// inner seals), so their lip drag is larger; told from the plain seal drag only by guides of
// different block length. A drag: c_b >= 0.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"

namespace LMCAL_API lmcal {

struct SealDragBlock {
  static constexpr FrictionEffectInfo info{"seal_drag_block", "N s2/m2 per 100 mm", "quadratic seal drag c (L_b/100 mm) V²",
                                           0.0, 0.0, 5000.0, 100.0,
                                           "guides with different block lengths, and speeds above 0.1 m/s"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>&, const FrictionConditions<C>& c, const B&, const Total&,
                           const E& coefficient) {
    return coefficient * (c.block_length_mm / 100.0) * c.velocity_m_s * c.velocity_m_s;
  }
};

}  // namespace lmcal
