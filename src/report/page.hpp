// Building blocks of the HTML report (private to the report layer) beside the public page
// (lmcal/report/page.hpp): numbers, intervals and the colours series share across plots.
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "lmcal/fit/fit_result.hpp"
#include "lmcal/fit/statistics.hpp"
#include "lmcal/report/page.hpp"
#include "lmcal/report/svg_plot.hpp"

namespace lmcal::report {

// "1 run", "3 runs".
inline std::string plural(std::size_t n, std::string_view noun) {
  return fmt::format("{} {}{}", n, noun, n == 1 ? "" : "s");
}

// A percentage with `decimals` decimals ("+0.12 %" with `sign`), "–" when it is not finite (a fit
// that failed gives none; the row's reason says why).
inline std::string percent(double v, int decimals, bool sign = false) {
  if (!std::isfinite(v)) return "–";
  return sign ? fmt::format("{:+.{}f} %", v, decimals) : fmt::format("{:.{}f} %", v, decimals);
}

// A p-value to 2 significant digits; below what a double resolves, "< 1e-16" (not "0").
inline std::string p_value(double p) { return std::isfinite(p) ? p_value_text(p) : "–"; }
// "p = 0.032", or "p < 1e-16".
using lmcal::p_is;

// The bounds of the 95 % interval a fit says to quote (profile or linear); NaN where none.
inline std::pair<double, double> quoted_bounds(const ParameterEstimate& p) {
  if (p.interval == "profile") return {p.profile_low, p.profile_high};
  if (p.interval == "none" || !std::isfinite(p.se)) return {std::nan(""), std::nan("")};
  return {p.ci_low, p.ci_high};
}

// The interval a fit says to quote, in words.
inline std::string interval(const ParameterEstimate& p) {
  const auto [low, high] = quoted_bounds(p);
  if (!std::isfinite(low) && !std::isfinite(high)) return "–";
  return bracket(low, high) + (p.interval == "profile"                             ? " (profile)"
                                : p.interval == "log" || p.interval == "logit" ? " (" + p.interval + " scale)"
                                : p.interval == "clipped"                        ? " (clipped at its bound)"
                                                                                 : "");
}

// A per-run nuisance parameter (thermocouple offset, start temperature, heat scale): left out
// of the tables of the model's parameters.
// Left out of the tables of a model's parameters: a run's nuisance parameter, or a constant the
// outputs do not show (friction_fit_as_shown: one a combination law held, β without a temperature).
inline bool nuisance(const ParameterEstimate& p) { return p.per_run || !p.listed; }

inline std::string flags(const ParameterEstimate& p) {
  if (!p.free) return "held (given)";
  if (p.held_unidentifiable) return "held: not identifiable";
  return p.at_bound ? "at a bound" : "";
}

// A correlation coefficient as a cell shaded by its size (orange positive, blue negative).
inline Cell correlation_cell(double r) {
  if (!std::isfinite(r)) return {"–", true, ""};
  const double a = std::min(1.0, std::abs(r));
  return {fmt::format("{:+.2f}", r), true, fmt::format("rgba({},{:.2f})", r >= 0 ? "230,159,0" : "0,114,178", 0.8 * a)};
}

// Colours shared by the series of one quantity across plots (Okabe-Ito).
inline const std::string& colour(std::size_t i) {
  static const std::vector<std::string> palette = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                                   "#E69F00", "#56B4E9", "#000000", "#F0E442"};
  return palette[i % palette.size()];
}

// The most points of one cloud a plot draws; a thinned cloud says how many it shows (shown_of).
inline constexpr std::size_t kMostPoints = 600;

// "(540 of 2154 shown)": a thinned series' legend label ends with it.
inline std::string shown_of(std::size_t shown, std::size_t of) { return fmt::format("({} of {} shown)", shown, of); }

// The indices of `values` a line keeps to draw every value's extent with at most 2 × `buckets`
// vertices: each run of consecutive values, in order, by its lowest and highest (all where they
// are few). A line through them spans what a line through all would, at the plot's resolution.
inline std::vector<std::size_t> extremes(const std::vector<double>& values, std::size_t buckets) {
  std::vector<std::size_t> kept;
  const std::size_t every = stride(values.size(), std::max<std::size_t>(buckets, 1));
  for (std::size_t begin = 0; begin < values.size(); begin += every) {
    const std::size_t end = std::min(values.size(), begin + every);
    const auto [low, high] = std::minmax_element(values.begin() + static_cast<std::ptrdiff_t>(begin),
                                                 values.begin() + static_cast<std::ptrdiff_t>(end));
    const auto first = static_cast<std::size_t>(std::min(low, high) - values.begin());
    const auto second = static_cast<std::size_t>(std::max(low, high) - values.begin());
    kept.push_back(first);
    if (second != first) kept.push_back(second);
  }
  return kept;
}

}  // namespace lmcal::report
