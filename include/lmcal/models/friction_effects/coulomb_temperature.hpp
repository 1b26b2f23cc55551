// Temperature-dependent Coulomb term: f_C (1 + c_T (T - T_i)), i.e. the correction
// f_C · c_T · (T - T_i), with T_i the law's reference temperature. Boundary friction of the
// rolling contacts changes with the lubricant's temperature; shows as a load-proportional
// offset that moves with the logged temperature.
#pragma once

#include "lmcal/export.hpp"

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"

namespace LMCAL_API lmcal {

struct CoulombTemperature {
  static constexpr FrictionEffectInfo info{"coulomb_temperature", "1/K", "Coulomb term (1 + c (T - T_i))", 0.0, -0.1, 0.1,
                                           0.01,
                                           "the same load at two oil temperatures within one run (or repeated setups)", false, "temperature_C"};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>& k, const FrictionConditions<C>& c, const B& b, const Total&,
                           const E& per_K) {
    return b.coulomb_N * per_K * (c.temperature_C - k.T_ref_C);
  }
};

}  // namespace lmcal
