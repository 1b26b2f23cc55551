// The weight on an inclined or vertical axis: the drive holds G = M·g·sin θ in both senses
// (+x up: G > 0), so read in the motion's sense it is + G·direction. Fitted with a trajectory
// whose axis is declared inclined (axis_incline_deg ≠ 0); on a horizontal axis the same shape
// is a force sensor's or a drive's offset (signed_zero_offset), which the data alone cannot
// tell from it (PHYSICS.md §8).
#pragma once

#include "lmcal/export.hpp"

#include <cmath>
#include <numbers>

#include "lmcal/models/friction.hpp"
#include "lmcal/models/friction_effect.hpp"

namespace LMCAL_API lmcal {

inline constexpr double kStandardGravity_m_s2 = 9.80665;  // CGPM 1901

// The weight along the axis, M g sin θ (+x up), N.
inline double axis_weight_N(double mass_kg, double incline_deg) {
  return mass_kg * kStandardGravity_m_s2 * std::sin(incline_deg * std::numbers::pi / 180);
}

struct AxisGravity {
  static constexpr FrictionEffectInfo info{"axis_gravity", "N", "weight along an inclined axis G: + direction G",
                                           0.0, -1e6, 1e6, 10.0,
                                           "the axis's incline and the carriage's mass (G = M g sin θ)", true};
  static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;

  template <typename P, typename C, typename B, typename Total, typename E>
  static auto correction_N(const FrictionConstants<P>&, const FrictionConditions<C>& c, const B&, const Total&,
                           const E& force_N) {
    return force_N * c.direction;
  }
};

}  // namespace lmcal
