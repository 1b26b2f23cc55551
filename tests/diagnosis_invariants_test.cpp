// One number per quantity: over random designs (virtual-rig data of several shapes, seeds and
// effects), every diagnosis quotes each model's held-out RMSE once — its summary, its JSON and
// the report agree; each step's before is the previous step's after, the first the baseline's
// and the last the final value; every gain lies in [-100, 100] %; no interval leaves its
// parameter's bounds. And the regressions of issue 38's "numbers that contradict each other",
// each from a rig case of the same shape.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "fit/bounded_interval.hpp"
#include "fit/friction_condition.hpp"
#include "lmcal/diagnose/friction_diagnosis.hpp"
#include "lmcal/diagnose/thermal_diagnosis.hpp"
#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/rig/axis_rig.hpp"
#include "lmcal/rig/virtual_rig.hpp"
#include "report/page.hpp"
#include "report/sections.hpp"
#include "support/temp_folder.hpp"

namespace lmcal {
namespace {

bool in_gain_range(double g) { return std::isnan(g) || (g >= -100 && g <= 100); }

// "1.234" as the texts print a held-out RMSE ({:.4g}).
std::string text_of(double v) { return fmt::format("{:.4g}", v); }

// What every diagnosis must satisfy, friction or thermal. `bounds(name)` gives a candidate's
// parameter bounds; `unit` the residuals'.
template <class Diagnosis, class Bounds>
void expect_one_number_per_quantity(const Diagnosis& d, double before, double after, const std::string& json_text,
                                    const std::string& unit, const Bounds& bounds, const std::string& label) {
  SCOPED_TRACE(label + ": " + d.summary);
  const auto j = nlohmann::json::parse(json_text);
  // JSON = the struct, exactly.
  EXPECT_DOUBLE_EQ(j.at("cv_rmse_before_" + unit).get<double>(), before);
  EXPECT_DOUBLE_EQ(j.at("cv_rmse_after_" + unit).get<double>(), after);
  ASSERT_EQ(j.at("steps").size(), d.steps.size());
  // The chain: baseline -> steps -> final.
  double level = before, shape = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < d.steps.size(); ++k) {
    const DiagnosisStep& s = d.steps[k];
    EXPECT_EQ(s.cv_rmse_before, level) << "step " << k + 1 << " (" << s.action << " " << s.name << ")";
    if (k > 0 && std::isfinite(shape)) {
      EXPECT_EQ(s.cv_shape_rmse_before, shape) << "step " << k + 1;
    }
    level = s.cv_rmse_after;
    shape = s.cv_shape_rmse_after;
    EXPECT_TRUE(in_gain_range(s.gain_percent)) << s.gain_percent;
    EXPECT_DOUBLE_EQ(j["steps"][k].at("cv_rmse_after_" + unit).get<double>(), s.cv_rmse_after);
  }
  EXPECT_EQ(after, level) << "the final value is not the last step's after";
  // The summary quotes the baseline's and the final model's held-out RMSE.
  EXPECT_NE(d.summary.find(text_of(before)), std::string::npos) << "baseline " << before;
  EXPECT_NE(d.summary.find(text_of(after)), std::string::npos) << "final " << after;
  // The empirical term's line: its criterion's own before and after, the step's, beside its gain.
  const EmpiricalFinding& e = d.empirical;
  if (e.found) {
    ASSERT_FALSE(d.steps.empty());
    const DiagnosisStep& term = d.steps.back();
    EXPECT_EQ(term.action, "add empirical term");
    EXPECT_EQ(e.criterion, term.criterion);
    EXPECT_EQ(e.cv_rmse_before, term.before());
    EXPECT_EQ(e.cv_rmse_after, term.after());
    EXPECT_DOUBLE_EQ(e.cv_gain_percent, held_out_gain_percent(e.cv_rmse_before, e.cv_rmse_after));
    EXPECT_NE(d.summary.find(text_of(e.cv_rmse_before) + " " + unit + " -> " + text_of(e.cv_rmse_after)), std::string::npos);
    EXPECT_TRUE(in_gain_range(e.cv_gain_percent));
  }
  EXPECT_TRUE(in_gain_range(d.cv_gain_percent)) << d.cv_gain_percent;
  EXPECT_DOUBLE_EQ(j.at("cv_gain_percent").get<double>(), d.cv_gain_percent);
  for (const auto& round : d.rounds)
    for (const auto& c : round) {
      EXPECT_TRUE(in_gain_range(c.cv_gain_percent)) << c.effect << " " << c.cv_gain_percent;
      EXPECT_TRUE(in_gain_range(c.cv_shape_gain_percent)) << c.effect << " " << c.cv_shape_gain_percent;
      if (std::isfinite(c.value) && std::isfinite(c.ci_low)) {
        const auto [lower, upper] = bounds(c.effect);
        EXPECT_GE(c.ci_low, lower) << c.effect << " [" << c.ci_low << ", " << c.ci_high << "]";
        EXPECT_LE(c.ci_high, upper) << c.effect << " [" << c.ci_low << ", " << c.ci_high << "]";
      }
    }
  // The report's diagnosis tables quote the same numbers.
  report::Page page;
  report::steps_table(page, d.steps, before, unit.c_str());
  report::empirical_section(page, e, "test", unit);
  for (const auto& s : d.steps) {
    EXPECT_NE(page.html().find(report::num(s.cv_rmse_before)), std::string::npos);
    EXPECT_NE(page.html().find(report::num(s.cv_rmse_after)), std::string::npos);
  }
  if (e.found) {
    EXPECT_NE(page.html().find("RMSE " + report::num(e.cv_rmse_before) + " " + unit + " before the term, " +
                               report::num(e.cv_rmse_after) + " " + unit + " with it"),
              std::string::npos);
  }
}

void expect_friction_invariants(const FrictionDiagnosis& d, const std::string& label) {
  auto effect_bounds = [](const std::string& name) {
    const auto& info = FrictionEffectLibrary::infos[friction_effect_slot(name)];
    return std::pair{info.lower, info.upper};
  };
  expect_one_number_per_quantity(d, d.cv_rmse_before_N, d.cv_rmse_after_N, friction_diagnosis_json(d), "N", effect_bounds, label);
  for (std::size_t j = 0; j < d.shifts.size(); ++j) {
    const auto& s = d.shifts[j];
    const ParameterEstimate& p = d.baseline_fit.fit.parameters[j];
    if (!s.free) continue;
    for (double v : {s.baseline_low, s.baseline_high, s.extended_low, s.extended_high})
      if (std::isfinite(v)) {
        EXPECT_GE(v, p.lower) << label << ": " << s.name;
        EXPECT_LE(v, p.upper) << label << ": " << s.name;
      }
  }
}

// Issue 38's first defect: on a drive's log (one setup per run) with a signed offset, a
// direction asymmetry fitted with random run zeros moved the law's level against a zero common
// to the runs ((F + c)(1 + a dir) - c = F (1 + a dir) + c a dir): held-out RMSEs of 120 N and
// "-1878 % better" on data of 6 N. Every candidate's held-out RMSE now stays within a few times
// the baseline's, and the signed offset is what is found first.
class DiagnosisInvariants : public test::TempFolderTest {
 protected:
  // `sensor`: the manifest's [raw] force_sensor, or none stated.
  FrictionLog axis_log(std::uint64_t seed, double asymmetry, const std::string& sensor = "") {
    const FrictionRigConfig setup = bundled_axis_setup(seed);
    AxisRigConfig axis;
    axis.cycles = 1;
    axis.cruise_s = 0.5;
    axis.current_offset_A = 0.05;  // 4 N on the drive's signed force: a signed offset in the motion's sense
    RigEffects effects;
    set_rig_effect(effects, "direction_asymmetry", asymmetry);
    const AxisRigOutput made = generate_axis_logs(setup, axis, effects);
    for (const auto& [file, text] : made.run_files) write(file, text);
    std::string manifest = made.manifest_toml;
    if (!sensor.empty()) manifest.replace(manifest.find("[raw]\n"), 6, fmt::format("[raw]\nforce_sensor = \"{}\"\n", sensor));
    return load_friction_dataset(write("friction.toml", manifest)).log;
  }
};

TEST_F(DiagnosisInvariants, ACommonRunZeroDoesNotActAsASignedOneBesideADirectionAsymmetry) {
  for (std::uint64_t seed : {3, 4, 5}) {
    const FrictionDiagnosis d = diagnose_friction(axis_log(seed, 0.1), {});
    for (const auto& round : d.rounds)
      for (const auto& c : round)
        EXPECT_LT(c.cv_rmse, 2 * d.cv_rmse_before_N) << "seed " << seed << " " << c.effect << ": " << d.summary;
    ASSERT_FALSE(d.accepted.empty()) << d.summary;
    EXPECT_EQ(d.accepted.front().effect, "signed_zero_offset") << "seed " << seed << ": " << d.summary;
    // A motor's force with no sensor stated: the constant signed force is not called a load
    // cell's zero, but reported as what it is, with its candidates (issue 38 #1).
    EXPECT_EQ(shown_name(d.accepted.front()), "signed_constant_force") << d.summary;
    EXPECT_NE(d.summary.find("signed_constant_force"), std::string::npos) << d.summary;
    EXPECT_EQ(d.summary.find("signed_zero_offset"), std::string::npos) << d.summary;
    EXPECT_NE(d.summary.find("a drive's current offset"), std::string::npos) << d.summary;
    expect_friction_invariants(d, fmt::format("axis seed {}", seed));
    // The same force measured by a load cell on an axis whose incline is stated: a load cell's
    // zero is what a constant signed force then is, and it is named so.
    const FrictionDiagnosis cell = diagnose_friction(axis_log(seed, 0.1, "load_cell"), {});
    ASSERT_FALSE(cell.accepted.empty()) << cell.summary;
    EXPECT_EQ(cell.accepted.front().effect, "signed_zero_offset") << "seed " << seed << ": " << cell.summary;
    EXPECT_EQ(shown_name(cell.accepted.front()), "signed_zero_offset") << cell.summary;
    EXPECT_EQ(cell.summary.find("signed_constant_force"), std::string::npos) << cell.summary;
  }
}

// A gain is quoted against the RMSE before, a loss against the RMSE after.
TEST(DiagnosisInvariantsUnit, GainsLieWithinPlusMinusOneHundredPercent) {
  EXPECT_DOUBLE_EQ(held_out_gain_percent(2, 1), 50);
  EXPECT_DOUBLE_EQ(held_out_gain_percent(1, 2), -50);
  EXPECT_DOUBLE_EQ(held_out_gain_percent(6.1, 120.7), 100 * (6.1 - 120.7) / 120.7);
  EXPECT_TRUE(std::isnan(held_out_gain_percent(0, 1)));
}

// Issue 38: "α's interval [-0.061, 0.511] below α's own bound of 0". An interval that would
// cross a bound is formed on the log (one bound) or logit (two) scale and stays inside; one
// within its bounds is the linear one; an estimate on its bound is clipped there.
TEST(DiagnosisInvariantsUnit, IntervalsStayWithinTheParametersBounds) {
  const auto linear = detail::bounded_interval(0.5, 0.1, 2, 0, 1);
  EXPECT_EQ(linear.method, "linear");
  EXPECT_DOUBLE_EQ(linear.low, 0.3);
  EXPECT_DOUBLE_EQ(linear.high, 0.7);
  const auto alpha = detail::bounded_interval(0.225, 0.143, 2, 0, 1);  // linear: [-0.061, 0.511]
  EXPECT_EQ(alpha.method, "logit");
  EXPECT_GT(alpha.low, 0);
  EXPECT_LT(alpha.low, 0.225);
  EXPECT_GT(alpha.high, 0.225);
  EXPECT_LT(alpha.high, 1);
  const auto one = detail::bounded_interval(0.2, 0.15, 2, 0, std::numeric_limits<double>::infinity());
  EXPECT_EQ(one.method, "log");
  EXPECT_NEAR(one.low, 0.2 * std::exp(-1.5), 1e-12);
  EXPECT_NEAR(one.high, 0.2 * std::exp(1.5), 1e-12);
  const auto upper = detail::bounded_interval(-0.2, 0.15, 2, -std::numeric_limits<double>::infinity(), 0);
  EXPECT_EQ(upper.method, "log");
  EXPECT_NEAR(upper.high, -0.2 * std::exp(-1.5), 1e-12);
  const auto on = detail::bounded_interval(0, 0.1, 2, 0, 1);
  EXPECT_EQ(on.method, "clipped");
  EXPECT_DOUBLE_EQ(on.low, 0);
  EXPECT_DOUBLE_EQ(on.high, 0.2);
}

// A run that heats and cools back rises by about 0 from start to end: its max error is taken
// against the sensor's span, not that rise (issue 38: "max error 4469 % of the measured rise").
// The heater's run is fitted with a heat-then-cool companion at another heat.
ThermalDataSet heat_then_cool(std::uint64_t seed, int repeats) {
  ThermalRigConfig rig;
  rig.heat_rate_W = 20;
  rig.heater_off_s = 10800;
  rig.duration_s = 21600;
  rig.record_every_s = 30;
  rig.repeats = repeats;
  rig.seed = seed;
  return generate_thermal_dataset(rig, {}, "heat-then-cool").set;
}

TEST(DiagnosisInvariantsUnit, AHeatThenCoolRunsMaxErrorIsAgainstItsSpan) {
  const ThermalDataSet data = heat_then_cool(5, 2);
  ThermalFitOptions o;  // the heater's given heat
  o.per_run_fits = false;
  o.time_step_s = 60;
  o.fit.profile = ProfileMode::none;
  const ThermalFitResult fit = fit_thermal(data, o);
  ASSERT_TRUE(fit.joint.solver.usable) << fit.joint.solver.termination;
  EXPECT_GT(fit.max_error_percent, 0);
  EXPECT_LT(fit.max_error_percent, 20) << "a few noise σ against a span of kelvins";
}

// Issue 38: "max relative error 1255 %" on friction near zero. The relative error is taken
// against the measured force's range (1st to 99th percentile), not each sample's own force: a
// log whose forces reach down to 0.01 N quotes its largest error as a share of the range.
TEST(DiagnosisInvariantsUnit, AFrictionFitsRelativeErrorIsAgainstTheMeasuredRange) {
  FrictionRigConfig rig;
  rig.guides = {"SRN 35C"};
  rig.runs = 3;
  rig.seed = 17;
  FrictionLog log = generate_friction_log(rig, {}).log;
  const double lowest = *std::min_element(log.friction_N.begin(), log.friction_N.end());
  for (double& f : log.friction_N) f -= lowest - 0.01;  // a zero offset the law's f0 takes: forces near 0
  FrictionFitOptions o;
  o.per_run_fits = false;
  o.fit.profile = ProfileMode::none;
  o.fit.bootstrap = 0;
  const FrictionFitResult fit = fit_friction(log, o);
  std::vector<double> sorted = log.friction_N;
  std::sort(sorted.begin(), sorted.end());
  auto at = [&](double q) { return sorted[static_cast<std::size_t>(std::round(q * static_cast<double>(sorted.size() - 1)))]; };
  double largest = 0;
  for (std::size_t i = 0; i < log.size(); ++i) largest = std::max(largest, std::abs(log.friction_N[i] - fit.predicted_N[i]));
  EXPECT_NEAR(fit.max_relative_error, largest / (at(0.99) - at(0.01)), 1e-12);
  EXPECT_LT(fit.max_relative_error, 0.5) << "errors of tenths of a newton against a range of tens";
}

// What issue 38 #3 and #5 add to every friction diagnosis: a lack of fit against pure error or
// against the noise, saying which and with the tolerance its conditions matched within (and
// the margin); "structure remains" in the summary whenever the final lack of fit rejects; every
// accepted cause's interval excludes its neutral value; every significant test left unexplained
// because of its size is in a design note; no between-run test of a covariate constant to its
// resolution.
void expect_issue_38_rules(const FrictionDiagnosis& d, const FrictionDiagnosisOptions& o, const std::string& label) {
  SCOPED_TRACE(label + ": " + d.summary);
  for (const LackOfFit* l : {&d.baseline.lack_of_fit, &d.final.lack_of_fit}) {
    if (!l->tested) continue;
    EXPECT_DOUBLE_EQ(l->condition_tolerance, o.condition_tolerance);
    EXPECT_NE(l->basis.find(fmt::format("within {:g} %", 100 * o.condition_tolerance)), std::string::npos) << l->basis;
    if (l->against == "noise") {
      EXPECT_DOUBLE_EQ(l->margin, o.noise_margin);
      EXPECT_NE(l->basis.find(fmt::format("exceeds {:g} times", o.noise_margin)), std::string::npos) << l->basis;
    } else {
      EXPECT_EQ(l->against, "pure error");
    }
  }
  if (d.final.lack_of_fit.tested && !d.final.lack_of_fit.fits) {
    EXPECT_NE(d.summary.find("tructure remains"), std::string::npos);
  }
  for (const CandidateScore& c : d.accepted) {
    if (std::isfinite(c.ci_low)) {
      EXPECT_TRUE(c.neutral < c.ci_low || c.neutral > c.ci_high)
          << c.effect << " [" << c.ci_low << ", " << c.ci_high << "] neutral " << c.neutral;
    }
  }
  for (const CovariateTest& t : d.final.covariates) {
    if (t.p_adjusted < o.structure_p && !t.structured) {
      EXPECT_TRUE(std::any_of(d.design_notes.begin(), d.design_notes.end(),
                              [&](const std::string& n) {
                                return n.starts_with("left unexplained") && n.find(t.covariate + " (p = ") != std::string::npos;
                              }))
          << t.covariate << " p = " << t.p_value << " left without a note";
    }
  }
  const auto j = nlohmann::json::parse(friction_diagnosis_json(d));
  EXPECT_DOUBLE_EQ(j["final_residuals"]["lack_of_fit"].at("condition_tolerance").get<double>(), o.condition_tolerance);
}

// Every covariate test name of the diagnosis's residuals.
std::set<std::string> tested_covariates(const FrictionDiagnosis& d) {
  std::set<std::string> out;
  for (const auto* r : {&d.baseline, &d.final})
    for (const auto& t : r->covariates) out.insert(t.covariate);
  return out;
}

// The invariants over 50 random designs (drawn from one seeded generator: the same every run):
// tidy campaigns with several setups per run, one setup per run, one load, one direction per
// run (direction confounded with the runs), raw load-cell time series cut into plateaus, with one
// library effect or none, white or AR(1) load-cell noise; and heat-then-cool and heated thermal
// data sets. Small designs (a few speeds, 3-4 runs) keep it quick.
TEST_F(DiagnosisInvariants, EveryDiagnosisQuotesOneNumberPerQuantity) {
  std::mt19937_64 rng(38);
  auto draw = [&](std::size_t n) { return static_cast<std::size_t>(rng() % n); };
  const std::pair<const char*, double> effects[] = {{"", 0},
                                                    {"", 0},
                                                    {"seal_drag", 40},
                                                    {"direction_asymmetry", 0.03},
                                                    {"viscous_load", 0.03},
                                                    {"signed_zero_offset", 0.25},
                                                    {"stribeck_exponent", 1.4},
                                                    {"viscous_direction", 0.04}};
  const std::vector<double> speeds = {0.002, 0.005, 0.01, 0.02, 0.04, 0.066, 0.11, 0.15};
  const char* kinds[] = {"campaign", "one setup per run", "one load", "one direction per run", "raw log"};
  const FrictionDiagnosisOptions o;
  int raw_logs = 0, direction_notes = 0, noise_tests = 0, pure_error_tests = 0;
  for (int k = 0; k < 46; ++k) {
    const int kind = k % 5;
    FrictionRigConfig rig;
    rig.guides = {draw(2) ? "SRN 35C" : "SRG 25C"};
    rig.preload_um = {2.5};
    rig.load_N = {1000, 3000};
    rig.temperature_C = {22, 40};
    std::vector<double> v = speeds;
    std::shuffle(v.begin(), v.end(), rng);
    v.resize(3 + draw(2));
    std::sort(v.begin(), v.end());
    rig.velocity_m_s = v;
    rig.runs = 3;
    rig.noise_ar1 = draw(3) == 0 ? 0.5 : 0.0;
    rig.seed = 3800 + static_cast<std::uint64_t>(k);
    const auto& [effect, magnitude] = effects[draw(std::size(effects))];
    RigEffects e;
    if (*effect) set_rig_effect(e, effect, magnitude);
    FrictionLog log;
    if (kind == 1) {
      rig.one_setup_per_run = true;
      rig.runs = 1;
    } else if (kind == 2) {
      rig.load_N = {2000};
    } else if (kind == 3) {
      rig.directions = {+1};
      rig.runs = 4;
      rig.temperature_C = {26};
    }
    if (kind == 4) {  // one setup per run (the raw rig's), short strokes
      rig.load_N = {2000};
      rig.temperature_C = {26};
      rig.velocity_m_s = {0.01, 0.02, 0.04};
      RawFrictionRigConfig raw;
      raw.sample_rate_Hz = 50;
      const RawFrictionRigOutput made = generate_raw_friction_logs(rig, raw, e);
      for (const auto& [file, text] : made.run_files) write(fmt::format("raw{}/{}", k, file), text);
      log = load_friction_dataset(write(fmt::format("raw{}/friction.toml", k), made.manifest_toml)).log;
      ++raw_logs;
    } else {
      log = generate_friction_log(rig, e).log;
    }
    if (kind == 3)  // every other run moves backwards: direction changes only between runs
      for (std::size_t i = 0; i < log.size(); ++i) log.direction[i] = log.run[i] % 2 ? -1 : +1;
    const std::string label = fmt::format("friction design {} ({}, {} {}, {} samples, {} runs)", k, kinds[kind],
                                          *effect ? effect : "no effect", magnitude, log.size(), log.run_names.size());
    const FrictionDiagnosis d = diagnose_friction(log, o);
    expect_friction_invariants(d, label);
    expect_issue_38_rules(d, o, label);
    // One guide: one block length, however its run means round — never tested between runs.
    for (const std::string& name : tested_covariates(d))
      EXPECT_EQ(name.find("block_length_mm"), std::string::npos) << label << ": " << name;
    if (kind == 3) {
      const bool noted = std::any_of(d.design_notes.begin(), d.design_notes.end(), [](const std::string& n) {
        return n.find("direction is confounded with the runs") != std::string::npos;
      });
      EXPECT_TRUE(noted) << label;
      direction_notes += noted;
    }
    noise_tests += d.baseline.lack_of_fit.against == "noise";
    pure_error_tests += d.baseline.lack_of_fit.against == "pure error";
  }
  EXPECT_EQ(raw_logs, 9);
  EXPECT_EQ(direction_notes, 9);
  EXPECT_GT(noise_tests, 0);
  EXPECT_GT(pure_error_tests, 0);
  // Thermal: heaters that heat and cool back (the given heat), and friction-heated runs at
  // three speeds in a room whose air swings, seen in part, with drifting thermocouples.
  for (int k = 0; k < 4; ++k) {
    ThermalDiagnosisOptions to;
    ThermalDataSet data;
    if (k < 2) {
      data = heat_then_cool(7 + static_cast<std::uint64_t>(k), 3);
    } else {
      ThermalRigConfig runs;
      runs.velocity_m_s = {0.066, 0.09, 0.11};
      runs.duration_s = (k == 2 ? 8 : 40) * 3600;
      runs.record_every_s = 120;
      runs.ambient_drift_K_per_h = 0.02;
      runs.seed = 8 + static_cast<std::uint64_t>(k);
      RigEffects daily;
      set_rig_effect(daily, "ambient_daily_K", 1.5);
      set_rig_effect(daily, "ambient_daily_seen", 0.3);
      set_rig_effect(daily, "tc_drift_K_per_h", 0.03);
      to.fit.heat = HeatInput::friction_law;
      data = generate_thermal_dataset(runs, daily, "daily").set;
    }
    const ThermalDiagnosis t = diagnose_thermal(data, to);
    auto no_bounds = [](const std::string&) {
      return std::pair{-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    };
    expect_one_number_per_quantity(t, t.cv_rmse_before_K, t.cv_rmse_after_K, thermal_diagnosis_json(t), "K", no_bounds,
                                   fmt::format("thermal design {} ({})", k, data.runs.front().id));
    if (t.final.lack_of_fit.tested && !t.final.lack_of_fit.fits) {
      EXPECT_NE(t.summary.find("tructure remains"), std::string::npos) << t.summary;
    }
    for (const auto& round : t.rounds)
      for (const auto& c : round)
        if (std::isfinite(c.alpha_low)) {
          EXPECT_GE(c.alpha_low, to.fit.alpha_lower) << c.effect;
          EXPECT_LE(c.alpha_high, to.fit.alpha_upper) << c.effect;
        }
  }
}

// Issue 38 #3: values that agree to their resolution are one value; values a design spaces by
// 20 % stay apart; dense continuous values do not chain into one.
TEST(DiagnosisInvariantsUnit, ConditionsMatchToTheirResolution) {
  const std::vector<double> plateaus = {0.10003, 0.09998, 0.1, 0.05001, 0.04999, 0.12};
  const auto snapped = detail::snap_to_resolution(plateaus, 0.01);
  EXPECT_EQ(snapped[0], snapped[1]);
  EXPECT_EQ(snapped[0], snapped[2]);
  EXPECT_EQ(snapped[3], snapped[4]);
  EXPECT_NE(snapped[0], snapped[5]);
  EXPECT_NE(snapped[0], snapped[3]);
  // 120.2 as run means of different lengths: apart in the last bit, one value.
  std::vector<double> means;
  for (int n : {7, 10, 13, 31}) {
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += 120.2;
    means.push_back(sum / n);
  }
  EXPECT_GT(std::set<double>(means.begin(), means.end()).size(), 1u) << "the case: run means apart in the last bit";
  const auto one = detail::snap_to_resolution(means, 0.01);
  EXPECT_EQ(std::set<double>(one.begin(), one.end()).size(), 1u);
  // 0.001 apart over 1.0 ... 1.1: clusters at most 1 % wide, about ten of them, not one.
  std::vector<double> dense;
  for (int i = 0; i <= 100; ++i) dense.push_back(1.0 + 0.001 * i);
  const auto clusters = detail::snap_to_resolution(dense, 0.01);
  const std::set<double> distinct(clusters.begin(), clusters.end());
  EXPECT_GE(distinct.size(), 9u);
  EXPECT_LE(distinct.size(), 11u);
  for (std::size_t i = 0; i < dense.size(); ++i) EXPECT_LE(dense[i] - clusters[i], 0.01 * dense[i] + 1e-12);
}

// Issue 38 #3: a raw log's repeats are matched. Three runs of one setup, each speed's plateau
// mean a little different in every run (its speed from the encoder): as exact doubles no
// condition recurs; to 1 % every one does, and the lack of fit is tested against pure error.
TEST_F(DiagnosisInvariants, ARawLogsPlateauSpeedsRepeatAcrossRuns) {
  FrictionRigConfig rig;
  rig.guides = {"SRN 35C"};
  rig.preload_um = {2.5};
  rig.load_N = {2000};
  rig.temperature_C = {26};
  rig.velocity_m_s = {0.01, 0.02, 0.04};
  rig.runs = 3;
  rig.seed = 5;
  RawFrictionRigConfig raw;
  raw.sample_rate_Hz = 50;
  const RawFrictionRigOutput made = generate_raw_friction_logs(rig, raw, {});
  for (const auto& [file, text] : made.run_files) write(file, text);
  FrictionLog log = load_friction_dataset(write("friction.toml", made.manifest_toml)).log;
  ASSERT_EQ(log.run_names.size(), 3u);
  // The rig's runs repeat their moves exactly; a real rig's plateau means differ in the fifth digit.
  for (std::size_t i = 0; i < log.size(); ++i) log.velocity_m_s[i] *= 1 + 2e-5 * (log.run[i] + 1.0);
  std::set<std::pair<double, std::uint32_t>> exact;  // (speed, run)
  std::set<double> speeds;
  for (std::size_t i = 0; i < log.size(); ++i) exact.emplace(log.velocity_m_s[i], log.run[i]), speeds.insert(log.velocity_m_s[i]);
  EXPECT_EQ(speeds.size(), exact.size()) << "each run's plateau speeds are its own as exact doubles";
  const FrictionDiagnosis d = diagnose_friction(log, {});
  const LackOfFit& l = d.baseline.lack_of_fit;
  ASSERT_TRUE(l.tested) << l.basis;
  EXPECT_EQ(l.against, "pure error") << l.basis;
  EXPECT_NE(l.basis.find("6 conditions, 6 of them repeated across runs"), std::string::npos) << l.basis;
  EXPECT_TRUE(l.fits) << d.summary;
}

// Issue 38 #3: without repeats (every setup a run of its own, once) the residuals are judged
// against the noise of their consecutive differences: the clean law fits it, with the rig's
// load-cell noise; a miss of about eight times the noise that no library cause draws (a bump
// over the middle speeds) leaves "structure remains" in the verdict, with its margin.
TEST(DiagnosisInvariantsUnit, WithoutRepeatsTheResidualsAreJudgedAgainstTheirNoise) {
  FrictionRigConfig rig;
  rig.guides = {"SRN 35C"};
  rig.preload_um = {2.5};
  rig.load_N = {1000, 2000, 3000};
  rig.temperature_C = {22, 40};
  rig.velocity_m_s.clear();
  for (int i = 0; i < 16; ++i) rig.velocity_m_s.push_back(0.002 * std::pow(75.0, i / 15.0));  // 0.002 ... 0.15
  rig.one_setup_per_run = true;
  rig.runs = 1;
  rig.seed = 11;
  FrictionDiagnosisOptions o;
  o.learn_term = false;  // what the library leaves, not what a term would learn
  const FrictionLog clean = generate_friction_log(rig, {}).log;
  const FrictionDiagnosis ok = diagnose_friction(clean, o);
  const LackOfFit& l = ok.baseline.lack_of_fit;
  ASSERT_TRUE(l.tested) << l.basis;
  EXPECT_EQ(l.against, "noise") << l.basis;
  EXPECT_NE(l.basis.find("0 of 192 conditions recur in another run"), std::string::npos) << l.basis;
  EXPECT_TRUE(l.fits) << ok.summary;
  EXPECT_NEAR(l.pure_error_rms, rig.noise_N, 0.05) << "the rig's load-cell noise";
  EXPECT_EQ(ok.verdict, "no significant discrepancy") << ok.summary;
  FrictionLog bumped = clean;
  for (std::size_t i = 0; i < bumped.size(); ++i)
    bumped.friction_N[i] += 3 * std::exp(-std::pow(std::log(bumped.velocity_m_s[i] / 0.02) / 0.5, 2));
  const FrictionDiagnosis bad = diagnose_friction(bumped, o);
  ASSERT_TRUE(bad.final.lack_of_fit.tested);
  EXPECT_EQ(bad.final.lack_of_fit.against, "noise");
  EXPECT_FALSE(bad.final.lack_of_fit.fits) << bad.summary << " | F " << bad.final.lack_of_fit.statistic << " lack "
                                           << bad.final.lack_of_fit.lack_rms << " noise " << bad.final.lack_of_fit.pure_error_rms;
  EXPECT_NE(bad.summary.find("tructure remains"), std::string::npos) << bad.summary;
  EXPECT_NE(bad.summary.find("exceeds 2 times it"), std::string::npos) << bad.summary;
  EXPECT_NE(bad.verdict, "explained") << bad.summary;
  EXPECT_NE(bad.verdict, "no significant discrepancy") << bad.summary;
}

// Issue 38 #5, from a rig case of the issue's shape: a 36-sample log (three runs, one load
// each, six speeds, both senses; AR(1) load-cell noise 0.6, a viscous-load slope of 0.006 /kN)
// where viscous_load passed the likelihood-ratio test and gained 12-13 % on the runs' shape while
// its 95 % interval contained 0 (the level: +0.6 % and -2.2 %). The old rules named it; it is
// not named now, and its round says why.
TEST(DiagnosisInvariantsUnit, ACauseWhoseIntervalContainsItsNeutralValueIsNotAccepted) {
  for (std::uint64_t seed : {136, 144}) {
    FrictionRigConfig rig;
    rig.guides = {"SRN 35C"};
    rig.preload_um = {2.5};
    rig.load_N = {1000, 2000, 3000};
    rig.temperature_C = {26};
    rig.velocity_m_s = {0.005, 0.01, 0.02, 0.05, 0.1, 0.15};
    rig.one_setup_per_run = true;
    rig.runs = 1;
    rig.noise_ar1 = 0.6;
    rig.seed = seed;
    RigEffects e;
    set_rig_effect(e, "viscous_load", 0.006);
    const FrictionLog log = generate_friction_log(rig, e).log;
    ASSERT_EQ(log.size(), 36u);
    const FrictionDiagnosis d = diagnose_friction(log, {});
    SCOPED_TRACE(fmt::format("seed {}: {}", seed, d.summary));
    const auto& round = d.rounds.front();
    const auto c = std::find_if(round.begin(), round.end(), [](const CandidateScore& c) { return c.effect == "viscous_load"; });
    ASSERT_NE(c, round.end());
    // The case: significant, a shape gain past the threshold, an interval holding 0.
    EXPECT_LT(c->lrt_p, 1e-3);
    EXPECT_GE(std::max(c->cv_gain_percent, c->cv_shape_gain_percent), 10);
    EXPECT_LT(c->cv_gain_percent, 1);
    EXPECT_LE(c->ci_low, 0);
    EXPECT_GE(c->ci_high, 0);
    EXPECT_FALSE(c->accepted);
    EXPECT_NE(c->reason.find("contains its neutral value 0"), std::string::npos) << c->reason;
    for (const CandidateScore& a : d.accepted) EXPECT_NE(a.effect, "viscous_load");
  }
}

}  // namespace
}  // namespace lmcal
