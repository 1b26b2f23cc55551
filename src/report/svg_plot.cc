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
constexpr double kLabelLinePx = 13;   // an axis label's second line

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

// `text` on at most `most` lines of at most `max_px` each: broken at spaces, the rest of what
// does not fit on the last line, and a line (a word) too long cut with "…".
std::vector<std::string> wrap_lines(const std::string& text, double max_px, std::size_t most) {
  std::vector<std::string> lines = wrap(text, max_px);
  if (lines.size() > most) {
    for (std::size_t k = most; k < lines.size(); ++k) lines[most - 1] += " " + lines[k];
    lines.resize(most);
  }
  for (std::string& line : lines) line = shortened(line, max_px);
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

// The axis' two ends, labelled with the digits that tell them apart: the ticks of last resort.
std::vector<Tick> end_ticks(const Axis& axis) {
  const double lo = axis.log ? std::pow(10.0, axis.lo) : axis.lo, hi = axis.log ? std::pow(10.0, axis.hi) : axis.hi;
  const double step = std::abs(hi - lo) / 10;
  return {{axis.lo, tick_label(lo, step)}, {axis.hi, tick_label(hi, step)}};
}

// Whether neighbouring x tick labels (centred under their ticks) run into each other.
bool labels_collide(const std::vector<Tick>& ticks, const Axis& axis) {
  for (std::size_t i = 1; i < ticks.size(); ++i)
    if (std::abs(axis.to_px(ticks[i].at) - axis.to_px(ticks[i - 1].at)) <
        (text_px(ticks[i].label) + text_px(ticks[i - 1].label)) / 2 + kCharPx)
      return true;
  return false;
}

// About one tick per `spacing_px`, and never fewer than two labelled ones: a finer step where the
// range holds fewer (a narrow range on a short axis), the axis' ends where no step does. Along x
// (`along_x`) a coarser step where the labels would run into each other.
std::vector<Tick> ticks_of(const Axis& axis, double length_px, double spacing_px, bool along_x) {
  const auto at = [&](int target) { return axis.log ? log_ticks(axis, target) : linear_ticks(axis, target); };
  const int target = std::max(2, static_cast<int>(length_px / spacing_px));
  const int finest = std::max(target, static_cast<int>(length_px / (along_x ? 2 * kCharPx : 12.0)));
  std::vector<Tick> ticks = at(target);
  for (int finer = target + 1; ticks.size() < 2 && finer <= finest; ++finer) ticks = at(finer);
  if (along_x)
    for (int coarser = target - 1; coarser >= 2 && ticks.size() > 2 && labels_collide(ticks, axis); --coarser) {
      std::vector<Tick> fewer = at(coarser);
      if (fewer.size() >= 2) ticks = std::move(fewer);
    }
  if (ticks.size() < 2 || (along_x && labels_collide(ticks, axis))) return end_ticks(axis);
  return ticks;
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

// Whether every line is at most `max_px` wide.
bool all_fit(const std::vector<std::string>& lines, double max_px) {
  return std::all_of(lines.begin(), lines.end(), [&](const std::string& line) { return text_px(line) <= max_px; });
}

// The title's lines: 13 px bold on up to two lines, else 11 px on up to three, the last cut with
// "…" where even they do not hold it (the whole title stays in the <title> and aria-label).
struct TitleLayout {
  std::vector<std::string> lines;
  double size_px = 13, line_px = 16;
  double baseline(std::size_t k) const { return 6 + size_px + line_px * static_cast<double>(k); }
  // The frame's top: under the last line.
  double bottom() const { return lines.empty() ? 12 : baseline(lines.size() - 1) + 11; }
};

TitleLayout title_layout(const std::string& title, double width) {
  if (title.empty()) return {};
  // Bold glyphs of s px are about s/11 · 1.1 as wide as the 11 px ones kCharPx measures.
  const auto room = [&](double size) { return (width - 12) / (size / 11.0 * 1.1); };
  if (std::vector<std::string> lines = wrap(title, room(13)); lines.size() <= 2 && all_fit(lines, room(13)))
    return {std::move(lines), 13, 16};
  return {wrap_lines(title, room(11), 3), 11, 14};
}

// An axis scale for the page's script, which reads a hovered line's values back from its
// pixels: "lo hi px_lo px_hi log" (lo and hi on the axis scale, log10 on a log axis).
std::string scale_attribute(const Axis& axis) {
  return fmt::format("{:.10g} {:.10g} {} {} {}", axis.lo, axis.hi, px(axis.px_lo), px(axis.px_hi), axis.log ? 1 : 0);
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

  // Layout: the title and the axis labels (on up to two lines each; their widths in a browser's
  // font +15 %), y ticks (their labels set the left margin), x ticks once the width is known.
  const TitleLayout heading = title_layout(plot.title, width);
  const std::vector<std::string> x_label = plot.x_label.empty() ? std::vector<std::string>{}
                                                                : wrap_lines(plot.x_label, (width - 8) / 1.15, 2);
  const std::vector<std::string> y_label = plot.y_label.empty() ? std::vector<std::string>{}
                                                                : wrap_lines(plot.y_label, (height - 8) / 1.15, 2);
  const auto label_lines_px = [](const std::vector<std::string>& lines) {
    return lines.empty() ? 0.0 : kLabelLinePx * static_cast<double>(lines.size() - 1);
  };
  const double top = heading.bottom();
  double bottom = height - (x_label.empty() ? 26 : 42 + label_lines_px(x_label));
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
    if (has_data) y_ticks = ticks_of(ay, bottom - top, 45, false);
    for (const Tick& t : y_ticks) y_tick_px = std::max(y_tick_px, text_px(t.label));
    left = (y_label.empty() ? 10 : 26 + label_lines_px(y_label)) + std::max(y_tick_px, 3 * kCharPx) + 8;
    right = width - 14 - legend_px;
    ax.px_lo = left;
    ax.px_hi = right;
  };
  place();
  if (has_data) {
    x_ticks = ticks_of(ax, right - left, 75, true);
    // A last label wider than the margin beside it: the frame narrows to hold it.
    if (!x_ticks.empty())
      if (const double over = ax.to_px(x_ticks.back().at) + text_px(x_ticks.back().label) / 2 - (width - 2); over > 0) {
        right -= over;
        ax.px_hi = right;
        x_ticks = ticks_of(ax, right - left, 75, true);
      }
  }
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
  // The axes' scales and names, for the page's script that gives a hovered line's values.
  const std::string scales = has_data ? fmt::format(" data-x=\"{}\" data-y=\"{}\" data-x-label=\"{}\" data-y-label=\"{}\"",
                                                    scale_attribute(ax), scale_attribute(ay), escape_xml(plot.x_label),
                                                    escape_xml(plot.y_label))
                                      : "";
  fmt::format_to(out,
                 "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" data-plot=\"{}\" viewBox=\"0 0 {} {}\" "
                 "width=\"{}\" height=\"{}\" role=\"img\" aria-label=\"{}\" font-family=\"sans-serif\" "
                 "font-size=\"11\"{}{}>\n<title>{}</title>\n",
                 id, width, height, width, height, title,
                 names.empty() ? "" : fmt::format(" data-x-names=\"{}\"", escape_xml(names)), scales, title);
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
      else  // under its tick, moved in where it would run past the plot's ends
        write_text(out, std::clamp(x, std::min(text_px(t.label) / 2 + 2, width / 2), std::max(width - text_px(t.label) / 2 - 2, width / 2)),
                   bottom + 15, "middle", t.label, " class=\"x-tick\"");
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
      // A label reads along its line inside the frame: cut to the frame's width, and left of a
      // vertical line where it would run past the plot's right edge.
      const std::string label = shortened(ref.label, right - left - 8);
      if (ref.horizontal) {
        write_line(out, left, p, right, p, style);
        if (!label.empty()) write_text(std::back_inserter(labels), right - 4, p - 4, "end", label);
      } else {
        write_line(out, p, top, p, bottom, style);
        const bool before = p + 4 + 1.15 * text_px(label) > width - 2;
        if (!label.empty()) write_text(std::back_inserter(labels), before ? p - 4 : p + 4, top + 12, before ? "end" : "start", label);
      }
    }
    // Every band under every series' marks.
    for (std::size_t i = 0; i < plot.series.size(); ++i) {
      const std::string d = band_path(samples[i], ax, ay);
      if (d.empty()) continue;
      banded[i] = true;
      fmt::format_to(out, "<path class=\"band\" data-label=\"{}\" data-series=\"{}\" fill=\"{}\" fill-opacity=\"0.2\" stroke=\"none\" d=\"{}\"/>\n",
                     escape_xml(plot.series[i].label), i, color_of(plot, i), d);
    }
    for (std::size_t i = 0; i < plot.series.size(); ++i) {
      if (samples[i].empty()) continue;
      write_series(out, plot.series[i], i, samples[i], color_of(plot, i), ax, ay, plot);
    }
    fmt::format_to(out, "</g>\n");
    if (!labels.empty()) fmt::format_to(out, "<g class=\"reference-labels\" fill=\"#555\">\n{}</g>\n", labels);
  } else {
    write_text(out, (left + right) / 2, (top + bottom) / 2 + 4, "middle", "no data", " fill=\"#777\"");
  }

  fmt::format_to(out, "<rect class=\"frame\" {} fill=\"none\" stroke=\"#333\" stroke-width=\"1\"/>\n", frame);
  for (std::size_t k = 0; k < heading.lines.size(); ++k)
    write_text(out, width / 2, heading.baseline(k), "middle", heading.lines[k],
               fmt::format(" class=\"title\" font-size=\"{}\" font-weight=\"bold\"", px(heading.size_px)));
  if (!x_label.empty()) {
    // Under the frame's middle, moved in where it would run past the plot's ends.
    double half = 0;
    for (const std::string& line : x_label) half = std::max(half, 0.575 * text_px(line));
    const double x = std::clamp((left + right) / 2, std::min(half + 2, width / 2), std::max(width - half - 2, width / 2));
    for (std::size_t k = 0; k < x_label.size(); ++k)
      write_text(out, x, height - 8 - kLabelLinePx * static_cast<double>(x_label.size() - 1 - k), "middle", x_label[k],
                 " class=\"x-label\"");
  }
  for (std::size_t k = 0; k < y_label.size(); ++k) {
    // Beside the frame's middle, but inside the plot where it is longer than the frame.
    const double half = 0.575 * text_px(y_label[k]);
    const double x = 14 + kLabelLinePx * static_cast<double>(k);
    const double y = std::clamp((top + bottom) / 2, std::min(half + 2, height / 2), std::max(height - half - 2, height / 2));
    write_text(out, x, y, "middle", y_label[k],
               fmt::format(" class=\"y-label\" transform=\"rotate(-90 {} {})\"", px(x), px(y)));
  }

  if (!legend.empty()) {
    fmt::format_to(out, "<g class=\"legend\">\n");
    double y = top + 8;  // of the next entry; a long label wraps onto lines of its own
    const double x = right + 10;
    for (std::size_t row = 0; row < legend.size(); ++row) {
      const Series& series = plot.series[legend[row]];
      const std::string color = color_of(plot, legend[row]);
      const std::vector<std::string> lines = wrap_lines(series.label, 0.9 * (width - x - 26 - 4), 4);
      if (y + 4 + kLegendLinePx * static_cast<double>(lines.size() - 1) > height - 4) {  // no room below: said so
        write_text(out, x, std::min(y, height - 4) + 4 - kLegendRowPx / 2, "start",
                   shortened(fmt::format("… and {} more", legend.size() - row), width - x - 4));
        break;
      }
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
      for (std::size_t k = 0; k < lines.size(); ++k) write_text(out, x + 26, y + 4 + kLegendLinePx * static_cast<double>(k), "start", lines[k]);
      y += kLegendRowPx + kLegendLinePx * static_cast<double>(lines.size() - 1);
    }
    fmt::format_to(out, "</g>\n");
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace lmcal::report
