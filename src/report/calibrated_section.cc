// The report's second section, after "What we found": the calibrated model — the published
// friction law and rail model with the causes the diagnoses accepted, refitted — every
// parameter with its standard error and its quoted 95 % interval.
#include <fmt/ranges.h>

#include <set>

#include "sections.hpp"

namespace lmcal::report {

namespace {

// "the published law (Eqs. 3-7) + seal_drag", or why it has no cause.
std::string with_causes(const std::string& model, const std::vector<std::string>& causes, bool diagnosed) {
  if (!causes.empty()) return fmt::format("{} + {}", model, fmt::join(causes, " + "));
  return model + (diagnosed ? " (the diagnosis accepted no cause)" : " (no diagnosis ran)");
}

// The model's parameters (per-run nuisance left out): value, SE, quoted interval. Where the
// intervals come from is said once, in words, under "What we found" (findings.hpp), with the
// method's statement and notes in its details.
void parameter_table(Page& page, const FitResult& fit) {
  std::vector<std::vector<std::string>> rows;
  for (const auto& p : fit.parameters)
    if (!nuisance(p)) rows.push_back({p.name, p.unit, num(p.value, 5), num(p.se, 3), interval(p), flags(p)});
  page.table({"parameter", "unit", "estimate", "standard error", "95 % interval", ""}, rows);
}

// The empirical terms of a calibrated friction model, labelled as such, and where they were learned.
void empirical_terms(Page& page, const std::vector<FrictionTerm>& terms) {
  if (terms.empty()) return;
  std::string symbols, ranges;
  std::set<TermCovariate> listed;
  for (std::size_t k = 0; k < terms.size(); ++k) {
    symbols += fmt::format("{}{}", k ? " + " : "", terms[k].symbol(k + 1));
    for (const auto& r : terms[k].seen) {
      if (!listed.insert(r.covariate).second) continue;
      const std::string unit = term_covariate_unit(r.covariate);
      ranges += fmt::format("{}{} {} to {}{}", ranges.empty() ? "" : "; ", term_covariate_name(r.covariate), num(r.min),
                            num(r.max), unit == "1" ? "" : " " + unit);
    }
  }
  page.paragraph(fmt::format("Includes an empirical term (not a named cause): {}; its predictions outside the covariate ranges "
                             "of the data{} are extrapolation.",
                             symbols, ranges.empty() ? "" : " (" + ranges + ")"),
                 "warning");
}

void friction_model(Page& page, const Calibration& c) {
  const CalibratedModel& m = c.calibrated;
  const FrictionFitResult& f = *m.friction;
  std::vector<std::string> parts = m.friction_causes;
  if (!f.terms.empty()) parts.push_back("an empirical term");
  page.heading(3, "Friction: " + with_causes("the published law (Eqs. 3-7)", parts, c.friction_diagnosis.has_value()));
  page.paragraph(fmt::format("Fitted to {} samples of {} runs, each run's load-cell zero a random run intercept (τ = {} N, "
                             "estimated with the constants). Held-out (leave-one-run-out, each run a new setup) RMSE {} N; "
                             "residual RMSE {} N.",
                             c.friction_log->size(), f.runs.size(), num(f.run_offset_sd_N, 3), num(f.cv_rmse_N), num(f.rmse_N)));
  if (const std::string caveat = held_out_caveat(f); !caveat.empty()) page.paragraph("Held out: " + caveat + ".");
  empirical_terms(page, f.terms);
  parameter_table(page, friction_fit_as_shown(f));
  fit_caveats(page, f.fit);
}

void thermal_model(Page& page, const Calibration& c) {
  const CalibratedModel& m = c.calibrated;
  const ThermalFitResult& t = *m.thermal;
  const std::string model = fmt::format("the published rail model (Eq. 11, {} source)", to_string(m.thermal_options.source));
  page.heading(3, "Rail temperature: " + with_causes(model, m.thermal_causes, c.thermal_diagnosis.has_value()));
  const bool nuisances = std::any_of(t.joint.parameters.begin(), t.joint.parameters.end(), nuisance);
  page.paragraph(fmt::format("{} runs, heat Q_f from {}. Held-out (leave-one-run-out) RMSE {} K; largest error {} % of the "
                             "sensor's span (its highest minus lowest 10-record mean).{}",
                             t.runs.size(), m.thermal_options.friction ? "the calibrated friction model" : "the measured mean friction",
                             num(t.cv_rmse_K), num(t.max_error_percent, 3),
                             nuisances ? " Per-run nuisance parameters (thermocouple offsets, start temperatures, heat scales) "
                                         "are fitted and not shown."
                                       : ""));
  parameter_table(page, t.joint);
  if (c.thermal_diagnosis)
    if (const auto [low, high] = candidate_alpha_range(c.thermal_diagnosis->rounds); std::isfinite(low))
      page.paragraph(fmt::format(
          "α is conditional on this model: its interval says how well these runs fix α if the model is right. The models "
          "the diagnosis tried put α between {} and {} (each candidate's α is in the diagnosis's tables): a mechanism left "
          "out moves α by more than any interval shows.",
          num(low), num(high)));
  fit_caveats(page, t.joint);
}

// Hours, for the plots' time axes.
std::vector<double> hours(const std::vector<double>& seconds) {
  std::vector<double> h;
  for (double s : seconds) h.push_back(s / 3600);
  return h;
}

// What the calibrated model predicts for the runs' own cycle: the rail's elongation and its
// temperature at the sensors, each with its band, and where the cycle leaves the calibration.
void prediction_part(Page& page, const Calibration& c) {
  if (!c.prediction || !c.duty) return;
  const Prediction& p = *c.prediction;
  const DutyCycle& d = *c.duty;
  const DutySegment& run = d.segments.front();
  page.heading(3, "Prediction: the runs' cycle", "prediction");
  page.paragraph(fmt::format("The calibrated model run over the calibration runs' own cycle: {} m/s under {} N for {} h, "
                             "then {} h at rest, ambient {} °C. A linear scale along the whole rail, fixed at its end "
                             "(x = {} m), is off by the rail's elongation at its far end. 95 % bands: {}.",
                             num(run.velocity_m_s), num(run.load_N), num(run.duration_s / 3600), num(d.segments.back().duration_s / 3600),
                             num(d.ambient.temperature_C.front()), num(d.scale.fixed_point_m()), p.method));
  const std::vector<double> t = hours(p.time_s);
  Plot elongation{.id = "prediction-elongation", .title = "Rail elongation = scale error at its far end", .x_label = "time (h)",
                  .y_label = "elongation (µm)"};
  elongation.series.push_back({.label = "model (95 % band)", .x = t, .y = p.elongation_um.value,
                               .band_low = p.elongation_um.low, .band_high = p.elongation_um.high});
  Plot temperature{.id = "prediction-temperature", .title = "Rail temperature at the runs' sensors", .x_label = "time (h)",
                   .y_label = "temperature (°C)"};
  for (std::size_t q = 0; q < p.positions_m.size(); ++q)
    temperature.series.push_back({.label = fmt::format("x = {} m (95 % band)", num(p.positions_m[q])), .x = t,
                                  .y = p.temperature_C[q].value, .band_low = p.temperature_C[q].low,
                                  .band_high = p.temperature_C[q].high});
  page.figures({elongation, temperature});
  for (const auto& f : p.outside)
    page.paragraph(fmt::format("Outside the calibrated range: {} {} = {} (the {} calibration saw {} to {}): an extrapolation.",
                               f.segment, f.quantity, num(f.value), f.what, num(f.low), num(f.high)),
                   "warning");
  for (const auto& note : p.notes) page.paragraph("Note: " + note);
  page << "<p>Written to <code>prediction.json</code> and <code>prediction_time.csv</code>. Another duty: "
          "<code>lmcal predict model.toml DUTY.toml</code> (segments of speed, load, stroke and duration; "
          "<code>examples/duty/two_shifts.toml</code> is one).</p>\n";
}

// The next friction conditions to log, and what they would do to each constant's SE.
void plan_part(Page& page, const Calibration& c) {
  if (!c.plan) return;
  const FrictionPlan& plan = *c.plan;
  page.heading(3, "Next measurements: friction", "plan");
  page.paragraph(fmt::format("The {} conditions, among every combination of the logs' own speeds, loads, preloads, temperatures and "
                             "directions, that most shrink the calibrated law's uncertainty ({}), each logged as {} samples:",
                             plan.picks.size(), plan.criterion, plan.samples_per_condition));
  std::vector<std::vector<std::string>> rows;
  for (std::size_t k = 0; k < plan.picks.size(); ++k) {
    const FrictionCandidate& p = plan.picks[k].candidate;
    rows.push_back({std::to_string(k + 1), p.guide, num(p.conditions.velocity_m_s), num(p.conditions.load_N),
                    num(p.conditions.preload_um), num(p.conditions.temperature_C), p.conditions.direction > 0 ? "+1" : "-1"});
  }
  page.table({"", "guide", "velocity (m/s)", "load (N)", "preload (µm)", "temperature (°C)", "direction"}, rows);
  std::vector<std::vector<std::string>> ses;
  for (const auto& p : plan.parameters)
    ses.push_back({p.name, p.unit, p.determined_before ? num(p.se_before, 3) : "not determined", num(p.se_after, 3),
                   p.determined_before ? num(100 * (1 - p.se_after / p.se_before), 2) + " %" : "–"});
  page.table({"parameter", "unit", "standard error now", "expected after", "shrink"}, ses);
  double largest = 0;
  bool undetermined = false;
  for (const auto& p : plan.parameters) {
    if (p.determined_before) largest = std::max(largest, 1 - p.se_after / p.se_before);
    undetermined = undetermined || !p.determined_before;
  }
  if (!undetermined && largest < 0.05)
    page.paragraph(fmt::format("The logs already determine the law well at these conditions: the best {} more shrink no "
                               "standard error by more than {} %. Wider ranges (lower speeds, other preloads or "
                               "temperatures) would do more: give them as candidates.",
                               plan.picks.size(), num(100 * largest, 2)));
  for (const auto& note : plan.notes) page.paragraph("Note: " + note);
  page << "<p>Written to <code>plan_friction.json</code> and <code>plan_friction_template.csv</code> (a friction log to fill on the rig). "
          "Other candidates or parameters: <code>lmcal plan friction LOG.csv --model model.toml --velocity 0.001:0.2:0.001 "
          "--parameters v_st_m_s,mu_st</code>.</p>\n";
}

// The next thermal runs, and what they would do to the rail model's SEs (or to a tie).
void thermal_plan_part(Page& page, const Calibration& c) {
  if (!c.thermal_plan) return;
  const ThermalPlan& plan = *c.thermal_plan;
  page.heading(3, "Next measurements: thermal runs", "plan-thermal");
  page.paragraph(fmt::format("The {} runs, at the runs' speeds and from half the slowest to 1.5 times the fastest, that most "
                             "shrink the calibrated rail model's uncertainty ({}):",
                             plan.picks.size(), plan.criterion));
  std::vector<std::vector<std::string>> rows;
  for (std::size_t r = 0; r < plan.picks.size(); ++r) {
    const ThermalCandidate& run = plan.picks[r].candidate;
    rows.push_back({std::to_string(r + 1), num(run.velocity_m_s), num(run.load_N), num(run.duration_s / 3600)});
  }
  page.table({"", "velocity (m/s)", "load (N)", "duration (h)"}, rows);
  std::vector<std::vector<std::string>> ses;
  for (const auto& p : plan.parameters)
    ses.push_back({p.name + (p.determined_before ? "" : " (not in the model)"), p.unit, num(p.se_before, 3), num(p.se_after, 3)});
  page.table({"parameter", "unit", "standard error now", "expected after"}, ses);
  for (const auto& note : plan.notes) page.paragraph("Note: " + note);
  page << "<p>Written to <code>plan_thermal.json</code> and <code>plan_thermal_manifest.toml</code> (the runs to log, a thermal "
          "manifest to complete). Other candidates: <code>lmcal plan thermal thermal.toml --model model.toml --velocity "
          "0.03:0.2:0.01 --separate base_loss,convection_velocity</code>.</p>\n";
}

}  // namespace

void calibrated_section(Page& page, const Calibration& c) {
  const CalibratedModel& m = c.calibrated;
  if (!m.friction && !m.thermal) return;
  page << "<section class=\"calibrated\">\n";
  page.heading(2, "The calibrated model", "calibrated");
  page.paragraph("The published friction law and rail model with the causes the diagnoses accepted, refitted: the result of "
                 "this calibration. The fits of the published models further down are for comparison.");
  page << "<p>Written to <code>model.toml</code>. Calibrate once, use everywhere: <code>lmcal simulate friction --model "
          "model.toml</code>, <code>lmcal simulate thermal --model model.toml</code>.</p>\n";
  if (m.friction) friction_model(page, c);
  if (m.thermal) thermal_model(page, c);
  prediction_part(page, c);
  plan_part(page, c);
  thermal_plan_part(page, c);
  page << "</section>\n";
}

void fit_caveats(Page& page, const FitResult& fit) {
  for (const auto& issue : fit.identifiability.issues)
    page.paragraph("Not identifiable: " + issue.why + ". To separate them: " + issue.measure + ".", "warning");
  for (const auto& w : fit.warnings) page.paragraph("Warning: " + w, "warning");
}

void correlation_table(Page& page, const FitResult& fit, const std::vector<std::size_t>& shown) {
  if (shown.size() < 2 || fit.correlation.rows() == 0) return;
  std::vector<std::string> header{"correlation"};
  for (std::size_t j : shown) header.push_back(fit.parameters[j].name);
  std::vector<std::vector<Cell>> rows;
  for (std::size_t i : shown) {
    rows.push_back({fit.parameters[i].name});
    for (std::size_t j : shown)
      rows.back().push_back(correlation_cell(fit.correlation(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j))));
  }
  page.table(header, rows);
}

}  // namespace lmcal::report
