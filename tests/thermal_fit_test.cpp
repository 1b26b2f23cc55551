#include "lmcal/io/units.hpp"
#include "lmcal/fit/thermal_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "fit/thermal_model.hpp"
#include "support/finite_differences.hpp"
#include "support/temp_folder.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/rig/virtual_rig.hpp"
#include "lmcal/fit/model_file.hpp"
#include "lmcal/models/thermal_mechanisms.hpp"

namespace lmcal {
namespace {

// Clean runs at the paper's speeds: no noise, no bias, averaged source, known α = 0.6.
ThermalRigConfig clean_rig(double duration_s = 4 * 3600.0) {
  ThermalRigConfig c;
  c.duration_s = duration_s;
  c.record_every_s = 30;
  c.noise_K = c.tc_bias_K = c.ambient_bias_K = 0;
  c.friction_noise_N = 0;
  return c;
}

// The estimate's interval holds the truth.
void expect_interval_holds(const ParameterEstimate& estimate, double truth) {
  EXPECT_LE(estimate.ci_low, truth) << estimate.name;
  EXPECT_GE(estimate.ci_high, truth) << estimate.name;
}

ThermalFitOptions options_for_rig() {
  ThermalFitOptions o;
  o.heat = HeatInput::friction_law;  // the rig's truth: the paper's law at the initial temperature
  o.half_rail_segments = 150;        // the rig's 2 mm grid
  o.time_step_s = 5;
  o.compare_sources = false;
  return o;
}

TEST(ThermalFit, RecoversAlphaWithinOnePercentOnCleanData) {
  const auto data = generate_thermal_dataset(clean_rig(), {}, "clean").set;
  const auto result = fit_thermal(data, options_for_rig());
  const auto& alpha = result.joint.parameter("alpha");
  EXPECT_NEAR(alpha.value, 0.6, 0.006);
  EXPECT_TRUE(result.joint.solver.converged);
  EXPECT_EQ(result.per_run.size(), 3u);
  for (const auto& run : result.per_run) EXPECT_NEAR(run.parameter("alpha").value, 0.6, 0.006);
  EXPECT_LT(result.max_error_percent, 1.0);
  // Three per-run α, their Eq. 1 spread and interval.
  EXPECT_EQ(result.alpha_spread.n, 3u);
  EXPECT_NEAR(result.alpha_spread.mean, 0.6, 0.006);
  // The α error curve (Fig. 11) of each run has its minimum at the grid point next to 0.6.
  for (const auto& run : result.runs) {
    double best_alpha = -1, best = 1e9;
    for (const auto& p : result.alpha_curve)
      if (p.run == run.id && p.rmse_K < best) {
        best = p.rmse_K;
        best_alpha = p.alpha;
      }
    EXPECT_NEAR(best_alpha, 0.6, 0.011) << run.id;
  }
}

TEST(ThermalFit, NoisyBiasedRunsGiveAnIntervalThatContainsTheTruth) {
  auto rig = clean_rig();
  rig.noise_K = 0.05;
  rig.tc_bias_K = 0.5;
  rig.seed = 3;
  const auto data = generate_thermal_dataset(rig, {}, "noisy").set;
  auto o = options_for_rig();
  o.offsets = ThermalOffsets::fitted;  // thermocouple bias is a per-sensor offset
  o.fit_initial_temperature = true;
  o.per_run_fits = false;
  const auto result = fit_thermal(data, o);
  const auto& alpha = result.joint.parameter("alpha");
  expect_interval_holds(alpha, 0.6);
  EXPECT_NEAR(alpha.value, 0.6, 0.03);
}

TEST(ThermalFit, FitsHTooAndTheSourceModelRatioIsAboutContactOverStroke) {
  const auto data = generate_thermal_dataset(clean_rig(), {}, "clean").set;
  auto o = options_for_rig();
  o.fit_h = true;
  o.h_W_m2K = 8.0;  // start away from the truth, 5.3
  o.per_run_fits = false;
  o.compare_sources = true;
  const auto result = fit_thermal(data, o);
  EXPECT_NEAR(result.joint.parameter("h_W_m2K").value, 5.3, 0.1);
  EXPECT_NEAR(result.joint.parameter("alpha").value, 0.6, 0.01);
  // PHYSICS.md §7: `paper` injects L1/Lb1 times the power, so its α is smaller by about Lb1/L1.
  EXPECT_NEAR(result.alpha_ratio_paper_over_averaged, result.contact_over_stroke, 0.1 * result.contact_over_stroke);
}

// Two noisy 1 h runs (0.083, 0.11 m/s) ready for the model: every 12th record of two sensors,
// Q_f = 4 W at the start temperature (24 °C, SRN 35C at 3 kN and 4 µm).
std::vector<detail::PreparedRun> prepared_runs() {
  auto rig = clean_rig(3600);
  rig.velocity_m_s = {0.083, 0.11};
  rig.noise_K = 0.05;
  const auto data = generate_thermal_dataset(rig, {}, "d").set;
  std::vector<detail::PreparedRun> runs;
  for (const auto& run : data.runs) {
    detail::PreparedRun pr;
    pr.id = run.id;
    pr.geometry = {.rail_length_m = 0.6, .area_m2 = 8.88e-4, .perimeter_m = 0.14, .stroke_m = 0.2,
                   .contact_length_m = 0.0822, .velocity_m_s = run.velocity_m_s};
    pr.params = {.heat_partition = 0.6, .heat_rate_W = 4.0, .initial_temperature_C = 24.0};
    pr.conditions = {.load_N = 3000, .preload_um = 4, .block_length_mm = 120.2, .velocity_m_s = run.velocity_m_s,
                     .temperature_C = 24.0};
    pr.ambient = {run.trace.time_s, run.trace.ambient[0].values};
    for (std::size_t t = 0; t < run.trace.size(); t += 12) {
      pr.times_s.push_back(run.trace.time_s[t]);
      pr.measured.push_back({run.trace.rail[0].values[t], run.trace.rail[1].values[t]});
    }
    pr.sensor_names = {"tc1_C", "tc2_C"};
    pr.sensor_positions_m = {0.0, 0.05};
    runs.push_back(pr);
  }
  return runs;
}

// ∂r/∂θ through the templated solver equals central finite differences.
TEST(ThermalFit, ResidualDerivativesEqualFiniteDifferences) {
  const auto runs = prepared_runs();
  // α, h, two offsets of the first run, T0 of the second.
  detail::ThermalLayout layout{.alpha = 0, .h = 1, .offsets = {{2, 3}, {-1, -1}}, .initial = {-1, 4}, .size = 5};
  const detail::ThermalModel model(runs, layout, {.half_rail_segments = 40, .time_step_s = 60});
  test::expect_jacobian_matches_central_differences(*model.cost_function({}, {}), {0.55, 6.0, 0.2, -0.1, 24.3}, 1e-5,
                                                    1e-6);
  EXPECT_TRUE(model.linear({false, true, false, false, false}));
  EXPECT_FALSE(model.linear({false, false, false, false, false}));
}

// The empirical sensor terms enter the residuals directly (not through the solver): their
// coefficients' and scales' derivatives — a period shared by a_P and b_P, a lag's τ, and the
// rise·t term that carries the simulation's — equal central finite differences.
TEST(ThermalFit, SensorTermDerivativesEqualFiniteDifferences) {
  const auto runs = prepared_runs();
  using K = ThermalTermKind;
  // α, T0 of the second run, then c_t, c_a, P, c_b, c_lag, τ, c_rise, c_V.
  detail::ThermalLayout layout{.alpha = 0, .offsets = {{-1, -1}, {-1, -1}}, .initial = {-1, 1}};
  layout.terms = {{.kind = K::time},           {.kind = K::ambient_in_phase},   {.kind = K::ambient_quadrature},
                  {.kind = K::ambient_lag},    {.kind = K::rise_time},          {.kind = K::velocity_time}};
  layout.term_coefficient = {2, 3, 5, 6, 8, 9};
  layout.term_scale = {-1, 4, 4, 7, -1, -1};
  layout.size = 10;
  const detail::ThermalModel model(runs, layout, {.half_rail_segments = 40, .time_step_s = 60});
  test::expect_jacobian_matches_central_differences(
      *model.cost_function({}, {}), {0.55, 24.3, 0.03, 0.8, 2 * 3600.0, -0.3, 0.5, 1800.0, 0.01, 0.2}, 1e-5, 1e-6);
  std::vector<bool> held(10, false);
  EXPECT_FALSE(model.linear(held));  // the scales and c·rise(α)
  held[4] = held[7] = held[8] = true;
  EXPECT_TRUE(model.linear(held));   // the coefficients alone are linear
}

// With the heat a measured run mean, the coupled heat is scaled to keep that mean: a fixed
// point solved by repeated simulation, whose derivatives must still be the model's.
TEST(ThermalFit, RunMeanCoupledHeatHasTheModelsDerivatives) {
  auto runs = prepared_runs();
  for (auto& run : runs) run.heat_is_run_mean = true;
  // α and κ, T0 of the second run.
  const detail::ThermalLayout layout{.alpha = 0,
                                     .extensions = {&detail::thermal_extension("coupling")},
                                     .extension_first = {1},
                                     .offsets = {{-1, -1}, {-1, -1}},
                                     .initial = {-1, 2},
                                     .size = 3};
  const detail::ThermalModel model(runs, layout, {.half_rail_segments = 40, .time_step_s = 60});
  test::expect_jacobian_matches_central_differences(*model.cost_function({}, {}), {0.55, 0.8, 24.3}, 1e-5, 1e-6);
  // And the scaling matters: a heat at the start temperature gives other temperatures.
  auto at_start = runs;
  for (auto& run : at_start) run.heat_is_run_mean = false;
  const detail::ThermalModel started(at_start, layout, {.half_rail_segments = 40, .time_step_s = 60});
  const auto mean = model.simulate({0.55, 0.8, 24.3}), start = started.simulate({0.55, 0.8, 24.3});
  EXPECT_GT(mean[1].back()[0] - start[1].back()[0], 0.05);  // the same mean is more heat than the warming start's
  // A coupled heat follows the rail, so the field is not affine in α even with κ held: the
  // model must not be called linear (a linear solve, or an end profile extrapolated in α,
  // would be wrong). The curvature it would miss is there:
  const auto low = started.simulate({0.3, 0.8, 24.3}), mid = started.simulate({0.6, 0.8, 24.3}),
             high = started.simulate({0.9, 0.8, 24.3});
  EXPECT_GT(std::abs(mid[1].back()[0] - 0.5 * (low[1].back()[0] + high[1].back()[0])), 1e-4);
  EXPECT_FALSE(started.linear({false, true, true}));
}

// A load cell's mean over a run that warms is below the friction of the cold rail. With the
// heat from that mean, the coupled heat keeps it as its run mean, and α and κ come back; with
// start_friction_N, the heat starts from the friction at the start temperature and so do they.
TEST(ThermalFit, CoupledHeatFromAMeasuredFrictionRecoversAlpha) {
  auto rig = clean_rig(3 * 3600.0);
  rig.velocity_m_s = {0.083, 0.11};
  RigEffects effects;
  set_rig_effect(effects, "coupling", 1);
  auto generated = generate_thermal_dataset(rig, effects, "coupled");
  const auto truth = nlohmann::json::parse(generated.truth_json);
  ThermalFitOptions o = options_for_rig();
  o.heat = HeatInput::measured_friction;
  o.extensions = {"coupling"};
  o.per_run_fits = false;
  for (std::size_t r = 0; r < generated.set.runs.size(); ++r) {
    const double start_N = truth["runs"][r]["heat_rate_start_W"].get<double>() / rig.velocity_m_s[r];
    EXPECT_LT(*generated.set.runs[r].mean_friction_N, 0.97 * start_N);  // the run mean is well below the start
  }
  const auto from_mean = fit_thermal(generated.set, o);
  EXPECT_EQ(from_mean.runs[0].heat_source, "measured mean friction");
  EXPECT_NEAR(from_mean.joint.parameter("alpha").value, 0.6, 0.006);
  EXPECT_NEAR(from_mean.joint.parameter("coupling").value, 1.0, 0.05);
  for (std::size_t r = 0; r < generated.set.runs.size(); ++r)
    generated.set.runs[r].start_friction_N = truth["runs"][r]["heat_rate_start_W"].get<double>() / rig.velocity_m_s[r];
  const auto from_start = fit_thermal(generated.set, o);
  EXPECT_EQ(from_start.runs[0].heat_source, "measured friction at the start temperature");
  EXPECT_NEAR(from_start.joint.parameter("alpha").value, 0.6, 0.006);
  EXPECT_NEAR(from_start.joint.parameter("coupling").value, 1.0, 0.05);
}

TEST(ThermalFit, ReportsEquationTwoBetweenAmbientSensorsAndRepeats) {
  auto rig = clean_rig(3600);
  rig.velocity_m_s = {0.11};
  rig.repeats = 2;
  rig.ambient_bias_K = 0;
  const auto data = generate_thermal_dataset(rig, {}, "r").set;
  const auto result = fit_thermal(data, options_for_rig());
  ASSERT_EQ(result.repeat_differences.size(), 1u);
  EXPECT_EQ(result.repeat_differences[0].runs, "v110_r1/v110_r2");
  EXPECT_LT(result.repeat_differences[0].percent, 1.0);  // same conditions, clean: α agrees
  for (const auto& run : result.runs) EXPECT_NEAR(run.ambient_difference_percent, 0.0, 1e-9);  // unbiased sensors
}

// A run too short to follow the rail's heating is refused, naming the run (three records
// fitted α 0.753 [0.398, 1.108]).
// Each run's heat reaching the rail 5 % off what its logged friction says: no record of the
// run sees it, only the runs' spread does. With the defaults the cluster covariance is quoted
// (the runs are the replicates), and α's SE is what the runs make it, Σ c_r² (SE_r² + τ²) with
// c_r each run's share of the information (1/SE² of its i.i.d. fit) and τ the REML spread of
// the per-run α, the t dof near runs − 1; repeats are compared against √(SE₁² + SE₂² + 2τ²).
TEST(ThermalFit, TheRunsAreAlphasReplicates) {
  ThermalRigConfig rig;
  rig.velocity_m_s = {0.05, 0.066, 0.083, 0.11};
  rig.repeats = 2;
  rig.heat_variation = 0.05;
  rig.seed = 41;
  ThermalFitOptions o;
  o.compare_sources = false;
  o.curve_points = 0;
  o.fit.bootstrap = 0;
  const auto fit = fit_thermal(generate_thermal_dataset(rig, {}, "replicates").set, o);
  const Uncertainty& u = fit.joint.uncertainty;
  EXPECT_EQ(u.method, "cluster") << u.reason;
  EXPECT_NE(u.reason.find("the runs are the replicates"), std::string::npos) << u.reason;
  const RandomEffects& re = fit.alpha_runs;
  ASSERT_EQ(re.k, 8u);
  EXPECT_GT(re.tau, 0.01) << "5 % heat error per run at α 0.6";
  double info = 0;
  for (const auto& run : fit.per_run) info += std::pow(run.uncertainty.find("iid")->se[0], -2);
  double variance = 0;
  for (const auto& run : fit.per_run)
    variance += std::pow(std::pow(run.uncertainty.find("iid")->se[0], -2) / info, 2) *
                (std::pow(run.parameter("alpha").se, 2) + re.tau * re.tau);
  const ParameterEstimate& alpha = fit.joint.parameter("alpha");
  EXPECT_NEAR(alpha.se, std::sqrt(variance), 1e-12 * alpha.se);
  EXPECT_GT(alpha.se, u.find("cluster")->se[0]);
  EXPECT_NEAR(alpha.dof, 7.0, 1e-9);
  EXPECT_LT(alpha.ci_low, alpha.value - 2.3 * alpha.se) << "t(7)";
  ASSERT_EQ(fit.repeat_differences.size(), 4u);
  for (const auto& d : fit.repeat_differences) EXPECT_LT(std::abs(d.z), std::abs(d.z_within)) << d.runs;
}

TEST(ThermalFit, ARunOfAFewRecordsIsRefused) {
  auto rig = clean_rig(3600);
  rig.velocity_m_s = {0.11};
  auto data = generate_thermal_dataset(rig, {}, "short").set;
  ThermalTrace& trace = data.runs.at(0).trace;
  trace.time_s.resize(3);
  for (auto* channels : {&trace.ambient, &trace.rail})
    for (TemperatureChannel& c : *channels) c.values.resize(3);
  try {
    fit_thermal(data, options_for_rig());
    FAIL() << "fitted a run of three records";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("3 records with a thermocouple value to fit"), std::string::npos) << e.what();
    EXPECT_EQ(e.parameter(), data.runs[0].id);
  }
}

// No heat in any run (issue 22: SIGSEGV when α alone was free; with offsets, minutes of profile
// searches): α cannot be told, and the fit says so before it starts.
TEST(ThermalFit, NoHeatInAnyRunIsRefusedAsAlphaNotIdentifiable) {
  auto rig = clean_rig(3600);
  rig.velocity_m_s = {0.066, 0.11};
  auto data = generate_thermal_dataset(rig, {}, "cold").set;
  for (ThermalRun& run : data.runs) run.mean_friction_N = 0.0;
  ThermalFitOptions o = options_for_rig();
  o.heat = HeatInput::measured_friction;
  try {
    fit_thermal(data, o);
    FAIL() << "fitted α without heat";
  } catch (const InvalidParameter& e) {
    EXPECT_EQ(e.parameter(), "alpha");
    EXPECT_NE(std::string(e.what()).find("not identifiable: no heat (every run's heat rate is 0 W"), std::string::npos) << e.what();
  }
  // One run with heat is enough: the other's zero heat only informs its own sensors.
  data.runs[1].mean_friction_N = 40.0;
  const ThermalFitResult fit = fit_thermal(data, o);
  EXPECT_TRUE(fit.joint.solver.usable) << fit.joint.solver.unusable_reason;
  EXPECT_FALSE(fit.joint.parameter("alpha").held_unidentifiable);
}

// Every thermocouple cell missing (NaN) gave 0 residuals, dof -1 and α at its start value 0.600
// [nan, nan] called usable (issue 23 #8): such a run has no record to fit.
TEST(ThermalFit, ARunWithoutAnyThermocoupleValueIsRefused) {
  auto rig = clean_rig(3600);
  rig.velocity_m_s = {0.11};
  auto data = generate_thermal_dataset(rig, {}, "blank").set;
  for (TemperatureChannel& c : data.runs.at(0).trace.rail) std::fill(c.values.begin(), c.values.end(), std::nan(""));
  try {
    fit_thermal(data, options_for_rig());
    FAIL() << "fitted a run without a thermocouple value";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("0 records with a thermocouple value to fit"), std::string::npos) << e.what();
  }
}

// A sensor is labelled by its name, not by the unit its column was written in: a column
// tc1_K (loaded into °C) is "tc1" beside measured_C in the samples and in its offset's name.
TEST(ThermalFit, SensorsAreLabelledWithoutTheirColumnsUnit) {
  auto rig = clean_rig(3600);
  rig.velocity_m_s = {0.11};
  auto data = generate_thermal_dataset(rig, {}, "k").set;
  ThermalRun& run = data.runs.at(0);
  const std::string column = run.trace.rail.at(0).name;
  ASSERT_EQ(column, "tc1_C");
  run.trace.rail[0].name = "tc1_K";
  run.sensor_position_m["tc1_K"] = run.sensor_position_m.at(column);
  run.sensor_position_m.erase(column);
  const auto result = fit_thermal(data, options_for_rig());
  EXPECT_EQ(result.sensor_names.at(0).at(0), "tc1");
  EXPECT_EQ(result.sensor_names.at(0).at(1), "tc2");
  EXPECT_NE(thermal_fit_samples_csv(result).find("\nv110,,tc1,"), std::string::npos) << "run, line (none: generated), sensor";
}

}  // namespace
}  // namespace lmcal

namespace lmcal {
namespace {

// Offsets by default where the data determine them: a run that starts at the ambient (at rest
// in the room) has its thermocouples' offsets fitted; a run that starts 3 K warm cannot tell
// an offset from the rail's own temperature, so its offsets are held, and the result says so.
TEST(ThermalFit, OffsetsAreFittedWhereARunStartsIsothermalAndHeldWhereNot) {
  auto rig = clean_rig(2 * 3600.0);
  rig.tc_bias_K = 0.3;
  const auto generated = generate_thermal_dataset(rig, {}, "offsets");
  ThermalFitOptions o = options_for_rig();
  o.per_run_fits = false;
  o.time_step_s = 30;
  o.half_rail_segments = 100;
  // Every run starts at rest: every offset fitted, and equal to its thermocouple's bias.
  const auto fit = fit_thermal(generated.set, o);
  const auto truth = nlohmann::json::parse(generated.truth_json);
  for (std::size_t r = 0; r < fit.runs.size(); ++r) {
    EXPECT_TRUE(fit.runs[r].offsets_fitted);
    for (const auto& tc : truth["runs"][r]["thermocouples"]) {
      const std::string sensor = split_unit(tc["column"].get<std::string>(), Quantity::temperature)->name;  // tc1_C: tc1
      EXPECT_NEAR(fit.joint.parameter("offset " + fit.runs[r].id + " " + sensor).value, tc["bias_K"].get<double>(), 0.03);
    }
  }
  EXPECT_NEAR(fit.joint.parameter("alpha").value, 0.6, 0.01);
  // The second run still warm from a run before: its offsets held, and said why.
  auto data = generated.set;
  for (auto& channel : data.runs[1].trace.rail)
    for (double& T : channel.values) T += 3.0;
  const auto warm = fit_thermal(data, o);
  EXPECT_TRUE(warm.runs[0].offsets_fitted);
  EXPECT_FALSE(warm.runs[1].offsets_fitted);
  EXPECT_NE(warm.runs[1].offsets_note.find("does not start isothermal"), std::string::npos) << warm.runs[1].offsets_note;
  std::size_t offsets = 0;
  for (const auto& p : warm.joint.parameters) offsets += p.name.starts_with("offset ") ? 1 : 0;
  EXPECT_EQ(offsets, 2 * data.runs[0].trace.rail.size());  // runs 0 and 2
  o.offsets = ThermalOffsets::held;
  for (const auto& run : fit_thermal(data, o).runs) EXPECT_FALSE(run.offsets_fitted);
}


// ---- Runs as rigs produce them ----

// A 6 W heater on for 2 h, then off for 2 h, on a clean rig.
ThermalRigConfig heater_rig() {
  ThermalRigConfig c = clean_rig();
  c.heat_rate_W = 6.0;
  c.heater_off_s = 7200;
  return c;
}

// A heater of known power on for 2 h, then off for 2 h: the joint fit recovers α within its
// interval, takes the heat's stated uncertainty into it, and fits the cooling records too.
TEST(ThermalFit, HeaterRunWithAnOffPhaseFitsAlphaFromBothPhases) {
  auto rig = heater_rig();
  rig.stated_heat_uncertainty = 0.01;
  rig.noise_K = 0.05;
  rig.repeats = 2;
  rig.seed = 5;
  const auto data = generate_thermal_dataset(rig, {}, "heater").set;
  ASSERT_EQ(data.runs.size(), 2u);
  ASSERT_EQ(data.runs[0].schedule.size(), 2u);
  auto o = options_for_rig();
  o.heat = HeatInput::automatic;
  o.per_run_fits = false;
  const auto result = fit_thermal(data, o);
  const auto& alpha = result.joint.parameter("alpha");
  expect_interval_holds(alpha, 0.6);
  EXPECT_NEAR(alpha.value, 0.6, 0.02);
  EXPECT_EQ(result.runs[0].heat_source, "given heat rate");
  EXPECT_NEAR(result.runs[0].heat_relative_se, 0.01, 1e-4);
  EXPECT_NEAR(result.runs[0].heat_rate_W, 3.0, 1e-9);  // the schedule's mean: 6 W for half the run
  // The cooling phase is fitted: its records are samples, and the model cools through them.
  std::size_t cooling = 0;
  double at_off = 0, at_end = 0;
  for (const auto& sample : result.samples) {
    if (sample.run != 0 || sample.sensor != 0) continue;
    if (sample.time_s > 7200) ++cooling;
    if (sample.time_s == 7200) at_off = sample.simulated_C;
    at_end = sample.simulated_C;
  }
  EXPECT_EQ(cooling, static_cast<std::size_t>(7200 / rig.record_every_s));
  EXPECT_LT(at_end, at_off - 1.0);
}

// Cooling alone determines α: a fit of the records after the switch-off (the heating's
// records hidden) still finds it.
TEST(ThermalFit, CoolingRecordsAloneCarryAlpha) {
  auto data = generate_thermal_dataset(heater_rig(), {}, "heater").set;
  for (auto& channel : data.runs[0].trace.rail)
    for (std::size_t i = 0; i < channel.values.size(); ++i)
      if (data.runs[0].trace.time_s[i] < 7200 && i > 0) channel.values[i] = std::nan("");
  auto o = options_for_rig();
  o.per_run_fits = false;
  o.offsets = ThermalOffsets::held;
  EXPECT_NEAR(fit_thermal(data, o).joint.parameter("alpha").value, 0.6, 0.006);
}

// No ambient column: the manifest's constant ambient_C drives the model.
TEST(ThermalFit, RunWithAmbientKeyAndNoAmbientColumnFits) {
  auto rig = clean_rig();
  rig.ambient_columns = false;
  rig.ambient_drift_K_per_h = rig.ambient_wave_K = 0;
  rig.velocity_m_s = {0.11};
  const auto data = generate_thermal_dataset(rig, {}, "no_ambient").set;
  ASSERT_TRUE(data.runs[0].trace.ambient.empty());
  ASSERT_TRUE(data.runs[0].ambient_C);
  const auto result = fit_thermal(data, options_for_rig());
  EXPECT_NEAR(result.joint.parameter("alpha").value, 0.6, 0.006);
  EXPECT_TRUE(std::isnan(result.runs[0].ambient_difference_percent));
}

// A stopped block (velocity 0 from 2 h) makes no heat: the fit takes the schedule's friction
// heat (the law at the phase's speed) and recovers α, with the model cooling after the stop.
TEST(ThermalFit, StopPhaseTurnsTheFrictionHeatOff) {
  auto rig = clean_rig();
  rig.stop_s = 7200;
  rig.velocity_m_s = {0.11};
  auto data = generate_thermal_dataset(rig, {}, "stop").set;
  ASSERT_EQ(data.runs[0].schedule.size(), 2u);
  EXPECT_EQ(data.runs[0].schedule[1].velocity_m_s, 0.0);
  auto o = options_for_rig();
  o.per_run_fits = false;
  const auto result = fit_thermal(data, o);
  EXPECT_NEAR(result.joint.parameter("alpha").value, 0.6, 0.006);
  double at_stop = 0, at_end = 0;
  for (const auto& sample : result.samples) {
    if (sample.sensor != 0) continue;
    if (sample.time_s == 7200) at_stop = sample.simulated_C;
    at_end = sample.simulated_C;
  }
  EXPECT_LT(at_end, at_stop - 1.0);
  // The moving block keeps one speed: a stop is refused with it.
  o.source = SourceModel::moving;
  EXPECT_THROW(fit_thermal(data, o), InvalidParameter);
}

// The run's h (manifest h_W_m2K) is the model's where h is not fitted.
TEST(ThermalFit, RunConvectionCoefficientWinsOverTheOption) {
  auto rig = clean_rig();
  rig.h_W_m2K = 8.0;
  rig.velocity_m_s = {0.11};
  auto data = generate_thermal_dataset(rig, {}, "h8").set;
  auto o = options_for_rig();
  o.per_run_fits = false;
  EXPECT_GT(std::abs(fit_thermal(data, o).joint.parameter("alpha").value - 0.6), 0.02);  // h = 5.3, wrong
  data.runs[0].h_W_m2K = 8.0;
  EXPECT_NEAR(fit_thermal(data, o).joint.parameter("alpha").value, 0.6, 0.006);
}

// The run's oil (viscosity40_mm2_s) goes into the friction law the heat comes from.
TEST(ThermalFit, RunViscosityFeedsTheFrictionLaw) {
  auto rig = clean_rig();
  rig.constants.nu_ref_mm2_s = 68;  // a VG68 oil instead of the paper's 99 mm²/s
  rig.velocity_m_s = {0.11};
  auto data = generate_thermal_dataset(rig, {}, "vg68").set;
  auto o = options_for_rig();
  o.per_run_fits = false;
  EXPECT_GT(std::abs(fit_thermal(data, o).joint.parameter("alpha").value - 0.6), 0.05);  // with ν40 = 99
  data.runs[0].viscosity40_mm2_s = 68;
  EXPECT_NEAR(fit_thermal(data, o).joint.parameter("alpha").value, 0.6, 0.006);
}

class ThermalFitCatalogTest : public test::TempFolderTest {};

// A user catalog's [[bar]], named by the manifest's catalog key, loads and fits.
TEST_F(ThermalFitCatalogTest, UserBarFromTheManifestCatalogFits) {
  write("bars.toml", "[[bar]]\nname = \"steel bar 20x20\"\narea_m2 = 4e-4\nperimeter_m = 0.08\n"
                     "conductivity_W_mK = 45\ndensity_kg_m3 = 7850\nspecific_heat_J_kgK = 470\ncontact_length_mm = 50\n");
  const GuideCatalog catalog = load_catalog(dir_ / "bars.toml");
  auto rig = clean_rig();
  rig.catalog = &catalog;
  rig.guide = "steel bar 20x20";
  rig.heat_rate_W = 4.0;
  rig.sensor_position_m = {0.0, 0.1};
  ThermalDataSet made = generate_thermal_dataset(rig, {}, "bar").set;
  for (ThermalRun& run : made.runs) {
    run.file = dir_ / run.file;
    write(run.file.lexically_relative(dir_), thermal_trace_csv(run.trace));
  }
  const std::string manifest = thermal_manifest_toml(made, dir_);
  ASSERT_NE(manifest.find("catalog = \"bars.toml\""), std::string::npos) << manifest;
  const ThermalDataSet data = load_thermal_dataset(write("bar.toml", manifest));
  EXPECT_EQ(data.catalog_file, dir_ / "bars.toml");
  EXPECT_EQ(data.runs[0].guide_spec.kind, "bar");
  EXPECT_NEAR(fit_thermal(data, options_for_rig()).joint.parameter("alpha").value, 0.6, 0.006);
}

}  // namespace
}  // namespace lmcal

namespace lmcal {
namespace {

// The end profiles come from the fit's last evaluation with derivatives (extrapolated exactly
// where the fit is linear, as for α alone; taken as they are after a nonlinear fit, with h):
// at each thermocouple the profile equals the model's last reading less the offset.
TEST(ThermalFit, EndProfilesAgreeWithTheFittedReadings) {
  ThermalRigConfig rig = clean_rig(2 * 3600.0);
  rig.noise_K = 0.05;
  const auto data = generate_thermal_dataset(rig, {}, "end").set;
  for (const bool fit_h : {false, true}) {
    ThermalFitOptions o = options_for_rig();
    o.fit_h = fit_h;
    o.per_run_fits = false;
    o.alpha_start = 0.45;  // away from the solution: the extrapolation must carry the whole step
    const auto result = fit_thermal(data, o);
    ASSERT_EQ(result.end_states.size(), result.runs.size());
    for (std::size_t r = 0; r < result.runs.size(); ++r) {
      const auto& end = result.end_states[r];
      const auto& x = end.model.position_m;
      const auto& T = end.model.temperature_C;
      for (std::size_t s = 0; s < end.sensor_position_m.size(); ++s) {
        double last = std::numeric_limits<double>::quiet_NaN(), time = -1;
        for (const auto& sample : result.samples)
          if (sample.run == r && sample.sensor == s && sample.time_s > time) time = sample.time_s, last = sample.simulated_C;
        const std::string name = "offset " + result.runs[r].id + " " + result.sensor_names[r][s];
        double offset = 0;
        for (const auto& p : result.joint.parameters)
          if (p.name == name) offset = p.value;
        const double position = std::abs(end.sensor_position_m[s]);
        const std::size_t j = static_cast<std::size_t>(std::upper_bound(x.begin(), x.end(), position) - x.begin()) - 1;
        const double w = j + 1 < x.size() ? (position - x[j]) / (x[j + 1] - x[j]) : 0.0;
        const double profile = j + 1 < x.size() ? T[j] + w * (T[j + 1] - T[j]) : T[j];
        EXPECT_NEAR(profile, last - offset, 1e-7) << (fit_h ? "with h, " : "alpha alone, ") << result.runs[r].id << " " << s;
      }
    }
  }
}


// The library of thermal mechanisms end to end, as a newly registered one must go (header +
// registration line, thermal_mechanism.hpp): the rig makes it (`--effect`, recorded as on in
// the truth, changing the readings), `fit thermal --extension` fits it (its parameters in
// the joint fit, finite), and the model file writes and reads it back bit for bit. (The
// diagnosis's cases hide each one: thermal_diagnosis_test.cpp.) A source switch the rig does
// not make (the averaged source is its truth, the paper's rectangle an approximation) is
// fitted on the plain data.
class ThermalMechanisms : public test::TempFolderTest {};

TEST_F(ThermalMechanisms, EveryRegisteredMechanismIsMadeByTheRigFittedAndKeptInTheModelFile) {
  ThermalRigConfig rig = clean_rig(2 * 3600.0);
  rig.velocity_m_s = {0.066, 0.11};
  rig.record_every_s = 60;
  const ThermalDataSet plain = generate_thermal_dataset(rig, {}, "plain").set;
  const std::vector<ThermalExtensionInfo> library = thermal_extension_library();
  ASSERT_EQ(library.size(), kThermalMechanismCount);
  for (std::size_t slot = 0; slot < kThermalMechanismCount; ++slot) {
    const ThermalMechanismInfo& info = ThermalMechanismLibrary::infos[slot];
    SCOPED_TRACE(info.name);
    EXPECT_EQ(library[slot].name, info.name);
    ThermalDataSet data = plain;
    if (info.rig) {
      // A typical size of its parameter (a switch: on).
      const double value = library[slot].parameter_scale.empty() ? 1.0 : library[slot].parameter_scale.front();
      RigEffects effects;
      set_rig_effect(effects, info.rig->name, value);
      EXPECT_EQ(rig_effect(effects, info.rig->name), value);
      const ThermalRigOutput made = generate_thermal_dataset(rig, effects, "with");
      EXPECT_TRUE(nlohmann::json::parse(made.truth_json)["effects"][info.rig->name]["active"].get<bool>());
      bool readings_differ = false;
      for (std::size_t r = 0; r < plain.runs.size(); ++r)
        for (std::size_t s = 0; s < plain.runs[r].trace.rail.size(); ++s)
          readings_differ |= made.set.runs[r].trace.rail[s].values != plain.runs[r].trace.rail[s].values;
      EXPECT_TRUE(readings_differ);
      data = made.set;
    } else {
      EXPECT_TRUE(library[slot].source.has_value()) << "a mechanism with parameters has a rig effect";
    }
    ThermalFitOptions o = options_for_rig();
    o.per_run_fits = false;
    o.extensions = {info.name};
    const ThermalFitResult fit = fit_thermal(data, o);
    ASSERT_FALSE(fit.samples.empty());
    for (const auto& name : library[slot].parameters) EXPECT_TRUE(std::isfinite(fit.joint.parameter(name).value)) << name;

    const ModelFile written = model_file_of(nullptr, {}, &fit, o);
    EXPECT_EQ(written.mechanisms, std::vector<std::string>{info.name});
    const ModelFile read = read_model_file(write("model.toml", model_file_toml(written)));
    EXPECT_EQ(read.mechanisms, written.mechanisms);
    EXPECT_EQ(read.source, written.source);
    ASSERT_EQ(read.mechanism_parameters.size(), library[slot].parameters.size());
    for (std::size_t i = 0; i < read.mechanism_parameters.size(); ++i) {
      EXPECT_EQ(read.mechanism_parameters[i].first, library[slot].parameters[i]);
      EXPECT_EQ(read.mechanism_parameters[i].second, written.mechanism_parameters[i].second);
    }
  }
}

}  // namespace
}  // namespace lmcal
