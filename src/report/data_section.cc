// The report's "Data loaded" section: what the loaders read, converted, skipped and
// ignored, per file; the warnings of the data checks (calibrate/data_checks.hpp); how the thermal runs
// were driven.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <map>

#include "sections.hpp"

namespace lmcal::report {

namespace {

std::string joined(const std::map<std::string, std::string>& m) {
  std::vector<std::string> parts;
  for (const auto& [k, v] : m) parts.push_back(fmt::format("{} ({})", k, v));
  return fmt::format("{}", fmt::join(parts, ", "));
}

std::string joined(const std::map<std::string, std::size_t>& m) {
  std::vector<std::string> parts;
  for (const auto& [k, v] : m) parts.push_back(fmt::format("{}: {}", k, v));
  return fmt::format("{}", fmt::join(parts, ", "));
}

std::vector<std::string> report_row(const LoadReport& r) {
  return {r.file,
          std::to_string(r.rows_read),
          std::to_string(r.rows_kept),
          joined(r.skipped),
          joined(r.conversions),
          fmt::format("{}", fmt::join(r.ignored_columns, ", ")),
          r.time_gaps ? std::to_string(r.time_gaps) : ""};
}

// Horizontal segments, one per plateau, at `level(p)`: NaN pairs break the line between them.
Series plateau_segments(const std::vector<Plateau>& plateaus, const std::function<double(const Plateau&)>& level) {
  Series s{.label = "kept plateaus", .color = "#d62728"};
  for (const Plateau& p : plateaus) {
    const double y = level(p);
    s.x.insert(s.x.end(), {p.start_s, p.end_s, std::numeric_limits<double>::quiet_NaN()});
    s.y.insert(s.y.end(), {y, y, std::numeric_limits<double>::quiet_NaN()});
  }
  return s;
}

// What segmentation kept of the raw load-cell runs, and the first run's trace with its kept
// plateaus marked.
void raw_friction_segmentation(Page& page, const FrictionLog& log) {
  if (log.segmentation.empty()) return;
  page.heading(3, "Raw load-cell runs: the constant-velocity plateaus kept");
  std::vector<std::vector<std::string>> rows;
  for (const RunSegmentation& s : log.segmentation)
    rows.push_back({s.run, s.file, std::to_string(s.samples), std::to_string(s.kept), std::to_string(s.plateaus.size()),
                    std::to_string(s.dropped_acceleration), std::to_string(s.dropped_settling),
                    std::to_string(s.dropped_stationary), std::to_string(s.dropped_short),
                    std::to_string(s.averaged_duplicates)});
  page.table({"run", "file", "samples", "kept", "plateaus", "accelerating", "settling", "at rest", "short plateaus",
              "repeated times averaged"},
             rows);
  const RawTrace& trace = log.raw_traces.front();
  const RunSegmentation& seg = log.segmentation.front();
  Plot velocity{.id = "raw-trace-velocity",
                .title = fmt::format("Run {}: velocity, plateaus kept", trace.run),
                .x_label = "time (s)",
                .y_label = "velocity (m/s)"};
  velocity.series.push_back({.label = "velocity", .x = trace.time_s, .y = trace.velocity_m_s});
  velocity.series.push_back(plateau_segments(seg.plateaus, [](const Plateau& p) { return p.velocity_m_s; }));
  Plot force{.id = "raw-trace-force",
             .title = fmt::format("Run {}: force as logged, plateau means", trace.run),
             .x_label = "time (s)",
             .y_label = "force (N)"};
  force.series.push_back({.label = "force", .x = trace.time_s, .y = trace.force_N});
  force.series.push_back(plateau_segments(seg.plateaus, [&](const Plateau& p) {
    double sum = 0;
    int n = 0;
    for (std::size_t i = 0; i < trace.time_s.size(); ++i)
      if (trace.time_s[i] >= p.start_s && trace.time_s[i] <= p.end_s) {
        sum += trace.force_N[i];
        ++n;
      }
    return n ? sum / n : std::numeric_limits<double>::quiet_NaN();
  }));
  page.figures({velocity, force});
  page.paragraph("Samples while the block accelerates (|a| above the threshold, or off the plateau's speed), for the "
                 "settling time after, at rest and in plateaus too short to trust are dropped; a kept sample's "
                 "velocity is its plateau's and its friction the force with the sign convention applied and the "
                 "inertia m·a taken off (calibration.json: options.raw_friction).");
}

// "steel bar 20x20 (a plain bar, from my_guides.toml)", "SRN 35C (guide, built-in catalog)".
std::string guide_text(const GuideSpec& spec) {
  const bool built_in = spec.source.empty() || spec.source == "<built-in>";
  return fmt::format("{} ({}, {})", spec.model, spec.kind == "bar" ? "a plain bar" : "guide",
                     built_in ? "built-in catalog" : "from " + spec.source);
}

}  // namespace

void data_section(Page& page, const Calibration& c) {
  page.heading(2, "Data loaded", "data");
  if (c.warnings.empty()) {
    page.paragraph("No warnings: nothing in the data looks like a mistake the checks know (columns that resemble known "
                   "ones, signed forces given as magnitudes, heat from the paper's constants, runs that disagree with "
                   "the others).");
  } else {
    page << "<ul class=\"warning\">\n";
    for (const auto& w : c.warnings) page << "<li>" << escape_xml(w) << "</li>\n";
    page << "</ul>\n";
  }
  for (const auto& note : c.notes) page.paragraph("Note: " + note, "warning");
  std::vector<std::vector<std::string>> rows;
  if (c.friction_log)
    for (const auto& r : c.friction_log->reports) rows.push_back(report_row(r));
  if (c.thermal_data)
    for (const auto& run : c.thermal_data->runs) rows.push_back(report_row(run.trace.report));
  page.table({"file", "rows read", "kept", "skipped", "converted", "ignored columns", "time gaps"}, rows);
  if (c.friction_log) raw_friction_segmentation(page, *c.friction_log);
  if (c.thermal && c.thermal_data) {
    rows.clear();
    for (const auto& run : c.thermal->runs) {
      const auto data = std::find_if(c.thermal_data->runs.begin(), c.thermal_data->runs.end(),
                                     [&](const ThermalRun& r) { return r.id == run.id; });
      rows.push_back({run.id, data == c.thermal_data->runs.end() ? "" : guide_text(resolved_guide(*data)),
                      num(run.velocity_m_s), num(run.load_N), num(run.heat_rate_W), run.heat_source});
    }
    page.table({"thermal run", "guide or bar (catalog)", "velocity (m/s)", "load (N)", "heat rate at the start (W)",
                "heat from"},
               rows);
  }
}

}  // namespace lmcal::report
