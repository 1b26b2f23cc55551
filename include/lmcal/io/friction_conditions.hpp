// The operating point of one block: what a friction log records per sample (io) and what the
// friction law (models/friction.hpp) and its effects are evaluated at. It lives in io, the
// lowest layer, so that the logs can hold it and the models can read it without either
// including the other's headers.
//
// Units are the friction law's (Cheng et al. 2017): P in N, pc in µm, Lb in mm, V in m/s,
// T in °C; the members added for the effects are SI (m/s², m).
//
// Templated on the scalar like the law, so that a derivative can flow through a condition
// (the rail temperature of a coupled thermal model); cast<U>() converts.
//
// Trap: V is a speed (>= 0); the sense of travel is `direction` (+1 or -1).
#pragma once

#include "lmcal/export.hpp"

namespace LMCAL_API lmcal {

// Operating point of one block.
template <typename T>
struct FrictionConditions {
  T load_N{};           // P, normal load on the block
  T preload_um{};       // pc, preload amount
  T block_length_mm{};  // Lb, block length
  T velocity_m_s{};     // V, sliding speed (>= 0)
  T temperature_C{};    // T, lubricant / rail temperature
  T direction{1.0};     // +1 or -1, sense of travel (the published law ignores it)
  // dV/dt along the travel, m/s² (signed in x): 0 on a plateau; a trajectory's inertia and the
  // moving_mass effect use it (the law ignores it).
  T acceleration_m_s2{};
  // Where along the travel the carriage is, m (the log's own origin), and how far it has moved
  // since it last reversed or rested, m: a raw log's (derived from its motion); 0 where a log
  // gives no motion. Position-periodic and pre-sliding effects use them (the law ignores them).
  T position_m{};
  T distance_since_reversal_m{};

  template <typename U>
  FrictionConditions<U> cast() const {
    return {U(load_N),      U(preload_um), U(block_length_mm),   U(velocity_m_s),
            U(temperature_C), U(direction), U(acceleration_m_s2), U(position_m),
            U(distance_since_reversal_m)};
  }
};

}  // namespace lmcal
