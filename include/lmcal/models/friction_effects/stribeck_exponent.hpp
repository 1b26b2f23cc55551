// Generalized Stribeck curve: f_St · exp(-(V/V_St)^δ) instead of exp(-V/V_St) (δ = 1: Eq. 5).
// Written as the correction f_St · (exp(r - r^δ) - 1), r = V/V_St, of the law's Stribeck term.
// Shows at the low speeds, below and around V_St. Trap: r^δ is evaluated as exp(δ ln r);
// at V = 0 the correction is exactly 0 and so is its derivative with respect to δ.
#pragma once

#include "lmcal/export.hpp"

#include <cmath>

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"

namespace LMCAL_API lmcal {

struct StribeckExponent {
  static constexpr FrictionEffectInfo info{"stribeck_exponent", "1", "exponent δ of the Stribeck decay exp(-(V/V_St)^δ)",
                                           1.0, 0.2, 5.0, 1.0,
                                           "several speeds between 0.002 and 0.03 m/s"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>& k, const FrictionConditions<C>& c, const B& b, const Total&,
                           const E& exponent) {
    using std::exp;
    using std::log;
    const auto r = c.velocity_m_s / k.v_st_m_s;
    if (!(r > 0.0)) return b.stribeck_N * 0.0 * exponent;
    return b.stribeck_N * (exp(r - exp(exponent * log(r))) - 1.0);
  }
};

}  // namespace lmcal
