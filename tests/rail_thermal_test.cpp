#include "lmcal/models/rail_thermal.hpp"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>

#include "lmcal/error.hpp"
#include "support/fin_analytic.hpp"
#include "support/srn35c.hpp"

namespace lmcal {
namespace {

using test::srn35c_geometry;
using test::srn35c_params;

constexpr double kSixHours_s = 6 * 3600.0;

RailNumerics numerics(SourceModel source, TimeScheme scheme, int segments, double dt) {
  return {.source = source, .scheme = scheme, .half_rail_segments = segments, .time_step_s = dt};
}

// Steady state of the published (uniform, half-stroke) source against the closed-form fin.
TEST(RailThermal, SteadyStateMatchesTheAnalyticFin) {
  const auto g = srn35c_geometry();
  const auto p = srn35c_params();
  const double line_power = p.heat_partition * p.heat_rate_W / g.contact_length_m;
  const test::FinAnalytic exact(p.h_W_m2K, g.perimeter_m, p.conductivity_W_mK, g.area_m2, line_power,
                                0.5 * g.stroke_m, 0.5 * g.rail_length_m);
  const std::vector<double> sensors = {0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3};
  const auto steady = steady_rail(g, numerics(SourceModel::paper, TimeScheme::backward_euler, 3000, 1), sensors, p, 20.0);
  const double peak = exact.excess_K(0.0);
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    const double rise = steady.temperature_C(0, i) - 20.0;
    EXPECT_LT(std::abs(rise - exact.excess_K(sensors[i])), 1e-3 * peak) << "x = " << sensors[i];
  }
  // A long transient settles on the same state.
  RailOutputs out{.duration_s = 40 * 3600.0, .sensor_positions_m = sensors, .output_times_s = {40 * 3600.0}};
  auto p20 = p;
  p20.initial_temperature_C = 20.0;
  const auto late = simulate_rail(g, numerics(SourceModel::paper, TimeScheme::backward_euler, 300, 60), out, p20,
                                  AmbientTrace::constant(20.0));
  EXPECT_NEAR(late.temperature_C(0, 0) - 20.0, peak, 2e-3 * peak);
}

// Injected = stored + convected for every source model and scheme, with a drifting ambient;
// and the injected energy is the model's analytic power times the duration.
TEST(RailThermal, EnergyIsConservedForEverySourceModel) {
  const auto g = srn35c_geometry();
  const auto p = srn35c_params();
  const AmbientTrace drift{{0.0, 7200.0, kSixHours_s}, {26.0, 27.5, 25.0}};
  RailOutputs out{.duration_s = kSixHours_s, .sensor_positions_m = {0.0}, .output_times_s = {kSixHours_s},
                  .energy_balance = true};
  const double P = p.heat_partition * p.heat_rate_W;
  for (auto source : {SourceModel::paper, SourceModel::averaged, SourceModel::moving}) {
    for (auto scheme : {TimeScheme::backward_euler, TimeScheme::crank_nicolson}) {
      const int segments = source == SourceModel::moving ? 150 : 50;
      const double dt = source == SourceModel::moving ? 0.5 : 600;
      const auto sol = simulate_rail(g, numerics(source, scheme, segments, dt), out, p, drift);
      const auto& e = sol.energy;
      const double expected = (source == SourceModel::paper ? g.stroke_m / g.contact_length_m : 1.0) * P * kSixHours_s;
      EXPECT_NEAR(e.injected_J, expected, 1e-9 * expected) << to_string(source);
      EXPECT_LT(std::abs(e.imbalance_J()), 1e-3 * e.injected_J) << to_string(source) << " " << to_string(scheme);
      EXPECT_GT(e.stored_J, 0.1 * e.injected_J);       // a real transient, not a trivial balance
      EXPECT_GT(e.convected_side_J, 0.1 * e.injected_J);
      EXPECT_GT(e.convected_end_J, 0.0);
    }
  }
}

double observed_order(double coarse_error, double fine_error, double ratio = 2.0) {
  return std::log(coarse_error / fine_error) / std::log(ratio);
}

TEST(RailThermal, SpaceConvergenceIsSecondOrder) {
  const auto g = srn35c_geometry();
  const auto p = srn35c_params();
  for (auto source : {SourceModel::paper, SourceModel::averaged}) {
    const std::vector<double> sensors = {0.0, 0.07, 0.12};
    auto steady = [&](int segments) {
      return steady_rail(g, numerics(source, TimeScheme::backward_euler, segments, 1), sensors, p, 26.0);
    };
    const auto reference = steady(19200);
    double previous = 0;
    for (int segments : {30, 60, 120, 240}) {
      const auto s = steady(segments);
      double error = 0;
      for (std::size_t i = 0; i < sensors.size(); ++i)
        error = std::max(error, std::abs(s.temperature_C(0, i) - reference.temperature_C(0, i)));
      if (previous > 0) {
        const double order = observed_order(previous, error);
        EXPECT_GT(order, 1.8) << to_string(source) << " segments " << segments;
        EXPECT_LT(order, 2.3) << to_string(source) << " segments " << segments;
      }
      previous = error;
    }
  }
}

TEST(RailThermal, TimeConvergenceIsFirstOrderForBackwardEulerAndSecondForCrankNicolson) {
  const auto g = srn35c_geometry();
  const auto p = srn35c_params();
  RailOutputs out{.duration_s = kSixHours_s, .sensor_positions_m = {0.0, 0.1},
                  .output_times_s = {1800, 3600, 3 * 3600, kSixHours_s}};
  for (auto scheme : {TimeScheme::backward_euler, TimeScheme::crank_nicolson}) {
    auto run = [&](double dt) {
      return simulate_rail(g, numerics(SourceModel::averaged, scheme, 60, dt), out, p, AmbientTrace::constant(26.0));
    };
    const auto reference = run(0.5);
    double previous = 0;
    for (double dt : {450.0, 225.0, 112.5, 56.25}) {
      const auto s = run(dt);
      double error = 0;
      for (std::size_t k = 0; k < s.sensor_temperature_C.size(); ++k)
        error = std::max(error, std::abs(s.sensor_temperature_C[k] - reference.sensor_temperature_C[k]));
      if (previous > 0) {
        const double order = observed_order(previous, error);
        const double expected = scheme == TimeScheme::backward_euler ? 1.0 : 2.0;
        EXPECT_NEAR(order, expected, 0.2) << to_string(scheme) << " dt " << dt;
      }
      previous = error;
    }
  }
}

// Cycle 2 L1 / V = 3.6 s against a 72 min time constant: the moving block looks like its average
// away from the stroke ends.
TEST(RailThermal, MovingApproachesAveragedAwayFromStrokeEnds) {
  const auto g = srn35c_geometry(0.11);
  const auto p = srn35c_params();
  const std::vector<double> sensors = {-0.04, 0.0, 0.03};
  RailOutputs out{.duration_s = kSixHours_s, .sensor_positions_m = sensors,
                  .output_times_s = {1800, 3600, 2 * 3600, kSixHours_s}};
  const auto moving = simulate_rail(g, numerics(SourceModel::moving, TimeScheme::crank_nicolson, 300, 0.5), out, p,
                                    AmbientTrace::constant(26.0));
  const auto averaged = simulate_rail(g, numerics(SourceModel::averaged, TimeScheme::crank_nicolson, 300, 0.5), out,
                                      p, AmbientTrace::constant(26.0));
  const double rise = averaged.temperature_C(3, 1) - 26.0;
  ASSERT_GT(rise, 0.5);
  for (std::size_t k = 0; k < moving.sensor_temperature_C.size(); ++k)
    EXPECT_LT(std::abs(moving.sensor_temperature_C[k] - averaged.sensor_temperature_C[k]), 0.01 * rise) << k;
}

// ∂T/∂θ from Jets equals central finite differences, for α, Q, h, k, ρ, c, T0.
TEST(RailThermal, JetDerivativesEqualFiniteDifferences) {
  using Jet = ceres::Jet<double, 8>;
  const auto g = srn35c_geometry();
  const AmbientTrace ambient{{0.0, kSixHours_s}, {25.0, 27.0}};
  RailOutputs out{.duration_s = kSixHours_s, .sensor_positions_m = {0.0, 0.13}, .output_times_s = {3600, kSixHours_s}};
  const auto p = srn35c_params();
  for (auto source : {SourceModel::paper, SourceModel::averaged, SourceModel::moving}) {
    for (auto scheme : {TimeScheme::backward_euler, TimeScheme::crank_nicolson}) {
      const auto n = source == SourceModel::moving ? numerics(source, scheme, 60, 2.0) : numerics(source, scheme, 40, 300);
      RailParams<Jet> pj{Jet(p.heat_partition, 0), Jet(p.heat_rate_W, 1), Jet(p.h_W_m2K, 2),
                         Jet(p.conductivity_W_mK, 3), Jet(p.density_kg_m3, 4), Jet(p.specific_heat_J_kgK, 5),
                         Jet(p.initial_temperature_C, 6)};
      const auto sj = simulate_rail(g, n, out, pj, ambient);
      auto value = [&](const RailParams<double>& q, std::size_t k) {
        return simulate_rail(g, n, out, q, ambient).sensor_temperature_C[k];
      };
      for (int i = 0; i < 7; ++i) {
        auto plus = p, minus = p;
        double* mp = &plus.heat_partition + i;
        double* mm = &minus.heat_partition + i;
        // Large enough that round-off accumulated over thousands of steps stays out of the quotient.
        const double step = 1e-4 * std::max(1.0, std::abs(*mp));
        *mp += step;
        *mm -= step;
        for (std::size_t k = 0; k < sj.sensor_temperature_C.size(); ++k) {
          const double fd = (value(plus, k) - value(minus, k)) / (2 * step);
          EXPECT_NEAR(sj.sensor_temperature_C[k].v[i], fd, 1e-5 * std::max(1e-2, std::abs(fd)))
              << "parameter " << i << " output " << k << " " << to_string(source) << " " << to_string(scheme);
        }
      }
    }
  }
}

TEST(RailThermal, OutputsAreInterpolatedInTimeAndSpace) {
  const auto g = srn35c_geometry();
  const auto p = srn35c_params();
  const auto n = numerics(SourceModel::averaged, TimeScheme::crank_nicolson, 60, 1200);  // Δx = 5 mm
  RailOutputs grid_out{.duration_s = 7200, .sensor_positions_m = {0.05, 0.0525}, .output_times_s = {0, 1200, 1800, 2400}};
  const auto s = simulate_rail(g, n, grid_out, p, AmbientTrace::constant(26.0));
  ASSERT_EQ(s.sensor_temperature_C.size(), 8u);
  EXPECT_DOUBLE_EQ(s.temperature_C(0, 0), 26.0);
  // 1800 s lies halfway between the steps at 1200 and 2400 s; 0.0525 m halfway between nodes 0.05 and 0.055.
  EXPECT_NEAR(s.temperature_C(2, 0), 0.5 * (s.temperature_C(1, 0) + s.temperature_C(3, 0)), 1e-12);
  RailOutputs node_out{.duration_s = 7200, .sensor_positions_m = {0.05, 0.055}, .output_times_s = {2400}};
  const auto nodes = simulate_rail(g, n, node_out, p, AmbientTrace::constant(26.0));
  EXPECT_NEAR(s.temperature_C(3, 1), 0.5 * (nodes.temperature_C(0, 0) + nodes.temperature_C(0, 1)), 1e-12);
  // Symmetry: a sensor at -x reads what one at +x reads.
  RailOutputs mirrored{.duration_s = 7200, .sensor_positions_m = {-0.05}, .output_times_s = {2400}};
  EXPECT_DOUBLE_EQ(simulate_rail(g, n, mirrored, p, AmbientTrace::constant(26.0)).temperature_C(0, 0),
                   s.temperature_C(3, 0));
}

TEST(RailThermal, AmbientFollowsTheTraceWhenThereIsNoHeat) {
  // No heat, rail starts at the ambient, ambient constant: the rail stays there exactly.
  const auto g = srn35c_geometry();
  auto p = srn35c_params();
  p.heat_partition = 0;
  p.initial_temperature_C = 23.0;
  RailOutputs out{.duration_s = kSixHours_s, .sensor_positions_m = {0.0, 0.3}, .output_times_s = {kSixHours_s}};
  const auto s = simulate_rail(g, numerics(SourceModel::averaged, TimeScheme::crank_nicolson, 50, 600), out, p,
                               AmbientTrace::constant(23.0));
  EXPECT_NEAR(s.temperature_C(0, 0), 23.0, 1e-9);
  // A 10 K higher ambient: the rail warms towards it, the end (convecting through A too) first.
  const auto w = simulate_rail(g, numerics(SourceModel::averaged, TimeScheme::crank_nicolson, 50, 600), out, p,
                               AmbientTrace::constant(33.0));
  EXPECT_GT(w.temperature_C(0, 1), w.temperature_C(0, 0));
  // Lumped exponential with the 72 min time constant far from the end.
  const double tau = p.density_kg_m3 * p.specific_heat_J_kgK * g.area_m2 / (p.h_W_m2K * g.perimeter_m);
  EXPECT_NEAR(w.temperature_C(0, 0), 33.0 - 10.0 * std::exp(-kSixHours_s / tau), 0.05);
}

// A time loop's reads keep their place (AmbientTrace::at(t, place)): whatever the order of the
// reads (forward by less or more than a sample, backward, far jumps, the ends, exact sample
// times), each is the same bits as the stand-alone read, which bisects.
TEST(RailThermal, AnAmbientReadThatKeepsItsPlaceReadsWhatABisectionReads) {
  AmbientTrace trace;
  for (int k = 0; k <= 200; ++k) {
    trace.time_s.push_back(k * 30.0 + (k % 7) * 1.5);
    trace.temperature_C.push_back(22.0 + 3.0 * std::sin(0.05 * k) + 0.01 * k);
  }
  const double last = trace.time_s.back();
  std::vector<double> reads;
  for (double t = 0; t <= last; t += 7.3) reads.push_back(t);                        // forward, under a sample
  for (double t = last; t >= 0; t -= 95.0) reads.push_back(t);                       // backward, over three
  for (double t : {-5.0, last + 10, 15.0, last - 1, 31.5, 30.0, 3000.0, 3000.0}) reads.push_back(t);  // jumps, ends, knots
  for (int k = 0; k < 400; ++k) reads.push_back(std::fmod(k * 613.7, last + 40) - 20);  // scattered
  std::size_t place = 1;
  int moved = 0;
  for (double t : reads) {
    const std::size_t before = place;
    EXPECT_EQ(trace.at(t, place), trace.at(t)) << "at t = " << t;
    moved += place != before;
    ASSERT_GE(place, 1u);
    ASSERT_LT(place, trace.time_s.size());
  }
  EXPECT_GT(moved, 100);  // the place did follow the reads
}

TEST(RailThermal, RefusesNonPhysicalInputNamingTheParameter) {
  const auto g = srn35c_geometry();
  const auto p = srn35c_params();
  const auto n = numerics(SourceModel::averaged, TimeScheme::backward_euler, 50, 600);
  const RailOutputs out{.duration_s = 3600, .sensor_positions_m = {0.0}, .output_times_s = {3600}};
  const auto ambient = AmbientTrace::constant(26.0);
  auto expect_refused = [&](const char* name, auto mutate) {
    auto g2 = g;
    auto n2 = n;
    auto p2 = p;
    auto o2 = out;
    mutate(g2, n2, p2, o2);
    try {
      simulate_rail(g2, n2, o2, p2, ambient);
      ADD_FAILURE() << name << " accepted";
    } catch (const InvalidParameter& e) {
      EXPECT_EQ(e.parameter(), name) << e.what();
    }
  };
  expect_refused("heat_partition", [](auto&, auto&, auto& p2, auto&) { p2.heat_partition = 1.2; });
  expect_refused("heat_partition", [](auto&, auto&, auto& p2, auto&) { p2.heat_partition = -0.1; });
  expect_refused("rail_length_m", [](auto& g2, auto&, auto&, auto&) { g2.rail_length_m = -1; });
  expect_refused("area_m2", [](auto& g2, auto&, auto&, auto&) { g2.area_m2 = 0; });
  expect_refused("half_rail_segments", [](auto&, auto& n2, auto&, auto&) { n2.half_rail_segments = 0; });
  expect_refused("time_step_s", [](auto&, auto& n2, auto&, auto&) { n2.time_step_s = 0; });
  expect_refused("h_W_m2K", [](auto&, auto&, auto& p2, auto&) { p2.h_W_m2K = std::nan(""); });
  expect_refused("sensor position_m", [](auto&, auto&, auto&, auto& o2) { o2.sensor_positions_m = {0.31}; });
  expect_refused("rail_length_m", [](auto& g2, auto&, auto&, auto&) { g2.rail_length_m = 0.25; });
  expect_refused("output_times_s", [](auto&, auto&, auto&, auto& o2) { o2.output_times_s = {4000}; });
}

}  // namespace
}  // namespace lmcal

namespace lmcal {
namespace {

// The figure docs/model.md states: how far the published numerics (paper source, 50 segments,
// Δt = 600 s, backward Euler) are from the converged solution for SRN 35C at 0.11 m/s, at
// spot 1 (x = 0), sampled at the paper's own step times. Nearly all of it is the time step.
TEST(RailThermal, PublishedNumericsErrorIsAboutOneKelvinAndComesFromTheTimeStep) {
  const auto g = srn35c_geometry(0.11);
  const auto p = srn35c_params();
  RailOutputs out{.duration_s = kSixHours_s, .sensor_positions_m = {0.0}};
  for (double t = 600; t <= kSixHours_s; t += 600) out.output_times_s.push_back(t);
  auto run = [&](TimeScheme scheme, int segments, double dt) {
    return simulate_rail(g, numerics(SourceModel::paper, scheme, segments, dt), out, p, AmbientTrace::constant(26.0));
  };
  auto max_error = [&](const RailSolution<double>& a, const RailSolution<double>& b) {
    double e = 0;
    for (std::size_t k = 0; k < a.sensor_temperature_C.size(); ++k)
      e = std::max(e, std::abs(a.sensor_temperature_C[k] - b.sensor_temperature_C[k]));
    return e;
  };
  const auto converged = run(TimeScheme::crank_nicolson, 400, 5);
  const double published = max_error(run(TimeScheme::backward_euler, 50, 600), converged);
  const double space_only = max_error(run(TimeScheme::crank_nicolson, 50, 5), converged);
  const double time_only = max_error(run(TimeScheme::backward_euler, 400, 600), converged);
  EXPECT_NEAR(published, 0.92, 0.03);  // docs/model.md, "Numerical error of the published setup"
  EXPECT_LT(space_only, 0.02);
  EXPECT_NEAR(time_only, published, 0.05 * published);
}

}  // namespace
}  // namespace lmcal

namespace lmcal {
namespace {

// Q_f from the friction law with Jet constants carries dT/d(friction constant) through the solver.
TEST(RailThermal, DerivativesReachTheFrictionConstantsThroughTheHeatRate) {
  using Jet = ceres::Jet<double, 2>;
  const auto g = srn35c_geometry(0.11);
  const auto conditions = test::srn35c_conditions(0.11);
  const RailNumerics n{.source = SourceModel::averaged, .scheme = TimeScheme::crank_nicolson,
                       .half_rail_segments = 50, .time_step_s = 120};
  const RailOutputs out{.duration_s = 7200, .sensor_positions_m = {0.0}, .output_times_s = {7200}};
  auto centre = [&](const FrictionConstants<double>& k) {
    auto p = srn35c_params(heat_rate_W(k, conditions));
    return simulate_rail(g, n, out, p, AmbientTrace::constant(26.0)).sensor_temperature_C[0];
  };
  const auto k = paper_friction_constants();
  auto kj = k.cast<Jet>();
  kj.mu_v.v[0] = 1.0;
  kj.beta_per_K.v[1] = 1.0;
  const auto p = srn35c_params();
  RailParams<Jet> pj{Jet(p.heat_partition), heat_rate_W(kj, conditions), Jet(p.h_W_m2K), Jet(p.conductivity_W_mK),
                     Jet(p.density_kg_m3), Jet(p.specific_heat_J_kgK), Jet(p.initial_temperature_C)};
  const Jet T = simulate_rail(g, n, out, pj, AmbientTrace::constant(26.0)).sensor_temperature_C[0];
  for (int i = 0; i < 2; ++i) {
    auto plus = k, minus = k;
    double& mp = i == 0 ? plus.mu_v : plus.beta_per_K;
    double& mm = i == 0 ? minus.mu_v : minus.beta_per_K;
    const double step = 1e-4 * std::abs(mp);
    mp += step;
    mm -= step;
    const double fd = (centre(plus) - centre(minus)) / (2 * step);
    EXPECT_NEAR(T.v[i], fd, 1e-5 * std::abs(fd)) << i;
    EXPECT_GT(std::abs(fd), 1.0);  // the derivative is real, not a zero that trivially matches
  }
}

}  // namespace
}  // namespace lmcal

namespace lmcal {
namespace {

TEST(RailThermal, BaseLossSteadyStateMatchesTheAnalyticFin) {
  const auto g = srn35c_geometry();
  auto p = srn35c_params();
  p.base_loss_W_mK = 0.5;  // a bolted rail: comparable to the side convection h p = 0.74 W/mK
  const double line_power = p.heat_partition * p.heat_rate_W / g.contact_length_m;
  const test::FinAnalytic exact(p.h_W_m2K, g.perimeter_m, p.conductivity_W_mK, g.area_m2, line_power,
                                0.5 * g.stroke_m, 0.5 * g.rail_length_m, p.base_loss_W_mK);
  const std::vector<double> sensors = {0.0, 0.1, 0.2};
  const auto steady = steady_rail(g, numerics(SourceModel::paper, TimeScheme::backward_euler, 3000, 1), sensors, p, 20.0);
  for (std::size_t i = 0; i < sensors.size(); ++i)
    EXPECT_LT(std::abs(steady.temperature_C(0, i) - 20.0 - exact.excess_K(sensors[i])), 1e-3 * exact.excess_K(0.0));
  // And it is cooler than without the base loss.
  EXPECT_LT(steady.temperature_C(0, 0),
            steady_rail(g, numerics(SourceModel::paper, TimeScheme::backward_euler, 300, 1), {0.0}, srn35c_params(), 20.0)
                .temperature_C(0, 0));
}

TEST(RailThermal, EnergyBalanceCountsBaseLossAndVaryingHeat) {
  const auto g = srn35c_geometry();
  auto p = srn35c_params();
  p.base_loss_W_mK = 0.3;
  RailOutputs out{.duration_s = kSixHours_s, .sensor_positions_m = {0.0}, .output_times_s = {kSixHours_s},
                  .energy_balance = true};
  const HeatRateModel<double> cooling = [](const double& T) { return 4.86 * std::exp(-0.05 * (T - 26.0)); };
  for (auto source : {SourceModel::averaged, SourceModel::moving}) {
    const auto n = source == SourceModel::moving ? numerics(source, TimeScheme::crank_nicolson, 150, 1.0)
                                                 : numerics(source, TimeScheme::crank_nicolson, 50, 60);
    const auto s = simulate_rail(g, n, out, p, AmbientTrace::constant(26.0), cooling);
    EXPECT_GT(s.energy.base_J, 0.1 * s.energy.injected_J);
    EXPECT_LT(std::abs(s.energy.imbalance_J()), 1e-9 * s.energy.injected_J) << to_string(source);
  }
}

// Q from the friction law at the rail temperature: as the rail warms the grease thins and
// the heat falls, so the rail ends cooler than with Q frozen at the start.
TEST(RailThermal, TwoWayCouplingLowersTheHeatAsTheRailWarms) {
  const auto g = srn35c_geometry(0.11);
  const auto k = paper_friction_constants();
  const auto conditions = test::srn35c_conditions(0.11);
  auto q_at = [&](const double& T) {
    auto c = conditions;
    c.temperature_C = T;
    return heat_rate_W(k, c);
  };
  const auto p = srn35c_params(q_at(26.0));
  const auto n = numerics(SourceModel::averaged, TimeScheme::crank_nicolson, 50, 30);
  RailOutputs out{.duration_s = kSixHours_s, .sensor_positions_m = {0.0}, .output_times_s = {0, 3600, kSixHours_s}};
  const auto frozen = simulate_rail(g, n, out, p, AmbientTrace::constant(26.0));
  const auto coupled = simulate_rail(g, n, out, p, AmbientTrace::constant(26.0), HeatRateModel<double>(q_at));
  EXPECT_DOUBLE_EQ(coupled.heat_rate_W[0], q_at(26.0));
  EXPECT_LT(coupled.heat_rate_W[2], 0.8 * coupled.heat_rate_W[0]);
  EXPECT_NEAR(coupled.heat_rate_W[2], q_at(coupled.source_temperature_C[2]), 1e-6);
  EXPECT_LT(coupled.temperature_C(2, 0), frozen.temperature_C(2, 0) - 1.0);
  // A model that returns the constant reproduces the uncoupled run exactly.
  const auto constant = simulate_rail(g, n, out, p, AmbientTrace::constant(26.0),
                                      HeatRateModel<double>([&](const double&) { return p.heat_rate_W; }));
  EXPECT_DOUBLE_EQ(constant.temperature_C(2, 0), frozen.temperature_C(2, 0));
}


// A heater switched on and off: the energy balance still closes, and the injected energy is
// α·∫Q dt of the schedule, for every source model and scheme.
TEST(RailThermal, OnOffScheduleKeepsTheEnergyBalanceExact) {
  const auto g = srn35c_geometry();
  auto p = srn35c_params();
  p.heat_schedule = HeatRateSchedule<double>::steps({0, 3000, 9000, 12000}, {6.0, 0.0, 3.0, 0.0});
  const double heat_J = 6.0 * 3000 + 3.0 * 3000;  // what the schedule puts in over the run
  RailOutputs out{.duration_s = kSixHours_s, .sensor_positions_m = {0.0}, .output_times_s = {0, 4000, kSixHours_s},
                  .energy_balance = true};
  for (auto source : {SourceModel::paper, SourceModel::averaged, SourceModel::moving}) {
    for (auto scheme : {TimeScheme::backward_euler, TimeScheme::crank_nicolson}) {
      const int segments = source == SourceModel::moving ? 150 : 50;
      const double dt = source == SourceModel::moving ? 0.5 : 600;
      const auto sol = simulate_rail(g, numerics(source, scheme, segments, dt), out, p, AmbientTrace::constant(26.0));
      const double expected =
          (source == SourceModel::paper ? g.stroke_m / g.contact_length_m : 1.0) * p.heat_partition * heat_J;
      EXPECT_NEAR(sol.energy.injected_J, expected, 1e-9 * expected) << to_string(source) << " " << to_string(scheme);
      EXPECT_LT(std::abs(sol.energy.imbalance_J()), 1e-3 * expected) << to_string(source) << " " << to_string(scheme);
      EXPECT_EQ(sol.heat_rate_W[1], 0.0);  // at 4000 s the heater is off
    }
  }
}

// A schedule that never changes is the constant heat rate, to the last bit of the solution.
TEST(RailThermal, ConstantScheduleEqualsTheConstantHeatRate) {
  const auto g = srn35c_geometry();
  const auto p = srn35c_params();
  auto scheduled = p;
  scheduled.heat_rate_W = 0;  // unused once a schedule is given
  scheduled.heat_schedule = HeatRateSchedule<double>::steps({0, 5000}, {p.heat_rate_W, p.heat_rate_W});
  RailOutputs out{.duration_s = kSixHours_s, .sensor_positions_m = {0.0, 0.1}, .output_times_s = {3600, kSixHours_s}};
  const auto n = numerics(SourceModel::averaged, TimeScheme::crank_nicolson, 50, 300);
  const auto a = simulate_rail(g, n, out, p, AmbientTrace::constant(26.0));
  const auto b = simulate_rail(g, n, out, scheduled, AmbientTrace::constant(26.0));
  for (std::size_t k = 0; k < a.sensor_temperature_C.size(); ++k)
    EXPECT_NEAR(b.sensor_temperature_C[k], a.sensor_temperature_C[k], 1e-12 * a.sensor_temperature_C[k]) << k;
  EXPECT_GT(a.temperature_C(1, 0), 27.0);  // the heat did warm the rail
}

// The heater switches off 450 s into a 600 s step: the step gets 450 s of heat, not 0 or 600;
// and a measured power ramp (linear knots) is integrated exactly too.
TEST(RailThermal, StepSwitchingOffMidStepInjectsTheExactEnergy) {
  const auto g = srn35c_geometry();
  auto p = srn35c_params();
  RailOutputs out{.duration_s = 1200, .sensor_positions_m = {0.0}, .output_times_s = {1200}, .energy_balance = true};
  const auto n = numerics(SourceModel::averaged, TimeScheme::backward_euler, 50, 600);
  p.heat_schedule = HeatRateSchedule<double>::steps({0, 450}, {5.0, 0.0});
  EXPECT_NEAR(simulate_rail(g, n, out, p, AmbientTrace::constant(26.0)).energy.injected_J,
              p.heat_partition * 5.0 * 450, 1e-10 * 5.0 * 450);
  p.heat_schedule = {{100, 700}, {2.0, 8.0}};  // 2 W until 100 s, a ramp to 8 W at 700 s, then 8 W
  const double ramp_J = 2.0 * 100 + 0.5 * (2.0 + 8.0) * 600 + 8.0 * 500;
  EXPECT_NEAR(simulate_rail(g, n, out, p, AmbientTrace::constant(26.0)).energy.injected_J, p.heat_partition * ramp_J,
              1e-10 * ramp_J);
  EXPECT_DOUBLE_EQ(p.heat_schedule.integral_J(400, 1000), 0.5 * (5.0 + 8.0) * 300 + 8.0 * 300);
}

// α and the phase heats as Jets: the derivative of a temperature after a switch-off matches
// central differences.
TEST(RailThermal, ScheduleCarriesJetDerivatives) {
  using J2 = ceres::Jet<double, 2>;
  const auto g = srn35c_geometry();
  const auto p = srn35c_params();
  RailOutputs out{.duration_s = 9000, .sensor_positions_m = {0.0}, .output_times_s = {9000}};
  const auto n = numerics(SourceModel::averaged, TimeScheme::crank_nicolson, 40, 300);
  auto simulate = [&](double alpha, double q_on) {
    RailParams<double> q = p;
    q.heat_partition = alpha;
    q.heat_schedule = HeatRateSchedule<double>::steps({0, 4000}, {q_on, 0.0});
    return simulate_rail(g, n, out, q, AmbientTrace::constant(26.0)).temperature_C(0, 0);
  };
  RailParams<J2> q{.heat_partition = J2(p.heat_partition, 0), .heat_rate_W = J2(0.0), .h_W_m2K = J2(p.h_W_m2K),
                   .conductivity_W_mK = J2(p.conductivity_W_mK), .density_kg_m3 = J2(p.density_kg_m3),
                   .specific_heat_J_kgK = J2(p.specific_heat_J_kgK), .initial_temperature_C = J2(26.0)};
  q.heat_schedule = HeatRateSchedule<J2>::steps({0, 4000}, {J2(5.0, 1), J2(0.0)});
  const J2 T = simulate_rail(g, n, out, q, AmbientTrace::constant(26.0)).temperature_C(0, 0);
  EXPECT_NEAR(T.a, simulate(p.heat_partition, 5.0), 1e-12 * T.a);
  const double h = 1e-5;
  EXPECT_NEAR(T.v[0], (simulate(p.heat_partition + h, 5.0) - simulate(p.heat_partition - h, 5.0)) / (2 * h), 1e-6);
  EXPECT_NEAR(T.v[1], (simulate(p.heat_partition, 5.0 + h) - simulate(p.heat_partition, 5.0 - h)) / (2 * h), 1e-6);
  EXPECT_GT(T.v[1], 0.0);
}

TEST(RailThermal, RefusesABadScheduleAndScheduleWithCoupling) {
  const auto g = srn35c_geometry();
  auto p = srn35c_params();
  RailOutputs out{.duration_s = 600, .sensor_positions_m = {0.0}, .output_times_s = {600}};
  const auto n = numerics(SourceModel::averaged, TimeScheme::backward_euler, 20, 60);
  p.heat_schedule = {{0, 300, 200}, {1.0, 1.0, 1.0}};
  EXPECT_THROW(simulate_rail(g, n, out, p, AmbientTrace::constant(26.0)), InvalidParameter);
  p.heat_schedule = {{0, 300}, {1.0, -1.0}};
  EXPECT_THROW(simulate_rail(g, n, out, p, AmbientTrace::constant(26.0)), InvalidParameter);
  p.heat_schedule = HeatRateSchedule<double>::steps({0, 300}, {1.0, 0.0});
  EXPECT_THROW(simulate_rail(g, n, out, p, AmbientTrace::constant(26.0),
                             HeatRateModel<double>([](const double&) { return 1.0; })),
               InvalidParameter);
}

}  // namespace
}  // namespace lmcal

namespace lmcal {
namespace {

// Runs in SIMD lanes give exactly what each run gives alone: six runs (a full sweep of four
// and a partial one), each with its own α, heat, h, k, T0, base loss and ambient trace, for
// both schemes and both static sources; profiles too. And what lanes cannot take is refused.
TEST(RailThermal, RunsInLanesEqualRunsAlone) {
  const RailGeometry g = test::srn35c_geometry(0.066);
  RailOutputs out{.duration_s = 3 * 3600.0, .sensor_positions_m = {0.0, 0.07, 0.2}, .profile_times_s = {1800.0, 3 * 3600.0}};
  for (double t = 0; t <= out.duration_s; t += 300) out.output_times_s.push_back(t);
  std::vector<RailParams<double>> params;
  std::vector<AmbientTrace> ambients;
  for (int r = 0; r < 6; ++r) {
    RailParams<double> p = test::srn35c_params();
    p.heat_partition = 0.5 + 0.05 * r;
    p.heat_rate_W = 8.0 + 2.0 * r;
    p.h_W_m2K = 4.0 + 0.5 * r;
    p.conductivity_W_mK = 17.0 + r;
    p.initial_temperature_C = 24.0 + 0.3 * r;
    p.base_loss_W_mK = 0.1 * r;
    params.push_back(p);
    ambients.push_back({{0.0, 5000.0, out.duration_s}, {24.0 + 0.2 * r, 25.0 - 0.1 * r, 24.5}});
  }
  for (const SourceModel source : {SourceModel::paper, SourceModel::averaged})
    for (const TimeScheme scheme : {TimeScheme::backward_euler, TimeScheme::crank_nicolson}) {
      const RailNumerics n = numerics(source, scheme, 60, 20);
      const auto lanes = simulate_rails(g, n, out, params, ambients);
      ASSERT_EQ(lanes.size(), params.size());
      for (std::size_t r = 0; r < params.size(); ++r) {
        const auto alone = simulate_rail(g, n, out, params[r], ambients[r]);
        EXPECT_EQ(lanes[r].sensor_temperature_C, alone.sensor_temperature_C) << "run " << r;
        EXPECT_EQ(lanes[r].profiles_C, alone.profiles_C) << "run " << r;
        EXPECT_EQ(lanes[r].source_temperature_C, alone.source_temperature_C) << "run " << r;
        EXPECT_EQ(lanes[r].steps, alone.steps);
      }
    }
  EXPECT_THROW(simulate_rails(g, numerics(SourceModel::moving, TimeScheme::crank_nicolson, 60, 20), out, params, ambients),
               InvalidParameter);
  EXPECT_THROW(simulate_rails(g, numerics(SourceModel::averaged, TimeScheme::crank_nicolson, 60, 20), out, params,
                              std::vector<AmbientTrace>(2, AmbientTrace::constant(25.0))),
               InvalidParameter);
  params[3].heat_partition = 1.5;  // every lane is checked, not only the first
  EXPECT_THROW(simulate_rails(g, numerics(SourceModel::averaged, TimeScheme::crank_nicolson, 60, 20), out, params, ambients),
               InvalidParameter);
}

}  // namespace
}  // namespace lmcal
