// lmcal calibrate end to end: a measurement folder made by the virtual rig goes through
// every step; the report holds every plot of the story; the bundled set's committed results
// (fits/cheng2017/) are what a fresh run gives.
#include "lmcal/calibrate/calibration.hpp"
#include "lmcal/report/calibration.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "lmcal/error.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/report/html_report.hpp"
#include "lmcal/report/svg_plot.hpp"
#include "lmcal/rig/virtual_rig.hpp"
#include "report/findings.hpp"
#include "report/sections.hpp"
#include "support/temp_folder.hpp"
#include "support/source_paths.hpp"

namespace lmcal {
namespace {

namespace fs = std::filesystem;

std::string read(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A measurement folder as a rig would leave it: a friction log of three runs (seal drag
// hidden in it) and three thermal runs.
class CalibrationTest : public test::TempFolderTest {
 protected:
  void write_friction(const std::string& file = "friction.csv") {
    FrictionRigConfig config;
    config.guides = {"SRN 35C"};
    config.runs = 3;
    RigEffects effects;
    set_rig_effect(effects, "seal_drag", 100);
    write(file, friction_log_csv(generate_friction_log(config, effects).log));
  }
  static ThermalRigConfig short_runs() {
    ThermalRigConfig config;
    config.velocity_m_s = {0.066, 0.083, 0.11};
    config.duration_s = 3 * 3600;
    config.record_every_s = 30;
    return config;
  }
  // The data set's runs, and how many.
  std::size_t write_thermal(const std::string& manifest = "thermal.toml", const ThermalRigConfig& config = short_runs(),
                            const RigEffects& effects = {}) {
    ThermalDataSet set = generate_thermal_dataset(config, effects, "test").set;
    OutputSet out;
    for (ThermalRun& run : set.runs) {
      run.file = dir_ / run.file;
      out.add(run.file, thermal_trace_csv(run.trace));
    }
    out.add(dir_ / manifest, thermal_manifest_toml(set, dir_));
    out.commit();
    return set.runs.size();
  }
};

// The plots each part of the story needs, by the IDs the report gives them.
std::vector<std::string> expected_plots(const Calibration& c) {
  std::vector<std::string> ids;
  if (c.friction) {
    for (const char* varied : {"load", "preload", "temperature"}) ids.push_back(std::string("friction-by-") + varied);
    for (const char* cov : {"velocity-m-s", "load-n", "preload-um", "temperature-c", "direction"})
      ids.push_back(std::string("friction-residual-") + cov);
    ids.push_back("friction-residual-run");
    for (const char* p : {"k1", "k2", "mu-st", "v-st-m-s", "mu-v", "beta-per-k", "f0"}) ids.push_back(std::string("friction-spread-") + p);
  }
  if (c.friction_diagnosis) ids.push_back("friction-diagnosis-velocity-m-s");
  if (c.friction_diagnosis && c.friction_diagnosis->empirical.found) ids.push_back("friction-empirical-term");
  if (c.thermal) {
    ids.push_back("thermal-alpha-curve");
    for (const auto& run : c.thermal_data->runs) {
      ids.push_back("thermal-time-" + run.id);
      ids.push_back("thermal-position-" + run.id);
    }
    for (const char* p : {"thermal-residual-time", "thermal-residual-position", "thermal-residual-velocity", "thermal-spread-alpha"})
      ids.push_back(p);
  }
  if (c.thermal_diagnosis) ids.insert(ids.end(), {"thermal-diagnosis-before", "thermal-diagnosis-after"});
  if (c.thermal_diagnosis && c.thermal_diagnosis->empirical.found && !c.thermal_diagnosis->empirical.curve.x.empty())
    ids.push_back("thermal-empirical-term");
  if (c.calibrated.friction && !c.calibrated.friction->spread.empty()) ids.push_back("calibrated-friction-runs-k1");
  if (c.calibrated.thermal) ids.push_back("calibrated-thermal-runs-alpha");
  // How sure: the multi-start waterfall of every fit that ran starts, a profile per profile interval.
  for (const auto& [prefix, fit] : {std::pair{"calibrated-friction-", c.calibrated.friction ? &c.calibrated.friction->fit : nullptr},
                                    std::pair{"calibrated-thermal-", c.calibrated.thermal ? &c.calibrated.thermal->joint : nullptr}}) {
    if (!fit) continue;
    const bool law = fit->solver.start_costs.size() < 2 && c.friction && fit == &c.calibrated.friction->fit;
    if ((law ? c.friction->fit : *fit).solver.start_costs.size() > 1) ids.push_back(std::string(prefix) + "starts");
    for (std::size_t j = 0; j < fit->parameters.size(); ++j)
      if (fit->parameters[j].interval == "profile" && !fit->parameters[j].per_run) ids.push_back(prefix + fmt::format("profile-{}", j));
  }
  return ids;
}

// Every expected plot is in the page once, with data drawn; the page loads nothing from outside.
void expect_complete_report(const Calibration& c, const std::string& html) {
  const auto listed = calibration_report_plots(c);
  for (const auto& id : expected_plots(c)) {
    EXPECT_NE(std::find(listed.begin(), listed.end(), id), listed.end()) << id << " is not listed";
    const std::string tag = "data-plot=\"" + id + "\"";
    const auto at = html.find(tag);
    ASSERT_NE(at, std::string::npos) << id << " is not in the page";
    EXPECT_EQ(html.find(tag, at + 1), std::string::npos) << id << " is in the page twice";
    const auto end = html.find("</svg>", at);
    EXPECT_NE(html.substr(at, end - at).find("class=\"series\""), std::string::npos) << id << " draws no data";
  }
  std::string ids;
  for (const auto& id : listed) ids += (ids.empty() ? "" : " ") + id;
  EXPECT_NE(html.find("<body data-plots=\"" + ids + "\">"), std::string::npos);
  EXPECT_FALSE(std::regex_search(html, std::regex(R"((src|href)\s*=\s*"(?!#))"))) << "the page refers to an outside resource";
  for (const auto& [file, hash] : c.inputs) EXPECT_NE(html.find(hash), std::string::npos) << file;
}

// The text of `html` from the first `from` to the next `to` after it ("" when `from` is absent).
std::string between(const std::string& html, const std::string& from, const std::string& to) {
  const auto at = html.find(from);
  if (at == std::string::npos) return "";
  return html.substr(at, html.find(to, at + from.size()) - at);
}

// A number as the report writes it (`digits` significant digits).
std::string shown(double v, int digits) { return fmt::format("{:.{}g}", v, digits); }

// The page opens with what was found, in sentences (each cause named with its calibrated value,
// how sure in words, the interval methods one click away in a <details>), then the calibrated
// model: its heading comes before any published model's; its table names each accepted cause
// with its value. The sentences are computed once: the report, calibration.json's "findings"
// and the terminal's summary carry the same strings.
void expect_found_then_calibrated_model(const Calibration& c, const std::string& html, const nlohmann::json& summary) {
  const std::string found_heading = "<h2 id=\"found\">What we found</h2>";
  const std::string heading = "<h2 id=\"calibrated\">The calibrated model</h2>";
  EXPECT_EQ(html.find("<h2"), html.find(found_heading)) << "what was found is not the first section";
  EXPECT_EQ(html.find("<h2", html.find(found_heading) + 1), html.find(heading)) << "the calibrated model is not the second section";
  std::smatch published;
  ASSERT_TRUE(std::regex_search(html, published, std::regex("<h2[^>]*>[^<]*published model"))) << "no published-model heading";
  EXPECT_LT(html.find(heading), static_cast<std::size_t>(published.position(0)));
  const std::string found = between(html, found_heading, "</section>");
  const std::string section = between(html, heading, "</section>");
  ASSERT_TRUE(c.calibrated.friction);
  ASSERT_FALSE(c.calibrated.friction_causes.empty());
  for (const auto& cause : c.calibrated.friction_causes) {
    EXPECT_NE(section.find("+ " + cause), std::string::npos) << cause << " is not named with the law";
    const std::string row = between(section, "<tr><td>" + cause + "</td>", "</tr>");
    ASSERT_FALSE(row.empty()) << cause << " has no row in the calibrated table";
    EXPECT_NE(row.find("<td>" + shown(c.calibrated.friction->fit.parameter(cause).value, 5) + "</td>"), std::string::npos) << row;
    EXPECT_NE(found.find(cause + " " + shown(c.calibrated.friction->fit.parameter(cause).value, 4)), std::string::npos)
        << cause << " is not said with its value under What we found";
  }
  EXPECT_NE(section.find("model.toml"), std::string::npos);
  // The methods' statements in the details, not in the tables: no covariance column.
  const std::string details = between(found, "<details>", "</details>");
  EXPECT_NE(details.find("95 % intervals: " + c.calibrated.friction->fit.uncertainty.method), std::string::npos);
  ASSERT_TRUE(c.calibrated.thermal);
  EXPECT_NE(details.find("95 % intervals: " + c.calibrated.thermal->joint.uncertainty.method), std::string::npos);
  EXPECT_NE(details.find("<dt>Cochran&#39;s Q</dt>"), std::string::npos) << "the terms are not defined";
  EXPECT_EQ(section.find("<th>covariance</th>"), std::string::npos);
  EXPECT_EQ(section.find("sqrt(sum"), std::string::npos) << "a formula on the first screen";
  // One place: the same sentences in the report, calibration.json and the summary.
  const report::Findings words = report::findings(c);
  ASSERT_EQ(words.found.size(), 2u);
  ASSERT_EQ(words.how_sure.size(), 2u);
  const std::string terminal = calibration_summary(c);
  for (const auto* list : {&words.found, &words.how_sure, &words.contradictions})
    for (const auto& sentence : *list) {
      EXPECT_NE(found.find(report::escape_xml(sentence)), std::string::npos) << sentence;
      EXPECT_NE(terminal.find(sentence), std::string::npos) << sentence;
    }
  EXPECT_EQ(summary["findings"]["found"].get<std::vector<std::string>>(), words.found);
  EXPECT_EQ(summary["findings"]["how_sure"].get<std::vector<std::string>>(), words.how_sure);
  EXPECT_EQ(summary["findings"]["contradictions"].get<std::vector<std::string>>(), words.contradictions);
}

// The how-sure panel of one fit lists the SE of every covariance method for `parameter`.
void expect_every_method(const std::string& panel, const FitResult& fit, const std::string& parameter) {
  std::vector<std::string> methods;
  for (const auto& m : fit.uncertainty.methods) methods.push_back(m.method);
  for (const char* m : {"iid", "hac", "cluster", "bootstrap"})
    EXPECT_NE(std::find(methods.begin(), methods.end(), m), methods.end()) << parameter << ": no " << m << " covariance";
  const std::string header = between(panel, "<thead>", "</thead>");
  const std::string row = between(panel, "<tr><td>" + parameter + "</td>", "</tr>");
  ASSERT_FALSE(row.empty()) << parameter << " has no row in the how-sure panel";
  const auto j = static_cast<std::size_t>(&fit.parameter(parameter) - fit.parameters.data());
  for (const auto& m : fit.uncertainty.methods) {
    EXPECT_NE(header.find("<th>" + m.method), std::string::npos) << m.method << " is not a column";
    if (m.ok && j < m.se.size() && std::isfinite(m.se[j])) {
      EXPECT_NE(row.find("<td>" + shown(m.se[j], 3) + "</td>"), std::string::npos) << m.method << " SE of " << parameter << ": " << row;
    }
  }
  EXPECT_NE(header.find("<th>quoted: " + fit.uncertainty.method + "</th>"), std::string::npos);
}

TEST_F(CalibrationTest, AFullFolderGoesThroughEveryStepIntoACompleteReport) {
  write_friction();
  write_thermal();
  const CalibrationSet set = find_calibration_set(dir_);
  ASSERT_EQ(set.friction_logs.size(), 1u);
  ASSERT_TRUE(set.thermal_manifest);
  std::vector<std::string> steps;
  const Calibration c = calibrate(set, {}, {.step = [&](std::size_t, std::size_t, const std::string& s) { steps.push_back(s); }});
  EXPECT_EQ(steps, (std::vector<std::string>{"loading the measurements", "friction fit", "friction diagnosis",
                                             "calibrated friction model", "plan of the next friction conditions", "thermal fit", "thermal diagnosis",
                                             "calibrated thermal model", "plan of the next thermal runs",
                                             "prediction of the runs' cycle"}));
  ASSERT_TRUE(c.friction && c.friction_diagnosis && c.thermal && c.thermal_diagnosis);
  EXPECT_TRUE(c.notes.empty());
  // The hidden seal drag is found, and the thermal heat came from the fitted law.
  ASSERT_FALSE(c.friction_diagnosis->accepted.empty()) << c.friction_diagnosis->summary;
  EXPECT_EQ(c.friction_diagnosis->accepted.front().effect, "seal_drag");
  ASSERT_TRUE(c.thermal_options.friction);
  EXPECT_EQ(c.thermal_options.friction->k1, c.friction->constants().k1);

  const auto outputs = calibration_outputs(c);
  std::vector<std::string> names;
  for (const auto& [name, text] : outputs) names.push_back(name);
  EXPECT_EQ(names, (std::vector<std::string>{"model.toml", "calibrated_friction.json", "calibrated_thermal.json", "friction.json",
                                             "friction_samples.csv", "friction_conditions.csv", "friction_diagnosis.json",
                                             "thermal.json", "thermal_samples.csv", "thermal_alpha_curve.csv",
                                             "thermal_diagnosis.json", "prediction.json", "prediction_time.csv", "plan_friction.json",
                                             "plan_friction_template.csv", "plan_thermal.json", "plan_thermal_manifest.toml",
                                             "calibration.json", "report.html"}));
  ASSERT_TRUE(c.prediction);  // the runs' cycle: the rail grows while the block runs
  EXPECT_GT(c.prediction->elongation_um.value[c.prediction->time_s.size() / 2 - 1], 1.0);
  const auto summary = nlohmann::json::parse(outputs[outputs.size() - 2].second);
  EXPECT_EQ(summary["friction_diagnosis"]["verdict"], c.friction_diagnosis->verdict);
  EXPECT_EQ(summary["published_model"]["thermal"]["alpha"]["value"].get<double>(), c.thermal->joint.parameter("alpha").value);
  EXPECT_EQ(summary["inputs"].size(), 2u + c.thermal_data->runs.size());
  const std::string& html = outputs.back().second;
  expect_complete_report(c, html);
  EXPECT_NE(html.find(c.friction_diagnosis->verdict), std::string::npos);
  EXPECT_NE(html.find(c.thermal_diagnosis->verdict), std::string::npos);

  // What was found, then the calibrated model; how sure it is, method by method; the published
  // models labelled.
  expect_found_then_calibrated_model(c, html, summary);
  const std::string panel = between(html, "<h2 id=\"how-sure\"", "<h2 id=\"friction\"");
  expect_every_method(between(panel, "Friction law: how sure", "Rail model: how sure"), c.calibrated.friction->fit, "k1");
  expect_every_method(between(panel, "Rail model: how sure", "</svg>"), c.calibrated.thermal->joint, "alpha");
  const std::string alpha_runs = between(html, "data-plot=\"calibrated-thermal-runs-alpha\"", "</svg>");
  EXPECT_NE(alpha_runs.find("class=\"error-bars\""), std::string::npos) << "each run's α without its interval";
  EXPECT_NE(alpha_runs.find("stroke-dasharray"), std::string::npos) << "no pooled 95 % interval";
  const std::string label = "published model (for comparison; conditional on a model the diagnosis rejects)";
  EXPECT_NE(between(html, "<h2 id=\"friction\">", "</h2>").find(label), std::string::npos);
  if (!c.thermal_diagnosis->accepted.empty()) {
    EXPECT_NE(between(html, "<h2 id=\"thermal\">", "</h2>").find(label), std::string::npos);
  }
  ASSERT_FALSE(c.friction_diagnosis->shifts.empty());
  const ParameterShift& shift = c.friction_diagnosis->shifts.front();
  const std::string shift_row = between(between(html, "The parameters that move", "</table>"), "<tr><td>" + shift.name + "</td>", "</tr>");
  for (const auto& [low, high] : {std::pair{shift.baseline_low, shift.baseline_high}, std::pair{shift.extended_low, shift.extended_high}})
    EXPECT_NE(shift_row.find(fmt::format("[{}, {}]", shown(low, 4), shown(high, 4))), std::string::npos) << shift_row;
}

// The curves of Fig. 6 pass through the points they were fitted to: on a log whose runs carry
// large load-cell zero offsets, the law with the accepted causes was drawn without its fit's
// offset and sat off every point of a one-setup run (regression). Each point set against its
// dashed curve, interpolated at the points' speeds: the mean gap is far below the runs' zeros.
TEST_F(CalibrationTest, TheCausesCurvesPassThroughThePointsDespiteRunOffsets) {
  FrictionRigConfig config;
  config.guides = {"SRN 35C"};
  config.runs = 3;
  config.run_offset_N = 0.6;
  config.one_setup_per_run = true;  // each plotted group is one run, with its own zero
  config.preload_um = {1.5, 4.0};
  config.temperature_C = {22, 32};
  RigEffects effects;
  set_rig_effect(effects, "seal_drag", 150);
  write("friction.csv", friction_log_csv(generate_friction_log(config, effects).log));
  const Calibration c = calibrate(find_calibration_set(dir_), {});
  ASSERT_TRUE(c.friction_diagnosis && !c.friction_diagnosis->accepted.empty());
  double rms_offset = 0;
  for (double o : c.friction_diagnosis->final_fit.run_offset_N) rms_offset += o * o;
  rms_offset = std::sqrt(rms_offset / static_cast<double>(c.friction_diagnosis->final_fit.run_offset_N.size()));
  ASSERT_GT(rms_offset, 0.3) << "runs whose zeros differ by far more than the noise";
  std::size_t compared = 0;
  for (const report::Plot& plot : report::friction_velocity_panels(c)) {
    for (std::size_t k = 0; k < plot.series.size(); ++k) {
      const report::Series& points = plot.series[k];
      if (points.mark != report::Mark::points) continue;
      const auto dashed = std::find_if(plot.series.begin() + static_cast<std::ptrdiff_t>(k), plot.series.end(),
                                       [&](const report::Series& s) { return s.dashed && s.color == points.color; });
      ASSERT_NE(dashed, plot.series.end()) << plot.id;
      double gap = 0;
      for (std::size_t i = 0; i < points.x.size(); ++i) {
        const auto hi = std::upper_bound(dashed->x.begin(), dashed->x.end(), points.x[i]);
        const auto j = static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(hi - dashed->x.begin(), 1, static_cast<std::ptrdiff_t>(dashed->x.size()) - 1));
        const double t = (points.x[i] - dashed->x[j - 1]) / (dashed->x[j] - dashed->x[j - 1]);
        gap += points.y[i] - (dashed->y[j - 1] + t * (dashed->y[j] - dashed->y[j - 1]));
      }
      gap /= static_cast<double>(points.x.size());
      EXPECT_LT(std::abs(gap), 0.15) << plot.id << " " << points.label << " (runs' zeros: rms " << rms_offset << " N)";
      ++compared;
    }
  }
  EXPECT_GE(compared, 6u);
}

// A verdict of "no significant discrepancy" must not stand alone beside per-run α that
// disagree beyond their intervals (here the heat reaching the rail varies from run to run and
// nothing logged sees it): the brief says so, and names both readings. (Clean runs disagree
// too, as long as a run's interval takes its heat as exact: the intervals' issue.)
TEST_F(CalibrationTest, RunsWhoseAlphaDisagreeAreSaidBesideTheVerdict) {
  ThermalRigConfig config = short_runs();
  config.repeats = 2;
  config.duration_s = 4 * 3600;
  config.heat_variation = 0.3;
  config.seed = 3;
  write_thermal("thermal.toml", config);
  const std::string html = calibration_report_html(calibrate(find_calibration_set(dir_), {}));
  EXPECT_NE(html.find("But this model's runs' own α differ beyond their intervals"), std::string::npos);
  EXPECT_NE(html.find("or the per-run intervals are too narrow"), std::string::npos);
}

// The thermal figures show the calibrated model beside the rejected one, as the friction
// figures do: a dashed curve per sensor, keyed once, in every run's time plot.
TEST_F(CalibrationTest, TheThermalFiguresShowTheModelWithItsMechanisms) {
  RigEffects effects;
  set_rig_effect(effects, "convection_velocity", 15);
  ThermalRigConfig config = short_runs();
  config.seed = 2;
  const std::size_t runs = write_thermal("thermal.toml", config, effects);
  const Calibration c = calibrate(find_calibration_set(dir_), {});
  ASSERT_FALSE(c.calibrated.thermal_causes.empty());
  // A long legend entry wraps onto lines of its own: consecutive legend texts are one entry.
  const std::string html = std::regex_replace(calibration_report_html(c),
                                              std::regex("</text>\n<text x=\"[^\"]*\" y=\"[^\"]*\" text-anchor=\"start\">"), " ");
  const std::string key = fmt::format("with {} (dashed)", fmt::join(c.calibrated.thermal_causes, " + "));
  std::size_t keys = 0;
  for (auto at = html.find(key); at != std::string::npos; at = html.find(key, at + 1)) ++keys;
  EXPECT_EQ(keys, runs);
}

// Where an interval is a profile one, the report draws the profile it came from: the curve
// through the fit's evaluated points, crossing the 95 % line at the interval quoted in its title.
TEST_F(CalibrationTest, AProfileIntervalIsDrawnWithItsProfile) {
  write_friction();
  CalibrationOptions options;
  options.diagnose = false;
  options.friction.fit.profile = ProfileMode::all;
  const Calibration c = calibrate(find_calibration_set(dir_), options);
  ASSERT_TRUE(c.calibrated.friction);
  const std::string html = calibration_report_html(c);
  expect_complete_report(c, html);
  const FitResult& fit = c.calibrated.friction->fit;
  const auto j = static_cast<std::size_t>(&fit.parameter("k1") - fit.parameters.data());
  ASSERT_EQ(fit.parameters[j].interval, "profile");
  const std::string plot = between(html, fmt::format("data-plot=\"calibrated-friction-profile-{}\"", j), "</svg>");
  ASSERT_FALSE(plot.empty());
  EXPECT_NE(plot.find(report::escape_xml(report::interval(fit.parameters[j]))), std::string::npos) << "the title quotes the interval";
  EXPECT_NE(plot.find("linear interval&#39;s parabola"), std::string::npos);
}

TEST_F(CalibrationTest, AFolderWithOneHalfCalibratesThatHalfAndSaysWhatWasSkipped) {
  write_friction("friction_run_a.csv");
  CalibrationOptions options;
  options.diagnose = false;
  const Calibration c = calibrate(find_calibration_set(dir_), options);
  EXPECT_TRUE(c.friction);
  EXPECT_FALSE(c.thermal);
  ASSERT_EQ(c.notes.size(), 1u);
  EXPECT_NE(c.notes[0].find("thermal"), std::string::npos);
  const std::string html = calibration_report_html(c);
  expect_complete_report(c, html);
  EXPECT_EQ(html.find("data-plot=\"thermal"), std::string::npos);
  EXPECT_NE(html.find(c.notes[0]), std::string::npos) << "the report says what was skipped";
}

TEST_F(CalibrationTest, RefusesAFolderWithoutMeasurementsOrWithTwoManifests) {
  EXPECT_THROW(find_calibration_set(dir_ / "missing"), InputError);
  EXPECT_THROW(find_calibration_set(dir_), InputError);  // empty
  write_thermal("thermal_a.toml");
  write_thermal("thermal_b.toml");
  try {
    find_calibration_set(dir_);
    FAIL() << "two manifests accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("thermal_b.toml"), std::string::npos) << e.what();
  }
}

TEST_F(CalibrationTest, NeverReadsItsOwnOutputsBackAsMeasurements) {
  write_friction();
  CalibrationOptions options;
  options.diagnose = false;
  options.friction.fit.starts = 3;
  const Calibration first = calibrate(find_calibration_set(dir_), options);
  // `lmcal calibrate -o SET`: the outputs land beside the logs (friction_samples.csv, …).
  OutputSet out;
  for (auto& [name, text] : calibration_outputs(first)) out.add(dir_ / name, text);
  out.commit();
  const CalibrationSet again = find_calibration_set(dir_);
  ASSERT_EQ(again.friction_logs.size(), 1u);
  EXPECT_EQ(again.friction_logs[0].filename(), "friction.csv");
  EXPECT_EQ(again.ignored_files.size(), 2u) << "friction_samples.csv and friction_conditions.csv";
  const Calibration second = calibrate(again, options);
  EXPECT_EQ(second.friction_log->size(), first.friction_log->size());
  EXPECT_NE(second.notes[0].find("not read: it is an output of lmcal calibrate"), std::string::npos) << second.notes[0];
  // The options it ran with are recorded.
  const auto j = nlohmann::json::parse(calibration_json(second));
  EXPECT_EQ(j["options"]["friction"]["fit"]["starts"], 3);
  EXPECT_EQ(j["options"]["diagnose"], false);
  EXPECT_TRUE(j["warnings"].empty()) << j["warnings"].dump();
}

TEST_F(CalibrationTest, ARunThatDisagreesWithTheOthersIsAWarningAndCleanDataHasNone) {
  FrictionRigConfig config;
  config.guides = {"SRN 35C"};
  config.runs = 5;
  FrictionLog log = generate_friction_log(config, {}).log;
  write("friction.csv", friction_log_csv(log));
  CalibrationOptions options;
  options.diagnose = false;
  options.friction.fit.bootstrap = 0;
  const Calibration clean = calibrate(find_calibration_set(dir_), options);
  EXPECT_TRUE(clean.warnings.empty()) << clean.warnings.front();
  // Run 3 logged with the load cell in another unit than stated: every force 1.5 times too large.
  for (std::size_t i = 0; i < log.size(); ++i)
    if (log.run_names[log.run[i]] == "run03") log.friction_N[i] *= 1.5;
  write("friction.csv", friction_log_csv(log));
  const Calibration mistaken = calibrate(find_calibration_set(dir_), options);
  ASSERT_EQ(mistaken.warnings.size(), 1u);
  EXPECT_NE(mistaken.warnings[0].find("friction run 'run03' disagrees with the others"), std::string::npos)
      << mistaken.warnings[0];
  EXPECT_NE(calibration_report_html(mistaken).find("friction run &#39;run03&#39; disagrees"), std::string::npos);
  EXPECT_EQ(nlohmann::json::parse(calibration_json(mistaken))["warnings"].size(), 1u);
}

TEST_F(CalibrationTest, HeatFromThePapersConstantsIsAWarning) {
  ThermalRigConfig config;
  config.velocity_m_s = {0.066, 0.11};
  config.duration_s = 2 * 3600;
  config.record_every_s = 60;
  ThermalDataSet set = generate_thermal_dataset(config, {}, "test").set;
  const auto write_set = [&](bool with_friction) {
    OutputSet out;
    for (ThermalRun run : set.runs) {
      if (!with_friction) run.mean_friction_N.reset();
      out.add(dir_ / run.file, thermal_trace_csv(run.trace));
    }
    ThermalDataSet written = set;
    for (ThermalRun& run : written.runs) {
      run.file = dir_ / run.file;
      if (!with_friction) run.mean_friction_N.reset();
    }
    out.add(dir_ / "thermal.toml", thermal_manifest_toml(written, dir_));
    out.commit();
  };
  CalibrationOptions options;
  options.diagnose = false;
  write_set(true);
  EXPECT_TRUE(calibrate(find_calibration_set(dir_), options).warnings.empty());
  write_set(false);
  const Calibration c = calibrate(find_calibration_set(dir_), options);
  ASSERT_EQ(c.warnings.size(), 1u);
  EXPECT_NE(c.warnings[0].find("the heat came from the paper's friction constants"), std::string::npos) << c.warnings[0];
}

// A lab's heated bar from the user's catalog (given on the command line, or by the manifest),
// heated and then left to cool: calibrated on both phases, and named in the report.
TEST_F(CalibrationTest, AUserCatalogBarCalibratesAndTheReportNamesIt) {
  const std::string bars = "[[bar]]\nname = \"steel bar 20x20\"\narea_m2 = 4e-4\nperimeter_m = 0.08\n"
                           "conductivity_W_mK = 45\ndensity_kg_m3 = 7850\nspecific_heat_J_kgK = 470\n"
                           "contact_length_mm = 50\n";
  std::ofstream(dir_ / "bars.toml") << bars;
  const GuideCatalog catalog = load_catalog(dir_ / "bars.toml");
  ThermalRigConfig config;
  config.catalog = &catalog;
  config.guide = "steel bar 20x20";
  config.heat_rate_W = 4.0;
  config.heater_off_s = 3 * 3600;
  config.duration_s = 5 * 3600;
  config.record_every_s = 60;
  config.sensor_position_m = {0.0, 0.1};
  ThermalDataSet set = generate_thermal_dataset(config, {}, "bar").set;
  OutputSet out;
  for (ThermalRun& run : set.runs) {
    out.add(dir_ / run.file, thermal_trace_csv(run.trace));
    run.file = dir_ / run.file;
  }
  set.catalog_file.clear();  // the manifest names no catalog: the command line must
  out.add(dir_ / "thermal.toml", thermal_manifest_toml(set, dir_));
  out.commit();
  CalibrationOptions options;
  options.diagnose = false;
  EXPECT_THROW(calibrate(find_calibration_set(dir_), options), InputError);  // an unknown guide, at its line
  options.catalog_file = (dir_ / "bars.toml").string();
  const Calibration c = calibrate(find_calibration_set(dir_), options);
  ASSERT_TRUE(c.calibrated.thermal);
  const ParameterEstimate& alpha = c.calibrated.thermal->joint.parameter("alpha");
  EXPECT_LE(alpha.ci_low, 0.6);
  EXPECT_GE(alpha.ci_high, 0.6);
  const std::size_t after_off = static_cast<std::size_t>(std::count_if(
      c.thermal->samples.begin(), c.thermal->samples.end(), [](const auto& s) { return s.time_s > 3 * 3600; }));
  EXPECT_GT(after_off, 100u);  // the cooling phase is fitted, not cut away
  const std::string html = calibration_report_html(c);
  EXPECT_NE(html.find("steel bar 20x20 (a plain bar, from " + options.catalog_file + ")"), std::string::npos);
  EXPECT_EQ(nlohmann::json::parse(calibration_json(c))["options"]["catalog"], options.catalog_file);
}

// ---- the committed results of the bundled set -------------------------------------------

// Numbers equal to a relative 1e-6 (or 1e-8 absolute, for values that are zero up to the fits'
// tolerance: a thermal sensor's bias, which its fitted offset makes 1e-12 K on one processor and
// 1e-9 K on another), everything else exactly. JSON fields named "seconds" (timings) are not compared. A percentage
// (a field ending in "_percent") is a difference of two fitted RMSEs over one: a last-bit change
// of the data's memory layout moves each fit within its solver tolerance (1e-9 relative), which
// moves a gain near 0 by up to 1e-6 percentage points; such fields compare to 1e-5 absolute.
void expect_same_json(const nlohmann::json& a, const nlohmann::json& b, const std::string& where) {
  if (a.is_number() && b.is_number()) {
    const double x = a.get<double>(), y = b.get<double>();
    const double absolute = where.ends_with("_percent") ? 1e-5 : 1e-8;
    EXPECT_NEAR(x, y, 1e-6 * std::max(std::abs(x), std::abs(y)) + absolute) << where;
  } else if (a.is_object() && b.is_object()) {
    ASSERT_EQ(a.size(), b.size()) << where;
    for (auto it = a.begin(); it != a.end(); ++it) {
      ASSERT_TRUE(b.contains(it.key())) << where << "." << it.key();
      if (it.key() != "seconds") expect_same_json(it.value(), b[it.key()], where + "." + it.key());
    }
  } else if (a.is_array() && b.is_array()) {
    ASSERT_EQ(a.size(), b.size()) << where;
    for (std::size_t i = 0; i < a.size(); ++i) expect_same_json(a[i], b[i], fmt::format("{}[{}]", where, i));
  } else {
    EXPECT_EQ(a, b) << where;
  }
}

void expect_same_text(const std::string& a, const std::string& b, double absolute, const std::string& file) {
  const std::regex number(R"([-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?)");
  std::sregex_token_iterator ia(a.begin(), a.end(), number, {-1, 0}), ib(b.begin(), b.end(), number, {-1, 0}), end;
  std::size_t differences = 0, token = 0;
  for (; ia != end && ib != end; ++ia, ++ib, ++token) {
    const std::string x = *ia, y = *ib;
    if (x == y) continue;
    const bool numeric = std::regex_match(x, number) && std::regex_match(y, number);
    if (numeric && std::abs(std::stod(x) - std::stod(y)) <= absolute + 1e-6 * std::abs(std::stod(x))) continue;
    if (++differences <= 5) ADD_FAILURE() << file << " token " << token << ": '" << x << "' vs '" << y << "'";
  }
  EXPECT_TRUE(ia == end && ib == end) << file << " has a different length";
  EXPECT_EQ(differences, 0u) << file;
}

TEST(BundledCalibration, AFreshRunReproducesTheCommittedResults) {
  const fs::path root = test::source_dir();
  const fs::path previous = fs::current_path();
  fs::current_path(root);  // the outputs record the set as given: measurements/cheng2017
  const Calibration c = calibrate(find_calibration_set("measurements/cheng2017"), {});
  fs::current_path(previous);
  for (const auto& [name, text] : calibration_outputs(c)) {
    if (name.ends_with("_samples.csv")) continue;  // per sample, 7 MB: not committed (fits/README.md)
    const fs::path committed = root / "fits" / "cheng2017" / name;
    ASSERT_TRUE(fs::exists(committed)) << committed << ": run scripts/run.sh and commit fits/cheng2017";
    const std::string stored = read(committed);
    if (committed.extension() == ".json")
      expect_same_json(nlohmann::json::parse(text), nlohmann::json::parse(stored), name);
    else
      expect_same_text(text, stored, committed.extension() == ".html" ? 0.011 : 1e-9, name);  // SVG: 0.01 px
  }
  // Its effects are all in the library: no empirical term, and the report says so in one sentence.
  ASSERT_TRUE(c.friction_diagnosis && c.thermal_diagnosis);
  const std::string html = calibration_report_html(c);
  // The published rail model's runs disagree on α (the heat of a run with the wrong model) where
  // the calibrated model's do not: named at the top as the two readings of one question, with
  // both tests, before the published model's warning further down.
  ASSERT_TRUE(c.thermal && c.calibrated.thermal);
  ASSERT_LT(c.thermal->alpha_runs.q_p, 0.05);
  ASSERT_GT(c.calibrated.thermal->alpha_runs.q_p, 0.05);
  const report::Findings words = report::findings(c);
  ASSERT_EQ(words.contradictions.size(), 1u);
  const std::string& both = words.contradictions.front();
  EXPECT_TRUE(both.starts_with("The published rail model's runs disagree on α")) << both;
  EXPECT_NE(both.find(report::p_is(c.thermal->alpha_runs.q_p)), std::string::npos) << both;
  EXPECT_NE(both.find("the calibrated rail model's runs do not (Cochran's Q = " + shown(c.calibrated.thermal->alpha_runs.q, 3)),
            std::string::npos) << both;
  EXPECT_LT(html.find(report::escape_xml(both)), html.find("But this model's runs' own α differ"));
  EXPECT_EQ(html.find("Beyond the library: an empirical term"), std::string::npos);
  EXPECT_EQ(html.find("class=\"empirical\""), std::string::npos);
  EXPECT_EQ(html.find("not a named cause"), std::string::npos);
  // Bands only in the prediction of the runs' cycle (an empirical term would draw its own).
  const std::size_t prediction = html.find("id=\"prediction\"");
  ASSERT_NE(prediction, std::string::npos);
  const std::string outside_prediction = html.substr(0, prediction) + html.substr(html.find("</section>", prediction));
  EXPECT_NE(html.find("class=\"band\"", prediction), std::string::npos);
  EXPECT_EQ(outside_prediction.find("class=\"band\""), std::string::npos);
  for (const auto* e : {&c.friction_diagnosis->empirical, &c.thermal_diagnosis->empirical}) {
    EXPECT_FALSE(e->found) << e->formula;
    if (e->searched) {
      EXPECT_NE(html.find(report::escape_xml(e->reason)), std::string::npos) << e->reason;
    }
  }
  // The answer holds the truth the set was made with (measurements/cheng2017/*_truth.json):
  // α inside its 95 % interval; the nine friction parameters each within 3 of their quoted SEs
  // (nine 95 % intervals all covering at once is a 63 % event: their coverage is tested by
  // simulation in coverage_test.cpp).
  const auto truth = [&](const char* file) { return nlohmann::json::parse(read(root / "measurements" / "cheng2017" / file)); };
  const auto friction_truth = truth("friction_truth.json"), thermal_truth = truth("thermal_truth.json");
  ASSERT_TRUE(c.calibrated.friction && c.calibrated.thermal);
  auto expect_near_truth = [](const ParameterEstimate& p, double value) {
    EXPECT_LT(std::abs(p.value - value), 3 * p.se) << p.name << " " << p.value << " ± " << p.se << ", truth " << value;
  };
  for (const auto& name : kFrictionConstantNames)
    expect_near_truth(c.calibrated.friction->fit.parameter(name), friction_truth["friction_constants"][name].get<double>());
  for (const char* effect : {"seal_drag", "direction_asymmetry"})
    expect_near_truth(c.calibrated.friction->fit.parameter(effect), friction_truth["effects"][effect]["value"].get<double>());
  const ParameterEstimate& alpha = c.calibrated.thermal->joint.parameter("alpha");
  const double true_alpha = thermal_truth["alpha_reference"].get<double>();
  EXPECT_LE(alpha.ci_low, true_alpha) << alpha.value << " ± " << alpha.se;
  EXPECT_GE(alpha.ci_high, true_alpha) << alpha.value << " ± " << alpha.se;
}

// The rig-shaped bundled set (measurements/rig: raw load-cell runs with a friction manifest,
// thermal runs that stop and cool without ambient sensors) calibrates to its truth: the seven
// constants within 3 SE, α inside its interval, nothing named by the diagnoses, and the
// report shows the raw trace with its plateaus.
TEST(BundledCalibration, TheRigShapedSetCalibratesToItsTruth) {
  const fs::path root = test::source_dir();
  const Calibration c = calibrate(find_calibration_set(root / "measurements" / "rig"), {});
  ASSERT_TRUE(c.set.friction_manifest);
  ASSERT_EQ(c.friction_log->segmentation.size(), 8u);
  for (const RunSegmentation& s : c.friction_log->segmentation) EXPECT_EQ(s.plateaus.size(), 10u) << s.run;  // 5 speeds × 2 senses
  ASSERT_TRUE(c.calibrated.friction && c.calibrated.thermal && c.friction_diagnosis && c.thermal_diagnosis);
  EXPECT_TRUE(c.friction_diagnosis->accepted.empty());
  EXPECT_TRUE(c.thermal_diagnosis->accepted.empty());
  EXPECT_TRUE(c.warnings.empty()) << c.warnings.front();
  const auto truth = [&](const char* file) { return nlohmann::json::parse(read(root / "measurements" / "rig" / file)); };
  const auto friction_truth = truth("friction_truth.json");
  for (const auto& name : kFrictionConstantNames) {
    const ParameterEstimate& p = c.calibrated.friction->fit.parameter(name);
    const double value = friction_truth["friction_constants"][name].get<double>();
    EXPECT_LT(std::abs(p.value - value), 3 * p.se) << p.name << " " << p.value << " ± " << p.se << ", truth " << value;
  }
  const ParameterEstimate& alpha = c.calibrated.thermal->joint.parameter("alpha");
  const double true_alpha = truth("thermal_truth.json")["alpha_reference"].get<double>();
  EXPECT_LE(alpha.ci_low, true_alpha) << alpha.value << " ± " << alpha.se;
  EXPECT_GE(alpha.ci_high, true_alpha) << alpha.value << " ± " << alpha.se;
  const std::string html = calibration_report_html(c);
  EXPECT_NE(html.find("data-plot=\"raw-trace-velocity\""), std::string::npos);
  EXPECT_NE(html.find("SRN 35C (guide, built-in catalog)"), std::string::npos);
}

}  // namespace
}  // namespace lmcal
