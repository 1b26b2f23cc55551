#include "lmcal/report/svg_plot.hpp"
#include "report/svg_parts.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <tuple>
#include <utility>

namespace lmcal::report {

using namespace svg;  // the text and axes this file draws with (svg_parts.hpp)

namespace {

// Okabe & Ito (2008), "Color Universal Design": distinguishable under the common colour-vision
// deficiencies. Yellow last: it is faint on white.
constexpr std::array<std::string_view, 8> kPalette{"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                                   "#E69F00", "#56B4E9", "#000000", "#F0E442"};
constexpr double kLegendRowPx = 16;
constexpr double kLegendLinePx = 13;  // a wrapped legend label's next line
constexpr double kLabelLinePx = 13;   // an axis label's second line

// A drawable pair on the axis scales; `starts_run` when the pair before it was not drawable.
struct Sample {
  double x, y;
  std::size_t index;  // of the pair in its series (its values for a tooltip)
  std::optional<double> y_lo, y_hi;  // error bar ends; none: not drawable (log axis: ≤ 0)
  bool has_error = false;
  bool starts_run = true;
  std::optional<double> band_lo, band_hi;  // band ends; none: no band here (it breaks)
};

std::vector<Sample> samples_of(const Series& series, bool log_x, bool log_y) {
  std::vector<Sample> samples;
  bool run = false;
  for (std::size_t i = 0; i < std::min(series.x.size(), series.y.size()); ++i) {
    const std::optional<double> x = to_scale(series.x[i], log_x), y = to_scale(series.y[i], log_y);
    if (!x || !y) {
      run = false;
      continue;
    }
    Sample s{*x, *y, i, std::nullopt, std::nullopt, false, !run};
    if (i < series.y_error.size() && std::isfinite(series.y_error[i]) && series.y_error[i] >= 0) {
      s.has_error = true;
      s.y_lo = to_scale(series.y[i] - series.y_error[i], log_y);
      s.y_hi = to_scale(series.y[i] + series.y_error[i], log_y);
    }
    if (i < series.band_low.size() && i < series.band_high.size()) {
      s.band_lo = to_scale(series.band_low[i], log_y);
      s.band_hi = to_scale(series.band_high[i], log_y);
    }
    samples.push_back(s);
    run = true;
  }
  return samples;
}

// What tooltips call the series: its tooltip name, else its legend label.
const std::string& name_of(const Series& series) { return series.tooltip.empty() ? series.label : series.tooltip; }

// "name: " before a tooltip's values, or nothing for a series without a name.
std::string name_prefix(const Series& series) { return name_of(series).empty() ? "" : name_of(series) + ": "; }

// A point's tooltip (the browser's own, from <title>): its series, and its values with the axes' names.
std::string tooltip(const Series& series, std::size_t i, const Plot& plot) {
  std::string text = name_prefix(series);
  const auto named = std::find_if(plot.x_tick_labels.begin(), plot.x_tick_labels.end(),
                                  [&](const auto& tick) { return tick.first == series.x[i]; });
  text += named != plot.x_tick_labels.end() ? fmt::format("{} {}", plot.x_label, named->second)
                                            : fmt::format("{} {:.5g}", plot.x_label, series.x[i]);
  text += fmt::format(", {} {:.5g}", plot.y_label, series.y[i]);
  if (i < series.y_error.size() && std::isfinite(series.y_error[i])) text += fmt::format(" ± {:.3g}", series.y_error[i]);
  return escape_xml(text);
}

// A line's tooltip: its series, and the span of its values (the page's script gives a vertex's
// own values on hover; the x span left out where the x axis names its positions).
std::string line_tooltip(const Series& series, const std::vector<Sample>& samples, const Plot& plot) {
  const auto span = [&](double Sample::*member, bool log) {
    const auto [lo, hi] = std::minmax_element(samples.begin(), samples.end(),
                                              [&](const Sample& a, const Sample& b) { return a.*member < b.*member; });
    const auto value = [&](double scaled) { return log ? std::pow(10.0, scaled) : scaled; };
    return fmt::format("{:.4g} to {:.4g}", value((*lo).*member), value((*hi).*member));
  };
  std::string text = name_prefix(series);
  if (plot.x_tick_labels.empty()) text += fmt::format("{} {}, ", plot.x_label, span(&Sample::x, plot.log_x));
  text += fmt::format("{} {} ({} points)", plot.y_label, span(&Sample::y, plot.log_y), samples.size());
  return escape_xml(text);
}

void write_series(Out out, const Series& series, std::size_t index, const std::vector<Sample>& samples,
                  std::string_view color, const Axis& ax, const Axis& ay, const Plot& plot) {
  fmt::format_to(out, "<g class=\"series\" data-label=\"{}\" data-series=\"{}\" fill=\"{}\" stroke=\"{}\" stroke-width=\"1.5\">\n",
                 escape_xml(name_of(series)), index, color, color);
  if (series.mark != Mark::points) {
    std::string d;
    for (const Sample& s : samples)
      fmt::format_to(std::back_inserter(d), "{}{} {}", s.starts_run ? "M" : "L", px(ax.to_px(s.x)), px(ay.to_px(s.y)));
    fmt::format_to(out, "<path class=\"line\" fill=\"none\"{} d=\"{}\"><title>{}</title></path>\n",
                   series.dashed ? " stroke-dasharray=\"6 4\"" : "", d, line_tooltip(series, samples, plot));
  }
  std::string bars;
  for (const Sample& s : samples) {
    if (!s.has_error) continue;
    const double x = ax.to_px(s.x);
    const double lo = s.y_lo ? ay.to_px(*s.y_lo) : ay.px_lo;  // below a log axis: to the frame
    const double hi = s.y_hi ? ay.to_px(*s.y_hi) : ay.px_hi;
    fmt::format_to(std::back_inserter(bars), "M{} {}V{}M{} {}h6M{} {}h6", px(x), px(lo), px(hi), px(x - 3), px(lo),
                   px(x - 3), px(hi));
  }
  if (!bars.empty()) fmt::format_to(out, "<path class=\"error-bars\" fill=\"none\" stroke-width=\"1\" d=\"{}\"/>\n", bars);
  // Points; on a line, only the isolated ones, which a path would not show.
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const bool isolated = samples[i].starts_run && (i + 1 == samples.size() || samples[i + 1].starts_run);
    if (series.mark != Mark::line || isolated)
      fmt::format_to(out, "<circle cx=\"{}\" cy=\"{}\" r=\"2.2\" fill-opacity=\"0.7\"><title>{}</title></circle>\n",
                     px(ax.to_px(samples[i].x)), px(ay.to_px(samples[i].y)), tooltip(series, samples[i].index, plot));
  }
  fmt::format_to(out, "</g>\n");
}

bool has_band(const Sample& s) { return s.band_lo && s.band_hi; }

// The band of a series: one closed outline (along the upper ends, back along the lower ones)
// per stretch of neighbouring samples with both ends drawable; "" when there is none.
std::string band_path(const std::vector<Sample>& samples, const Axis& ax, const Axis& ay) {
  std::string d;
  std::size_t begin = 0;
  while (begin < samples.size()) {
    if (!has_band(samples[begin])) {
      ++begin;
      continue;
    }
    std::size_t end = begin + 1;
    while (end < samples.size() && !samples[end].starts_run && has_band(samples[end])) ++end;
    if (end - begin >= 2) {
      const auto to = std::back_inserter(d);
      for (std::size_t i = begin; i < end; ++i)
        fmt::format_to(to, "{}{} {}", i == begin ? "M" : "L", px(ax.to_px(samples[i].x)), px(ay.to_px(*samples[i].band_hi)));
      for (std::size_t i = end; i-- > begin;)
        fmt::format_to(to, "L{} {}", px(ax.to_px(samples[i].x)), px(ay.to_px(*samples[i].band_lo)));
      d += "Z";
    }
    begin = end;
  }
  return d;
}

// The series' own colour, else the palette's colour for its index.
std::string color_of(const Plot& plot, std::size_t index) {
  const std::string& color = plot.series[index].color;
  return color.empty() ? std::string(kPalette[index % kPalette.size()]) : escape_xml(color);
}

// Letters, digits, '-' and '_' of the plot id; the rest becomes '_'.
std::string clip_id(std::string_view id) {
  std::string out = "lmcal-clip-";
  for (const char c : id) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
  return out;
}

// An axis scale for the page's script, which reads a hovered line's values back from its
// pixels: "lo hi px_lo px_hi log" (lo and hi on the axis scale, log10 on a log axis).
std::string scale_attribute(const Axis& axis) {
  return fmt::format("{:.10g} {:.10g} {} {} {}", axis.lo, axis.hi, px(axis.px_lo), px(axis.px_hi), axis.log ? 1 : 0);
}

// What a plot draws: its series' drawable samples, everything the unset limits must hold, the
// series the legend names and the widest of their labels.
struct Contents {
  std::vector<std::vector<Sample>> samples;
  std::vector<double> xs, ys;
  bool has_data = false;
  std::vector<std::size_t> legend;  // series indices
  double legend_text_px = 0;
};

Contents contents_of(const Plot& plot) {
  Contents c;
  for (const Series& series : plot.series) {
    c.samples.push_back(samples_of(series, plot.log_x, plot.log_y));
    for (const Sample& s : c.samples.back()) {
      c.xs.push_back(s.x);
      c.ys.push_back(s.y);
      for (const auto& end : {s.y_lo, s.y_hi, s.band_lo, s.band_hi})
        if (end) c.ys.push_back(*end);
    }
  }
  c.has_data = !c.xs.empty();
  for (const ReferenceLine& ref : plot.references)
    if (const auto at = to_scale(ref.at, ref.horizontal ? plot.log_y : plot.log_x); at && c.has_data)
      (ref.horizontal ? c.ys : c.xs).push_back(*at);
  for (std::size_t i = 0; i < plot.series.size(); ++i)
    if ((!c.samples[i].empty() || plot.series[i].legend_only) && !plot.series[i].label.empty()) {
      c.legend.push_back(i);
      c.legend_text_px = std::max(c.legend_text_px, text_px(plot.series[i].label));
    }
  return c;
}

// Where everything goes: the title and the axis labels (on up to two lines each), the frame
// (top, bottom, left, right) with its axes and their ticks, the legend's width beside it.
struct Layout {
  double width = 0, height = 0;
  TitleLayout heading;
  std::vector<std::string> x_label, y_label;
  double top = 0, bottom = 0, left = 0, right = 0;
  double legend_px = 0;
  Axis ax, ay;
  std::vector<Tick> x_ticks, y_ticks;
  bool upright = false;  // the x tick labels (named positions) turned to read upwards
};

// The extra height of an axis label's second line.
double label_lines_px(const std::vector<std::string>& lines) {
  return lines.empty() ? 0.0 : kLabelLinePx * static_cast<double>(lines.size() - 1);
}

// The frame for the layout's bottom: y ticks set the left margin, the legend the right.
void place_frame(Layout& l, bool has_data) {
  l.ay.px_lo = l.bottom;
  double y_tick_px = 0;
  if (has_data) l.y_ticks = ticks_of(l.ay, l.bottom - l.top, 45, false);
  for (const Tick& t : l.y_ticks) y_tick_px = std::max(y_tick_px, text_px(t.label));
  l.left = (l.y_label.empty() ? 10 : 26 + label_lines_px(l.y_label)) + std::max(y_tick_px, 3 * kCharPx) + 8;
  l.right = l.width - 14 - l.legend_px;
  l.ax.px_lo = l.left;
  l.ax.px_hi = l.right;
}

// The x ticks; a last label wider than the margin beside it: the frame narrows to hold it.
void place_x_ticks(Layout& l) {
  l.x_ticks = ticks_of(l.ax, l.right - l.left, 75, true);
  if (!l.x_ticks.empty())
    if (const double over = l.ax.to_px(l.x_ticks.back().at) + text_px(l.x_ticks.back().label) / 2 - (l.width - 2); over > 0) {
      l.right -= over;
      l.ax.px_hi = l.right;
      l.x_ticks = ticks_of(l.ax, l.right - l.left, 75, true);
    }
}

// Named positions (runs, units): side by side where they fit, else turned upright (the frame
// rises by the longest, at most 0.3 of the height: longer names are cut, "…"), else (too many
// to stand side by side even upright) the numbers stand.
void name_x_positions(const Plot& plot, Layout& l) {
  std::vector<Tick> named;
  double text = 0, longest = 0;
  for (const auto& [at, label] : plot.x_tick_labels)
    if (l.ax.contains(at)) {
      named.push_back({at, label});
      text += text_px(label) + kCharPx;
      longest = std::max(longest, text_px(label));
    }
  const double span = l.right - l.left;
  l.upright = !named.empty() && text >= 0.95 * span && 14.0 * static_cast<double>(named.size()) < 0.95 * span;
  const double most = 0.3 * l.height;
  if (l.upright && longest > most) {
    for (Tick& t : named) t.label = shortened(t.label, most);
    longest = most;
  }
  if (l.upright) {
    l.bottom -= longest - 8;
    place_frame(l, true);
  }
  if (!named.empty() && (l.upright || text < 0.95 * span)) l.x_ticks = std::move(named);
}

// The title and the axis labels (their widths in a browser's font +15 %), y ticks (their labels
// set the left margin), x ticks once the width is known.
Layout lay_out(const Plot& plot, const Contents& c) {
  Layout l;
  l.width = std::clamp(plot.width_px, 160, 4000);
  l.height = std::clamp(plot.height_px, 120, 4000);
  l.heading = title_layout(plot.title, l.width);
  if (!plot.x_label.empty()) l.x_label = wrap_lines(plot.x_label, (l.width - 8) / 1.15, 2);
  if (!plot.y_label.empty()) l.y_label = wrap_lines(plot.y_label, (l.height - 8) / 1.15, 2);
  l.top = l.heading.bottom();
  l.bottom = l.height - (l.x_label.empty() ? 26 : 42 + label_lines_px(l.x_label));
  l.ax = Axis{plot.log_x};
  l.ay = Axis{plot.log_y};
  l.ay.px_hi = l.top;
  if (c.has_data) {
    std::tie(l.ax.lo, l.ax.hi) = axis_range(c.xs, plot.x_min, plot.x_max, plot.log_x);
    std::tie(l.ay.lo, l.ay.hi) = axis_range(c.ys, plot.y_min, plot.y_max, plot.log_y);
  }
  l.legend_px = c.legend.empty() ? 0 : std::min(0.35 * l.width, 40 + c.legend_text_px);
  place_frame(l, c.has_data);
  if (c.has_data) place_x_ticks(l);
  if (c.has_data && !plot.x_tick_labels.empty()) name_x_positions(plot, l);
  return l;
}

// The frame's rectangle as attributes.
std::string frame_attributes(const Layout& l) {
  return fmt::format("x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"", px(l.left), px(l.top), px(l.right - l.left),
                     px(l.bottom - l.top));
}

// The <svg> element's opening with its <title> and the white background.
void write_opening(Out out, const Plot& plot, const Layout& l, bool has_data) {
  const std::string id = escape_xml(plot.id), title = escape_xml(plot.title.empty() ? "plot" : plot.title);
  // The names the x axis should show, for a check in the browser that it does ("|"-separated).
  std::string names;
  for (const auto& [at, label] : plot.x_tick_labels) names += (names.empty() ? "" : "|") + label;
  // The axes' scales and names, for the page's script that gives a hovered line's values.
  const std::string scales = has_data ? fmt::format(" data-x=\"{}\" data-y=\"{}\" data-x-label=\"{}\" data-y-label=\"{}\"",
                                                    scale_attribute(l.ax), scale_attribute(l.ay), escape_xml(plot.x_label),
                                                    escape_xml(plot.y_label))
                                      : "";
  fmt::format_to(out,
                 "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" data-plot=\"{}\" viewBox=\"0 0 {} {}\" "
                 "width=\"{}\" height=\"{}\" role=\"img\" aria-label=\"{}\" font-family=\"sans-serif\" "
                 "font-size=\"11\"{}{}>\n<title>{}</title>\n",
                 id, l.width, l.height, l.width, l.height, title,
                 names.empty() ? "" : fmt::format(" data-x-names=\"{}\"", escape_xml(names)), scales, title);
  fmt::format_to(out, "<rect class=\"background\" width=\"{}\" height=\"{}\" fill=\"#fff\"/>\n", l.width, l.height);
}

// The grid, the ticks and their labels.
void write_axes(Out out, const Layout& l) {
  fmt::format_to(out, "<g class=\"grid\" stroke=\"#e6e6e6\" stroke-width=\"1\">\n");
  for (const Tick& t : l.x_ticks) write_line(out, l.ax.to_px(t.at), l.top, l.ax.to_px(t.at), l.bottom);
  for (const Tick& t : l.y_ticks) write_line(out, l.left, l.ay.to_px(t.at), l.right, l.ay.to_px(t.at));
  fmt::format_to(out, "</g>\n<g class=\"ticks\" stroke=\"#333\" stroke-width=\"1\">\n");
  for (const Tick& t : l.x_ticks) write_line(out, l.ax.to_px(t.at), l.bottom, l.ax.to_px(t.at), l.bottom + 4);
  for (const Tick& t : l.y_ticks) write_line(out, l.left - 4, l.ay.to_px(t.at), l.left, l.ay.to_px(t.at));
  fmt::format_to(out, "</g>\n<g class=\"tick-labels\" fill=\"#333\">\n");
  for (const Tick& t : l.x_ticks) {
    const double x = l.ax.to_px(t.at);
    if (l.upright)  // reads upwards, ending under its tick
      write_text(out, x + 4, l.bottom + 8, "end", t.label,
                 fmt::format(" class=\"x-tick\" transform=\"rotate(-90 {} {})\"", px(x + 4), px(l.bottom + 8)));
    else  // under its tick, moved in where it would run past the plot's ends
      write_text(out,
                 std::clamp(x, std::min(text_px(t.label) / 2 + 2, l.width / 2), std::max(l.width - text_px(t.label) / 2 - 2, l.width / 2)),
                 l.bottom + 15, "middle", t.label, " class=\"x-tick\"");
  }
  for (const Tick& t : l.y_ticks) write_text(out, l.left - 6, l.ay.to_px(t.at) + 4, "end", t.label);
  fmt::format_to(out, "</g>\n");
}

// The reference lines (their labels into `labels`, to go outside the clip so that they stay whole).
void write_references(Out out, const Plot& plot, const Layout& l, std::string& labels) {
  for (const ReferenceLine& ref : plot.references) {
    const Axis& axis = ref.horizontal ? l.ay : l.ax;
    const auto at = to_scale(ref.at, axis.log);
    if (!at || !axis.contains(*at)) continue;
    const double p = axis.to_px(*at);
    constexpr std::string_view style = " class=\"reference\" stroke=\"#555\" stroke-width=\"1\" stroke-dasharray=\"4 3\"";
    // A label reads along its line inside the frame: cut to the frame's width, and left of a
    // vertical line where it would run past the plot's right edge.
    const std::string label = shortened(ref.label, l.right - l.left - 8);
    if (ref.horizontal) {
      write_line(out, l.left, p, l.right, p, style);
      if (!label.empty()) write_text(std::back_inserter(labels), l.right - 4, p - 4, "end", label);
    } else {
      write_line(out, p, l.top, p, l.bottom, style);
      const bool before = p + 4 + 1.15 * text_px(label) > l.width - 2;
      if (!label.empty())
        write_text(std::back_inserter(labels), before ? p - 4 : p + 4, l.top + 12, before ? "end" : "start", label);
    }
  }
}

// The data clipped to the frame: reference lines under every band, every band under every
// series' marks; which series have a band drawn (the legend shows it).
std::vector<bool> write_data(Out out, const Plot& plot, const Contents& c, const Layout& l) {
  std::vector<bool> banded(plot.series.size(), false);
  std::string labels;
  fmt::format_to(out, "<g class=\"data\" clip-path=\"url(#{})\">\n", clip_id(plot.id));
  write_references(out, plot, l, labels);
  for (std::size_t i = 0; i < plot.series.size(); ++i) {
    const std::string d = band_path(c.samples[i], l.ax, l.ay);
    if (d.empty()) continue;
    banded[i] = true;
    fmt::format_to(out, "<path class=\"band\" data-label=\"{}\" data-series=\"{}\" fill=\"{}\" fill-opacity=\"0.2\" stroke=\"none\" d=\"{}\"/>\n",
                   escape_xml(plot.series[i].label), i, color_of(plot, i), d);
  }
  for (std::size_t i = 0; i < plot.series.size(); ++i) {
    if (c.samples[i].empty()) continue;
    write_series(out, plot.series[i], i, c.samples[i], color_of(plot, i), l.ax, l.ay, plot);
  }
  fmt::format_to(out, "</g>\n");
  if (!labels.empty()) fmt::format_to(out, "<g class=\"reference-labels\" fill=\"#555\">\n{}</g>\n", labels);
  return banded;
}

// The title's lines and the axis labels.
void write_labels(Out out, const Layout& l) {
  for (std::size_t k = 0; k < l.heading.lines.size(); ++k)
    write_text(out, l.width / 2, l.heading.baseline(k), "middle", l.heading.lines[k],
               fmt::format(" class=\"title\" font-size=\"{}\" font-weight=\"bold\"", px(l.heading.size_px)));
  if (!l.x_label.empty()) {
    // Under the frame's middle, moved in where it would run past the plot's ends.
    double half = 0;
    for (const std::string& line : l.x_label) half = std::max(half, 0.575 * text_px(line));
    const double x = std::clamp((l.left + l.right) / 2, std::min(half + 2, l.width / 2), std::max(l.width - half - 2, l.width / 2));
    for (std::size_t k = 0; k < l.x_label.size(); ++k)
      write_text(out, x, l.height - 8 - kLabelLinePx * static_cast<double>(l.x_label.size() - 1 - k), "middle", l.x_label[k],
                 " class=\"x-label\"");
  }
  for (std::size_t k = 0; k < l.y_label.size(); ++k) {
    // Beside the frame's middle, but inside the plot where it is longer than the frame.
    const double half = 0.575 * text_px(l.y_label[k]);
    const double x = 14 + kLabelLinePx * static_cast<double>(k);
    const double y = std::clamp((l.top + l.bottom) / 2, std::min(half + 2, l.height / 2), std::max(l.height - half - 2, l.height / 2));
    write_text(out, x, y, "middle", l.y_label[k], fmt::format(" class=\"y-label\" transform=\"rotate(-90 {} {})\"", px(x), px(y)));
  }
}

// The legend beside the frame: each entry's band, line and point as its series draws them, and
// its label wrapped; "… and N more" where the plot's height ends.
void write_legend(Out out, const Plot& plot, const Contents& c, const Layout& l, const std::vector<bool>& banded) {
  fmt::format_to(out, "<g class=\"legend\">\n");
  double y = l.top + 8;  // of the next entry; a long label wraps onto lines of its own
  const double x = l.right + 10;
  for (std::size_t row = 0; row < c.legend.size(); ++row) {
    const Series& series = plot.series[c.legend[row]];
    const std::string color = color_of(plot, c.legend[row]);
    const std::vector<std::string> lines = wrap_lines(series.label, 0.9 * (l.width - x - 26 - 4), 4);
    if (y + 4 + kLegendLinePx * static_cast<double>(lines.size() - 1) > l.height - 4) {  // no room below: said so
      write_text(out, x, std::min(y, l.height - 4) + 4 - kLegendRowPx / 2, "start",
                 shortened(fmt::format("… and {} more", c.legend.size() - row), l.width - x - 4));
      break;
    }
    if (banded[c.legend[row]])
      fmt::format_to(out, "<rect x=\"{}\" y=\"{}\" width=\"20\" height=\"10\" fill=\"{}\" fill-opacity=\"0.2\"/>\n", px(x),
                     px(y - 5), color);
    if (series.mark != Mark::points)
      write_line(out, x, y, x + 20, y,
                 fmt::format(" stroke=\"{}\" stroke-width=\"1.5\"{}", color, series.dashed ? " stroke-dasharray=\"6 4\"" : ""));
    if (series.mark != Mark::line)
      fmt::format_to(out, "<circle cx=\"{}\" cy=\"{}\" r=\"2.2\" fill=\"{}\" stroke=\"{}\" stroke-width=\"1.5\"/>\n",
                     px(x + 10), px(y), color, color);
    for (std::size_t k = 0; k < lines.size(); ++k) write_text(out, x + 26, y + 4 + kLegendLinePx * static_cast<double>(k), "start", lines[k]);
    y += kLegendRowPx + kLegendLinePx * static_cast<double>(lines.size() - 1);
  }
  fmt::format_to(out, "</g>\n");
}

}  // namespace

std::string render_svg(const Plot& plot) {
  const Contents contents = contents_of(plot);
  const Layout layout = lay_out(plot, contents);
  std::string svg;
  const Out out = std::back_inserter(svg);
  write_opening(out, plot, layout, contents.has_data);
  const std::string frame = frame_attributes(layout);
  std::vector<bool> banded(plot.series.size(), false);  // a band drawn: shown in the legend
  if (contents.has_data) {
    fmt::format_to(out, "<defs><clipPath id=\"{}\"><rect {}/></clipPath></defs>\n", clip_id(plot.id), frame);
    write_axes(out, layout);
    banded = write_data(out, plot, contents, layout);
  } else {
    write_text(out, (layout.left + layout.right) / 2, (layout.top + layout.bottom) / 2 + 4, "middle", "no data", " fill=\"#777\"");
  }
  fmt::format_to(out, "<rect class=\"frame\" {} fill=\"none\" stroke=\"#333\" stroke-width=\"1\"/>\n", frame);
  write_labels(out, layout);
  if (!contents.legend.empty()) write_legend(out, plot, contents, layout, banded);
  svg += "</svg>\n";
  return svg;
}

}  // namespace lmcal::report
