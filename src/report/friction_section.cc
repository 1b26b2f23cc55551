// The friction half of the report: Fig. 6-style force over velocity, the constants, the
// residuals against every covariate, the spread across runs and the diagnosis.
#include <fmt/format.h>

#include <map>
#include <tuple>

#include "lmcal/models/friction_effects.hpp"
#include "lmcal/fit/statistics.hpp"
#include "sections.hpp"

namespace lmcal::report {

namespace {

// The four things a Fig. 6 panel varies or holds; temperature rounded to 1 K.
struct Key {
  std::uint32_t guide;
  double preload_um, load_N, temperature_C;
  bool operator==(const Key&) const = default;
};

Key key_of(const FrictionLog& log, std::size_t i) {
  return {log.guide[i], log.preload_um[i], log.load_N[i], std::round(log.temperature_C[i])};
}

// The most frequent value of each of the four (the conditions a panel holds fixed).
Key reference_key(const FrictionLog& log) {
  std::map<std::uint32_t, std::size_t> guides;
  std::map<double, std::size_t> preloads, loads, temperatures;
  for (std::size_t i = 0; i < log.size(); ++i) {
    const Key k = key_of(log, i);
    ++guides[k.guide], ++preloads[k.preload_um], ++loads[k.load_N], ++temperatures[k.temperature_C];
  }
  auto mode = [](const auto& counts) {
    return std::max_element(counts.begin(), counts.end(), [](auto& a, auto& b) { return a.second < b.second; })->first;
  };
  return {mode(guides), mode(preloads), mode(loads), mode(temperatures)};
}

// The law (with effects), averaged over both directions, along a velocity grid at the
// conditions of sample `i` (its temperature replaced by the group's mean).
std::vector<double> law_over_velocity(const FrictionLog& log, std::size_t i, double temperature_C,
                                      FrictionConstants<double> k, const FrictionEffects<double>& e,
                                      const std::vector<double>& grid) {
  k.nu_ref_mm2_s = log.viscosity40_mm2_s[i];
  FrictionConditions<double> c = log.conditions(i);
  c.temperature_C = temperature_C;
  std::vector<double> force;
  for (double v : grid) {
    c.velocity_m_s = v;
    c.direction = 1;
    const double forward = friction_force_with_effects_N(k, e, c);
    c.direction = -1;
    force.push_back(0.5 * (forward + friction_force_with_effects_N(k, e, c)));
  }
  return force;
}

// What a Fig. 6 panel varies; the other conditions are held at their most frequent value.
struct Varied {
  const char* name;
  const char* unit;
  double Key::*member;
};
constexpr Varied kVaried[] = {{"load", "N", &Key::load_N},
                              {"preload", "um", &Key::preload_um},
                              {"temperature", "°C", &Key::temperature_C}};

// Whether the log gave the quantity (a combination law's log holds neutral stand-ins for the rest).
bool given(const FrictionLawConditions& law, const Varied& v) {
  return v.member == &Key::load_N ? law.load : v.member == &Key::preload_um ? law.preload : law.temperature;
}

// The held conditions the log gave, in words: "1.5 um, 26 °C".
std::string held_conditions(const Key& ref, const Varied& varied, const FrictionLawConditions& law) {
  std::string text;
  for (const Varied& v : kVaried)
    if (v.member != varied.member && given(law, v))
      text += fmt::format("{}{} {}", text.empty() ? "" : ", ", num(ref.*v.member), v.unit);
  return text;
}

// Fig. 6: measured force (means over runs and directions) and the fitted law over velocity,
// one series per value of the varied quantity.
Plot velocity_panel(const Calibration& c, const Varied& varied) {
  const FrictionLog& log = *c.friction_log;
  const Key ref = reference_key(log);
  // value -> velocity -> (sum, n); value -> (a sample, temperature sum, n); value -> the sum of
  // each fit's zero offset of the samples' runs (published, with causes): a curve carries the
  // mean offset of the points it is drawn through, or it sits off them by the runs' zero.
  std::map<double, std::map<double, std::pair<double, std::size_t>>> measured;
  std::map<double, std::tuple<std::size_t, double, std::size_t>> groups;
  std::map<double, std::pair<double, double>> offsets;
  const bool extended = c.friction_diagnosis && !c.friction_diagnosis->accepted.empty();
  auto run_offset = [&](const FrictionFitResult& fit, std::size_t i) {
    return log.run[i] < fit.run_offset_N.size() ? fit.run_offset_N[log.run[i]] : 0.0;
  };
  double v_max = 0;
  for (std::size_t i = 0; i < log.size(); ++i) {
    const Key k = key_of(log, i);
    Key held = ref;
    held.*varied.member = k.*varied.member;
    if (!(k == held)) continue;
    const double value = k.*varied.member;
    auto& m = measured[value][log.velocity_m_s[i]];
    m.first += log.friction_N[i], ++m.second;
    auto& g = groups.try_emplace(value, i, 0.0, 0).first->second;
    std::get<1>(g) += log.temperature_C[i], ++std::get<2>(g);
    auto& o = offsets[value];
    o.first += run_offset(*c.friction, i);
    if (extended) o.second += run_offset(c.friction_diagnosis->final_fit, i);
    v_max = std::max(v_max, log.velocity_m_s[i]);
  }
  std::vector<double> grid;
  for (int j = 0; j <= 60; ++j) grid.push_back(v_max * j / 60.0);
  const std::string guide = log.guide_names.empty() || log.guide_names[ref.guide].empty() ? "" : log.guide_names[ref.guide];
  const std::string held = held_conditions(ref, varied, log.law);
  const std::string setup = guide.empty() || held.empty() ? guide + held : guide + ", " + held;
  const bool varies = given(log.law, varied);  // else the one panel of a log that gave none of them
  Plot plot{.id = std::string("friction-by-") + varied.name,
            .title = fmt::format("Friction vs velocity{}{}", varies ? fmt::format(" by {}", varied.name) : "",
                                 setup.empty() ? "" : " (" + setup + ")"),
            .x_label = "velocity (m/s)",
            .y_label = "friction force (N)"};
  // Every velocity's mean where that is cheap; a drive's trajectory log (a velocity per sample)
  // thinned evenly along the velocity within each value, said in the legend.
  std::size_t velocities = 0;
  for (const auto& [value, by_velocity] : measured) velocities += by_velocity.size();
  const std::size_t every = stride(velocities, kMostPoints);
  std::size_t index = 0;
  for (const auto& [value, by_velocity] : measured) {
    const std::string name = varies ? fmt::format("{} {}", num(value), varied.unit) : "measured";
    Series points{.label = name, .tooltip = name, .mark = Mark::points, .color = colour(index)};
    std::size_t seen = 0;
    for (const auto& [v, sum] : by_velocity) {
      if (seen++ % every != 0) continue;
      points.x.push_back(v);
      points.y.push_back(sum.first / static_cast<double>(sum.second));
    }
    if (points.x.size() < by_velocity.size()) points.label += fmt::format(" {}", shown_of(points.x.size(), by_velocity.size()));
    const auto& [sample, temperature_sum, n] = groups.at(value);
    const double temperature_C = temperature_sum / static_cast<double>(n);
    FrictionConstants<double> k = c.friction->constants();
    k.T_ref_C = c.friction_options.start.T_ref_C;
    const auto shifted = [](std::vector<double> y, double by) {
      for (double& v : y) v += by;
      return y;
    };
    const auto& [published_offset, extended_offset] = offsets.at(value);
    plot.series.push_back(std::move(points));
    plot.series.push_back({.tooltip = "published law, " + name,
                           .x = grid,
                           .y = shifted(law_over_velocity(log, sample, temperature_C, k, c.friction->effects(), grid),
                                        published_offset / static_cast<double>(n)),
                           .color = colour(index)});
    if (extended) {
      const auto& fit = c.friction_diagnosis->final_fit;
      FrictionConstants<double> ke = fit.constants();
      ke.T_ref_C = k.T_ref_C;
      plot.series.push_back({.tooltip = "law + causes, " + name,
                             .x = grid,
                             .y = shifted(law_over_velocity(log, sample, temperature_C, ke, fit.effects(), grid),
                                          extended_offset / static_cast<double>(n)),
                             .color = colour(index),
                             .dashed = true});
    }
    ++index;
  }
  // The curves' legend in a neutral colour: each curve is drawn in its points' colour.
  plot.series.push_back({.label = "published law (line)", .color = "#444444", .legend_only = true});
  if (extended) plot.series.push_back({.label = "law + causes (dashed)", .color = "#444444", .dashed = true, .legend_only = true});
  return plot;
}

}  // namespace

std::vector<Plot> friction_velocity_panels(const Calibration& c) {
  std::vector<Plot> panels;
  for (const Varied& varied : kVaried)
    if (given(c.friction_log->law, varied)) panels.push_back(velocity_panel(c, varied));
  if (panels.empty()) panels.push_back(velocity_panel(c, kVaried[0]));  // speed and force only: one panel
  return panels;
}

namespace {

// Mean residual of each condition against one covariate.
Plot condition_residuals(const std::string& id, const std::string& title, const std::string& x_label,
                         const std::vector<std::pair<std::string, const std::vector<ConditionResidual>*>>& fits,
                         double ConditionResidual::*x) {
  Plot plot{.id = id, .title = title, .x_label = x_label, .y_label = "mean residual (N)"};
  plot.references.push_back({});
  for (std::size_t f = 0; f < fits.size(); ++f) {
    const auto& conditions = *fits[f].second;
    // The conditions (thinned to a readable cloud), and the mean of each level of the covariate
    // with its 95 % interval: what the eye cannot read from thousands of overlapping points.
    const std::string prefix = fits[f].first.empty() ? "" : fits[f].first + ": ";
    Series s{.tooltip = prefix + "condition", .mark = Mark::points, .color = colour(f)};
    const std::size_t every = stride(conditions.size(), kMostPoints);
    std::map<double, std::vector<double>> levels;
    // Thinned within each stratum (the plotted level and the direction), so that every level in
    // both senses keeps its share: the conditions alternate direction, and a plain every-4th
    // kept one sense only.
    std::map<std::pair<double, double>, std::size_t> seen;
    for (const ConditionResidual& r : conditions) {
      const double level = std::stod(fmt::format("{:.3g}", r.*x));
      levels[level].push_back(r.bias_N);
      if (seen[{level, r.direction}]++ % every != 0) continue;
      s.x.push_back(r.*x);
      s.y.push_back(r.bias_N);
    }
    s.label = prefix + "each condition";
    if (s.x.size() < conditions.size()) s.label += fmt::format(" {}", shown_of(s.x.size(), conditions.size()));
    plot.series.push_back(std::move(s));
    if (levels.size() > 30) continue;  // a covariate that barely repeats: no levels to average
    Series means{.label = prefix + "mean per level (95 %)", .tooltip = prefix + "level mean ± 95 %", .mark = Mark::line_points,
                 .color = colour(f + 4)};
    for (const auto& [level, values] : levels) {
      const Spread sp = spread(values);
      means.x.push_back(level);
      means.y.push_back(sp.mean);
      means.y_error.push_back(sp.n >= 2 ? sp.half_width : 0.0);
    }
    plot.series.push_back(std::move(means));
  }
  return plot;
}

struct Covariate {
  const char* name;  // as the diagnosis names it
  const char* label;
  double ConditionResidual::*member;
};
constexpr Covariate kCovariates[] = {{"velocity_m_s", "velocity (m/s)", &ConditionResidual::velocity_m_s},
                                     {"load_N", "load (N)", &ConditionResidual::load_N},
                                     {"preload_um", "preload (um)", &ConditionResidual::preload_um},
                                     {"temperature_C", "temperature (°C)", &ConditionResidual::temperature_C},
                                     {"direction", "direction (+1 forward, -1 backward)", &ConditionResidual::direction}};

// Whether the log gave the covariate (a combination law's log holds neutral stand-ins).
bool given(const FrictionLawConditions& law, const Covariate& cov) {
  const std::string_view name = cov.name;
  return name == "load_N" ? law.load : name == "preload_um" ? law.preload : name == "temperature_C" ? law.temperature : true;
}

void spread_section(Page& page, const FrictionFitResult& f) {
  if (f.spread.empty()) return;
  page.heading(3, "Spread across runs of the published law");
  page.paragraph(
      "Each run fitted alone. The spread of repeats (Eq. 1 σ) is the runs' standard deviation; the interval is the "
      "Student-t 95 % interval of their mean. The ratio σ_runs / (SE_pooled √runs) is about 1 when the runs differ by "
      "noise only. p: the pooled fit's test of heterogeneity between runs (each run's score against the within-run "
      "covariance, χ²(runs − 1)), Holm-adjusted across the constants; below 0.05 the runs differ beyond what the model "
      "explains.");
  std::vector<std::vector<std::string>> rows;
  const FitResult shown = friction_fit_as_shown(f);  // the spread's names: a combination law's combinations
  for (const auto& sp : f.spread) {
    const auto& pooled = shown.parameter(sp.parameter);
    // Why runs gave no value (friction_fit.cc says it once, for the summary too).
    const std::string note = sp.undetermined.empty() ? ""
                             : sp.spread.n < 2       ? "no spread: not determined run by run (" + sp.undetermined + ")"
                                                     : "without " + sp.undetermined;
    rows.push_back({sp.parameter, num(pooled.value), num(pooled.se, 3), num(sp.spread.mean), num(sp.spread.sd, 3),
                    bracket(sp.spread.low, sp.spread.high), num(sp.spread.min), num(sp.spread.max), num(sp.ratio, 3),
                    p_value(sp.p_holm), sp.wider_than_pooled ? "the runs differ beyond the model" + (note.empty() ? "" : "; " + note) : note});
  }
  page.table({"parameter", "pooled", "SE", "run mean", "spread of repeats (Eq. 1 σ)", "95 % interval of the mean", "min",
              "max", "ratio", "p (Holm)", "note"},
             rows);
  friction_run_figures(page, f, "friction-spread-");
}

void diagnosis_section(Page& page, const Calibration& c) {
  const FrictionDiagnosis& d = *c.friction_diagnosis;
  page.heading(3, "What the published law gets wrong");
  verdict_paragraph(page, d.verdict, d.summary);
  page.paragraph(fmt::format("Held-out (leave-one-run-out) RMSE: {} N before, {} N after: a gain of {}.",
                             num(d.cv_rmse_before_N), num(d.cv_rmse_after_N), percent(d.cv_gain_percent, 1)));
  lack_of_fit_paragraph(page, d.baseline.lack_of_fit, d.final.lack_of_fit, "N", d.design_notes);
  candidate_tables(page, d.rounds, "N");
  steps_table(page, d.steps, d.cv_rmse_before_N, "N");
  if (!d.accepted.empty()) shift_table(page, d.shifts, "the law alone");
  // Before/after against velocity and against the covariate the baseline residuals follow most.
  std::vector<std::string> shown{"velocity_m_s"};
  if (!d.baseline.covariates.empty() && d.baseline.covariates.front().covariate != shown.front())
    shown.push_back(d.baseline.covariates.front().covariate);
  std::vector<Plot> plots;
  for (const auto& name : shown)
    for (const auto& cov : kCovariates)
      if (name == cov.name && given(c.friction_log->law, cov))
        plots.push_back(condition_residuals(plot_id(std::string("friction-diagnosis-") + cov.name),
                                            std::string("Residuals before and after, against ") + cov.label, cov.label,
                                            {{"the law", &d.baseline_fit.conditions}, {"law + causes", &d.final_fit.conditions}},
                                            cov.member));
  page.figures(plots);
  empirical_section(page, d.empirical, "friction", "N");
}

// "c1 = 0.1012 N/(m/s)" and its quoted interval.
std::pair<std::string, std::string> estimate_cells(const ParameterEstimate& p) {
  const bool unit = !p.unit.empty() && p.unit != "1";
  return {fmt::format("{} = {}{}", p.name, num(p.value), unit ? " " + p.unit : ""), interval(p)};
}

// The residual bin means before and after the term, and the term's mean contribution with its band.
Plot empirical_plot(const EmpiricalCurve& curve, const std::string& id, const std::string& unit) {
  const std::string x_label = curve.unit.empty() || curve.unit == "1" ? curve.covariate
                                                                      : fmt::format("{} ({})", curve.covariate, curve.unit);
  Plot plot{.id = id,
            .title = "The empirical term against " + curve.covariate,
            .x_label = x_label,
            .y_label = fmt::format("mean residual, term ({})", unit)};
  plot.references.push_back({});
  plot.series.push_back({.label = "residual without the term", .x = curve.x, .y = curve.residual_before, .mark = Mark::points, .color = colour(0)});
  plot.series.push_back({.label = "residual with it", .x = curve.x, .y = curve.residual_after, .mark = Mark::points, .color = colour(1)});
  plot.series.push_back({.label = "term (95 % band)", .x = curve.x, .y = curve.value, .color = colour(2),
                         .band_low = curve.low, .band_high = curve.high});
  return plot;
}

}  // namespace

void friction_section(Page& page, const Calibration& c) {
  const FrictionFitResult& f = *c.friction;
  const FrictionLog& log = *c.friction_log;
  page.heading(2, "Friction: " + published_label(rejects(c.friction_diagnosis)), "friction");
  const std::size_t files = std::max<std::size_t>(c.set.friction_logs.size(), c.set.friction_manifest ? 1 : 0);
  page.paragraph(fmt::format("{} samples in {} from {}. The published law (Eqs. 3-7) fitted by weighted least squares; "
                             "residual RMSE {} N, largest error {} % of the measured force's range (its 1st to 99th percentile).",
                             log.size(), plural(f.runs.size(), "run"), plural(files, "file"), num(f.rmse_N),
                             num(100 * f.max_relative_error, 3)));
  page.figures(friction_velocity_panels(c));

  if (f.law.combination()) {
    page.heading(3, "The law's combinations");
    page.paragraph(fmt::format("The log gives no {}: the paper's constants cannot be separated, and the law is fitted in the "
                               "combinations the data determine, {}.",
                               fmt::join(f.law.not_logged(), ", "),
                               f.law.temperature ? fmt::format("at the mean logged temperature, {} °C", num(f.law_temperature_C))
                                                 : std::string("with the oil's viscosity at 40 °C (ν40: no temperature logged)")));
  } else {
    page.heading(3, "Constants of the published law");
  }
  parameter_tables(page, friction_fit_as_shown(f), [](const ParameterEstimate& p) { return p.listed; });

  page.heading(3, "Residuals against the covariates");
  page.paragraph("Mean residual (measured - fitted) of each condition; structure here is what the law misses.");
  std::vector<Plot> plots;
  for (const auto& cov : kCovariates)
    if (given(log.law, cov))
      plots.push_back(condition_residuals(plot_id(std::string("friction-residual-") + cov.name), std::string("Residuals vs ") + cov.label,
                                          cov.label, {{"", &f.conditions}}, cov.member));
  Plot runs{.id = "friction-residual-run", .title = "Mean residual of each run", .x_label = "run", .y_label = "mean residual (N)"};
  runs.references.push_back({});
  Series s{.mark = Mark::points};
  for (std::size_t r = 0; r < f.run_offset_N.size(); ++r) {
    s.x.push_back(static_cast<double>(r + 1));
    s.y.push_back(f.run_offset_N[r]);
  }
  runs.series.push_back(std::move(s));
  plots.push_back(std::move(runs));
  page.figures(plots);

  spread_section(page, f);
  if (c.friction_diagnosis) diagnosis_section(page, c);
}

void candidate_tables(Page& page, const std::vector<std::vector<CandidateScore>>& rounds, const char* unit) {
  const bool alpha = std::isfinite(candidate_alpha_range(rounds).first);
  for (std::size_t r = 0; r < rounds.size(); ++r) {
    std::vector<std::vector<std::string>> rows;
    for (const auto& cand : rounds[r]) {
      const bool shape = std::isfinite(cand.cv_shape_gain_percent);
      rows.push_back({shown_name(cand), num(cand.value) + (cand.unit.empty() || cand.unit == "1" ? "" : " " + cand.unit),
                      bracket(cand.ci_low, cand.ci_high) + (cand.interval == "linear" ? "" : " (" + cand.interval + ")"),
                      p_value(cand.lrt_p), num(cand.cv_rmse), percent(cand.cv_gain_percent, 2, true),
                      shape ? num(cand.cv_shape_rmse) + " (" + percent(cand.cv_shape_gain_percent, 2, true) + ")" : "–",
                      (cand.accepted ? "accepted: " : "") + cand.reason});
      if (alpha) rows.back().insert(rows.back().begin() + 3, num(cand.alpha) + " " + bracket(cand.alpha_low, cand.alpha_high));
    }
    page.paragraph(fmt::format("Candidates, step {} (held-out RMSE in {}, gain against the model so far):", r + 1, unit));
    std::vector<std::string> header{"cause", "estimate", "95 % interval", "LRT p", "held-out RMSE", "gain",
                                    "held-out RMSE of the runs' shape", "decision"};
    if (alpha) header.insert(header.begin() + 3, "α of that model");
    page.table(header, rows);
  }
}

void steps_table(Page& page, const std::vector<DiagnosisStep>& steps, double baseline, const char* unit) {
  if (steps.empty()) return;
  page.paragraph(fmt::format("From the baseline (held-out RMSE {} {}) to the final model, step by step: each step's "
                             "before is the step's before it, and the last step's after is the final value.",
                             num(baseline), unit));
  std::vector<std::vector<std::string>> rows;
  for (const auto& s : steps)
    rows.push_back({s.action, s.name, num(s.cv_rmse_before), num(s.cv_rmse_after),
                    std::isfinite(s.cv_shape_rmse_before) ? num(s.cv_shape_rmse_before) + " → " + num(s.cv_shape_rmse_after) : "–",
                    fmt::format("{} ({})", percent(s.gain_percent, 1, true), s.criterion == "shape" ? "runs' shape" : "held-out RMSE")});
  page.table({"step", "what", std::string("held-out RMSE before (") + unit + ")", std::string("after (") + unit + ")",
              std::string("of the runs' shape (") + unit + ")", "gain (counted on)"},
             rows);
}

void lack_of_fit_paragraph(Page& page, const LackOfFit& baseline, const LackOfFit& final, const std::string& unit,
                           const std::vector<std::string>& design_notes) {
  auto words = [&](const LackOfFit& l) {
    return fmt::format("F = {} on ({:.0f}, {:.0f}) dof, p = {}: {}", num(l.statistic, 3), l.df1, l.df2, p_value(l.p_value),
                       l.fits ? "within the noise" : fmt::format("structure remains, {} {} beyond it", num(l.lack_rms, 3), unit));
  };
  if (baseline.tested)
    page.paragraph(fmt::format("Lack of fit against {} (noise {} {}): the published model {}; with the causes {}.",
                               baseline.basis, num(baseline.pure_error_rms, 3), unit, words(baseline),
                               final.tested ? words(final) : "not tested"));
  else
    page.paragraph("Lack of fit not tested: " + baseline.basis + ".");
  for (const auto& note : design_notes) page.paragraph("Design: " + note + ".");
}

void shift_table(Page& page, const std::vector<ParameterShift>& shifts, const std::string& published) {
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> held;
  for (const auto& s : shifts) {
    if (!s.free) {
      held.push_back(s.name);
      continue;
    }
    rows.push_back({s.name, num(s.baseline), bracket(s.baseline_low, s.baseline_high), num(s.extended),
                    bracket(s.extended_low, s.extended_high)});
  }
  std::string held_note;
  for (const auto& h : held) held_note += (held_note.empty() ? "" : ", ") + h;
  page.paragraph("The parameters that move once the causes are modelled (95 % intervals as quoted: linear or profile)" +
                 (held_note.empty() ? std::string(":")
                                    : "; held in one of the two models, so not compared: " + held_note + ":"));
  page.table({"parameter", published, "95 % interval", "with the causes", "95 % interval"}, rows);
}

void empirical_section(Page& page, const EmpiricalFinding& e, const std::string& id_prefix, const std::string& unit) {
  if (!e.searched) return;
  if (!e.found) {
    page.paragraph(fmt::format("Beyond the library: no empirical term was kept ({} candidate terms of the covariates "
                               "searched): {}.",
                               e.dictionary_size, e.reason));
    return;
  }
  page << "<div class=\"empirical\">\n";
  page.heading(4, "Beyond the library: an empirical term", plot_id(id_prefix + "-empirical"));
  page.paragraph(fmt::format("Learned from the residuals; not a named cause. The library's named causes leave "
                             "structure, so a search over {} candidate terms of the covariates ({}) chose a term, fitted "
                             "jointly with the model and added to {}:",
                             e.dictionary_size,
                             e.form == "smooth" ? "no sparse form won; a smooth term, cubic B-splines in one covariate"
                                                : "a sparse regression, SINDy-style, by leave-one-run-out error",
                             e.where));
  page << "<p class=\"formula\"><code>" << escape_xml(e.formula) << "</code></p>\n";
  std::vector<std::vector<std::string>> rows;
  for (const auto& component : e.components) {
    std::string covariates;
    for (const auto& name : component.covariates) covariates += (covariates.empty() ? "" : ", ") + name;
    const auto [coefficient, coefficient_interval] = estimate_cells(component.coefficient);
    const auto [scale, scale_interval] =
        component.has_scale ? estimate_cells(component.scale) : std::pair<std::string, std::string>{"–", "–"};
    rows.push_back({component.symbol, component.words, covariates, coefficient, coefficient_interval, scale, scale_interval});
  }
  page.table({"term", "what it does", "covariates", "coefficient", "95 % interval", "scale", "95 % interval"}, rows);
  page.paragraph(fmt::format("H{}: RMSE {} {} before the term, {} {} with it: a gain of {} "
                             "(LRT p = {}, ΔBIC = {}). Kept: {}.",
                             held_out_criterion_words(e.criterion).substr(1), num(e.cv_rmse_before), unit,
                             num(e.cv_rmse_after), unit, percent(e.cv_gain_percent, 1), p_value(e.lrt_p),
                             num(e.delta_bic, 3), e.reason));
  page.paragraph(e.resembles.empty() ? "It resembles no mechanism we know of."
                                     : "It resembles " + e.resembles + ". A resemblance, not a diagnosis: to name the "
                                       "cause, log what it would change.");
  std::string ranges;
  for (const auto& r : e.ranges)
    ranges += fmt::format("{}{} from {} to {}", ranges.empty() ? "" : "; ", r.covariate, num(r.min), num(r.max));
  if (!ranges.empty())
    page.paragraph("Learned on " + ranges + ". Beyond these ranges the term is an extrapolation.", "warning");
  if (!e.curve.x.empty()) {
    page.paragraph(fmt::format("Means over bins of {}: the residuals without the term (the jointly fitted model's "
                               "residuals with the term added back: the structure it learned) and with it, and the term's "
                               "mean contribution with its 95 % band (delta method, from the joint fit's covariance of its "
                               "parameters).",
                               e.curve.covariate));
    page.figures({empirical_plot(e.curve, plot_id(id_prefix + "-empirical-term"), unit)});
  }
  page << "</div>\n";
}

void friction_run_figures(Page& page, const FrictionFitResult& f, const std::string& id_prefix) {
  std::vector<Plot> plots;
  std::string runs;
  for (std::size_t r = 0; r < f.runs.size(); ++r) runs += fmt::format("{}{} {}", r ? ", " : "", r + 1, f.runs[r]);
  const FitResult shown = friction_fit_as_shown(f);  // the spread's names: a combination law's combinations
  for (const auto& sp : f.spread) {
    if (std::none_of(sp.per_run.begin(), sp.per_run.end(), [](double v) { return std::isfinite(v); })) continue;
    Plot plot = per_run_plot(plot_id(id_prefix + sp.parameter), sp.parameter + " per run", shown.parameter(sp.parameter),
                             {.value = sp.per_run, .half_width_95 = sp.per_run_half_width_95, .names = f.runs}, "");
    plot.width_px = 300, plot.height_px = 220;
    plots.push_back(std::move(plot));
  }
  if (plots.empty()) return;
  page.paragraph(fmt::format("Points: each run fitted alone, with its own 95 % interval (runs {}); solid line: the pooled estimate; dashed lines: its "
                             "quoted 95 % interval. A run alone is about √runs times less certain than the pooled fit, so "
                             "its points scatter beyond that interval without disagreeing (the ratio σ_runs / (SE √runs) and "
                             "the between-run test say whether they do).",
                             runs));
  page.figures(plots);
}

}  // namespace lmcal::report
