#include "lmcal/models/heat_source.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "lmcal/error.hpp"

namespace lmcal {
namespace {

std::vector<double> uniform_faces(double from, double to, int cells) {
  std::vector<double> f(cells + 1);
  for (int i = 0; i <= cells; ++i) f[i] = from + (to - from) * i / cells;
  return f;
}

const BlockMotion kMotion{.stroke_m = 0.2, .contact_length_m = 0.0822, .velocity_m_s = 0.11};

double sum(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

TEST(HeatSource, WindowOverlapIntegralMatchesQuadrature) {
  const double w = 0.08, a = -0.013, b = 0.021;
  for (auto [c0, c1] : {std::pair{-0.2, 0.2}, std::pair{0.0, 0.05}, std::pair{0.03, -0.1}}) {
    const int n = 200000;
    double q = 0;
    for (int i = 0; i < n; ++i) {
      const double c = c0 + (c1 - c0) * (i + 0.5) / n;
      q += std::max(0.0, std::min(b, c + w / 2) - std::max(a, c - w / 2));
    }
    q *= (c1 - c0) / n;
    EXPECT_NEAR(window_overlap_integral(c0, c1, w, a, b), q, 1e-9);
  }
}

TEST(HeatSource, AveragedShapeCarriesExactlyThePowerAsATrapezoid) {
  const auto faces = uniform_faces(-0.3, 0.3, 600);
  const auto weights = static_source_weights(SourceModel::averaged, kMotion, faces);
  EXPECT_NEAR(sum(weights), 1.0, 1e-12);
  // Plateau P/L1 for |x| <= (L1 - w)/2, zero beyond (L1 + w)/2.
  const double dx = 0.001;
  EXPECT_NEAR(weights[300] / dx, 1.0 / kMotion.stroke_m, 1e-9);
  EXPECT_NEAR(weights[300 + 55] / dx, 1.0 / kMotion.stroke_m, 1e-9);
  EXPECT_EQ(weights[300 + 142], 0.0);
  // Half rail: half the power.
  EXPECT_NEAR(sum(static_source_weights(SourceModel::averaged, kMotion, uniform_faces(0, 0.3, 300))), 0.5, 1e-12);
}

TEST(HeatSource, AveragedShapeOfAVanishingStrokeIsTheContactWindowAtTheCentre) {
  // The stroke's mean of the window tends to the window at the centre: finite, the whole power,
  // the same as a short stroke's (5e-324 m gave 0/0 through the closed form's cancellation).
  const auto faces = uniform_faces(-0.3, 0.3, 600);
  const auto shape = [&](double stroke_m) {
    return static_source_weights(SourceModel::averaged, {.stroke_m = stroke_m, .contact_length_m = 0.0822, .velocity_m_s = 0.11}, faces);
  };
  const auto tiny = shape(5e-324), short_stroke = shape(1e-5);
  for (double w : tiny) EXPECT_TRUE(std::isfinite(w));
  EXPECT_NEAR(sum(tiny), 1.0, 1e-12);
  for (std::size_t i = 0; i < tiny.size(); ++i) EXPECT_NEAR(tiny[i], short_stroke[i], 1e-4) << "volume " << i;
  // Either side of the switch to the limit (1e-6 of the contact length) the shapes agree.
  const auto below = shape(0.99e-6 * 0.0822), above = shape(1.01e-6 * 0.0822);
  for (std::size_t i = 0; i < below.size(); ++i) EXPECT_NEAR(below[i], above[i], 1e-6) << "volume " << i;
}

TEST(HeatSource, PaperShapePutsL1OverLb1TimesThePowerIntoTheRail) {
  const auto faces = uniform_faces(-0.3, 0.3, 77);  // stroke ends fall inside volumes
  EXPECT_NEAR(sum(static_source_weights(SourceModel::paper, kMotion, faces)), 0.2 / 0.0822, 1e-12);
}

TEST(HeatSource, MovingSweepDepositsExactlyPowerTimesStepAndAveragesToTheTrapezoid) {
  const auto faces = uniform_faces(-0.3, 0.3, 600);
  const double period = 2 * kMotion.stroke_m / kMotion.velocity_m_s;
  SweepEnergy sweep;
  const double dt = 0.37;  // not commensurate with the period: legs split at turning points
  const int steps = static_cast<int>(std::round(10 * period / dt));
  for (int s = 0; s < steps; ++s) {
    moving_source_energy(kMotion, faces, s * dt, (s + 1) * dt, sweep);
    EXPECT_NEAR(sum(sweep.energy_s), dt, 1e-12);
  }
  // Over whole cycles the sweep equals the cycle-average shape.
  std::vector<double> whole(600, 0.0);
  moving_source_energy(kMotion, faces, 0.0, 10 * period, sweep);
  for (std::size_t k = 0; k < sweep.energy_s.size(); ++k) whole[sweep.first + k] = sweep.energy_s[k];
  const auto averaged = static_source_weights(SourceModel::averaged, kMotion, faces);
  for (int i = 0; i < 600; ++i) EXPECT_NEAR(whole[i] / (10 * period), averaged[i], 1e-12) << i;
}

TEST(HeatSource, MovingSweepOfManyCyclesEqualsItsLegsSweptOneByOne) {
  // One step of 7.3 cycles from mid-leg (its whole cycles taken as the averaged shape) against
  // steps shorter than a leg (each swept exactly): the same energy in every volume.
  const auto faces = uniform_faces(-0.3, 0.3, 600);
  const double period = 2 * kMotion.stroke_m / kMotion.velocity_m_s;
  const double t0 = 0.5, t1 = t0 + 7.3 * period;
  const auto spread = [&](const SweepEnergy& e, std::vector<double>& into) {
    for (std::size_t k = 0; k < e.energy_s.size(); ++k) into[e.first + k] += e.energy_s[k];
  };
  std::vector<double> at_once(600, 0.0), by_legs(600, 0.0);
  SweepEnergy sweep;
  moving_source_energy(kMotion, faces, t0, t1, sweep);
  spread(sweep, at_once);
  for (double t = t0; t < t1; t += 0.37) {
    moving_source_energy(kMotion, faces, t, std::min(t + 0.37, t1), sweep);
    spread(sweep, by_legs);
  }
  for (int i = 0; i < 600; ++i) EXPECT_NEAR(at_once[i], by_legs[i], 1e-11) << "volume " << i;
}

TEST(HeatSource, MovingSweepOfAStrokeFarShorterThanTheStepIsTheAveragedShapeAtOnce) {
  // 1e-9 m at 0.11 m/s is 3e10 legs in a 600 s step: swept as whole cycles, not leg by leg.
  const auto faces = uniform_faces(-0.3, 0.3, 600);
  const BlockMotion tiny{.stroke_m = 1e-9, .contact_length_m = 0.0822, .velocity_m_s = 0.11};
  SweepEnergy sweep;
  moving_source_energy(tiny, faces, 0.0, 600.0, sweep);
  EXPECT_NEAR(sum(sweep.energy_s), 600.0, 1e-9);
  const auto averaged = static_source_weights(SourceModel::averaged, tiny, faces);
  for (std::size_t k = 0; k < sweep.energy_s.size(); ++k)
    EXPECT_NEAR(sweep.energy_s[k], 600.0 * averaged[sweep.first + k], 1e-6) << "volume " << sweep.first + k;
}

TEST(HeatSource, BlockOscillatesOverTheStroke) {
  EXPECT_DOUBLE_EQ(block_centre_m(kMotion, 0.0), -0.1);
  EXPECT_NEAR(block_centre_m(kMotion, 0.2 / 0.11), 0.1, 1e-12);
  EXPECT_NEAR(block_centre_m(kMotion, 0.4 / 0.11), -0.1, 1e-12);
  EXPECT_NEAR(block_centre_m(kMotion, 0.1 / 0.11), 0.0, 1e-12);
}

TEST(HeatSource, ParsesModelNamesAndRefusesUnknownOnes) {
  EXPECT_EQ(parse_source_model("moving"), SourceModel::moving);
  EXPECT_THROW(parse_source_model("uniform"), InvalidParameter);
}

}  // namespace
}  // namespace lmcal
