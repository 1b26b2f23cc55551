// The filters a raw run goes through (raw_friction.hpp): local lines over centred windows,
// the trajectory filter built from them and the noise it leaves, and the robust scales the
// segmentation reads.
#include <algorithm>
#include <array>
#include <cmath>

#include "io/raw_friction.hpp"
#include "parallel_slices.hpp"

namespace lmcal::raw {

namespace {

// The window of `window` samples centred on sample i of n, [lo, hi) (shorter at the ends).
struct Window {
  std::size_t lo, hi;
};
Window window_at(std::size_t n, std::size_t window, std::size_t i) {
  const std::size_t half = window / 2;
  return {i >= half ? i - half : 0, std::min(n, i + half + 1)};
}

// f(i, lo, hi) at every sample i, over its window.
template <typename F>
std::vector<double> over_windows(std::size_t n, std::size_t window, F f) {
  std::vector<double> out(n);
  // Each sample's window on its own: slices of the samples on the threads, the same bits.
  detail::for_each_slice(n, detail::slice_threads(n, 16384), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Window w = window_at(n, window, i);
      out[i] = f(i, w.lo, w.hi);
    }
  });
  return out;
}

// The difference quotient of y across [lo, last]: (y_last − y_lo) / (t_last − t_lo), 0 for one sample.
double across(const std::vector<double>& t, double y_lo, double y_last, std::size_t lo, std::size_t last) {
  return last > lo ? (y_last - y_lo) / (t[last] - t[lo]) : 0.0;
}

// The sums of the least-squares lines through samples [lo, hi) of K series on one time axis,
// in offsets from sample i (for round-off: times may be epoch seconds), one pass: the time's
// shared, each series' own, each accumulated in the same order whatever K.
template <std::size_t K>
struct WindowSums {
  double st = 0, stt = 0, sy[K] = {}, sty[K] = {}, count = 0;
  WindowSums(const std::vector<double>& t, const std::array<const std::vector<double>*, K>& y, std::size_t i, std::size_t lo,
             std::size_t hi)
      : count(static_cast<double>(hi - lo)) {
    for (std::size_t j = lo; j < hi; ++j) {
      const double dt = t[j] - t[i];
      st += dt;
      stt += dt * dt;
      for (std::size_t k = 0; k < K; ++k) {
        const double dy = (*y[k])[j] - (*y[k])[i];
        sy[k] += dy;
        sty[k] += dt * dy;
      }
    }
  }
  double slope(std::size_t k) const {
    const double var = stt - st * st / count;
    return var > 0 ? (sty[k] - st * sy[k] / count) / var : 0.0;
  }
};

// The least-squares line through samples [lo, hi): its value at t_i and its slope.
struct LineAt {
  double value, slope;
};
LineAt line_at(const std::vector<double>& t, const std::vector<double>& y, std::size_t i, std::size_t lo, std::size_t hi) {
  const WindowSums<1> s(t, {&y}, i, lo, hi);
  const double slope = s.slope(0);
  return {.value = y[i] + s.sy[0] / s.count - slope * s.st / s.count, .slope = slope};  // the line at t_i
}

// The local slopes of K series on one time axis, the time's sums shared: the same bits as K
// calls of local_slope.
template <std::size_t K>
std::array<std::vector<double>, K> local_slopes(const std::vector<double>& t, const std::array<const std::vector<double>*, K>& y,
                                                std::size_t window) {
  const std::size_t n = t.size();
  std::array<std::vector<double>, K> out;
  for (auto& v : out) v.resize(n);
  detail::for_each_slice(n, detail::slice_threads(n, 16384), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Window w = window_at(n, window, i);
      const WindowSums<K> s(t, y, i, w.lo, w.hi);
      for (std::size_t k = 0; k < K; ++k) out[k][i] = s.slope(k);
    }
  });
  return out;
}

}  // namespace

LocalLine local_line(const std::vector<double>& t, const std::vector<double>& y, std::size_t window) {
  LocalLine line;
  line.value.resize(t.size());
  line.slope = over_windows(t.size(), window, [&](std::size_t i, std::size_t lo, std::size_t hi) {
    const LineAt at = line_at(t, y, i, lo, hi);
    line.value[i] = at.value;
    return at.slope;
  });
  return line;
}

// The slope alone: no value column allocated and filled (a million samples: 8 MB a call).
std::vector<double> local_slope(const std::vector<double>& t, const std::vector<double>& y, std::size_t window) {
  return over_windows(t.size(), window,
                      [&](std::size_t i, std::size_t lo, std::size_t hi) { return line_at(t, y, i, lo, hi).slope; });
}

std::vector<double> window_difference(const std::vector<double>& t, const std::vector<double>& y, std::size_t window) {
  return over_windows(t.size(), window, [&](std::size_t, std::size_t lo, std::size_t hi) { return across(t, y[lo], y[hi - 1], lo, hi - 1); });
}

// The median of |x|.
double median_abs(std::vector<double> x) {
  if (x.empty()) return 0;
  for (double& v : x) v = std::abs(v);
  const auto middle = x.begin() + static_cast<std::ptrdiff_t>(x.size() / 2);
  std::nth_element(x.begin(), middle, x.end());
  return *middle;
}

// σ of white noise on y from its `order`-th differences (variance 6σ² for the second, 20σ²
// for the third), robustly (1.4826 · median |d|): a smooth motion sampled fast adds little.
double difference_noise(const std::vector<double>& y, int order) {
  std::vector<double> d = y;
  for (int k = 0; k < order && !d.empty(); ++k) {
    for (std::size_t i = 0; i + 1 < d.size(); ++i) d[i] = d[i + 1] - d[i];
    d.pop_back();
  }
  return 1.4826 * median_abs(d) / std::sqrt(order == 3 ? 20.0 : order == 2 ? 6.0 : 2.0);
}

double rms(const std::vector<double>& x) {
  double s = 0;
  for (double v : x) s += v * v;
  return x.empty() ? 0 : std::sqrt(s / static_cast<double>(x.size()));
}

// The running trapezoid integral of y over t (0 at the first sample).
std::vector<double> running_integral(const std::vector<double>& t, const std::vector<double>& y) {
  std::vector<double> out(y.size(), 0.0);
  for (std::size_t i = 1; i < y.size(); ++i) out[i] = out[i - 1] + 0.5 * (y[i] + y[i - 1]) * (t[i] - t[i - 1]);
  return out;
}

// The RMS of the acceleration filter_trajectory gives (K[x] from positions, the local line's
// slope from a velocity column) over every `stride`-th sample (the same values at each of them;
// all of them at stride 1): a scale for choosing the window. Each sampled acceleration
// needs the local slopes at its window's two ends only (positions) or at itself (velocities).
double filtered_acceleration_rms(const RunSamples& run, Motion motion, std::size_t window, std::size_t stride) {
  const std::vector<double>& t = run.time_s;
  const std::size_t n = t.size(), count = (n + stride - 1) / stride;
  const auto slope = [&](std::size_t i) {
    const Window w = window_at(n, window, i);
    return line_at(t, run.motion, i, w.lo, w.hi).slope;
  };
  std::vector<double> a(count);
  detail::for_each_slice(count, detail::slice_threads(count, 16384), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const std::size_t i = k * stride;
      const Window w = window_at(n, window, i);
      a[k] = motion != Motion::position_m ? slope(i) : across(t, slope(w.lo), slope(w.hi - 1), w.lo, w.hi - 1);
    }
  });
  return rms(a);
}

// v, a and the force over a window of 2h + 1 samples, zero phase, through one operator (see
// segment in raw_friction.hpp). A velocity column: v the local line's value, a its slope, the
// force the slope of its integral.
void filter_trajectory(const RunSamples& run, Motion motion, std::size_t window, Segmented& s) {
  const std::vector<double>& t = run.time_s;
  const std::vector<double> impulse = running_integral(t, run.force_N);
  if (motion == Motion::position_m) {
    // One operator K for all three: a = K[x], v = K[∫x], F = K[∫∫F]; the friction is then
    // evaluated at the velocity it was smoothed with. (The three local slopes in one pass.)
    const std::vector<double> distance = running_integral(t, run.motion), momentum = running_integral(t, impulse);
    const auto slopes = local_slopes<3>(t, {&distance, &run.motion, &momentum}, window);
    s.velocity_m_s = window_difference(t, slopes[0], window);
    s.acceleration_m_s2 = window_difference(t, slopes[1], window);
    s.force_N = window_difference(t, slopes[2], window);
  } else {
    LocalLine line = local_line(t, run.motion, window);
    s.velocity_m_s = std::move(line.value);
    s.acceleration_m_s2 = std::move(line.slope);
    s.force_N = local_slope(t, impulse, window);
  }
}

// The noise left in v and a by a window of 2h + 1 samples at step dt, for white noise σ on the
// motion column: σ times the root sum of squares of the filter's own impulse response (the
// very code filter_trajectory runs, on a unit impulse in the middle of a uniform series).
std::pair<double, double> filter_noise(Motion motion, double sigma, double dt, std::size_t h) {
  const std::size_t n = 8 * h + 9;
  RunSamples impulse;
  impulse.time_s.resize(n);
  for (std::size_t i = 0; i < n; ++i) impulse.time_s[i] = static_cast<double>(i) * dt;
  impulse.motion.assign(n, 0.0);
  impulse.motion[n / 2] = 1;
  impulse.force_N.assign(n, 0.0);
  Segmented response;
  filter_trajectory(impulse, motion, 2 * h + 1, response);
  const auto gain = [](const std::vector<double>& y) {
    double sum = 0;
    for (double v : y) sum += v * v;
    return std::sqrt(sum);
  };
  return {sigma * gain(response.velocity_m_s), sigma * gain(response.acceleration_m_s2)};
}

}  // namespace lmcal::raw
