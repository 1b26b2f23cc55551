// prediction.html: the calibrated model over a duty, its plots and moments (predict_pages.hpp).

#include <fmt/format.h>

#include <algorithm>
#include <set>

#include "lmcal/report/predict_pages.hpp"
#include "report/sections.hpp"

namespace lmcal {

namespace {

using report::Page;
using report::Plot;
using report::Series;

// The most output times a plot draws.
constexpr std::size_t kMostTimes = 400;

// The output times drawn: every n-th, every segment's end and the largest elongation.
std::vector<std::size_t> drawn_times(const Prediction& p, const PredictionSummary& s) {
  std::set<std::size_t> kept;
  const std::size_t every = report::stride(p.time_s.size(), kMostTimes);
  for (std::size_t t = 0; t < p.time_s.size(); t += every) kept.insert(t);
  for (const auto& m : s.segment_ends) kept.insert(m.index);
  kept.insert(s.largest.index);
  return {kept.begin(), kept.end()};
}

// A band over the drawn times, time in hours.
Series band_series(const std::string& label, const Band& b, const std::vector<double>& time_s, const std::vector<std::size_t>& at) {
  Series s{.label = label};
  for (std::size_t t : at) {
    s.x.push_back(time_s[t] / 3600);
    s.y.push_back(b.value[t]);
    s.band_low.push_back(b.low[t]);
    s.band_high.push_back(b.high[t]);
  }
  return s;
}

std::string band_text(const BandAt& b) { return fmt::format("{} {}", report::num(b.value), report::bracket(b.low, b.high)); }

std::vector<Plot> plots(const Prediction& p, const PredictionSummary& s) {
  const std::vector<std::size_t> at = drawn_times(p, s);
  const std::string thinned = at.size() < p.time_s.size() ? fmt::format(" {}", report::shown_of(at.size(), p.time_s.size())) : "";
  const auto time_plot = [&](std::string id, std::string title, std::string y_label) {
    Plot plot{.id = std::move(id), .title = std::move(title), .x_label = "time (h)", .y_label = std::move(y_label)};
    plot.width_px = 620;
    for (std::size_t k = 0; k + 1 < s.segment_ends.size() && k < 24; ++k)
      plot.references.push_back({.horizontal = false, .at = s.segment_ends[k].time_s / 3600});
    return plot;
  };
  std::vector<Plot> out;
  Plot elongation = time_plot("prediction-elongation", "Rail elongation over the duty (dashed: segment ends)", "elongation (µm)");
  elongation.series.push_back(band_series("model (95 % band)" + thinned, p.elongation_um, p.time_s, at));
  elongation.series.push_back({.label = "largest", .x = {s.largest.time_s / 3600}, .y = {s.largest.elongation_um.value},
                               .y_error = {}, .mark = report::Mark::points, .color = "#000000"});
  out.push_back(elongation);
  Plot temperature = time_plot("prediction-temperature", "Rail temperature", "temperature (°C)");
  for (std::size_t q = 0; q < p.positions_m.size(); ++q)
    temperature.series.push_back(
        band_series(fmt::format("x = {} m (95 % band){}", report::num(p.positions_m[q]), thinned), p.temperature_C[q], p.time_s, at));
  if (!temperature.series.empty()) out.push_back(temperature);
  Plot scale = time_plot("prediction-scale-error", "Linear scale's positioning error", "error (µm)");
  for (std::size_t q = 0; q < p.scale_positions_m.size(); ++q)
    scale.series.push_back(band_series(fmt::format("x = {} m (95 % band){}", report::num(p.scale_positions_m[q]), thinned),
                                       p.scale_error_um[q], p.time_s, at));
  if (!scale.series.empty()) out.push_back(scale);
  Plot heat = time_plot("prediction-heat", "Heat the block puts into the rail", "heat rate (W)");
  heat.series.push_back(band_series("model (95 % band)" + thinned, p.heat_rate_W, p.time_s, at));
  out.push_back(heat);
  return out;
}

// The moments table: the largest elongation, then every segment's end.
void moments(Page& page, const Prediction& p, const PredictionSummary& s) {
  std::vector<std::string> header = {"moment", "segment", "time (h)", "elongation (µm)"};
  for (double x : p.positions_m) header.push_back(fmt::format("rail at x = {} m (°C)", report::num(x)));
  for (double x : p.scale_positions_m) header.push_back(fmt::format("scale error at x = {} m (µm)", report::num(x)));
  std::vector<std::vector<report::Cell>> rows;
  const auto row = [&](const std::string& what, const PredictionMoment& m) {
    std::vector<report::Cell> r = {what, m.segment, {report::num(m.time_s / 3600), true, ""}, {band_text(m.elongation_um), true, ""}};
    for (const auto& b : m.temperature_C) r.push_back({band_text(b), true, ""});
    for (const auto& b : m.scale_error_um) r.push_back({band_text(b), true, ""});
    rows.push_back(std::move(r));
  };
  row("largest elongation", s.largest);
  for (const auto& m : s.segment_ends) row("segment end", m);
  page.table(header, rows);
}

}  // namespace

std::string prediction_html(const Prediction& p, const DutyCycle& duty, const std::vector<std::string>& command) {
  const PredictionSummary s = summarize(p);
  Page page;
  page.heading(1, "lmcal prediction: " + duty.guide.model + (duty.file.empty() ? "" : ", " + duty.file));
  page.paragraph(fmt::format("The calibrated model over {} segments, {} h, rail {} m. Bands: 95 %, pointwise in time, from {} "
                             "parameter draws: {}",
                             duty.segments.size(), report::num(duty.duration_s() / 3600), report::num(duty.rail_length_m),
                             p.samples, p.method));
  page.paragraph(fmt::format("Largest rail elongation: {} µm at {} h ({}). At the end: {} µm.", band_text(s.largest.elongation_um),
                             report::num(s.largest.time_s / 3600), s.largest.segment, band_text(s.end.elongation_um)),
                 "brief");
  for (const auto& f : p.outside)
    page.paragraph(fmt::format("Outside the calibrated range: {} {} = {} (the {} calibration saw {} to {}): an extrapolation.",
                               f.segment, f.quantity, report::num(f.value), f.what, report::num(f.low), report::num(f.high)),
                   "warning");
  page.figures(plots(p, s));
  page.heading(2, "At the largest elongation and at the end of each segment", "moments");
  moments(page, p, s);
  for (const auto& note : p.notes) page.paragraph("Note: " + note);
  std::string line;
  for (const auto& part : command) line += (line.empty() ? "" : " ") + part;
  page.paragraph("Every output time is in prediction_time.csv; these numbers are prediction.json's. Command: " + line);
  return report::html_document("lmcal prediction", page);
}

}  // namespace lmcal
