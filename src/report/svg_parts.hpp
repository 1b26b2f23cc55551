// The SVG plots' private parts (report/svg_plot.hpp; render_svg in svg_plot.cc draws with
// them): text measured, wrapped and written (svg_text.cc), an axis' range and ticks
// (svg_axes.cc). Widths are estimates: kCharPx per code point of the 11 px sans-serif text.
#pragma once

#include <algorithm>
#include <cstddef>
#include <iterator>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace lmcal::report::svg {

constexpr double kLargest = 1e300;  // beyond this a value counts as non-finite: spans stay finite
constexpr double kCharPx = 6.2;     // mean glyph advance of the 11 px sans-serif text

// --- Text (svg_text.cc) ---

// A pixel coordinate: at most 2 decimals, trailing zeros dropped, never "-0".
std::string px(double v);
// A tick label with the digits that tell ticks `step` apart: 0.2, 1.5, 2000, 1e-05.
std::string tick_label(double v, double step);
// Number of code points, the width estimate of UTF-8 text.
double text_px(std::string_view text);
// `text` cut to at most `max_px`, ending in "…" where cut (at a character, not inside one).
std::string shortened(const std::string& text, double max_px);
// `text` broken at spaces into lines of at most `max_px` (a word longer than that stands alone).
std::vector<std::string> wrap(const std::string& text, double max_px);
// `text` on at most `most` lines of at most `max_px` each: broken at spaces, the rest of what
// does not fit on the last line, and a line (a word) too long cut with "…".
std::vector<std::string> wrap_lines(const std::string& text, double max_px, std::size_t most);

// The title's lines: 13 px bold on up to two lines, else 11 px on up to three, the last cut with
// "…" where even they do not hold it (the whole title stays in the <title> and aria-label).
struct TitleLayout {
  std::vector<std::string> lines;
  double size_px = 13, line_px = 16;
  double baseline(std::size_t k) const { return 6 + size_px + line_px * static_cast<double>(k); }
  // The frame's top: under the last line.
  double bottom() const { return lines.empty() ? 12 : baseline(lines.size() - 1) + 11; }
};
TitleLayout title_layout(const std::string& title, double width);

using Out = std::back_insert_iterator<std::string>;
// <text> at (x, y), `text` escaped, `extra` attributes as given.
void write_text(Out out, double x, double y, std::string_view anchor, std::string_view text, std::string_view extra = "");
// <line> from (x1, y1) to (x2, y2), `extra` attributes as given.
void write_line(Out out, double x1, double y1, double x2, double y2, std::string_view extra = "");

// --- Axes (svg_axes.cc) ---

// The value on the axis' own scale (log10 on a log axis), or nothing if it cannot be drawn.
std::optional<double> to_scale(double v, bool log);

// Maps [lo, hi] on the axis scale to [px_lo, px_hi]; clamped so that far-off points stay short.
struct Axis {
  bool log = false;
  double lo = 0, hi = 1;
  double px_lo = 0, px_hi = 1;

  double to_px(double scaled) const {
    return std::clamp(px_lo + (scaled - lo) / (hi - lo) * (px_hi - px_lo), -1e5, 1e5);
  }
  bool contains(double scaled) const {
    const double slack = 1e-9 * (hi - lo);
    return scaled >= lo - slack && scaled <= hi + slack;
  }
};

// [lo, hi] on the axis scale: the fixed limits where given, else the values (non-empty)
// widened by 5 %. A zero span opens up on the free sides, ±10 % (±1 at 0, ±0.5 decade on log).
std::pair<double, double> axis_range(const std::vector<double>& values, std::optional<double> fixed_lo,
                                     std::optional<double> fixed_hi, bool log);

struct Tick {
  double at;  // on the axis scale
  std::string label;
};

// About one tick per `spacing_px`, and never fewer than two labelled ones: a finer step where the
// range holds fewer (a narrow range on a short axis), the axis' ends where no step does. Along x
// (`along_x`) a coarser step where the labels would run into each other.
std::vector<Tick> ticks_of(const Axis& axis, double length_px, double spacing_px, bool along_x);

}  // namespace lmcal::report::svg
