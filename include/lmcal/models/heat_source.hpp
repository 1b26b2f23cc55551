// Where the block's frictional heat enters the rail: three source models.
// See shared/PHYSICS.md §4 and §7.
//
// Coordinates: x in metres from the rail centre, which is the stroke centre.
// The block (contact length w = Lb1) oscillates with its centre c(t) between
// -L1/2 and +L1/2 at constant speed V; it starts at -L1/2 moving towards +x.
// All shapes are per watt of rail heat input P = α·Q_f.
//
//   paper    (Eqs. 13-14)  line density P/w on 0 <= |x| <= L1/2, as published.
//                          Over the whole rail that is P·L1/w ≈ 2.4 P for SRN 35C:
//                          the published model injects more than the block makes.
//   averaged               cycle average of the moving block:
//                          g(x) = P/(w·L1) · |[x - w/2, x + w/2] ∩ [-L1/2, L1/2]|,
//                          a trapezoid over stroke + contact length, ∫g dx = P exactly.
//   moving                 the block at its actual position; the energy a control
//                          volume receives over a step is the exact integral of the
//                          block's sweep, so the total is P·Δt to round-off.
//
// Trap: a fitted α belongs to the source model it was fitted with; α from `paper`
// is ≈ w/L1 times α from `averaged`.
#pragma once

#include "lmcal/export.hpp"

#include <cstddef>
#include <string_view>
#include <vector>

namespace LMCAL_API lmcal {

enum class SourceModel { paper, averaged, moving };

std::string_view to_string(SourceModel model);
// Accepts "paper", "averaged", "moving"; throws InvalidParameter otherwise.
SourceModel parse_source_model(std::string_view name);

struct BlockMotion {
  double stroke_m;          // L1, travel of the block centre
  double contact_length_m;  // w = Lb1
  double velocity_m_s;      // V (used by `moving` only)
};

// ∫_{c0}^{c1} |[c - w/2, c + w/2] ∩ [a, b]| dc, exactly (negative when c1 < c0).
// The one integral behind both the averaged shape and the moving sweep.
double window_overlap_integral(double c0, double c1, double width, double a, double b);

// Block centre at time t (triangle wave), m.
double block_centre_m(const BlockMotion& motion, double time_s);

// Fraction of P entering each control volume [faces[i], faces[i+1]] (faces ascending),
// for the time-independent models. `paper` uses |x| (the domain may be the half rail).
std::vector<double> static_source_weights(SourceModel model, const BlockMotion& motion,
                                          const std::vector<double>& faces);

// Energy per watt of P (J/W = s) each control volume receives from the moving block
// during [t0, t1]. Writes only the touched volumes: energy[first .. first + count).
struct SweepEnergy {
  std::size_t first = 0;
  std::vector<double> energy_s;
};
void moving_source_energy(const BlockMotion& motion, const std::vector<double>& faces, double t0_s,
                          double t1_s, SweepEnergy& out);

}  // namespace lmcal
