// The SVG plots' axes: a range that holds the data, and ticks with labels that tell them apart
// and do not collide (svg_parts.hpp; nice_ticks in svg_plot.hpp).

#include "lmcal/report/svg_plot.hpp"
#include "report/svg_parts.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace lmcal::report {

namespace {

// n × 10^e, rounded once (0.6, not 6 × 0.1).
double decimal(double n, int e) { return e >= 0 ? n * std::pow(10.0, e) : n / std::pow(10.0, -e); }

}  // namespace

namespace svg {

std::optional<double> to_scale(double v, bool log) {
  if (!std::isfinite(v) || std::abs(v) > kLargest || (log && v <= 0)) return std::nullopt;
  return log ? std::log10(v) : v;
}

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

namespace {

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

}  // namespace

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

}  // namespace svg

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

}  // namespace lmcal::report
