#include "lmcal/report/svg_plot.hpp"

#include "io/input_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <utility>

namespace lmcal::report {

namespace {

// Okabe & Ito (2008), "Color Universal Design": distinguishable under the common colour-vision
// deficiencies. Yellow last: it is faint on white.
constexpr std::array<std::string_view, 8> kPalette{"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                                   "#E69F00", "#56B4E9", "#000000", "#F0E442"};
constexpr double kLargest = 1e300;  // beyond this a value counts as non-finite: spans stay finite
constexpr double kCharPx = 6.2;     // mean glyph advance of the 11 px sans-serif text
constexpr double kLegendRowPx = 16;
constexpr double kLegendLinePx = 13;  // a wrapped legend label's next line

// A pixel coordinate: at most 2 decimals, trailing zeros dropped, never "-0".
std::string px(double v) {
  std::string s = fmt::format("{:.2f}", v);
  s.erase(s.find_last_not_of('0') + 1);
  if (s.back() == '.') s.pop_back();
  if (s == "-0") s = "0";
  return s;
}

// A tick label with the digits that tell ticks `step` apart: 0.2, 1.5, 2000, 1e-05.
std::string tick_label(double v, double step) {
  if (!(step > 0)) return fmt::format("{:g}", v);
  if (std::abs(v) < 1e-9 * step) return "0";
  const int digits = static_cast<int>(std::floor(std::log10(std::abs(v)))) -
                     static_cast<int>(std::floor(std::log10(step))) + 1;
  return fmt::format("{:.{}g}", v, std::clamp(digits, 6, 15));
}

// Number of code points, the width estimate of UTF-8 text.
double text_px(std::string_view text) {
  const auto n = std::count_if(text.begin(), text.end(),
                               [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; });
  return kCharPx * static_cast<double>(n);
}

// `text` cut to at most `max_px`, ending in "…" where cut (at a character, not inside one).
std::string shortened(const std::string& text, double max_px) {
  if (text_px(text) <= max_px) return text;
  std::string out;
  double used = kCharPx;  // the ellipsis
  for (std::size_t i = 0; i < text.size();) {
    std::size_t next = i + 1;
    while (next < text.size() && (static_cast<unsigned char>(text[next]) & 0xC0) == 0x80) ++next;
    if (used + kCharPx > max_px) break;
    out.append(text, i, next - i);
    used += kCharPx;
    i = next;
  }
  return out + "…";
}

// `text` broken at spaces into lines of at most `max_px` (a word longer than that stands alone).
std::vector<std::string> wrap(const std::string& text, double max_px) {
  std::vector<std::string> lines;
  std::string line;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t end = std::min(text.find(' ', at), text.size());
    const std::string word = text.substr(at, end - at);
    if (!line.empty() && text_px(line + " " + word) > max_px) {
      lines.push_back(line);
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
    at = end + 1;
  }
  if (!line.empty() || lines.empty()) lines.push_back(line);
  return lines;
}

// The value on the axis' own scale (log10 on a log axis), or nothing if it cannot be drawn.
std::optional<double> to_scale(double v, bool log) {
  if (!std::isfinite(v) || std::abs(v) > kLargest || (log && v <= 0)) return std::nullopt;
  return log ? std::log10(v) : v;
}

// n × 10^e, rounded once (0.6, not 6 × 0.1).
double decimal(double n, int e) { return e >= 0 ? n * std::pow(10.0, e) : n / std::pow(10.0, -e); }

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
                                     std::optional<double> fixed_hi, bool log) {
  const auto [min, max] = std::minmax_element(values.begin(), values.end());
  const std::optional<double> flo = fixed_lo ? to_scale(*fixed_lo, log) : std::nullopt;
  const std::optional<double> fhi = fixed_hi ? to_scale(*fixed_hi, log) : std::nullopt;
  double lo = flo.value_or(*min), hi = fhi.value_or(*max);
  if (hi < lo) {
    if (flo && fhi) std::swap(lo, hi);
    else if (flo) hi = lo;
    else lo = hi;
  }
  const double span = hi - lo;
  if (span <= 1e-12 * std::max(std::abs(lo), std::abs(hi))) {
    const double half = log ? 0.5 : std::abs(lo) < 1e-300 ? 1.0 : 0.1 * std::abs(lo);
    if (flo && !fhi) return {lo, lo + 2 * half};
    if (fhi && !flo) return {hi - 2 * half, hi};
    return {lo - half, hi + half};
  }
  return {flo ? lo : lo - 0.05 * span, fhi ? hi : hi + 0.05 * span};
}

struct Tick {
  double at;  // on the axis scale
  std::string label;
};

std::vector<Tick> linear_ticks(const Axis& axis, int target) {
  const std::vector<double> values = nice_ticks(axis.lo, axis.hi, target);
  const double step = values.size() >= 2 ? values[1] - values[0] : 0;
  std::vector<Tick> ticks;
  for (const double v : values)
    if (axis.contains(v)) ticks.push_back({v, tick_label(v, step)});
  return ticks;
}

// Decades (every k-th when there are many, else the first and last); 1-2-5 when fewer than
// two decades show; linear ticks when even those are fewer than two.
std::vector<Tick> log_ticks(const Axis& axis, int target) {
  std::vector<Tick> ticks;
  const auto decade = [](int k) { return Tick{static_cast<double>(k), tick_label(decimal(1, k), decimal(1, k))}; };
  // Within ±300 decades (kLargest): the margin of a huge range may reach past what a double holds.
  const int first = static_cast<int>(std::ceil(std::max(axis.lo, -300.0) - 1e-9));
  const int last = static_cast<int>(std::floor(std::min(axis.hi, 300.0) + 1e-9));
  if (last > first) {
    const int stride = std::max(1, (last - first + target) / target);
    for (int k = first; k <= last; ++k)
      if (k % stride == 0) ticks.push_back(decade(k));
    if (ticks.size() < 2) ticks = {decade(first), decade(last)};
    return ticks;
  }

  for (int k = first - 1; k <= last; ++k)
    for (const int m : {1, 2, 5}) {
      const double v = decimal(m, k);
      if (axis.contains(std::log10(v))) ticks.push_back({std::log10(v), tick_label(v, v)});
    }
  if (ticks.size() >= 2) return ticks;

  ticks.clear();
  const std::vector<double> values = nice_ticks(std::pow(10.0, axis.lo), std::pow(10.0, axis.hi), target);
  const double step = values.size() >= 2 ? values[1] - values[0] : 0;
  for (const double v : values)
    if (v > 0 && axis.contains(std::log10(v))) ticks.push_back({std::log10(v), tick_label(v, step)});
  return ticks;
}

std::vector<Tick> ticks_of(const Axis& axis, double length_px, double spacing_px) {
  const int target = std::max(2, static_cast<int>(length_px / spacing_px));
  return axis.log ? log_ticks(axis, target) : linear_ticks(axis, target);
}

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

using Out = std::back_insert_iterator<std::string>;

void write_text(Out out, double x, double y, std::string_view anchor, std::string_view text,
                std::string_view extra = "") {
  fmt::format_to(out, "<text x=\"{}\" y=\"{}\" text-anchor=\"{}\"{}>{}</text>\n", px(x), px(y), anchor, extra,
                 escape_xml(text));
}

void write_line(Out out, double x1, double y1, double x2, double y2, std::string_view extra = "") {
  fmt::format_to(out, "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"{}/>\n", px(x1), px(y1), px(x2), px(y2), extra);
}

// A point's tooltip (the browser's own, from <title>): its series, and its values with the axes' names.
std::string tooltip(const Series& series, std::size_t i, const Plot& plot) {
  std::string text = series.label.empty() ? "" : series.label + ": ";
  const auto named = std::find_if(plot.x_tick_labels.begin(), plot.x_tick_labels.end(),
                                  [&](const auto& tick) { return tick.first == series.x[i]; });
  text += named != plot.x_tick_labels.end() ? fmt::format("{} {}", plot.x_label, named->second)
                                            : fmt::format("{} {:.5g}", plot.x_label, series.x[i]);
  text += fmt::format(", {} {:.5g}", plot.y_label, series.y[i]);
  if (i < series.y_error.size() && std::isfinite(series.y_error[i])) text += fmt::format(" ± {:.3g}", series.y_error[i]);
  return escape_xml(text);
}

void write_series(Out out, const Series& series, const std::vector<Sample>& samples, std::string_view color,
                  const Axis& ax, const Axis& ay, const Plot& plot) {
  fmt::format_to(out, "<g class=\"series\" data-label=\"{}\" fill=\"{}\" stroke=\"{}\" stroke-width=\"1.5\">\n",
                 escape_xml(series.label), color, color);
  if (series.mark != Mark::points) {
    std::string d;
    for (const Sample& s : samples)
      fmt::format_to(std::back_inserter(d), "{}{} {}", s.starts_run ? "M" : "L", px(ax.to_px(s.x)), px(ay.to_px(s.y)));
    fmt::format_to(out, "<path fill=\"none\"{} d=\"{}\"/>\n", series.dashed ? " stroke-dasharray=\"6 4\"" : "", d);
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

}  // namespace

std::string escape_xml(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    // A bidirectional control would reorder everything after it on the page: shown as its name.
    if (const auto control = io::bidi_control_at(text.substr(i))) {
      out += fmt::format("[U+{:04X}]", static_cast<unsigned>(control->code));
      i += control->length - 1;
      continue;
    }
    const char c = text[i];
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default:
        if (static_cast<unsigned char>(c) >= 0x20 || c == '\t' || c == '\n' || c == '\r') out += c;
    }
  }
  return out;
}

std::vector<double> nice_ticks(double lo, double hi, int target_count) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || !std::isfinite(hi - lo)) return {};
  if (hi < lo) std::swap(lo, hi);
  const int target = std::clamp(target_count, 2, 100);
  const double raw_step = (hi - lo) / (target - 1);
  // Too narrow for steps that a double tells apart (or for 10^-e to stay finite).
  if (raw_step < 1e-307 || raw_step <= 1e-14 * std::max(std::abs(lo), std::abs(hi)))
    return lo == hi ? std::vector{lo} : std::vector{lo, hi};
  // Steps m × 10^e around raw_step; the one with span / step + 1 nearest the target wins
  // (the ticks inside the range number one less or so, those covering it one more).
  const int e = static_cast<int>(std::floor(std::log10(raw_step)));
  int best_m = 0;
  double best_miss = 0, best_first = 0, best_count = 0;
  for (const int m : {1, 2, 5, 10}) {
    const double step = decimal(m, e);
    if (!std::isfinite(step)) continue;
    const double miss = std::abs((hi - lo) / step + 1 - target);
    if (best_m == 0 || miss < best_miss) {
      best_m = m;
      best_miss = miss;
      best_first = std::floor(lo / step + 1e-9);
      best_count = std::ceil(hi / step - 1e-9) - best_first + 1;
    }
  }
  std::vector<double> ticks;
  for (double k = 0; k < std::min(best_count, 1000.0); ++k) ticks.push_back(decimal((best_first + k) * best_m, e));
  return ticks;
}

std::string render_svg(const Plot& plot) {
  const double width = std::clamp(plot.width_px, 160, 4000), height = std::clamp(plot.height_px, 120, 4000);

  // Drawable samples, and everything the unset limits must hold.
  std::vector<std::vector<Sample>> samples;
  std::vector<double> xs, ys;
  for (const Series& series : plot.series) {
    samples.push_back(samples_of(series, plot.log_x, plot.log_y));
    for (const Sample& s : samples.back()) {
      xs.push_back(s.x);
      ys.push_back(s.y);
      for (const auto& end : {s.y_lo, s.y_hi, s.band_lo, s.band_hi})
        if (end) ys.push_back(*end);
    }
  }
  const bool has_data = !xs.empty();
  for (const ReferenceLine& ref : plot.references)
    if (const auto at = to_scale(ref.at, ref.horizontal ? plot.log_y : plot.log_x); at && has_data)
      (ref.horizontal ? ys : xs).push_back(*at);

  std::vector<std::size_t> legend;  // series indices
  double legend_text_px = 0;
  for (std::size_t i = 0; i < plot.series.size(); ++i)
    if ((!samples[i].empty() || plot.series[i].legend_only) && !plot.series[i].label.empty()) {
      legend.push_back(i);
      legend_text_px = std::max(legend_text_px, text_px(plot.series[i].label));
    }

  // Layout: y ticks first (their labels set the left margin), x ticks once the width is known.
  const double top = plot.title.empty() ? 12 : 30;
  double bottom = height - (plot.x_label.empty() ? 26 : 42);
  Axis ax{plot.log_x}, ay{plot.log_y};
  ay.px_hi = top;
  std::vector<Tick> x_ticks, y_ticks;
  if (has_data) {
    std::tie(ax.lo, ax.hi) = axis_range(xs, plot.x_min, plot.x_max, plot.log_x);
    std::tie(ay.lo, ay.hi) = axis_range(ys, plot.y_min, plot.y_max, plot.log_y);
  }
  const double legend_px = legend.empty() ? 0 : std::min(0.35 * width, 40 + legend_text_px);
  double left = 0, right = 0;
  const auto place = [&] {  // the frame for this bottom: y ticks set the left margin
    ay.px_lo = bottom;
    double y_tick_px = 0;
    if (has_data) y_ticks = ticks_of(ay, bottom - top, 45);
    for (const Tick& t : y_ticks) y_tick_px = std::max(y_tick_px, text_px(t.label));
    left = (plot.y_label.empty() ? 10 : 26) + std::max(y_tick_px, 3 * kCharPx) + 8;
    right = width - 14 - legend_px;
    ax.px_lo = left;
    ax.px_hi = right;
  };
  place();
  if (has_data) x_ticks = ticks_of(ax, right - left, 75);
  // Named positions (runs, units): side by side where they fit, else turned upright (the frame
  // rises by the longest, at most 0.3 of the height: longer names are cut, "…"), else (too many
  // to stand side by side even upright) the numbers stand.
  bool upright = false;
  if (has_data && !plot.x_tick_labels.empty()) {
    std::vector<Tick> named;
    double text = 0, longest = 0;
    for (const auto& [at, label] : plot.x_tick_labels)
      if (ax.contains(at)) {
        named.push_back({at, label});
        text += text_px(label) + kCharPx;
        longest = std::max(longest, text_px(label));
      }
    const double span = right - left;
    upright = !named.empty() && text >= 0.95 * span && 14.0 * static_cast<double>(named.size()) < 0.95 * span;
    const double most = 0.3 * height;
    if (upright && longest > most) {
      for (Tick& t : named) t.label = shortened(t.label, most);
      longest = most;
    }
    if (upright) {
      bottom -= longest - 8;
      place();
    }
    if (!named.empty() && (upright || text < 0.95 * span)) x_ticks = std::move(named);
  }

  std::string svg;
  const Out out = std::back_inserter(svg);
  const std::string id = escape_xml(plot.id), title = escape_xml(plot.title.empty() ? "plot" : plot.title);
  // The names the x axis should show, for a check in the browser that it does ("|"-separated).
  std::string names;
  for (const auto& [at, label] : plot.x_tick_labels) names += (names.empty() ? "" : "|") + label;
  fmt::format_to(out,
                 "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" data-plot=\"{}\" viewBox=\"0 0 {} {}\" "
                 "width=\"{}\" height=\"{}\" role=\"img\" aria-label=\"{}\" font-family=\"sans-serif\" "
                 "font-size=\"11\"{}>\n<title>{}</title>\n",
                 id, width, height, width, height, title,
                 names.empty() ? "" : fmt::format(" data-x-names=\"{}\"", escape_xml(names)), title);
  fmt::format_to(out, "<rect class=\"background\" width=\"{}\" height=\"{}\" fill=\"#fff\"/>\n", width, height);
  const std::string frame = fmt::format("x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"", px(left), px(top),
                                        px(right - left), px(bottom - top));

  std::vector<bool> banded(plot.series.size(), false);  // a band drawn: shown in the legend
  if (has_data) {
    fmt::format_to(out, "<defs><clipPath id=\"{}\"><rect {}/></clipPath></defs>\n", clip_id(plot.id), frame);
    fmt::format_to(out, "<g class=\"grid\" stroke=\"#e6e6e6\" stroke-width=\"1\">\n");
    for (const Tick& t : x_ticks) write_line(out, ax.to_px(t.at), top, ax.to_px(t.at), bottom);
    for (const Tick& t : y_ticks) write_line(out, left, ay.to_px(t.at), right, ay.to_px(t.at));
    fmt::format_to(out, "</g>\n<g class=\"ticks\" stroke=\"#333\" stroke-width=\"1\">\n");
    for (const Tick& t : x_ticks) write_line(out, ax.to_px(t.at), bottom, ax.to_px(t.at), bottom + 4);
    for (const Tick& t : y_ticks) write_line(out, left - 4, ay.to_px(t.at), left, ay.to_px(t.at));
    fmt::format_to(out, "</g>\n<g class=\"tick-labels\" fill=\"#333\">\n");
    for (const Tick& t : x_ticks) {
      const double x = ax.to_px(t.at);
      if (upright)  // reads upwards, ending under its tick
        write_text(out, x + 4, bottom + 8, "end", t.label,
                   fmt::format(" class=\"x-tick\" transform=\"rotate(-90 {} {})\"", px(x + 4), px(bottom + 8)));
      else
        write_text(out, x, bottom + 15, "middle", t.label, " class=\"x-tick\"");
    }
    for (const Tick& t : y_ticks) write_text(out, left - 6, ay.to_px(t.at) + 4, "end", t.label);
    fmt::format_to(out, "</g>\n");

    // Reference lines under the data, their labels outside the clip so that they stay whole.
    std::string labels;
    fmt::format_to(out, "<g class=\"data\" clip-path=\"url(#{})\">\n", clip_id(plot.id));
    for (const ReferenceLine& ref : plot.references) {
      const Axis& axis = ref.horizontal ? ay : ax;
      const auto at = to_scale(ref.at, axis.log);
      if (!at || !axis.contains(*at)) continue;
      const double p = axis.to_px(*at);
      constexpr std::string_view style = " class=\"reference\" stroke=\"#555\" stroke-width=\"1\" stroke-dasharray=\"4 3\"";
      if (ref.horizontal) {
        write_line(out, left, p, right, p, style);
        if (!ref.label.empty()) write_text(std::back_inserter(labels), right - 4, p - 4, "end", ref.label);
      } else {
        write_line(out, p, top, p, bottom, style);
        if (!ref.label.empty()) write_text(std::back_inserter(labels), p + 4, top + 12, "start", ref.label);
      }
    }
    // Every band under every series' marks.
    for (std::size_t i = 0; i < plot.series.size(); ++i) {
      const std::string d = band_path(samples[i], ax, ay);
      if (d.empty()) continue;
      banded[i] = true;
      fmt::format_to(out, "<path class=\"band\" data-label=\"{}\" fill=\"{}\" fill-opacity=\"0.2\" stroke=\"none\" d=\"{}\"/>\n",
                     escape_xml(plot.series[i].label), color_of(plot, i), d);
    }
    for (std::size_t i = 0; i < plot.series.size(); ++i) {
      if (samples[i].empty()) continue;
      write_series(out, plot.series[i], samples[i], color_of(plot, i), ax, ay, plot);
    }
    fmt::format_to(out, "</g>\n");
    if (!labels.empty()) fmt::format_to(out, "<g class=\"reference-labels\" fill=\"#555\">\n{}</g>\n", labels);
  } else {
    write_text(out, (left + right) / 2, (top + bottom) / 2 + 4, "middle", "no data", " fill=\"#777\"");
  }

  fmt::format_to(out, "<rect class=\"frame\" {} fill=\"none\" stroke=\"#333\" stroke-width=\"1\"/>\n", frame);
  if (!plot.title.empty()) {
    // A title wider than the plot is set smaller (down to 8 px) rather than clipped at both ends;
    // bold 13 px glyphs are about 13/11 · 1.1 of the 11 px ones.
    const double wide = text_px(plot.title) * 13.0 / 11.0 * 1.1;
    const double size = std::clamp(13.0 * (width - 12) / std::max(wide, 1.0), 8.0, 13.0);
    write_text(out, width / 2, 19, "middle", plot.title,
               fmt::format(" font-size=\"{}\" font-weight=\"bold\"{}", px(size),
                           wide * size / 13.0 > width - 12 ? " textLength=\"" + px(width - 12) + "\" lengthAdjust=\"spacingAndGlyphs\"" : ""));
  }
  if (!plot.x_label.empty()) write_text(out, (left + right) / 2, height - 8, "middle", plot.x_label);
  if (!plot.y_label.empty()) {
    // Beside the frame's middle, but inside the plot where it is longer than the frame (its
    // width in a browser's font: +15 %).
    const double half = 0.575 * text_px(plot.y_label);
    const double x = 14, y = half * 2 + 4 < height ? std::clamp((top + bottom) / 2, half + 2, height - half - 2) : height / 2;
    write_text(out, x, y, "middle", plot.y_label, fmt::format(" transform=\"rotate(-90 {} {})\"", px(x), px(y)));
  }

  if (!legend.empty()) {
    fmt::format_to(out, "<g class=\"legend\">\n");
    double y = top + 8;  // of the next entry; a long label wraps onto lines of its own
    for (std::size_t row = 0; row < legend.size(); ++row) {
      const Series& series = plot.series[legend[row]];
      const std::string color = color_of(plot, legend[row]);
      const double x = right + 10;
      if (banded[legend[row]])
        fmt::format_to(out, "<rect x=\"{}\" y=\"{}\" width=\"20\" height=\"10\" fill=\"{}\" fill-opacity=\"0.2\"/>\n", px(x),
                       px(y - 5), color);
      if (series.mark != Mark::points)
        write_line(out, x, y, x + 20, y,
                   fmt::format(" stroke=\"{}\" stroke-width=\"1.5\"{}", color,
                               series.dashed ? " stroke-dasharray=\"6 4\"" : ""));
      if (series.mark != Mark::line)
        fmt::format_to(out, "<circle cx=\"{}\" cy=\"{}\" r=\"2.2\" fill=\"{}\" stroke=\"{}\" stroke-width=\"1.5\"/>\n",
                       px(x + 10), px(y), color, color);
      const std::vector<std::string> lines = wrap(series.label, 0.9 * (width - x - 26 - 4));
      for (std::size_t k = 0; k < lines.size(); ++k) write_text(out, x + 26, y + 4 + kLegendLinePx * static_cast<double>(k), "start", lines[k]);
      y += kLegendRowPx + kLegendLinePx * static_cast<double>(lines.size() - 1);
    }
    fmt::format_to(out, "</g>\n");
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace lmcal::report
