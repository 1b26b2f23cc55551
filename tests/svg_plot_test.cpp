// Tests for the SVG plots of the reports: 1-2-5 ticks, where a value lands in pixels (read back
// from the output against the drawn frame), skipped non-finite and non-positive-on-log values,
// escaping, well-formed and deterministic output.
#include "lmcal/report/svg_plot.hpp"
#include "report/page.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <regex>
#include <string>
#include <vector>

namespace lmcal::report {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
  return n;
}

// Code points of UTF-8 text: the width of a line in glyphs.
double glyphs(const std::string& text) {
  return static_cast<double>(std::count_if(text.begin(), text.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

// Empty when every tag is closed in order; else what went wrong, and where.
std::string tag_balance_error(const std::string& svg) {
  std::vector<std::string> open;
  for (std::size_t at = svg.find('<'); at != std::string::npos; at = svg.find('<', at + 1)) {
    const std::size_t end = svg.find('>', at);
    if (end == std::string::npos) return "unterminated tag at " + std::to_string(at);
    const bool closing = svg[at + 1] == '/';
    const std::size_t name_at = at + (closing ? 2 : 1);
    const std::string name = svg.substr(name_at, svg.find_first_of(" />", name_at) - name_at);
    if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) return "bad tag at " + std::to_string(at);
    if (closing) {
      if (open.empty() || open.back() != name) return "</" + name + "> closes " + (open.empty() ? "nothing" : open.back());
      open.pop_back();
    } else if (svg[end - 1] != '/') {
      open.push_back(name);
    }
  }
  return open.empty() ? "" : "<" + open.back() + "> never closed";
}

// Every '&' starts one of the entities escape_xml writes.
bool ampersands_are_entities(const std::string& svg) {
  static const std::regex entity("^&(amp|lt|gt|quot|#39);");
  for (std::size_t at = svg.find('&'); at != std::string::npos; at = svg.find('&', at + 1))
    if (!std::regex_search(svg.substr(at, 8), entity)) return false;
  return true;
}

bool has_non_finite_text(std::string svg) {
  std::transform(svg.begin(), svg.end(), svg.begin(), [](unsigned char c) { return std::tolower(c); });
  return svg.find("nan") != std::string::npos || svg.find("inf") != std::string::npos;
}

struct Point {
  double x, y;
};

// The circles of the k-th series group.
std::vector<Point> circles_of_series(const std::string& svg, std::size_t k) {
  std::size_t at = svg.find("<g class=\"series\"");
  for (std::size_t i = 0; i < k && at != std::string::npos; ++i) at = svg.find("<g class=\"series\"", at + 1);
  if (at == std::string::npos) return {};
  const std::string group = svg.substr(at, svg.find("</g>", at) - at);
  static const std::regex circle(R"re(<circle cx="([-0-9.]+)" cy="([-0-9.]+)")re");
  std::vector<Point> points;
  for (std::sregex_iterator it(group.begin(), group.end(), circle), end; it != end; ++it)
    points.push_back({std::stod((*it)[1]), std::stod((*it)[2])});
  return points;
}

struct Rect {
  double x, y, width, height;
};

Rect frame_of(const std::string& svg) {
  static const std::regex frame(R"re(<rect class="frame" x="([-0-9.]+)" y="([-0-9.]+)" width="([0-9.]+)" height="([0-9.]+)")re");
  std::smatch m;
  if (!std::regex_search(svg, m, frame)) return {kNaN, kNaN, kNaN, kNaN};
  return {std::stod(m[1]), std::stod(m[2]), std::stod(m[3]), std::stod(m[4])};
}

// Tick labels of the x axis (centred under the frame) or the y axis (right-aligned beside it).
std::vector<std::string> tick_labels(const std::string& svg, bool x_axis) {
  const std::size_t at = svg.find("<g class=\"tick-labels\"");
  if (at == std::string::npos) return {};
  const std::string group = svg.substr(at, svg.find("</g>", at) - at);
  const std::regex label(x_axis ? "class=\"x-tick\"[^>]*>([^<]*)</text>" : "text-anchor=\"end\">([^<]*)</text>");
  std::vector<std::string> labels;
  for (std::sregex_iterator it(group.begin(), group.end(), label), end; it != end; ++it) labels.push_back((*it)[1]);
  return labels;
}

// The texts whose extent, as the layout estimates it (6.2 px a glyph at 11 px, in proportion at
// other sizes, bold 1.1 times wider), leaves the viewBox; upright ones (rotate(-90)) run up from
// their anchor.
std::vector<std::string> text_outside_view(const std::string& svg) {
  std::smatch box;
  if (!std::regex_search(svg, box, std::regex(R"re(viewBox="0 0 ([0-9.]+) ([0-9.]+)")re"))) return {"no viewBox"};
  const double width = std::stod(box[1]), height = std::stod(box[2]);
  static const std::regex text(R"re(<text x="([-0-9.]+)" y="([-0-9.]+)" text-anchor="(start|middle|end)"([^>]*)>([^<]*)</text>)re");
  std::vector<std::string> outside;
  for (std::sregex_iterator it(svg.begin(), svg.end(), text), end; it != end; ++it) {
    const double x = std::stod((*it)[1]), y = std::stod((*it)[2]);
    const std::string anchor = (*it)[3], extra = (*it)[4], content = (*it)[5];
    std::smatch size_match;
    const double size = std::regex_search(extra, size_match, std::regex(R"re(font-size="([0-9.]+)")re")) ? std::stod(size_match[1]) : 11;
    const double length = glyphs(content) * 6.2 * size / 11 * (extra.find("bold") != std::string::npos ? 1.1 : 1);
    const double before = anchor == "start" ? 0 : anchor == "middle" ? length / 2 : length;  // along the text
    double lo_x = x - before, hi_x = x - before + length, lo_y = y - 0.8 * size, hi_y = y + 0.25 * size;
    if (extra.find("rotate(-90") != std::string::npos) {
      lo_x = x - 0.8 * size, hi_x = x + 0.25 * size;
      lo_y = y - (length - before), hi_y = y + before;
    }
    if (lo_x < -0.5 || hi_x > width + 0.5 || lo_y < -0.5 || hi_y > height + 0.5) outside.push_back(content);
  }
  return outside;
}

Plot points_on_fixed_limits(std::vector<double> x, std::vector<double> y) {
  Plot plot{.id = "fixed", .x_min = 0, .x_max = 10, .y_min = -1, .y_max = 1};
  plot.series.push_back({.x = std::move(x), .y = std::move(y), .mark = Mark::points});
  return plot;
}

// Steps 1, 2 or 5 × 10^k, evenly spaced, the first at or below lo, the last at or above hi,
// neither a whole step further out than needed.
void expect_nice(double lo, double hi, int target) {
  SCOPED_TRACE(testing::Message() << "nice_ticks(" << lo << ", " << hi << ", " << target << ")");
  const std::vector<double> ticks = nice_ticks(lo, hi, target);
  ASSERT_GE(ticks.size(), 2u);
  const double step = ticks[1] - ticks[0];
  const double mantissa = step / std::pow(10.0, std::floor(std::log10(step)));
  EXPECT_TRUE(std::abs(mantissa - 1) < 1e-6 || std::abs(mantissa - 2) < 1e-6 || std::abs(mantissa - 5) < 1e-6 ||
              std::abs(mantissa - 10) < 1e-6)
      << "step " << step;
  for (std::size_t i = 1; i < ticks.size(); ++i) EXPECT_NEAR(ticks[i] - ticks[i - 1], step, 1e-9 * step);
  const double slack = 1e-9 * step;
  EXPECT_LE(ticks.front(), lo + slack);
  EXPECT_GE(ticks.back(), hi - slack);
  EXPECT_GT(ticks.front(), lo - step);
  EXPECT_LT(ticks.back(), hi + step);
  EXPECT_GE(static_cast<int>(ticks.size()), target / 2 + 1);
  EXPECT_LE(static_cast<int>(ticks.size()), 2 * target + 2);
}

TEST(SvgPlot, NiceTicksOfTheExample) {
  EXPECT_EQ(nice_ticks(0, 0.97, 5), (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1.0}));  // exact decimals
  EXPECT_EQ(nice_ticks(-3.7, -0.2, 5), (std::vector<double>{-4, -3, -2, -1, 0}));
  EXPECT_EQ(nice_ticks(0.97, 0, 5), nice_ticks(0, 0.97, 5));
}

TEST(SvgPlot, NiceTicksAreOneTwoFiveStepsCoveringTheRange) {
  const double ranges[][2] = {{0, 0.97},   {-3.7, -0.2},   {-12, 17},         {1e-9, 3.3e-9},  {1, 1 + 1e-10},
                              {2e5, 9e6},  {-1e-6, 2e-7},  {0.013, 0.0171},   {99.5, 100.5},   {-1e300, 1e300},
                              {3, 1000.5}, {12345, 12346}, {-273.15, -200.0}, {1e-300, 2e-300}};
  for (const auto& [lo, hi] : ranges)
    for (const int target : {2, 3, 5, 8, 12}) expect_nice(lo, hi, target);
}

TEST(SvgPlot, NiceTicksOfDegenerateInput) {
  EXPECT_EQ(nice_ticks(2, 2, 5), (std::vector<double>{2}));
  EXPECT_TRUE(nice_ticks(kNaN, 1, 5).empty());
  EXPECT_TRUE(nice_ticks(0, kInf, 5).empty());
  EXPECT_TRUE(nice_ticks(-1.7e308, 1.7e308, 5).empty());  // the span itself overflows
  EXPECT_EQ(nice_ticks(0, 1, -3), nice_ticks(0, 1, 2));  // target clamped
}

TEST(SvgPlot, PointsLandOnTheFrameAtTheLimitsAndInBetweenLinearly) {
  const std::string svg = render_svg(points_on_fixed_limits({0, 10, 5, 2.5}, {-1, 1, 0, 0.5}));
  const Rect frame = frame_of(svg);
  ASSERT_GT(frame.width, 100);
  ASSERT_GT(frame.height, 100);
  const std::vector<Point> p = circles_of_series(svg, 0);
  ASSERT_EQ(p.size(), 4u);
  const double tol = 0.011;  // coordinates carry 2 decimals
  EXPECT_NEAR(p[0].x, frame.x, tol);  // (x_min, y_min): bottom left, y grows downwards
  EXPECT_NEAR(p[0].y, frame.y + frame.height, tol);
  EXPECT_NEAR(p[1].x, frame.x + frame.width, tol);  // (x_max, y_max): top right
  EXPECT_NEAR(p[1].y, frame.y, tol);
  EXPECT_NEAR(p[2].x, frame.x + frame.width / 2, tol);
  EXPECT_NEAR(p[2].y, frame.y + frame.height / 2, tol);
  EXPECT_NEAR(p[3].x, frame.x + frame.width / 4, tol);
  EXPECT_NEAR(p[3].y, frame.y + frame.height / 4, tol);
}

// Per-run plots name their runs on the x axis (not ticks 1, 1.5, 2 …) when the names fit side by
// side; too many names for the axis leave the numeric ticks.
TEST(SvgPlot, NamedTicksReplaceTheNumbersWhenTheyFit) {
  Plot plot{.id = "runs", .x_label = "run", .y_label = "alpha"};
  plot.series.push_back({.x = {1, 2, 3}, .y = {0.6, 0.61, 0.59}, .mark = Mark::points});
  plot.x_tick_labels = {{1, "v066"}, {2, "v083"}, {3, "v110"}};
  const std::string named = render_svg(plot);
  for (const char* name : {">v066<", ">v083<", ">v110<"}) EXPECT_NE(named.find(name), std::string::npos) << name;
  EXPECT_EQ(named.find(">1.5<"), std::string::npos);
  // Names too long even upright are cut to 0.3 of the height, with "…", and still stand.
  plot.x_tick_labels.clear();
  for (int r = 1; r <= 3; ++r) plot.x_tick_labels.emplace_back(r, fmt::format("{}{}", r, std::string(200, 'x')));
  const std::string cut = render_svg(plot);
  const std::smatch m = [&] {
    std::smatch found;
    std::regex_search(cut, found, std::regex(">(2x+)…<"));
    return found;
  }();
  ASSERT_FALSE(m.empty());
  EXPECT_LE(static_cast<double>(m[1].length() + 1) * 6.2, 0.3 * plot.height_px + 1e-9);
  EXPECT_GE(m[1].length(), 10);
  EXPECT_EQ(cut.find(">1.5<"), std::string::npos);
  // Too many to stand side by side even upright (14 px each): the numbers stand.
  plot.x_tick_labels.clear();
  plot.series.front() = {.x = {1, 500}, .y = {0.6, 0.61}, .mark = Mark::points};
  for (int r = 1; r <= 500; ++r) plot.x_tick_labels.emplace_back(r, fmt::format("run{}", r));
  const std::string numeric = render_svg(plot);
  EXPECT_EQ(numeric.find(">run250<"), std::string::npos);
  EXPECT_TRUE(std::regex_search(numeric, std::regex("class=\"x-tick\"[^>]*>[0-9]+<"))) << numeric.substr(0, 3000);
}

TEST(SvgPlot, ASeriesWithoutPointsIsALegendKeyOnly) {
  Plot plot{.id = "key"};
  plot.series.push_back({.x = {0, 1}, .y = {0, 1}, .color = "#E69F00"});
  plot.series.push_back({.label = "law (line)", .color = "#444444", .legend_only = true});
  plot.series.push_back({.label = "gone", .x = {NAN}, .y = {NAN}});  // points, none drawable, not a key: no entry
  const std::string svg = render_svg(plot);
  EXPECT_NE(svg.find(">law (line)<"), std::string::npos);
  EXPECT_EQ(svg.find(">gone<"), std::string::npos);
}

// The lines of the plot's title as drawn, and their font size.
std::pair<std::vector<std::string>, double> title_lines(const std::string& svg) {
  static const std::regex line(R"re(<text x="[-0-9.]+" y="[-0-9.]+" text-anchor="middle" class="title" font-size="([0-9.]+)" font-weight="bold">([^<]*)</text>)re");
  std::vector<std::string> lines;
  double size = 0;
  for (std::sregex_iterator it(svg.begin(), svg.end(), line), end; it != end; ++it) {
    lines.push_back((*it)[2]);
    size = std::stod((*it)[1]);
  }
  return {lines, size};
}

// A long title wraps onto lines that fit the plot's width (6.2 px a glyph at 11 px, bold 13 px
// about 1.3 times that), never squeezed or clipped at both ends; the whole title stays the
// plot's <title>.
TEST(SvgPlot, ALongTitleWrapsToTheWidth) {
  Plot plot{.id = "title", .title = "α of each run alone (±t·SE) and the pooled 95 % interval", .width_px = 300};
  plot.series.push_back({.x = {0, 1}, .y = {0, 1}});
  std::string svg = render_svg(plot);
  auto [lines, size] = title_lines(svg);
  ASSERT_EQ(lines.size(), 2u) << svg;
  EXPECT_EQ(size, 13);
  EXPECT_EQ(lines[0] + " " + lines[1], plot.title);
  for (const auto& line : lines) EXPECT_LE(6.2 * 13 / 11 * 1.1 * glyphs(line), 300 - 12) << line;
  EXPECT_EQ(svg.find("textLength"), std::string::npos);
  EXPECT_NE(svg.find("<title>" + plot.title + "</title>"), std::string::npos);
  EXPECT_GE(frame_of(svg).y, 19 + 16);  // the frame under the second line

  plot.title = std::string(40, 'T') + " " + std::string(40, 'U') + " " + std::string(40, 'V') + " " + std::string(40, 'W');
  std::tie(lines, size) = title_lines(render_svg(plot));
  ASSERT_EQ(lines.size(), 3u);  // 11 px, and cut only beyond three lines
  EXPECT_EQ(size, 11);
  EXPECT_EQ(lines[0], std::string(40, 'T'));
  EXPECT_TRUE(lines[2].starts_with("VVV") && lines[2].ends_with("…")) << lines[2];

  plot.title = "short";
  std::tie(lines, size) = title_lines(render_svg(plot));
  EXPECT_EQ(lines, std::vector<std::string>{"short"});
  EXPECT_EQ(size, 13);
}

TEST(SvgPlot, ErrorBarsSpanYPlusMinusError) {
  Plot plot = points_on_fixed_limits({5}, {0});
  plot.series[0].y_error = {0.5};
  const std::string svg = render_svg(plot);
  const Rect frame = frame_of(svg);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(svg, m, std::regex(R"re(class="error-bars"[^>]* d="M([-0-9.]+) ([-0-9.]+)V([-0-9.]+))re")));
  EXPECT_NEAR(std::stod(m[1]), frame.x + frame.width / 2, 0.011);
  EXPECT_NEAR(std::stod(m[2]), frame.y + 0.75 * frame.height, 0.011);  // y - 0.5
  EXPECT_NEAR(std::stod(m[3]), frame.y + 0.25 * frame.height, 0.011);  // y + 0.5
}

// The outline of a band: every "M" or "L" vertex, in order, and the number of closed pieces.
std::vector<Point> band_vertices(const std::string& svg, std::size_t* pieces = nullptr) {
  std::smatch m;
  if (!std::regex_search(svg, m, std::regex(R"re(<path class="band"[^>]* d="([^"]*)")re"))) return {};
  const std::string d = m[1];
  if (pieces) *pieces = count_of(d, "Z");
  static const std::regex vertex(R"re([ML]([-0-9.]+) ([-0-9.]+))re");
  std::vector<Point> points;
  for (std::sregex_iterator it(d.begin(), d.end(), vertex), end; it != end; ++it)
    points.push_back({std::stod((*it)[1]), std::stod((*it)[2])});
  return points;
}

TEST(SvgPlot, ABandIsShadedFromItsLowToItsHighEndsUnderTheSeries) {
  Plot plot = points_on_fixed_limits({}, {});
  plot.series[0] = {.label = "term", .x = {0, 5, 10}, .y = {0, 0, 0}, .band_low = {-1, -0.5, 0}, .band_high = {1, 0.5, 0}};
  const std::string svg = render_svg(plot);
  const Rect frame = frame_of(svg);
  const double bottom = frame.y + frame.height, middle = frame.y + frame.height / 2, tol = 0.011;
  std::size_t pieces = 0;
  const std::vector<Point> p = band_vertices(svg, &pieces);
  ASSERT_EQ(p.size(), 6u) << svg;  // along the highs left to right, back along the lows
  EXPECT_EQ(pieces, 1u);
  const double expected[6][2] = {{frame.x, frame.y},
                                 {frame.x + frame.width / 2, frame.y + frame.height / 4},
                                 {frame.x + frame.width, middle},
                                 {frame.x + frame.width, middle},
                                 {frame.x + frame.width / 2, frame.y + 0.75 * frame.height},
                                 {frame.x, bottom}};
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_NEAR(p[i].x, expected[i][0], tol) << i;
    EXPECT_NEAR(p[i].y, expected[i][1], tol) << i;
  }
  EXPECT_LT(svg.find("class=\"band\""), svg.find("<g class=\"series\"")) << "the band covers the series";
  EXPECT_NE(svg.find("fill=\"#0072B2\" fill-opacity=\"0.2\""), std::string::npos) << "not in the series' colour";
  const std::string legend = svg.substr(svg.find("<g class=\"legend\">"));
  EXPECT_NE(legend.find("<rect"), std::string::npos) << "the legend does not show the band";
  EXPECT_EQ(tag_balance_error(svg), "");
}

TEST(SvgPlot, ABandWidensTheFreeLimitsAndBreaksWhereAnEndCannotBeDrawn) {
  Plot plot{.id = "band"};
  plot.series.push_back({.x = {0, 1, 2, 3, 4, 5, 6}, .y = {0, 0, 0, 0, 0, 0, 0},
                         .band_low = {-1, -1, kNaN, -1, -1, -1, -1}, .band_high = {1, 1, 1, 1, 1, kInf, 1}});
  const std::string svg = render_svg(plot);
  std::size_t pieces = 0;
  EXPECT_EQ(band_vertices(svg, &pieces).size(), 8u);  // {0, 1} and {3, 4}; 6 alone draws nothing
  EXPECT_EQ(pieces, 2u);
  const std::vector<std::string> y = tick_labels(svg, false);
  ASSERT_GE(y.size(), 2u);
  EXPECT_LE(std::stod(y.front()), -1);  // the band, not only the line at 0, sets the range
  EXPECT_GE(std::stod(y.back()), 1);
  EXPECT_FALSE(has_non_finite_text(svg));
  EXPECT_EQ(svg.find("class=\"legend\""), std::string::npos);

  Plot none{.id = "no-band"};
  none.series.push_back({.x = {0, 1}, .y = {0, 1}, .band_low = {0}, .band_high = {1}});  // one point: no band
  EXPECT_EQ(render_svg(none).find("class=\"band\""), std::string::npos);
}

TEST(SvgPlot, NonFiniteValuesAreSkippedAndBreakTheLine) {
  Plot plot{.id = "gaps"};
  plot.series.push_back({.x = {0, 1, 2, kNaN, 4, 5, 6}, .y = {0, 1, kInf, 3, 4, -kInf, 6}, .mark = Mark::line_points});
  const std::string svg = render_svg(plot);
  EXPECT_EQ(circles_of_series(svg, 0).size(), 4u);  // (0,0) (1,1) (4,4) (6,6)
  std::smatch m;
  ASSERT_TRUE(std::regex_search(svg, m, std::regex(R"re(<path class="line" fill="none" d="([^"]*)")re")));
  EXPECT_EQ(count_of(m[1], "M"), 3u) << m[1];  // runs {0,1}, {4}, {6}
  EXPECT_FALSE(has_non_finite_text(svg));
}

TEST(SvgPlot, WithoutDrawableDataSaysNoData) {
  Plot all_bad{.id = "bad", .log_y = true};
  all_bad.series.push_back({.label = "bad", .x = {1, 2, kNaN}, .y = {-1, 0, 3}});  // y ≤ 0 on a log axis
  all_bad.references.push_back({.at = 1});
  for (const Plot& plot : {Plot{.id = "empty"}, all_bad}) {
    const std::string svg = render_svg(plot);
    EXPECT_NE(svg.find("no data"), std::string::npos);
    EXPECT_NE(svg.find("data-plot=\"" + plot.id + "\""), std::string::npos);
    EXPECT_EQ(count_of(svg, "<svg"), 1u);
    EXPECT_EQ(count_of(svg, "class=\"series\""), 0u);
    EXPECT_EQ(count_of(svg, "class=\"legend\""), 0u);
    EXPECT_EQ(tag_balance_error(svg), "");
    EXPECT_EQ(svg.find("nan"), std::string::npos);
  }
}

TEST(SvgPlot, SinglePointOrZeroRangeGetsAnOpenAxis) {
  Plot plot{.id = "one"};
  plot.series.push_back({.x = {3}, .y = {7}});  // a line of one point still shows it
  const std::string svg = render_svg(plot);
  const Rect frame = frame_of(svg);
  const std::vector<Point> p = circles_of_series(svg, 0);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NEAR(p[0].x, frame.x + frame.width / 2, 0.011);
  EXPECT_NEAR(p[0].y, frame.y + frame.height / 2, 0.011);
  const std::vector<std::string> y = tick_labels(svg, false);  // 7 ± 10 %
  ASSERT_GE(y.size(), 2u);
  EXPECT_GE(std::stod(y.front()), 6.3);
  EXPECT_LE(std::stod(y.back()), 7.7);

  Plot zeros{.id = "zeros"};
  zeros.series.push_back({.x = {0, 0}, .y = {0, 0}, .mark = Mark::points});
  const std::vector<std::string> z = tick_labels(render_svg(zeros), true);  // 0 ± 1
  ASSERT_GE(z.size(), 2u);
  EXPECT_EQ(z.front(), "-1");
  EXPECT_EQ(z.back(), "1");
}

TEST(SvgPlot, LogAxisSkipsNonPositiveAndTicksAtDecades) {
  Plot plot{.id = "log", .log_x = true};
  plot.series.push_back({.x = {-5, 0, 1, 10, 100, 1000}, .y = {1, 2, 3, 4, 5, 6}, .mark = Mark::points});
  const std::string svg = render_svg(plot);
  const std::vector<Point> p = circles_of_series(svg, 0);
  ASSERT_EQ(p.size(), 4u);
  EXPECT_NEAR(p[1].x - p[0].x, p[2].x - p[1].x, 0.02);  // decades evenly spaced
  EXPECT_NEAR(p[2].x - p[1].x, p[3].x - p[2].x, 0.02);
  EXPECT_EQ(tick_labels(svg, true), (std::vector<std::string>{"1", "10", "100", "1000"}));

  Plot wide{.id = "wide", .log_y = true};
  wide.series.push_back({.x = {0, 1, 2}, .y = {1e-9, 1, 1e9}});
  const std::vector<std::string> labels = tick_labels(render_svg(wide), false);
  ASSERT_GE(labels.size(), 3u);
  for (const std::string& label : labels) {
    const double decade = std::log10(std::stod(label));
    EXPECT_NEAR(decade, std::round(decade), 1e-12) << label;
    EXPECT_LE(label.size(), 6u) << label;  // "1e-09", not "0.000000001"
  }

  Plot narrow{.id = "narrow", .log_y = true};  // within a decade: 1-2-5
  narrow.series.push_back({.x = {0, 1}, .y = {12, 80}});
  EXPECT_EQ(tick_labels(render_svg(narrow), false), (std::vector<std::string>{"20", "50"}));
}

TEST(SvgPlot, TickLabelsAreCompact) {
  Plot plot{.id = "compact"};
  plot.series.push_back({.x = {0.1, 0.3}, .y = {1e-5, 5e-5}});
  const std::string svg = render_svg(plot);
  const std::vector<std::string> x = tick_labels(svg, true), y = tick_labels(svg, false);
  EXPECT_NE(std::find(x.begin(), x.end(), "0.3"), x.end());
  EXPECT_NE(std::find(y.begin(), y.end(), "2e-05"), y.end());
  for (const auto* labels : {&x, &y})
    for (const std::string& label : *labels) EXPECT_LE(label.size(), 6u) << label;

  Plot big{.id = "big", .x_min = 0, .x_max = 3000};
  big.series.push_back({.x = {0, 3000}, .y = {0, 1}});
  const std::vector<std::string> b = tick_labels(render_svg(big), true);
  EXPECT_NE(std::find(b.begin(), b.end(), "2000"), b.end());
}

// Names too wide to stand side by side stand upright under their ticks, the frame raised to
// make room: ten runs named like a rig's on a narrow per-run plot.
TEST(SvgPlot, NamesTooWideSideBySideStandUpright) {
  Plot plot{.id = "runs", .x_label = "run", .y_label = "k1", .width_px = 260};
  std::vector<double> x, y;
  for (int r = 1; r <= 10; ++r) {
    x.push_back(r);
    y.push_back(0.3 + 0.001 * r);
    plot.x_tick_labels.emplace_back(r, fmt::format("v066_r{:02}", r));
  }
  plot.series.push_back({.x = x, .y = y, .mark = Mark::points});
  const std::string svg = render_svg(plot);
  EXPECT_NE(svg.find("data-x-names=\"v066_r01|v066_r02|"), std::string::npos);
  for (int r = 1; r <= 10; ++r) EXPECT_NE(svg.find(fmt::format(">v066_r{:02}</text>", r)), std::string::npos) << r;
  EXPECT_NE(svg.find("class=\"x-tick\" transform=\"rotate(-90"), std::string::npos);
  EXPECT_EQ(tag_balance_error(svg), "");
}

// Every point's values on hover, with the axes' names, a named position by its name.
TEST(SvgPlot, PointsCarryTheirValuesAsTooltips) {
  Plot plot{.id = "runs", .x_label = "run", .y_label = "α"};
  plot.series.push_back({.label = "each <run>", .x = {1, 2}, .y = {0.6, 0.612345678}, .y_error = {0.01, 0.02}, .mark = Mark::points});
  plot.x_tick_labels = {{1, "v066"}, {2, "v083"}};
  const std::string svg = render_svg(plot);
  EXPECT_NE(svg.find("<title>each &lt;run&gt;: run v066, α 0.6 ± 0.01</title>"), std::string::npos) << svg;
  EXPECT_NE(svg.find("<title>each &lt;run&gt;: run v083, α 0.61235 ± 0.02</title>"), std::string::npos);
  plot.x_tick_labels.clear();
  EXPECT_NE(render_svg(plot).find(": run 2, α 0.61235"), std::string::npos);
  EXPECT_EQ(tag_balance_error(svg), "");
}

// Estimated x tick label extents (6.2 px a glyph, centred on their ticks) that overlap.
bool x_labels_overlap(const std::string& svg) {
  static const std::regex label(R"re(<text x="([-0-9.]+)" y="[-0-9.]+" text-anchor="middle" class="x-tick">([^<]*)</text>)re");
  std::vector<std::pair<double, double>> spans;
  for (std::sregex_iterator it(svg.begin(), svg.end(), label), end; it != end; ++it) {
    const double x = std::stod((*it)[1]), half = 3.1 * glyphs((*it)[2]);
    spans.emplace_back(x - half, x + half);
  }
  std::sort(spans.begin(), spans.end());
  for (std::size_t i = 1; i < spans.size(); ++i)
    if (spans[i].first < spans[i - 1].second) return true;
  return false;
}

// Every numeric axis says what it spans with two labelled ticks or more: a narrow range on the
// short axis of a per-run plot (names upright under it; it had one tick label, or none), a
// narrow range on a log axis, a huge and a tiny one, and labels too long to stand at the
// step the axis' length asks for (a coarser step, not labels running into each other).
TEST(SvgPlot, EveryAxisHasTwoLabelledTicksThatDoNotCollide) {
  std::vector<Plot> plots;
  plots.push_back({.id = "per-run", .title = "k2 per run", .x_label = "run", .y_label = "k2 (1/um)", .width_px = 300, .height_px = 220});
  for (int r = 1; r <= 10; ++r) plots.back().x_tick_labels.emplace_back(r, fmt::format("run{:02}", r));
  plots.back().series.push_back({.x = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10},
                                 .y = {0.02961, 0.02958, 0.02955, 0.02962, 0.0296, 0.02957, 0.02959, 0.02956, 0.02963, 0.02954},
                                 .mark = Mark::points});
  plots.push_back({.id = "narrow-log", .log_y = true, .height_px = 130});
  plots.back().series.push_back({.x = {0, 1}, .y = {12.1, 12.4}});
  plots.push_back({.id = "long-labels", .width_px = 200});
  plots.back().series.push_back({.x = {1234567.1234, 1234567.2}, .y = {1e-12, 3e-12}});
  plots.push_back({.id = "huge", .log_x = true});
  plots.back().series.push_back({.x = {1e-290, 1e290}, .y = {-1e299, 1e299}});
  for (const Plot& plot : plots) {
    SCOPED_TRACE(plot.id);
    const std::string svg = render_svg(plot);
    EXPECT_GE(tick_labels(svg, false).size(), 2u) << svg;
    if (plot.x_tick_labels.empty()) {
      EXPECT_GE(tick_labels(svg, true).size(), 2u);
    }
    EXPECT_FALSE(x_labels_overlap(svg)) << svg;
    EXPECT_EQ(text_outside_view(svg), std::vector<std::string>{});
  }
}

// Labels longer than the plot wraps onto a second line, inside the plot; a legend longer than
// the plot says how many entries it leaves out; a reference label near the right edge turns left.
TEST(SvgPlot, LongLabelsAndLegendsStayInsideThePlot) {
  Plot plot{.id = "labels",
            .title = "Convection coefficient per run",
            .x_label = "speed of the block along the rail during the heating phase of the run (m/s)",
            .y_label = "heat transfer coefficient of the rail's free surface (W/m2K)",
            .width_px = 300,
            .height_px = 220};
  plot.series.push_back({.x = {0, 1}, .y = {0, 1}});
  for (int k = 0; k < 20; ++k) plot.series.push_back({.label = fmt::format("series {}", k), .x = {0.5}, .y = {0.5}, .mark = Mark::points});
  const std::string svg = render_svg(plot);
  EXPECT_EQ(text_outside_view(svg), std::vector<std::string>{});
  EXPECT_EQ(count_of(svg, "class=\"x-label\""), 2u);
  EXPECT_EQ(count_of(svg, "class=\"y-label\""), 2u);
  EXPECT_NE(svg.find("… and "), std::string::npos);
  EXPECT_EQ(tag_balance_error(svg), "");

  Plot reference{.id = "reference", .width_px = 300};
  reference.series.push_back({.x = {0, 1}, .y = {0, 1}});
  reference.references.push_back({.horizontal = false, .at = 0.98, .label = "the fitted value"});
  const std::string turned = render_svg(reference);
  EXPECT_NE(turned.find("text-anchor=\"end\">the fitted value</text>"), std::string::npos);
  EXPECT_EQ(text_outside_view(turned), std::vector<std::string>{});
}

// A line says the span of its values on hover (no script), and the svg carries each axis'
// scale ("lo hi px_lo px_hi log"), from which the page's script reads a vertex's values back.
TEST(SvgPlot, LinesCarryTheirSpanAndTheSvgItsScales) {
  Plot plot{.id = "line", .x_label = "time (h)", .y_label = "elongation (µm)", .log_y = true};
  plot.series.push_back({.label = "model", .tooltip = "model (95 % band)", .x = {0, 1, 2}, .y = {1, 10, 100}});
  const std::string svg = render_svg(plot);
  EXPECT_NE(svg.find("<title>model (95 % band): time (h) 0 to 2, elongation (µm) 1 to 100 (3 points)</title></path>"),
            std::string::npos)
      << svg;
  EXPECT_NE(svg.find("data-x-label=\"time (h)\" data-y-label=\"elongation (µm)\""), std::string::npos);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(svg, m, std::regex(R"re(data-x="([^ ]+) ([^ ]+) ([^ ]+) ([^ ]+) 0" data-y="([^ ]+) ([^ ]+) ([^ ]+) ([^ ]+) 1")re")));
  std::smatch d;
  ASSERT_TRUE(std::regex_search(svg, d, std::regex(R"re(d="M([-0-9.]+) ([-0-9.]+)L([-0-9.]+) ([-0-9.]+))re")));
  const auto back = [&](int k, double pixel) {  // the value at `pixel` on axis k (0: x, 1: y)
    const double lo = std::stod(m[1 + 4 * k]), hi = std::stod(m[2 + 4 * k]), p0 = std::stod(m[3 + 4 * k]), p1 = std::stod(m[4 + 4 * k]);
    const double scaled = lo + (pixel - p0) / (p1 - p0) * (hi - lo);
    return k == 1 ? std::pow(10.0, scaled) : scaled;
  };
  EXPECT_NEAR(back(0, std::stod(d[3])), 1, 1e-3);
  EXPECT_NEAR(back(1, std::stod(d[4])), 10, 1e-3 * 10);
  EXPECT_NE(svg.find("data-label=\"model (95 % band)\" data-series=\"0\""), std::string::npos);
  EXPECT_NE(svg.find(">model</text>"), std::string::npos);  // the legend keeps the label
}

TEST(SvgPlot, EscapesEveryUserString) {
  Plot plot{.id = "p\"><script>", .title = "Force <F> & \"v\" 'x'", .x_label = "a<b", .y_label = "c&d"};
  plot.series.push_back({.label = "fit </g>", .x = {0, 1}, .y = {0, 1}, .color = "red\"/><x"});
  plot.references.push_back({.at = 0.5, .label = "<ref>"});
  const std::string svg = render_svg(plot);
  EXPECT_NE(svg.find("<title>Force &lt;F&gt; &amp; &quot;v&quot; &#39;x&#39;</title>"), std::string::npos);
  EXPECT_NE(svg.find("data-plot=\"p&quot;&gt;&lt;script&gt;\""), std::string::npos);
  EXPECT_EQ(svg.find("<script"), std::string::npos);
  EXPECT_EQ(svg.find("<F>"), std::string::npos);
  EXPECT_EQ(svg.find("<ref>"), std::string::npos);
  EXPECT_EQ(svg.find("<x"), std::string::npos);
  EXPECT_TRUE(ampersands_are_entities(svg));
  EXPECT_EQ(tag_balance_error(svg), "");
  EXPECT_EQ(escape_xml("a\x01\tb"), "a\tb");  // XML forbids most control characters
  // A bidirectional control would reverse the rest of the line: shown by its name instead.
  EXPECT_EQ(escape_xml("r1\u202Eevil\u2066x\u200F"), "r1[U+202E]evil[U+2066]x[U+200F]");
  EXPECT_EQ(escape_xml("\u00E9\u2026\u20AC"), "\u00E9\u2026\u20AC");  // other characters untouched
}

// A table cell is text: a leading \x01 made the rest raw HTML (issue 23 #1); the shading of a
// correlation is a member of the cell, not markup in its text.
TEST(SvgPlot, PageTablesTakeEveryCellAsText) {
  report::Page page;
  page.table({"run", "<b>"}, std::vector<std::vector<std::string>>{{"\x01<img src=x onerror=alert(1)>", "a\u202Eb"}});
  const std::string html = page.html();
  EXPECT_EQ(html.find("<img"), std::string::npos) << html;
  EXPECT_NE(html.find("<td>&lt;img src=x onerror=alert(1)&gt;</td>"), std::string::npos) << html;
  EXPECT_NE(html.find("<td>a[U+202E]b</td>"), std::string::npos) << html;
  EXPECT_NE(html.find("<th>&lt;b&gt;</th>"), std::string::npos) << html;
  report::Page shaded;
  shaded.table({"correlation", "k1"}, std::vector<std::vector<report::Cell>>{{"\x01<i>k1</i>", report::correlation_cell(-0.5)}});
  EXPECT_NE(shaded.html().find("<td>&lt;i&gt;k1&lt;/i&gt;</td>"), std::string::npos) << shaded.html();
  EXPECT_NE(shaded.html().find("<td class=\"num\" style=\"background:rgba(0,114,178,0.40)\">-0.50</td>"), std::string::npos)
      << shaded.html();
}

TEST(SvgPlot, OneWellFormedSvgWithAGroupPerSeriesWithData) {
  Plot plot{.id = "four", .title = "t", .x_label = "velocity (m/s)", .y_label = "force (N)"};
  plot.series.push_back({.label = "measured", .x = {0, 1, 2}, .y = {1, 2, 3}, .y_error = {0.1, 0.1, 0.1},
                         .mark = Mark::points});
  plot.series.push_back({.label = "empty"});
  plot.series.push_back({.label = "all NaN", .x = {kNaN, 1}, .y = {1, kNaN}});
  plot.series.push_back({.label = "", .x = {0, 2}, .y = {1, 3}, .dashed = true});
  plot.references.push_back({.horizontal = false, .at = 1, .label = "x = 1"});
  const std::string svg = render_svg(plot);
  EXPECT_EQ(svg.rfind("<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" data-plot=\"four\"", 0), 0u);
  EXPECT_EQ(count_of(svg, "<svg"), 1u);
  EXPECT_EQ(count_of(svg, "</svg>"), 1u);
  EXPECT_EQ(tag_balance_error(svg), "");
  EXPECT_EQ(count_of(svg, "class=\"series\""), 2u);
  EXPECT_NE(svg.find("data-label=\"measured\""), std::string::npos);
  EXPECT_EQ(count_of(svg, ">measured</text>"), 1u);  // in the legend; series without data are not
  EXPECT_EQ(svg.find(">empty</text>"), std::string::npos);
  EXPECT_EQ(svg.find(">all NaN</text>"), std::string::npos);
  EXPECT_EQ(count_of(svg, "class=\"reference\""), 1u);
}

TEST(SvgPlot, OddInputStaysWellFormed) {
  const double denormal = std::numeric_limits<double>::denorm_min();
  std::vector<Plot> plots;
  plots.push_back({.id = "extremes"});
  plots.back().series.push_back({.x = {-1e300, 0, 1e300}, .y = {1e-300, denormal, -1e300}, .mark = Mark::line_points});
  plots.back().series.push_back({.x = {1e308, 2}, .y = {1, 1e308}});  // beyond 1e300: skipped
  plots.push_back({.id = "reversed", .x_min = 5, .x_max = -5, .y_min = 3});  // y_min above all data
  plots.back().series.push_back({.x = {0, 1, 2, 3}, .y = {0, 1}, .y_error = {kNaN, -1}});  // lengths differ
  plots.push_back({.id = "log", .log_x = true, .log_y = true, .x_min = -1, .y_max = 0, .width_px = 0, .height_px = -4});
  plots.back().series.push_back({.x = {1e-300, 1e300}, .y = {2, 3}, .y_error = {5, 1}});  // bar below 0 on log y
  plots.back().references.push_back({.horizontal = false, .at = -1, .label = "off the log axis"});
  plots.push_back({.id = "flat", .x_min = 1, .x_max = 1});
  plots.back().series.push_back({.x = {1, 1}, .y = {-2, -2}, .mark = Mark::points});
  for (const Plot& plot : plots) {
    SCOPED_TRACE(plot.id);
    const std::string svg = render_svg(plot);
    EXPECT_EQ(tag_balance_error(svg), "");
    EXPECT_EQ(count_of(svg, "<svg"), 1u);
    EXPECT_FALSE(has_non_finite_text(svg));
    EXPECT_EQ(svg.find("no data"), std::string::npos);
    EXPECT_LT(svg.size(), 20000u);  // clamped coordinates stay short
    EXPECT_GE(tick_labels(svg, true).size(), 2u);
    EXPECT_GE(tick_labels(svg, false).size(), 2u);
    EXPECT_EQ(text_outside_view(svg), std::vector<std::string>{});
  }
}

TEST(SvgPlot, PaletteColoursFollowSeriesOrder) {
  Plot plot{.id = "colours"};
  for (int i = 0; i < 3; ++i) plot.series.push_back({.x = {0, 1}, .y = {0, 1.0 * i}});
  plot.series[1].color = "purple";
  const std::string svg = render_svg(plot);
  EXPECT_NE(svg.find("stroke=\"#0072B2\""), std::string::npos);
  EXPECT_NE(svg.find("stroke=\"purple\""), std::string::npos);
  EXPECT_NE(svg.find("stroke=\"#009E73\""), std::string::npos);  // third colour for the third series
  EXPECT_EQ(svg.find("stroke=\"#D55E00\""), std::string::npos);
  EXPECT_EQ(svg.find("class=\"legend\""), std::string::npos);  // no labels, no legend
}

TEST(SvgPlot, SameInputSameBytes) {
  Plot plot{.id = "det", .title = "determinism", .log_y = true};
  plot.series.push_back({.label = "a", .x = {0.1, 0.2, 0.7}, .y = {3, 30, 300}, .y_error = {1, 2, 3}});
  const std::string first = render_svg(plot);
  render_svg(points_on_fixed_limits({1, 2}, {0.5, 0.25}));
  EXPECT_EQ(render_svg(plot), first);
}

}  // namespace
}  // namespace lmcal::report
