// Private: a raw load-cell run cut into constant-velocity plateaus (see friction_log.hpp for
// the format and the options). The loader gathers a run's samples, in time order with
// duplicate times already merged, and maps a SampleError back to the file's line and column.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "lmcal/io/friction_log.hpp"

namespace lmcal::raw {

// What the motion column holds.
enum class Motion { position_m, velocity_m_s };

// One run, in time order (strictly increasing times).
struct RunSamples {
  std::vector<double> time_s, motion, force_N;
};

// What became of a sample.
// A trajectory's: acceleration = within the filter's reach of a step of the force; settling =
// pre-sliding; stationary = at rest or reversing, or within the filter's reach of it or of the
// log's ends.
enum class Fate : std::uint8_t { kept, acceleration, settling, stationary, short_plateau };

struct Segmented {
  std::vector<Fate> fate;                     // per sample
  std::vector<std::uint32_t> plateau;         // per sample: index into plateaus (kept samples only)
  std::vector<Plateau> plateaus;              // kept plateaus, in time order
  std::vector<double> velocity_m_s;           // per sample, signed: derived, or the given one filtered (local line)
  std::vector<double> acceleration_m_s2;      // per sample: the derivative of the filtered velocity
  // A trajectory's: the force smoothed by the same window as the acceleration (parallel
  // filtering: both see one bandwidth), and the filter; empty and 0 for plateaus.
  std::vector<double> force_N;
  std::size_t window = 0;
  double window_s = 0, sigma_v = 0, sigma_a = 0;
  bool trajectory() const { return window != 0; }
  // The sense of the motion at sample i: its plateau's, or (a trajectory's) its own.
  double sense(std::size_t i) const;
};

// A sample that makes the run unusable: its index in RunSamples and what is wrong.
struct SampleError : std::runtime_error {
  SampleError(std::size_t index, const std::string& what) : std::runtime_error(what), sample(index) {}
  std::size_t sample;
};

// The least-squares line through y over t in a centred window of `window` samples (shorter at
// the ends), at every sample: its value there (the filtered y) and its slope (the filtered
// derivative); unbiased on a linear trend, also in the shorter windows at the ends.
struct LocalLine {
  std::vector<double> value, slope;
};
LocalLine local_line(const std::vector<double>& t, const std::vector<double>& y, std::size_t window);
// local_line's slope alone.
std::vector<double> local_slope(const std::vector<double>& t, const std::vector<double>& y, std::size_t window);

// The difference quotient of y across a centred window of `window` samples (shorter at the
// ends): the derivative of an already filtered series, in O(1) per sample.
std::vector<double> window_difference(const std::vector<double>& t, const std::vector<double>& y, std::size_t window);

// The trajectory filter's pieces (raw_filters.cc), for segment():
// the median of |x|; σ of white noise on y from its `order`-th differences (robustly); the RMS;
// the running trapezoid integral of y over t (0 at the first sample);
double median_abs(std::vector<double> x);
double difference_noise(const std::vector<double>& y, int order);
double rms(const std::vector<double>& x);
std::vector<double> running_integral(const std::vector<double>& t, const std::vector<double>& y);
// the RMS of the filtered acceleration over every `stride`-th sample (all at stride 1);
double filtered_acceleration_rms(const RunSamples& run, Motion motion, std::size_t window, std::size_t stride);
// v, a and the force over a window, zero phase, through one operator (into s's columns);
void filter_trajectory(const RunSamples& run, Motion motion, std::size_t window, Segmented& s);
// the noise left in v and a by a window of 2h + 1 samples at step dt, for white noise σ on the motion.
std::pair<double, double> filter_noise(Motion motion, double sigma, double dt, std::size_t h);

// Segments one run (options.segmentation: plateaus, or the whole trajectory). Throws SampleError
// when the position goes back between reversals (the velocity cannot be derived), when no
// plateau is long enough, or when a trajectory never accelerates (no mass to identify).
//
// A trajectory keeps every sample in motion. Its filter is one zero-phase operator over a
// centred window, K = (difference across the window) ∘ (local line's slope): a = K[x],
// v = K[∫x], F = K[∫∫F] — M·a, the force and the speed the friction is evaluated at all see
// exactly the same filter (parallel filtering: a trapezoid's corners smear them alike). The
// window is the smallest (from 5 samples) whose acceleration noise is under 2 % of the
// trajectory's RMS acceleration; at most 0.1 s. That noise is the position's own σ_x (robustly
// from third differences, 20σ² for white noise) through the filter's impulse response.
// Dropped as at rest: samples slower than max(min_speed_m_s, 3σ_v), where static and
// pre-sliding friction rule (the law is a sliding law); samples within the filter's reach (two
// half-windows from positions) of one at rest or reversing, whose filtered values mix in static
// friction or both senses; samples within that reach of the log's first or last sample (the
// window cut short); the first presliding_m of travel after rest or a reversal; and, as
// Fate::acceleration, samples within the filter's reach of a step of the force (a jump between
// two samples 5 σ out of its local trend): where in its sample interval the step happened is not
// in the log, and the ±h/2 that leaves biased the law near every corner of a trapezoidal move.
Segmented segment(const RunSamples& run, Motion motion, const RawFrictionOptions& options);

// The friction sample i gives: the force in the motion's sense (a kept sample's plateau's) less
// the inertia m·a, by the sign convention.
double friction_N(const RunSamples& run, const Segmented& s, const RawFrictionOptions& o, std::size_t i);

// Where each sample is along the travel and how far and how long the carriage has moved since it
// last turned: the position (the motion's own, or the velocity's running integral from the
// run's start); the turning point is the last sample at rest (slower than max(min_speed_m_s,
// 3 σ_v)) or where the filtered sense flips, the run's first sample before any.
struct Travel {
  std::vector<double> position_m, distance_since_reversal_m, time_since_reversal_s;
};
Travel travel(const RunSamples& run, Motion motion, const Segmented& s, const RawFrictionOptions& o);

// Counts per fate, into `out` (kept, dropped_*), and the plateaus.
void tally(const Segmented& s, RunSegmentation& out);

// Warnings about the sign convention, from a run's kept samples: a force that keeps its sign
// while the motion reverses (a magnitude), friction that comes out mostly negative.
std::vector<std::string> sign_warnings(const std::string& run, const std::string& force_column, const RunSamples& samples,
                                       const Segmented& s, const RawFrictionOptions& o);

}  // namespace lmcal::raw
