// The thermal half of the report: α, the error against α (Fig. 11), temperature over time
// and along the rail (Figs. 14-16), residuals, the spread across runs and the diagnosis.
#include "sections.hpp"

namespace lmcal::report {

namespace {

constexpr std::size_t kPointsPerSeries = 120;
constexpr double kHour_s = 3600.0;

// Measured points (thinned) and the simulated line of every sensor of run r, with the
// measured ambient (the paper's Figs. 14-15).
Plot time_plot(const Calibration& c, std::size_t r) {
  const ThermalFitResult& f = *c.thermal;
  const ThermalRun& run = c.thermal_data->runs[r];
  Plot plot{.id = plot_id("thermal-time-" + run.id),
            .title = fmt::format("Run {}: {} m/s, {} N", run.id, num(run.velocity_m_s), num(run.load_N)),
            .x_label = "time (h)",
            .y_label = "temperature (°C)"};
  const auto& sensors = f.sensor_names[r];
  for (std::size_t s = 0; s < sensors.size(); ++s) {
    // One legend entry per sensor, in its colour: its points measured (evenly in time, how many
    // of how many said), its line the model.
    Series measured{.tooltip = sensors[s] + " measured", .mark = Mark::points, .color = colour(s)};
    Series simulated{.tooltip = sensors[s] + " model", .color = colour(s)};
    std::vector<const ThermalFitResult::Sample*> mine;
    for (const auto& sample : f.samples)
      if (sample.run == r && sample.sensor == s) mine.push_back(&sample);
    const std::size_t every = stride(mine.size(), kPointsPerSeries);
    const std::size_t line_every = stride(mine.size(), 3 * kPointsPerSeries);
    for (std::size_t k = 0; k < mine.size(); ++k) {
      if (k % line_every == 0 || k + 1 == mine.size()) {
        simulated.x.push_back(mine[k]->time_s / kHour_s);
        simulated.y.push_back(mine[k]->simulated_C);
      }
      if (k % every != 0) continue;
      measured.x.push_back(mine[k]->time_s / kHour_s);
      measured.y.push_back(mine[k]->measured_C);
    }
    measured.label = fmt::format("{} (points{}; line: model)", sensors[s],
                                 measured.x.size() < mine.size() ? fmt::format(", {} of {} shown", measured.x.size(), mine.size()) : "");
    plot.series.push_back(std::move(measured));
    plot.series.push_back(std::move(simulated));
  }
  // The calibrated model (the published one with the accepted mechanisms), dashed in each
  // sensor's colour: as the friction figures show the law with its causes.
  const CalibratedModel& m = c.calibrated;
  if (m.thermal && !m.thermal_causes.empty()) {
    for (std::size_t s = 0; s < sensors.size(); ++s) {
      Series calibrated{.tooltip = sensors[s] + " calibrated model", .color = colour(s), .dashed = true};
      std::vector<const ThermalFitResult::Sample*> mine;
      for (const auto& sample : m.thermal->samples)
        if (sample.run == r && sample.sensor == s) mine.push_back(&sample);
      const std::size_t every = stride(mine.size(), 3 * kPointsPerSeries);
      for (std::size_t k = 0; k < mine.size(); ++k)
        if (k % every == 0 || k + 1 == mine.size()) {
          calibrated.x.push_back(mine[k]->time_s / kHour_s);
          calibrated.y.push_back(mine[k]->simulated_C);
        }
      plot.series.push_back(std::move(calibrated));
    }
    plot.series.push_back({.label = fmt::format("with {} (dashed)", fmt::join(m.thermal_causes, " + ")),
                           .color = "#444444", .dashed = true, .legend_only = true});
  }
  const auto& trace = run.trace;
  if (!trace.ambient.empty()) {
    Series ambient{.label = "ambient (mean)", .color = "#999999", .dashed = true};
    const std::size_t every = stride(trace.size(), 4 * kPointsPerSeries);
    for (std::size_t t = 0; t < trace.size(); t += every) {
      double sum = 0;
      std::size_t n = 0;
      for (const auto& channel : trace.ambient)
        if (std::isfinite(channel.values[t])) sum += channel.values[t], ++n;
      ambient.x.push_back(trace.time_s[t] / kHour_s);
      ambient.y.push_back(n ? sum / static_cast<double>(n) : std::nan(""));
    }
    plot.series.push_back(std::move(ambient));
  }
  return plot;
}

// The model along the rail at the end of run r and what the sensors read there (Fig. 16).
Plot position_plot(const Calibration& c, std::size_t r) {
  const auto& end = c.thermal->end_states[r];
  const ThermalRun& run = c.thermal_data->runs[r];
  Plot plot{.id = plot_id("thermal-position-" + run.id),
            .title = fmt::format("Run {} along the rail at {} h", run.id, num(end.model.time_s / kHour_s, 3)),
            .x_label = "position from the rail centre (mm)",
            .y_label = "temperature (°C)"};
  Series model{.label = "model", .color = "#444444"};
  for (std::size_t i = 0; i < end.model.position_m.size(); ++i) {
    model.x.push_back(1e3 * end.model.position_m[i]);
    model.y.push_back(end.model.temperature_C[i]);
  }
  plot.series.push_back(std::move(model));
  // Each sensor in its colour, as in the run's time plot.
  const bool offsets = std::any_of(c.thermal->joint.parameters.begin(), c.thermal->joint.parameters.end(),
                                   [](const ParameterEstimate& p) { return p.name.starts_with("offset "); });
  const auto& sensors = c.thermal->sensor_names[r];
  for (std::size_t s = 0; s < end.sensor_position_m.size(); ++s)
    plot.series.push_back({.label = (s < sensors.size() ? sensors[s] : std::to_string(s + 1)) + (offsets ? " less its offset" : ""),
                           .x = {1e3 * end.sensor_position_m[s]},
                           .y = {end.measured_C[s]},
                           .mark = Mark::points,
                           .color = colour(s)});
  return plot;
}

// Residuals over time, one line per run and sensor, from one fit: every record's extent (each
// run of records by its lowest and highest), said in the legend when records were merged so.
Plot residual_time_plot(const std::string& id, const std::string& title, const ThermalFitResult& f,
                        const std::vector<ThermalRun>& runs, std::optional<std::pair<double, double>> y_limits = {}) {
  Plot plot{.id = id, .title = title, .x_label = "time (h)", .y_label = "measured - model (K)"};
  plot.references.push_back({});
  std::size_t most_records = 0, merged = 1;
  for (std::size_t r = 0; r < runs.size(); ++r)
    for (std::size_t s = 0; s < f.sensor_names[r].size(); ++s) {
      Series line{.label = s == 0 ? runs[r].id : "", .tooltip = runs[r].id + " " + f.sensor_names[r][s], .color = colour(r)};
      std::vector<const ThermalFitResult::Sample*> mine;
      std::vector<double> residual;
      for (const auto& sample : f.samples)
        if (sample.run == r && sample.sensor == s) {
          mine.push_back(&sample);
          residual.push_back(sample.measured_C - sample.simulated_C);
        }
      for (const std::size_t k : extremes(residual, kPointsPerSeries)) {
        line.x.push_back(mine[k]->time_s / kHour_s);
        line.y.push_back(residual[k]);
      }
      most_records = std::max(most_records, mine.size());
      merged = std::max(merged, stride(mine.size(), kPointsPerSeries));
      plot.series.push_back(std::move(line));
    }
  if (merged > 1)
    plot.series.push_back({.label = fmt::format("lines: each {} records' lowest and highest ({} per sensor)",
                                                merged, most_records),
                           .color = "#444444",
                           .legend_only = true});
  if (y_limits) plot.y_min = y_limits->first, plot.y_max = y_limits->second;
  return plot;
}

// Mean residual and RMSE of each sensor against position, and of each run against velocity.
std::vector<Plot> covariate_plots(const Calibration& c) {
  const ThermalFitResult& f = *c.thermal;
  Plot position{.id = "thermal-residual-position", .title = "Residuals by sensor position",
                .x_label = "position from the rail centre (mm)", .y_label = "residual (K)"};
  Plot velocity{.id = "thermal-residual-velocity", .title = "Residuals by run velocity", .x_label = "velocity (m/s)",
                .y_label = "residual (K)"};
  for (Plot* p : {&position, &velocity}) p->references.push_back({});
  Series bias{.label = "mean", .mark = Mark::points, .color = colour(0)}, rmse{.label = "RMSE", .mark = Mark::points, .color = colour(1)};
  Series run_bias = bias, run_rmse = rmse;
  for (std::size_t r = 0; r < c.thermal_data->runs.size(); ++r) {
    double run_sum = 0, run_ss = 0;
    std::size_t run_n = 0;
    for (const auto& g : f.goodness) {
      if (g.run != c.thermal_data->runs[r].id) continue;
      double sum = 0;
      std::size_t n = 0;
      for (const auto& sample : f.samples)
        if (sample.run == r && f.sensor_names[r][sample.sensor] == g.sensor) sum += sample.measured_C - sample.simulated_C, ++n;
      bias.x.push_back(1e3 * g.position_m), bias.y.push_back(n ? sum / static_cast<double>(n) : std::nan(""));
      rmse.x.push_back(1e3 * g.position_m), rmse.y.push_back(g.rmse_K);
      run_sum += sum, run_ss += g.rmse_K * g.rmse_K * static_cast<double>(g.n), run_n += g.n;
    }
    const double v = c.thermal_data->runs[r].velocity_m_s, n = static_cast<double>(std::max<std::size_t>(run_n, 1));
    run_bias.x.push_back(v), run_bias.y.push_back(run_sum / n);
    run_rmse.x.push_back(v), run_rmse.y.push_back(std::sqrt(run_ss / n));
  }
  position.series = {std::move(bias), std::move(rmse)};
  velocity.series = {std::move(run_bias), std::move(run_rmse)};
  return {std::move(position), std::move(velocity)};
}

void spread_section(Page& page, const Calibration& c) {
  const ThermalFitResult& f = *c.thermal;
  page.heading(3, "Spread across runs of the published model");
  const Spread& s = f.alpha_spread;
  page.paragraph(fmt::format("α of each run fitted alone: mean {}, spread of the runs (Eq. 1 σ) {}, 95 % interval of the "
                             "mean [{}, {}] ({}; the joint fit gives {}).",
                             num(s.mean), num(s.sd, 3), num(s.low), num(s.high), plural(s.n, "run"),
                             num(f.joint.parameter("alpha").value)));
  const RandomEffects& re = f.alpha_runs;
  if (re.k >= 2 && re.tau > 0)
    page.paragraph(fmt::format(
        "The runs' α differ beyond their own intervals by τ = {} (REML; Cochran's Q = {} on {}, {}): each run's heat "
        "reaching the rail has its own error that none of its records sees, so a run's α is known to √(SE² + τ²), not "
        "to the interval in its row. The repeats below are compared against that.",
        num(re.tau, 3), num(re.q, 3), plural(re.k, "run"), p_is(re.q_p)));
  std::vector<std::vector<std::string>> rows;
  for (std::size_t r = 0; r < f.runs.size(); ++r) {
    const RunInfo& info = f.runs[r];
    const ParameterEstimate* a = r < f.per_run.size() ? &f.per_run[r].parameter("alpha") : nullptr;
    rows.push_back({info.id, num(info.velocity_m_s), num(info.load_N), num(info.heat_rate_W), info.heat_source,
                    a ? num(a->value) : "–", a ? interval(*a) : "–",
                    std::isfinite(info.ambient_difference_percent) ? num(info.ambient_difference_percent, 3) : "one sensor"});
  }
  page.table({"run", "velocity (m/s)", "load (N)", "Q_f (W)", "heat from", "α", "95 % interval", "ambient sensors' difference (Eq. 2, %)"},
             rows);
  rows.clear();
  for (const auto& d : f.repeat_differences) rows.push_back({d.runs, num(d.percent, 3), num(d.z, 3), num(d.z_within, 3)});
  if (!rows.empty())
    page.table({"repeated runs", "Eq. 2 difference of α (%)", "z against √(SE₁² + SE₂² + 2τ²)", "z against their own SEs only"},
               rows);
  page.figures({per_run_plot("thermal-spread-alpha", "α of each run (95 % interval)", f.joint.parameter("alpha"),
                             per_run_estimates(f, "alpha"), "joint")});
}

void diagnosis_section(Page& page, const Calibration& c) {
  const ThermalDiagnosis& d = *c.thermal_diagnosis;
  page.heading(3, "What the published rail model gets wrong");
  verdict_paragraph(page, d.verdict, d.summary);
  page.paragraph(fmt::format("Held-out (leave-one-run-out) RMSE: {} K before, {} K after: a gain of {}; the "
                             "thermocouples' noise is {} K.",
                             num(d.cv_rmse_before_K), num(d.cv_rmse_after_K), percent(d.cv_gain_percent, 1), num(d.noise_K, 3)));
  candidate_tables(page, d.rounds, "K");
  steps_table(page, d.steps, d.cv_rmse_before_K, "K");
  for (const auto& skipped : d.skipped) page.paragraph("Not tried: " + skipped);
  lack_of_fit_paragraph(page, d.baseline.lack_of_fit, d.final.lack_of_fit, "K");
  if (!d.accepted.empty()) shift_table(page, d.shifts, "published model");
  // Before and after on one scale.
  double lo = 0, hi = 0;
  for (const auto* fit : {&d.baseline_fit, &d.final_fit})
    for (const auto& s : fit->samples) lo = std::min(lo, s.measured_C - s.simulated_C), hi = std::max(hi, s.measured_C - s.simulated_C);
  const auto& runs = c.thermal_data->runs;
  page.figures({residual_time_plot("thermal-diagnosis-before", "Residuals, published model", d.baseline_fit, runs, {{lo, hi}}),
                residual_time_plot("thermal-diagnosis-after", "Residuals, with the causes", d.final_fit, runs, {{lo, hi}})});
  empirical_section(page, d.empirical, "thermal", "K");
}

}  // namespace

void thermal_section(Page& page, const Calibration& c) {
  const ThermalFitResult& f = *c.thermal;
  const auto& runs = c.thermal_data->runs;
  page.heading(2, "Thermal: " + published_label(rejects(c.thermal_diagnosis)), "thermal");
  const ParameterEstimate& alpha = f.joint.parameter("alpha");
  page.paragraph(fmt::format("{} runs; the rail model (Eq. 11, {} source) driven by each run's measured ambient, heat Q_f "
                             "from {}. Heat partition α = {} {} (joint fit); largest error {} % of the sensor's span (its highest minus lowest 10-record mean).",
                             runs.size(), to_string(c.thermal_options.source),
                             c.thermal_options.friction ? "the fitted friction law" : "the measured mean friction",
                             num(alpha.value), interval(alpha), num(f.max_error_percent, 3)));
  if (std::isfinite(f.alpha_ratio_paper_over_averaged))
    page.paragraph(fmt::format("With the {} source α is {}; α_paper / α_averaged = {} (the contact over the stroke, "
                               "Lb1/L1, is {}).",
                               f.other_source, num(f.other_source_alpha), num(f.alpha_ratio_paper_over_averaged),
                               num(f.contact_over_stroke)));

  page.heading(3, "Parameters of the published model");
  parameter_tables(page, f.joint, [](const ParameterEstimate& p) { return !nuisance(p); });
  std::vector<std::vector<std::string>> rows;
  for (const auto& p : f.joint.parameters)
    if (nuisance(p)) rows.push_back({p.name, p.unit, num(p.value, 5), num(p.se, 3), interval(p), flags(p)});
  if (!rows.empty()) {
    page << "<details><summary>Per-run nuisance parameters (thermocouple offsets, start temperatures, heat scales)</summary>\n";
    page.table({"parameter", "unit", "estimate", "standard error", "95 % interval", ""}, rows);
    page << "</details>\n";
  }

  page.heading(3, "Error against α (Fig. 11)");
  Plot curve{.id = "thermal-alpha-curve", .title = "RMSE at the first sensor against α", .x_label = "α",
             .y_label = "RMSE (K)"};
  for (std::size_t r = 0; r < runs.size(); ++r) {
    Series s{.label = runs[r].id, .color = colour(r)};
    for (const auto& p : f.alpha_curve)
      if (p.run == runs[r].id) s.x.push_back(p.alpha), s.y.push_back(p.rmse_K);
    curve.series.push_back(std::move(s));
  }
  curve.references.push_back({.horizontal = false, .at = alpha.value, .label = "fitted"});
  page.figures({curve});

  page.heading(3, "Temperature over time (Figs. 14-15) and along the rail (Fig. 16)");
  for (std::size_t r = 0; r < runs.size(); ++r) page.figures({time_plot(c, r), position_plot(c, r)});

  page.heading(3, "Residuals");
  std::vector<Plot> plots{residual_time_plot("thermal-residual-time", "Residuals over time", f, runs)};
  for (auto& p : covariate_plots(c)) plots.push_back(std::move(p));
  page.figures(plots);

  spread_section(page, c);
  if (c.thermal_diagnosis) diagnosis_section(page, c);
}

}  // namespace lmcal::report
