// Load-dependent viscous coefficient: μv (1 + c_P · P / 1 kN), i.e. the correction
// c_P · (P / 1 kN) · Lb μv pc V ν of the viscous term (Eq. 7 without f0). The lubricant film
// thins under load; shows as a speed slope that grows with load.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"

namespace LMCAL_API lmcal {

struct ViscousLoad {
  static constexpr FrictionEffectInfo info{"viscous_load", "1/kN", "viscous coefficient grows with load: μv (1 + c P/kN)",
                                           0.0, -1.0, 1.0, 0.1,
                                           "the same speeds at two or more loads", false, "load_N"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>& k, const FrictionConditions<C>& c, const B& b, const Total&,
                           const E& per_kN) {
    const auto velocity_part = b.viscous_N - c.block_length_mm * k.f0;  // Lb μv pc V ν
    return per_kN * (c.load_N * 1e-3) * velocity_part;
  }
};

}  // namespace lmcal
