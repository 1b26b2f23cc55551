// Small x-y plots as inline SVG for self-contained HTML reports: no script, no style sheet,
// no dependency beyond the string.
//
// A Plot is a frame with ticks, gridlines, axis labels, a title, data series (lines, points,
// symmetric error bars, shaded bands), reference lines (y = 0 under residuals) and a legend
// beside the frame when any series has a label. render_svg returns one <svg> element, xmlns
// set, ready to paste into HTML or save as a .svg file. The same Plot always gives the same bytes.
//
//   Plot plot{.id = "friction-fit", .title = "Friction force vs velocity",
//             .x_label = "velocity (m/s)", .y_label = "friction force (N)"};
//   plot.series.push_back({.label = "measured", .x = v_m_s, .y = f_N, .mark = Mark::points});
//   plot.series.push_back({.label = "fit", .x = v_grid_m_s, .y = f_fit_N});
//   html += render_svg(plot);
//
// A band (an interval around a curve) belongs to its series: band_low..band_high shaded in the
// series' colour under every series' lines and points, its legend entry a shaded box behind the
// line: {.label = "term (95 % band)", .x = x, .y = mean, .band_low = low, .band_high = high}.
//
// Every point carries its values as a tooltip (an SVG <title>: the browser shows it on hover,
// no script): "name: x_label x, y_label y ± error", a named x position by its name; every line
// the span of its values. The <svg> carries its axes' scales (data-x, data-y: "lo hi px_lo px_hi
// log") and names, so that a page's script can give a hovered line's values at each vertex (the
// HTML report's does; report::html_document).
//
// Text is never lost: a title too wide for the plot wraps (13 px on two lines, else 11 px on
// three, cut with "…" only beyond that; the whole title stays in the <title>), axis labels wrap
// onto a second line, every numeric axis has at least two labelled ticks (a finer step on a
// short axis or a narrow range, else its two ends) and x tick labels do not run into each other.
//
// A series marked legend_only is a legend entry and nothing else: a line style or colour
// explained once for curves drawn in their points' colours.
//
// Pairs with a non-finite x or y (beyond ±1e300 counts as non-finite; on a log axis, so does a
// non-positive one) are skipped and break a line there; a point left alone on a line is drawn
// as a dot; a plot without any drawable pair says "no data". Unset limits come from the
// data and the reference lines with a 5 % margin; a zero span becomes ±10 % around the value
// (±1 around 0, ±half a decade on a log axis). Data outside fixed limits is clipped.
//
// Trap: Plot::id must be unique in the page. The clip rectangle of the data is an SVG
// clipPath named after it, and ids live in the one namespace of the HTML document: two plots
// with the same id (or ids that differ only in characters other than letters, digits, '-'
// and '_') clip one plot's data to the other's frame.
#pragma once

#include "lmcal/export.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace LMCAL_API lmcal {
namespace report {

enum class Mark { line, points, line_points };

struct Series {
  std::string label;           // legend text; empty: not in the legend
  // What tooltips call the series ("tc1 measured"); empty: its label. A legend label that says
  // how many points are shown need not repeat in every point's tooltip.
  std::string tooltip;
  std::vector<double> x, y;    // paired by index (the shorter length counts)
  std::vector<double> y_error; // empty, or per point: symmetric error bar y ± e (e ≥ 0)
  Mark mark = Mark::line;
  std::string color;           // CSS colour; empty: the palette colour of the series' index
  bool dashed = false;
  // Empty, or per point: a band from band_low to band_high, shaded. A point whose band ends
  // cannot be drawn breaks the band there, as a non-finite pair breaks a line; a band needs two
  // neighbouring points to show.
  std::vector<double> band_low, band_high;
  bool legend_only = false;  // no data: only its legend entry (label, colour, dashes)
};

// A full-width (horizontal, y = at) or full-height (vertical, x = at) dashed line.
struct ReferenceLine {
  bool horizontal = true;
  double at = 0;
  std::string label;
};

struct Plot {
  std::string id;                       // unique in the page: data-plot="id", clip-path name
  std::string title, x_label, y_label;  // labels carry units: "velocity (m/s)"
  std::vector<Series> series;
  std::vector<ReferenceLine> references;
  bool log_x = false, log_y = false;    // log axes skip non-positive values
  std::optional<double> x_min, x_max, y_min, y_max;  // fixed limits, in data units
  // Named x positions (runs, units) instead of numeric ticks: drawn when their labels fit side by
  // side along the axis, else the numeric ticks stand.
  std::vector<std::pair<double, std::string>> x_tick_labels;
  int width_px = 520, height_px = 340;  // clamped to [160, 4000] × [120, 4000]
};

// One <svg class="plot" data-plot="id" ...> element. Never throws on odd data.
std::string render_svg(const Plot& plot);

// Text for XML content and attribute values: & < > " ' escaped; control characters that
// XML 1.0 forbids (all below 0x20 except tab, newline, carriage return) are dropped, and
// bidirectional controls (U+202E reverses the rest of a line) are shown as "[U+202E]".
std::string escape_xml(std::string_view text);

// Ticks at multiples of a 1, 2 or 5 × 10^k step, from the last multiple ≤ lo to the first
// ≥ hi, their count as near target_count (clamped to [2, 100]) as the steps allow:
// nice_ticks(0, 0.97, 5) = {0, 0.2, 0.4, 0.6, 0.8, 1}. Values are exact decimals
// (0.6, not 0.6000000000000001). lo > hi is swapped; lo == hi gives {lo}, a span too narrow for
// steps a double tells apart (a step below 1e-14 of the magnitude) {lo, hi}; non-finite gives {}.
std::vector<double> nice_ticks(double lo, double hi, int target_count);

}  // namespace report
}  // namespace lmcal
