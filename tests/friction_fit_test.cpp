#include "lmcal/fit/friction_fit.hpp"

#include <ceres/cost_function.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <map>
#include <set>
#include <tuple>

#include "fit/friction_model.hpp"
#include "parallel_slices.hpp"
#include "support/finite_differences.hpp"
#include "lmcal/rig/virtual_rig.hpp"

namespace lmcal {
namespace {

// A compact rig: two guides, three preloads, three loads, speeds down to 2 mm/s, three
// temperatures, both directions.
FrictionRigConfig compact_rig(std::uint64_t seed, int runs = 2) {
  FrictionRigConfig c;
  c.guides = {"SRG 25C", "SRN 35C"};
  c.velocity_m_s = {0.002, 0.005, 0.01, 0.02, 0.04, 0.066, 0.11};
  c.temperature_C = {22, 30, 40};
  c.runs = runs;
  c.run_offset_N = 0;  // independent errors: what the intervals assume
  c.seed = seed;
  return c;
}

double truth(std::size_t j) {
  const auto k = paper_friction_constants();
  const double values[] = {k.k1, k.k2, k.mu_st, k.v_st_m_s, k.mu_v, k.beta_per_K, k.f0};
  return values[j];
}

bool covers(const ParameterEstimate& p, double value) {
  if (p.interval == "profile") return value >= p.profile_low && value <= p.profile_high;
  return value >= p.ci_low && value <= p.ci_high;
}

TEST(FrictionFit, RecoversThePapersConstantsWithinTheirIntervals) {
  const auto log = generate_friction_log(compact_rig(11, 3), {}).log;
  const auto result = fit_friction(log, {});
  ASSERT_TRUE(result.fit.solver.usable);
  EXPECT_TRUE(result.fit.solver.covariance_ok);
  EXPECT_TRUE(result.fit.identifiability.identifiable);
  EXPECT_GE(2 * result.fit.solver.starts_agreed, result.fit.solver.starts);  // most starts find the same minimum
  for (std::size_t j = 0; j < 7; ++j) {
    const auto& p = result.fit.parameters[j];
    EXPECT_TRUE(covers(p, truth(j))) << p.name << " = " << p.value << " ± " << p.se << ", true " << truth(j);
    EXPECT_LT(p.se, 0.2 * std::abs(truth(j))) << p.name;  // determined, not just covered
  }
  // The residual σ is the rig's load-cell noise; the RMSE is in newtons.
  EXPECT_NEAR(std::sqrt(result.fit.residual_variance), 0.15, 0.02);
  EXPECT_NEAR(result.rmse_N, 0.15, 0.02);
  // Correlation matrix: symmetric with a unit diagonal.
  for (Eigen::Index i = 0; i < 7; ++i) {
    EXPECT_NEAR(result.fit.correlation(i, i), 1.0, 1e-12);
    for (Eigen::Index j = 0; j < 7; ++j) EXPECT_NEAR(result.fit.correlation(i, j), result.fit.correlation(j, i), 1e-12);
  }
}

// Over 150 replicates, the 95 % intervals contain the truth 90-98 % of the time.
TEST(FrictionFit, IntervalsCoverTheTruthAtTheirNominalRate) {
  FrictionFitOptions options;
  options.per_run_fits = false;
  options.fit.starts = 2;
  int covered = 0, total = 0;
  std::array<int, 7> per_parameter{};
  const int replicates = 150;
  for (int r = 0; r < replicates; ++r) {
    auto rig = compact_rig(1000 + r, 1);
    rig.guides = {"SRN 35C"};
    rig.load_N = {1000, 3000};
    rig.directions = {1};
    const auto log = generate_friction_log(rig, {}).log;
    const auto result = fit_friction(log, options);
    ASSERT_TRUE(result.fit.solver.usable) << r;
    for (std::size_t j = 0; j < 7; ++j) {
      const bool c = covers(result.fit.parameters[j], truth(j));
      per_parameter[j] += c;
      covered += c;
      ++total;
    }
  }
  const double rate = double(covered) / total;
  RecordProperty("coverage_percent", std::to_string(100 * rate));
  EXPECT_GE(rate, 0.90);
  EXPECT_LE(rate, 0.98);
  for (std::size_t j = 0; j < 7; ++j)
    EXPECT_GE(per_parameter[j], 0.85 * replicates) << kFrictionConstantNames[j] << " covered " << per_parameter[j];
}

TEST(FrictionFit, OnePreloadClassReportsK1AndK2Inseparable) {
  auto rig = compact_rig(5);
  rig.preload_um = {2.5};
  const auto log = generate_friction_log(rig, {}).log;
  const auto result = fit_friction(log, {});
  const auto& id = result.fit.identifiability;
  ASSERT_FALSE(id.identifiable);
  ASSERT_EQ(id.issues.size(), 1u);
  const auto& issue = id.issues[0];
  EXPECT_NE(issue.why.find("one preload class"), std::string::npos) << issue.why;
  EXPECT_NE(issue.measure.find("second preload"), std::string::npos);
  ASSERT_EQ(issue.held.size(), 1u);
  EXPECT_TRUE(issue.held[0] == "k1" || issue.held[0] == "k2");
  // The held one is reported as such, with no interval that looks fine.
  const auto& held = result.fit.parameter(issue.held[0]);
  EXPECT_TRUE(held.held_unidentifiable);
  EXPECT_TRUE(std::isnan(held.se));
  EXPECT_EQ(held.interval, "none");
  // The rest is still fitted and the Coulomb combination k1 - k2·pc is right.
  const double combination = result.fit.parameter("k1").value - result.fit.parameter("k2").value * 2.5;
  EXPECT_NEAR(combination, 0.315 - 0.03 * 2.5, 0.01);
  EXPECT_TRUE(result.fit.solver.covariance_ok);
}

// Held out, a run the others cannot stand in for: one setup per run at two loads, so each run
// alone has its load. Without it the other run leaves the law's load dependence undetermined
// (one load: the Coulomb force and f0 are both constants), and the leave-one-run-out step was a
// singular solve, an arbitrary step (1.6 x 10^5 N held-out on 1.7 N of noise on the axis rig).
// That direction now stays at the full fit's estimate, the runs are named, and the caveat says
// the number is optimistic. With each setup repeated, nothing is said.
TEST(FrictionFit, HeldOutARunThatAloneVariesAConditionIsNamedNotExtrapolated) {
  FrictionFitOptions options;
  options.cross_validate = true;
  auto rig = compact_rig(7, 1);
  rig.guides = {"SRN 35C"};
  rig.preload_um = {2.5};
  rig.temperature_C = {26};
  rig.load_N = {1000, 2000};
  rig.one_setup_per_run = true;
  for (const int repeats : {1, 2}) {
    rig.runs = repeats;
    const FrictionLog log = generate_friction_log(rig, {}).log;
    const FrictionFitResult fit = fit_friction(log, options);
    std::cout << log.run_names.size() << " runs: RMSE " << fit.rmse_N << " N, held-out " << fit.cv_rmse_N << " N; "
              << held_out_caveat(fit) << "\n";
    ASSERT_TRUE(std::isfinite(fit.cv_rmse_N));
    EXPECT_LT(fit.cv_rmse_N, 5 * fit.rmse_N);
    if (repeats == 1) {
      EXPECT_EQ(fit.cv_undetermined_runs, log.run_names) << held_out_caveat(fit);
      EXPECT_NE(held_out_caveat(fit).find("optimistic"), std::string::npos);
    } else {
      EXPECT_TRUE(fit.cv_undetermined_runs.empty()) << held_out_caveat(fit);
      EXPECT_EQ(held_out_caveat(fit), "");
    }
  }
}

TEST(FrictionFit, OneTemperatureReportsBetaAndNoLowSpeedReportsStribeck) {
  auto rig = compact_rig(6);
  rig.temperature_C = {26};
  auto result = fit_friction(generate_friction_log(rig, {}).log, {});
  ASSERT_FALSE(result.fit.identifiability.identifiable);
  EXPECT_NE(result.fit.identifiability.issues[0].why.find("one temperature"), std::string::npos)
      << result.fit.identifiability.issues[0].why;

  rig = compact_rig(7);
  rig.velocity_m_s = {0.066, 0.083, 0.11, 0.15};
  result = fit_friction(generate_friction_log(rig, {}).log, {});
  ASSERT_FALSE(result.fit.identifiability.identifiable);
  bool stribeck = false;
  for (const auto& issue : result.fit.identifiability.issues)
    stribeck |= issue.why.find("no samples below 0.03 m/s") != std::string::npos;
  EXPECT_TRUE(stribeck);
}

// ∂r/∂θ from the Jets equals central finite differences, with effects and with a robust loss.
TEST(FrictionFit, ResidualDerivativesEqualFiniteDifferences) {
  RigEffects truth_effects;
  set_rig_effect(truth_effects, "seal_drag", 100);
  const auto log = generate_friction_log(compact_rig(8, 1), truth_effects).log;
  detail::FrictionData data{&log, {}, {}, 40.0};
  for (std::size_t i = 0; i < log.size(); i += 7) {
    data.samples.push_back(i);
    data.inv_sigma.push_back(1 / 0.15);
  }
  for (const auto& loss : {detail::RowLoss{}, detail::RowLoss{RobustLoss::huber, 1.345}, detail::RowLoss{RobustLoss::cauchy, 2.0}}) {
    const detail::FrictionModel model(data, {friction_effect_slot("seal_drag"), friction_effect_slot("stribeck_exponent")});
    const auto cost = model.cost_function({}, loss);
    // Relative step 1e-6 of |θ| (the constants are small numbers).
    test::expect_jacobian_matches_central_differences(*cost, {0.3, 0.02, 1.4, 0.017, 0.0032, 0.065, 0.03, 80.0, 1.1},
                                                      1e-6, 1e-6);
  }
}

// 2 % gross outliers: the Huber loss keeps the constants inside their intervals; plain least
// squares does not.
TEST(FrictionFit, RobustLossResistsGrossOutliers) {
  auto log = generate_friction_log(compact_rig(9, 3), {}).log;
  for (std::size_t i = 0; i < log.size(); i += 50) log.friction_N[i] += 8.0;  // 2 %, ~50 σ
  FrictionFitOptions robust;
  robust.fit.loss = RobustLoss::huber;
  const auto result = fit_friction(log, robust);
  ASSERT_TRUE(result.fit.solver.usable);
  for (std::size_t j = 0; j < 7; ++j)
    EXPECT_TRUE(covers(result.fit.parameters[j], truth(j)))
        << result.fit.parameters[j].name << " = " << result.fit.parameters[j].value << ", true " << truth(j);
  const auto plain = fit_friction(log, {});
  int missed = 0;
  for (std::size_t j = 0; j < 7; ++j) missed += !covers(plain.fit.parameters[j], truth(j));
  EXPECT_GT(missed, 0) << "the outliers should bias plain least squares";
}

TEST(FrictionFit, FitsANamedEffectOnTopOfTheLaw) {
  RigEffects effects;
  set_rig_effect(effects, "seal_drag", 150);
  const auto log = generate_friction_log(compact_rig(10, 3), effects).log;
  FrictionFitOptions options;
  options.effects = {"seal_drag"};
  const auto result = fit_friction(log, options);
  const auto& drag = result.fit.parameter("seal_drag");
  EXPECT_TRUE(covers(drag, 150.0)) << drag.value << " ± " << drag.se;
  EXPECT_NEAR(result.effects().of<SealDrag>(), drag.value, 0);
  EXPECT_THROW(
      [&] {
        FrictionFitOptions bad;
        bad.effects = {"warp"};
        fit_friction(log, bad);
      }(),
      InvalidParameter);
}

TEST(FrictionFit, SpreadAcrossRunsUsesEquationOneAndFlagsRunToRunDifferences) {
  auto rig = compact_rig(12, 6);
  const auto clean = fit_friction(generate_friction_log(rig, {}).log, {});
  ASSERT_EQ(clean.spread.size(), 7u);
  for (const auto& s : clean.spread) {
    EXPECT_EQ(s.spread.n, 6u) << s.parameter;
    EXPECT_FALSE(s.wider_than_pooled) << s.parameter << " ratio " << s.ratio;
    EXPECT_LT(s.ratio, 2.5) << s.parameter;
  }
  EXPECT_EQ(clean.fit.uncertainty.method, "hac") << clean.fit.uncertainty.reason;
}

// A thermometer's noise is a classical error in a covariate: taken as exact it flattens the
// law's temperature dependence (β biased toward 0). The default fit sees each block's mean
// logged temperature (one run at one setting) instead: every sample of a block gets the mean
// of the block's logged values, blocks of other runs or settings keep their own, and β comes
// out where it is, where the logged temperature (noise 0.5 K here) puts it several SEs low.
TEST(FrictionFit, TheLawSeesEachBlocksMeanLoggedTemperatureNotTheThermometersNoise) {
  auto rig = compact_rig(31, 4);
  rig.temperature_noise_K = 0.5;
  const FrictionLog log = generate_friction_log(rig, {}).log;
  const FrictionLog seen = with_block_mean_temperature(log);
  ASSERT_EQ(seen.size(), log.size());
  {  // each setting on a free thread: the same bits as one after another
    const int before = detail::limit_slice_threads(1);
    const FrictionLog serial = with_block_mean_temperature(log);
    detail::limit_slice_threads(before);
    for (std::size_t i = 0; i < log.size(); ++i)
      ASSERT_EQ(std::bit_cast<std::uint64_t>(serial.temperature_C[i]), std::bit_cast<std::uint64_t>(seen.temperature_C[i]));
  }
  // The rig holds each setting at a set point (its temperatures), one run after another:
  // every sample of a (run, guide, preload, load, set point) block sees the block's mean.
  std::map<std::tuple<std::uint32_t, std::uint32_t, double, double, double>, std::pair<double, double>> blocks;
  const auto set_point = [&](std::size_t i) {
    double nearest = rig.temperature_C.front();
    for (double t : rig.temperature_C)
      if (std::abs(t - log.temperature_C[i]) < std::abs(nearest - log.temperature_C[i])) nearest = t;
    return std::tuple{log.run[i], log.guide[i], log.preload_um[i], log.load_N[i], nearest};
  };
  for (std::size_t i = 0; i < log.size(); ++i) {
    auto& [sum, count] = blocks[set_point(i)];
    sum += log.temperature_C[i], count += 1;
  }
  for (std::size_t i = 0; i < log.size(); ++i) {
    const auto& [sum, count] = blocks[set_point(i)];
    EXPECT_NEAR(seen.temperature_C[i], sum / count, 1e-12) << "sample " << i;
  }
  // A temperature that drifts over a block is cut into 1 K bins: none is more than 0.5 K from its mean.
  FrictionLog drifting = log;
  for (std::size_t i = 0; i < drifting.size(); ++i) drifting.temperature_C[i] = 20 + 20 * static_cast<double>(i) / static_cast<double>(log.size());
  const FrictionLog binned = with_block_mean_temperature(drifting);
  for (std::size_t i = 0; i < drifting.size(); ++i) ASSERT_LE(std::abs(binned.temperature_C[i] - drifting.temperature_C[i]), 0.5);

  FrictionFitOptions o;
  o.fit.bootstrap = 0;
  const auto fit = fit_friction(log, o);
  const ParameterEstimate& beta = fit.fit.parameter("beta_per_K");
  EXPECT_TRUE(covers(beta, truth(5))) << beta.value << " ± " << beta.se;
  o.temperature = FrictionTemperature::logged;
  const ParameterEstimate logged = fit_friction(log, o).fit.parameter("beta_per_K");
  EXPECT_LT(logged.value, truth(5) - 3 * logged.se) << "the noise taken as exact flattens β: " << logged.value;
}

// Clean, independent data: the chosen covariance is the within-run sandwich, and it keeps the
// intervals the i.i.d. covariance gives (no needless widening).
TEST(FrictionFit, CleanIndependentDataKeepTheIidIntervals) {
  for (std::uint64_t seed : {21, 22, 23}) {
    auto rig = compact_rig(seed, 6);
    rig.temperature_noise_K = 0;  // else the force's error grows with dF/dT: heteroscedastic, not i.i.d.
    const auto fit = fit_friction(generate_friction_log(rig, {}).log, {});
    const Uncertainty& u = fit.fit.uncertainty;
    EXPECT_EQ(u.method, "hac") << u.reason;
    const CovarianceSummary* iid = u.find("iid");
    ASSERT_NE(iid, nullptr);
    for (std::size_t j = 0; j < 7; ++j) {
      const double ratio = fit.fit.parameters[j].se / iid->se[j];
      EXPECT_GE(ratio, 0.9) << fit.fit.parameters[j].name << " with " << u.hac_lags << " lags";
      EXPECT_LE(ratio, 1.2) << fit.fit.parameters[j].name << " with " << u.hac_lags << " lags";
    }
  }
}

// Runs that disagree beyond their noise widen the quoted intervals: a load-cell zero that
// moves by run (the model has no term for it) makes every run's residuals one slow shift; the
// quoted covariance counts it (the within-run sandwich sees it as memory that lasts the whole
// run, the cluster one as runs that disagree), and the spread of the runs' own fits is then
// inside the pooled SE. Fitted without the offsets (the default models them as random).
TEST(FrictionFit, RunsThatDisagreeWidenTheIntervals) {
  auto rig = compact_rig(12, 6);
  rig.run_offset_N = 1.0;
  FrictionFitOptions o;
  o.run_offsets = RunOffsets::none;
  const auto offset = fit_friction(generate_friction_log(rig, {}).log, o);
  const Uncertainty& u = offset.fit.uncertainty;
  EXPECT_TRUE(u.method == "hac" || u.method == "cluster") << u.method;
  EXPECT_LT(u.dof, 30) << "few runs: a t quantile well above the normal one";
  EXPECT_GT(u.lag1_autocorrelation, 0.9);
  const auto& f0 = offset.fit.parameter("f0");
  EXPECT_GT(f0.se, 3 * u.find("iid")->se[6]) << "the zero offsets move f0 by run";
  for (const auto& s : offset.spread) EXPECT_LT(s.ratio, 2.5) << s.parameter << ": the quoted SE holds the runs' spread";
}

// The profile curve each interval came from, and where each start ended: the curve is 0 at the
// estimate, rises on both sides and crosses 1 at the quoted interval's edges; the multi-start
// record holds one cost per start, the agreeing ones within 0.1 % of the best.
TEST(FrictionFit, RecordsTheProfileCurvesAndWhereEachStartEnded) {
  FrictionFitOptions o;
  o.fit.profile = ProfileMode::all;
  const auto fit = fit_friction(generate_friction_log(compact_rig(14, 2), {}).log, o);
  for (std::size_t j = 0; j < 7; ++j) {
    const ParameterEstimate& p = fit.fit.parameters[j];
    ASSERT_EQ(p.interval, "profile") << p.name;
    ASSERT_GE(p.profile_curve.size(), 8u) << p.name;
    auto at = [&](double value) {  // the curve, linearly interpolated
      const auto& c = p.profile_curve;
      for (std::size_t k = 1; k < c.size(); ++k)
        if (c[k].value >= value) return c[k - 1].excess + (c[k].excess - c[k - 1].excess) * (value - c[k - 1].value) / (c[k].value - c[k - 1].value);
      return c.back().excess;
    };
    EXPECT_TRUE(std::is_sorted(p.profile_curve.begin(), p.profile_curve.end(),
                               [](const ProfilePoint& a, const ProfilePoint& b) { return a.value < b.value; }));
    EXPECT_NEAR(at(p.value), 0.0, 1e-6) << p.name;
    EXPECT_NEAR(at(p.profile_low), 1.0, 0.02) << p.name;
    EXPECT_NEAR(at(p.profile_high), 1.0, 0.02) << p.name;
    EXPECT_GT(p.profile_curve.front().excess, 1.0) << p.name << ": the curve reaches beyond the interval";
    EXPECT_GT(p.profile_curve.back().excess, 1.0) << p.name;
  }
  const SolverReport& s = fit.fit.solver;
  ASSERT_EQ(s.start_costs.size(), static_cast<std::size_t>(s.starts));
  EXPECT_GT(s.start_residuals, 0u);
  const double best = *std::min_element(s.start_costs.begin(), s.start_costs.end());
  EXPECT_EQ(std::count_if(s.start_costs.begin(), s.start_costs.end(), [&](double c) { return c - best <= 1e-3 * best + 1e-12; }),
            s.starts_agreed);
}

// Logs that carry no friction law are refused with the reason, not fitted to an exact,
// meaningless agreement: nothing in motion; every sample at one condition.
TEST(FrictionFit, LogsWithoutMotionOrWithoutAnyVariationAreRefused) {
  FrictionLog log = generate_friction_log(compact_rig(15, 1), {}).log;
  FrictionLog still = log;
  std::fill(still.velocity_m_s.begin(), still.velocity_m_s.end(), 0.0);
  try {
    fit_friction(still, {});
    FAIL() << "fitted a log in which nothing moves";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("no sample in motion"), std::string::npos) << e.what();
  }
  FrictionLog one = log;
  for (auto* column : {&one.velocity_m_s, &one.load_N, &one.preload_um, &one.temperature_C})
    std::fill(column->begin(), column->end(), column->front());
  try {
    fit_friction(one, {});
    FAIL() << "fitted a log of one condition";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("every sample at one condition"), std::string::npos) << e.what();
  }
}

// The convergence claim holds: at a minimum the step still to go is ~0 SE; a polish stopped short
// (here after one iteration, from a start far off) is reported as not converged, with why.
TEST(FrictionFit, ConvergedMeansNoStepIsLeftToTake) {
  const FrictionLog log = generate_friction_log(compact_rig(16, 2), {}).log;
  const auto fit = fit_friction(log, {});
  EXPECT_TRUE(fit.fit.solver.converged);
  EXPECT_LT(fit.fit.solver.remaining_step_se, 1e-3);
  FrictionFitOptions cut;
  cut.fit.starts = 0;  // no multi-start: the polish alone, from the start
  cut.fit.max_iterations = 1;
  cut.start.mu_v *= 30;
  cut.start.k1 *= 0.5;
  const auto stopped = fit_friction(log, cut);
  EXPECT_FALSE(stopped.fit.solver.converged);
  EXPECT_GT(stopped.fit.solver.remaining_step_se, 0.1);
  EXPECT_TRUE(std::any_of(stopped.fit.warnings.begin(), stopped.fit.warnings.end(),
                          [](const std::string& w) { return w.find("standard errors to go") != std::string::npos; }));
}

TEST(FrictionFit, WeightsFromTheSpreadOfRepeats) {
  auto rig = compact_rig(13, 4);
  rig.noise_N = 0.3;
  const auto log = generate_friction_log(rig, {}).log;
  FrictionFitOptions options;
  options.weighting = FrictionWeighting::per_run;
  const auto result = fit_friction(log, options);
  for (double s : result.sigma_N) EXPECT_NEAR(s, 0.3, 0.06);
  // Whitened by the right σ, the residual variance is about 1.
  EXPECT_NEAR(result.fit.residual_variance, 1.0, 0.15);
}

}  // namespace
}  // namespace lmcal

#include <ceres/covariance.h>
#include <ceres/problem.h>

namespace lmcal {
namespace {

// The engine's (JᵀJ)⁻¹ from a rank-revealing QR is what ceres::Covariance computes.
TEST(FrictionFit, CovarianceEqualsCeresCovariance) {
  const auto log = generate_friction_log(compact_rig(14, 1), {}).log;
  detail::FrictionData data{&log, {}, {}, 40.0};
  for (std::size_t i = 0; i < log.size(); ++i) {
    data.samples.push_back(i);
    data.inv_sigma.push_back(1 / 0.15);
  }
  const detail::FrictionModel model(data, {});
  std::vector<double> theta = {0.31, 0.031, 1.5, 0.0152, 0.00301, 0.0668, 0.0291};
  const std::vector<bool> held = {false, true, false, false, false, false, false};  // k2 held, as a fit may
  Eigen::MatrixXd J, ours;
  std::string message;
  detail::evaluate_residuals(model, theta, {}, &J);
  ASSERT_TRUE(detail::covariance_from_jacobian(J, held, ours, message)) << message;

  const auto cost = model.cost_function({}, {});
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  problem.AddResidualBlock(cost.get(), nullptr, theta.data());
  problem.SetManifold(theta.data(), new ceres::SubsetManifold(7, {1}));
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  ceres::Covariance covariance(co);
  const std::vector<std::pair<const double*, const double*>> blocks = {{theta.data(), theta.data()}};
  ASSERT_TRUE(covariance.Compute(blocks, &problem));
  Eigen::Matrix<double, 7, 7, Eigen::RowMajor> theirs;
  covariance.GetCovarianceBlock(theta.data(), theta.data(), theirs.data());
  for (int a = 0; a < 7; ++a)
    for (int b = 0; b < 7; ++b)
      EXPECT_NEAR(ours(a, b), theirs(a, b), 1e-8 * std::sqrt(std::abs(theirs(a, a) * theirs(b, b))) + 1e-300)
          << a << "," << b;

  // A column that no residual depends on: rank deficient, reported, not a crash.
  Eigen::MatrixXd deficient = J;
  deficient.col(3).setZero();
  EXPECT_FALSE(detail::covariance_from_jacobian(deficient, std::vector<bool>(7, false), ours, message));
  EXPECT_NE(message.find("rank deficient"), std::string::npos);
}

}  // namespace
}  // namespace lmcal
