#include "lmcal/models/heat_source.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "lmcal/error.hpp"

namespace lmcal {

std::string_view to_string(SourceModel model) {
  switch (model) {
    case SourceModel::paper: return "paper";
    case SourceModel::averaged: return "averaged";
    case SourceModel::moving: return "moving";
  }
  return "?";
}

SourceModel parse_source_model(std::string_view name) {
  for (auto m : {SourceModel::paper, SourceModel::averaged, SourceModel::moving})
    if (name == to_string(m)) return m;
  throw InvalidParameter("source", "unknown source model '" + std::string(name) +
                                       "'; expected paper, averaged or moving");
}

namespace {

// ∫_{c0}^{c1} max(k - c, 0) dc = R(k - c0) - R(k - c1) with R(u) = max(u, 0)² / 2.
double ramp_integral(double k, double c0, double c1) {
  auto R = [](double u) { return u > 0 ? 0.5 * u * u : 0.0; };
  return R(k - c0) - R(k - c1);
}

// G(y) = ∫_{c0}^{c1} |[c - w/2, c + w/2] ∩ (-∞, y]| dc; the overlap with [a, b] is G(b) - G(a).
// |[l, r] ∩ (-∞, y]| = ρ(y - l) - ρ(y - r) with ρ(u) = max(u, 0), l = c - w/2, r = c + w/2:
// both terms are ρ(k - c) and integrate in closed form.
double window_cumulative(double c0, double c1, double width, double y) {
  const double h = 0.5 * width;
  return ramp_integral(y + h, c0, c1) - ramp_integral(y - h, c0, c1);
}

}  // namespace

double window_overlap_integral(double c0, double c1, double width, double a, double b) {
  return window_cumulative(c0, c1, width, b) - window_cumulative(c0, c1, width, a);
}

namespace {
// Block centre after the block has travelled a path s (m) from -L1/2: a triangle wave.
double centre_at_path(double path_m, double stroke_m) {
  const double s = std::fmod(path_m, 2 * stroke_m);
  return -0.5 * stroke_m + (s <= stroke_m ? s : 2 * stroke_m - s);
}
}  // namespace

double block_centre_m(const BlockMotion& motion, double time_s) {
  if (motion.stroke_m <= 0) return 0.0;
  return centre_at_path(motion.velocity_m_s * time_s, motion.stroke_m);
}

std::vector<double> static_source_weights(SourceModel model, const BlockMotion& motion,
                                          const std::vector<double>& faces) {
  LMCAL_ASSERT(faces.size() >= 2, "a grid needs at least one control volume");
  LMCAL_ASSERT(model != SourceModel::moving, "the moving source has no static shape");
  const double w = motion.contact_length_m;
  const double half_stroke = 0.5 * motion.stroke_m;
  std::vector<double> weights(faces.size() - 1);
  for (std::size_t i = 0; i + 1 < faces.size(); ++i) {
    const double a = faces[i], b = faces[i + 1];
    if (model == SourceModel::paper) {
      // Uniform P/w on |x| <= L1/2: overlap of [a, b] with [-L1/2, L1/2].
      const double overlap = std::max(0.0, std::min(b, half_stroke) - std::max(a, -half_stroke));
      weights[i] = overlap / w;
    } else if (motion.stroke_m < 1e-6 * w) {
      // The stroke's mean of the window's overlap, as the stroke shrinks: the overlap at the
      // centre (within L1/w of it). The closed form below loses eps·|x|/L1 to cancellation and
      // gives 0/0 for a stroke of 5e-324 m.
      weights[i] = std::max(0.0, std::min(b, 0.5 * w) - std::max(a, -0.5 * w)) / w;
    } else {
      weights[i] = window_overlap_integral(a, b, w, -half_stroke, half_stroke) / (w * motion.stroke_m);
    }
  }
  return weights;
}

void moving_source_energy(const BlockMotion& motion, const std::vector<double>& faces, double t0_s,
                          double t1_s, SweepEnergy& out) {
  const double w = motion.contact_length_m;
  const double L1 = motion.stroke_m;
  const double V = motion.velocity_m_s;
  LMCAL_ASSERT(V > 0 && L1 > 0 && t1_s >= t0_s, "moving source needs V > 0, L1 > 0, t1 >= t0");

  // Split the path s = V t at the turning points (multiples of L1); on each leg the
  // centre moves linearly, so the sweep integral is exact. Whole back-and-forth cycles after the
  // first leg sweep the window over the stroke twice each: exactly the averaged shape for their
  // time (`bulk_path`), so a stroke far shorter than V·Δt costs two legs, not V·Δt/L1 of them
  // (a stroke of 1e-9 m took minutes a step; beyond 2^52 cycles the last part cycle is dropped).
  struct Leg { double c0, c1; };
  std::vector<Leg> legs;
  const double s1 = V * t1_s;
  double s = V * t0_s;
  double lo = centre_at_path(s, L1), hi = lo;
  double bulk_path = 0;
  do {
    if (!legs.empty() && bulk_path == 0) {
      const double cycles = std::floor((s1 - s) / (2 * L1));
      if (cycles >= 1) {
        bulk_path = cycles < 0x1p52 ? cycles * 2 * L1 : s1 - s;
        s += bulk_path;
        lo = std::min(lo, -0.5 * L1);
        hi = std::max(hi, 0.5 * L1);
        if (s >= s1) break;
      }
    }
    double turn = (std::floor(s / L1) + 1) * L1;
    if (turn <= s) turn += L1;  // guards against s/L1 rounding down at a turning point
    const double s_end = std::min(turn, s1);
    // Evaluate the leg's end from inside the leg: the triangle wave is continuous, and this
    // keeps fmod's wrap at a multiple of 2·L1 from mattering.
    const Leg leg{centre_at_path(s, L1), centre_at_path(s_end, L1)};
    legs.push_back(leg);
    lo = std::min({lo, leg.c0, leg.c1});
    hi = std::max({hi, leg.c0, leg.c1});
    s = s_end;
  } while (s < s1);

  // Volumes the window touches: faces overlapping [lo - w/2, hi + w/2].
  const double left = lo - 0.5 * w, right = hi + 0.5 * w;
  const auto first_face = std::upper_bound(faces.begin(), faces.end(), left);
  std::size_t first = first_face == faces.begin() ? 0 : static_cast<std::size_t>(first_face - faces.begin()) - 1;
  std::size_t last = static_cast<std::size_t>(std::lower_bound(faces.begin(), faces.end(), right) - faces.begin());
  last = std::min(last, faces.size() - 1);  // one past the last touched volume
  out.first = first;
  out.energy_s.assign(last > first ? last - first : 0, 0.0);
  // Per leg, G(y) = ∫ |[c - w/2, c + w/2] ∩ (-∞, y]| dc at every face; a volume receives the
  // difference of G at its faces (one evaluation per face instead of two per volume).
  const double scale = 1.0 / (w * V);
  if (bulk_path > 0 && last > first) {
    const std::vector<double> range(faces.begin() + static_cast<std::ptrdiff_t>(first),
                                    faces.begin() + static_cast<std::ptrdiff_t>(last) + 1);
    const std::vector<double> averaged = static_source_weights(SourceModel::averaged, motion, range);
    for (std::size_t i = 0; i < averaged.size(); ++i) out.energy_s[i] += bulk_path / V * averaged[i];
  }
  for (const Leg& leg : legs) {
    const double sign = leg.c1 >= leg.c0 ? scale : -scale;
    double below = window_cumulative(leg.c0, leg.c1, w, faces[first]);
    for (std::size_t i = first; i < last; ++i) {
      const double above = window_cumulative(leg.c0, leg.c1, w, faces[i + 1]);
      out.energy_s[i - first] += (above - below) * sign;
      below = above;
    }
  }
}

}  // namespace lmcal
