#include "io/raw_friction.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"
#include "parallel_slices.hpp"

namespace lmcal {

std::string_view to_string(ForceSign sign) {
  switch (sign) {
    case ForceSign::follows_motion: return "follows-motion";
    case ForceSign::opposes_motion: return "opposes-motion";
    case ForceSign::magnitude: return "magnitude";
  }
  return "?";
}

ForceSign parse_force_sign(std::string_view name) {
  for (ForceSign s : {ForceSign::follows_motion, ForceSign::opposes_motion, ForceSign::magnitude})
    if (name == to_string(s)) return s;
  throw InvalidParameter("force_sign", fmt::format("'{}': expected follows-motion, opposes-motion or magnitude", name));
}

std::string_view to_string(RawSegmentation s) { return s == RawSegmentation::plateaus ? "plateaus" : "trajectory"; }

RawSegmentation parse_raw_segmentation(std::string_view name) {
  for (RawSegmentation s : {RawSegmentation::plateaus, RawSegmentation::trajectory})
    if (name == to_string(s)) return s;
  throw InvalidParameter("segmentation", fmt::format("'{}': expected plateaus or trajectory", name));
}

std::string_view to_string(DuplicateTimes d) { return d == DuplicateTimes::refuse ? "refuse" : "average"; }

DuplicateTimes parse_duplicate_times(std::string_view name) {
  if (name == "refuse") return DuplicateTimes::refuse;
  if (name == "average") return DuplicateTimes::average;
  throw InvalidParameter("duplicate_times", fmt::format("'{}': expected refuse or average", name));
}

void RawFrictionOptions::validate() const {
  if (!(max_acceleration_m_s2 > 0)) throw InvalidParameter("max_acceleration_m_s2", max_acceleration_m_s2, "> 0");
  if (!(settling_s >= 0)) throw InvalidParameter("settling_s", settling_s, ">= 0");
  if (!(min_speed_m_s > 0)) throw InvalidParameter("min_speed_m_s", min_speed_m_s, "> 0");
  if (!(velocity_tolerance > 0 && velocity_tolerance < 1))
    throw InvalidParameter("velocity_tolerance", velocity_tolerance, "between 0 and 1");
  if (min_plateau_samples < 2)
    throw InvalidParameter("min_plateau_samples", static_cast<double>(min_plateau_samples), ">= 2");
  if (velocity_window < 3 || velocity_window % 2 == 0 || velocity_window > io::kMaxVelocityWindow)
    throw InvalidParameter("velocity_window", static_cast<double>(velocity_window),
                           fmt::format("an odd number from 3 to {} (docs/formats.md#limits)", io::kMaxVelocityWindow));
  if (!(moving_mass_kg >= 0)) throw InvalidParameter("moving_mass_kg", moving_mass_kg, ">= 0");
  if (!(presliding_m >= 0 && presliding_m <= 1)) throw InvalidParameter("presliding_m", presliding_m, "from 0 to 1 m");
  if (trajectory_window != 0 &&
      (trajectory_window < 3 || trajectory_window % 2 == 0 || trajectory_window > io::kMaxVelocityWindow))
    throw InvalidParameter("trajectory_window", static_cast<double>(trajectory_window),
                           fmt::format("0 (chosen from the data) or an odd number from 3 to {}", io::kMaxVelocityWindow));
  if (!(axis_incline_deg >= -90 && axis_incline_deg <= 90))
    throw InvalidParameter("axis_incline_deg", axis_incline_deg, "an angle from -90 to 90 degrees (+x up: positive)");
  drive.validate();
}

namespace raw {

namespace {

double sign_of(double v) { return v < 0 ? -1.0 : 1.0; }

// Marks acceleration (|a| above the threshold, or `off_speed`), rest and settling; everything
// else is a plateau candidate.
void classify(const RunSamples& run, const RawFrictionOptions& o, const std::vector<bool>& off_speed, Segmented& s) {
  const std::size_t n = run.time_s.size();
  s.fate.assign(n, Fate::kept);
  double last_unsteady_s = -std::numeric_limits<double>::infinity();
  double last_sign = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double v = s.velocity_m_s[i];
    if (std::abs(s.acceleration_m_s2[i]) > o.max_acceleration_m_s2 || off_speed[i]) {
      s.fate[i] = Fate::acceleration;
    } else if (std::abs(v) < o.min_speed_m_s) {
      s.fate[i] = Fate::stationary;
    } else if (last_sign != 0 && sign_of(v) != last_sign) {
      s.fate[i] = Fate::acceleration;  // a reversal between two samples: too fast to see in a
    }
    if (s.fate[i] != Fate::kept) {
      last_unsteady_s = run.time_s[i];
      if (std::abs(v) >= o.min_speed_m_s) last_sign = sign_of(v);
      continue;
    }
    last_sign = sign_of(v);
    if (run.time_s[i] - last_unsteady_s < o.settling_s) s.fate[i] = Fate::settling;
  }
}

// The candidates whose velocity is off the median of their stretch of candidates by more
// than the tolerance (true: a transient).
std::vector<bool> off_speed(const RawFrictionOptions& o, const Segmented& s) {
  const std::size_t n = s.fate.size();
  std::vector<bool> off(n, false);
  std::vector<double> speeds;
  for (std::size_t i = 0; i < n;) {
    if (s.fate[i] != Fate::kept) {
      ++i;
      continue;
    }
    std::size_t end = i;
    while (end < n && s.fate[end] == Fate::kept) ++end;
    speeds.assign(s.velocity_m_s.begin() + static_cast<std::ptrdiff_t>(i),
                  s.velocity_m_s.begin() + static_cast<std::ptrdiff_t>(end));
    const auto middle = speeds.begin() + static_cast<std::ptrdiff_t>(speeds.size() / 2);
    std::nth_element(speeds.begin(), middle, speeds.end());
    const double median = *middle;
    for (std::size_t j = i; j < end; ++j)
      off[j] = std::abs(s.velocity_m_s[j] - median) > o.velocity_tolerance * std::abs(median);
    i = end;
  }
  return off;
}

// Groups runs of candidates into plateaus; short ones are dropped.
void group(const RunSamples& run, Motion motion, const RawFrictionOptions& o, Segmented& s) {
  const std::size_t n = run.time_s.size();
  s.plateau.assign(n, 0);
  std::size_t i = 0;
  while (i < n) {
    if (s.fate[i] != Fate::kept) {
      ++i;
      continue;
    }
    std::size_t end = i;
    while (end < n && s.fate[end] == Fate::kept) ++end;
    if (end - i < o.min_plateau_samples) {
      std::fill(s.fate.begin() + static_cast<std::ptrdiff_t>(i), s.fate.begin() + static_cast<std::ptrdiff_t>(end),
                Fate::short_plateau);
      i = end;
      continue;
    }
    Plateau p{.start_s = run.time_s[i], .end_s = run.time_s[end - 1], .samples = end - i};
    if (motion == Motion::position_m) {
      // Exact for a constant velocity, whatever the filter: distance over time.
      p.velocity_m_s = (run.motion[end - 1] - run.motion[i]) / (p.end_s - p.start_s);
    } else {
      double sum = 0;
      for (std::size_t j = i; j < end; ++j) sum += run.motion[j];
      p.velocity_m_s = sum / static_cast<double>(end - i);
    }
    for (std::size_t j = i; j < end; ++j) s.plateau[j] = static_cast<std::uint32_t>(s.plateaus.size());
    s.plateaus.push_back(p);
    i = end;
  }
}

// Between reversals the position must move one way: within every stretch of samples moving
// in one sense (not at rest), a step back means the velocity cannot be derived. An encoder's
// jitter is no such step: where the block rests the encoder shows it (the smallest step seen
// at rest is a count), and steps back of up to two counts are allowed while it moves.
void check_monotone(const RunSamples& run, const Segmented& s, std::size_t reach) {
  double count_m = 0;
  for (std::size_t j = 1; j < run.motion.size(); ++j) {
    if (s.fate[j] != Fate::stationary || s.fate[j - 1] != Fate::stationary) continue;
    const double step = std::abs(run.motion[j] - run.motion[j - 1]);
    if (step > 0 && (count_m == 0 || step < count_m)) count_m = step;
  }
  const double jitter_m = 2.5 * count_m;  // two counts, and the rounding of the logged numbers
  // Within the filter's reach of a reversal the filtered sense lags the position's: a log that
  // never rests (a drive's) turns there without a sample at rest, and its genuine reversal is
  // no step back.
  std::vector<bool> turning(s.fate.size(), false);
  for (std::size_t j = 1; j < s.fate.size(); ++j) {
    if (sign_of(s.velocity_m_s[j]) == sign_of(s.velocity_m_s[j - 1])) continue;
    for (std::size_t k = j >= reach ? j - reach : 0; k < std::min(s.fate.size(), j + reach + 1); ++k) turning[k] = true;
  }
  for (std::size_t j = 1; j < s.fate.size(); ++j) {
    if (s.fate[j] == Fate::stationary || s.fate[j - 1] == Fate::stationary || turning[j]) continue;
    const double sense = sign_of(s.velocity_m_s[j]);
    if (sense != sign_of(s.velocity_m_s[j - 1])) continue;  // the reversal itself
    if (sense * (run.motion[j] - run.motion[j - 1]) < -jitter_m) {
      throw SampleError(j, fmt::format("the position goes back ({:.6g} m after {:.6g} m, at {:.6g} s) while the block "
                                       "moves {}, by more than the encoder's jitter at rest ({:.3g} m): position must be "
                                       "monotone between reversals, or the velocity cannot be derived (a wrapped "
                                       "encoder, a glitch? give a velocity column instead)",
                                       run.motion[j], run.motion[j - 1], run.time_s[j],
                                       sense > 0 ? "towards +x" : "towards -x", count_m));
    }
  }
}

}  // namespace

double Segmented::sense(std::size_t i) const {
  return fate[i] == Fate::kept && !trajectory() ? sign_of(plateaus[plateau[i]].velocity_m_s) : sign_of(velocity_m_s[i]);
}

double friction_N(const RunSamples& run, const Segmented& s, const RawFrictionOptions& o, std::size_t i) {
  const double sense = s.sense(i);
  const double inertia_N = o.moving_mass_kg * s.acceleration_m_s2[i];
  const double f = s.force_N.empty() ? run.force_N[i] : s.force_N[i];
  switch (o.force_sign) {
    case ForceSign::follows_motion: return sense * (f - inertia_N);
    case ForceSign::opposes_motion: return sense * (-f - inertia_N);
    case ForceSign::magnitude: return f - sense * inertia_N;
  }
  return f;
}

namespace {

// A step of the drive force between two samples (a trapezoidal move's feedforward M·a_ref
// jumps at every corner) happened somewhere in that sample interval, and where is not in the
// log: on a servo clock the steps fall on the sampling instants, and whether the sample at the
// step shows the old or the new force is the drive's convention. ∫F by the trapezoid rule puts
// the step mid-interval, ±h/2 from where it was, an impulse error of up to ΔF·h/2 that the
// parallel filter turns into a bump of that area in the filtered force over the filter's reach
// — a friction error of ~2 N at each corner of a 40 kg, 1 m/s² move (0.0 N elsewhere). Next to
// rest only one side of a corner is kept, so it does not cancel: the Stribeck amplitude came
// out 4-8 % low and the viscous slope 0.4 % low (5-8 SE) on the virtual rig's closed-loop
// axis. A step is a jump that stands out of the force's local trend (the difference d_i less
// the mean of its neighbours) by more than 5 σ of that statistic (robust, at least the force's
// resolution: its smallest nonzero difference); the samples within the filter's reach of it
// are dropped (Fate::acceleration). A smooth force (a measured current, a sinusoid) has none.
void drop_force_steps(const RunSamples& run, std::size_t reach, Segmented& s) {
  const std::vector<double>& F = run.force_N;
  const std::size_t n = F.size();
  std::vector<double> d(n - 1), jump(n - 1, 0.0);
  double resolution = 0;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    d[i] = F[i + 1] - F[i];
    if (const double step = std::abs(d[i]); step > 0 && (resolution == 0 || step < resolution)) resolution = step;
  }
  for (std::size_t i = 1; i + 2 < n; ++i) jump[i] = d[i] - 0.5 * (d[i - 1] + d[i + 1]);
  const double threshold = 5 * std::max(1.4826 * median_abs(jump), resolution);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (!(std::abs(jump[i]) > threshold)) continue;
    for (std::size_t j = i >= reach ? i - reach : 0; j < std::min(n, i + reach + 2); ++j)
      if (s.fate[j] == Fate::kept) s.fate[j] = Fate::acceleration;
  }
}

// Samples the acceleration scale that chooses a trajectory's window is taken from, at least.
constexpr std::size_t kWindowScaleSamples = 65536;

Segmented segment_trajectory(const RunSamples& run, Motion motion, const RawFrictionOptions& o) {
  const std::size_t n = run.time_s.size();
  if (n < 20) throw SampleError(0, fmt::format("a trajectory of {} samples: at least 20 are needed to filter it", n));
  std::vector<double> steps(n - 1);
  for (std::size_t i = 0; i + 1 < n; ++i) steps[i] = run.time_s[i + 1] - run.time_s[i];
  const double dt = median_abs(steps);
  // The motion's noise: from its differences, and at least an encoder's quantisation (count/√12,
  // the smallest step it makes): most differences of a slow quantised motion are exactly 0.
  double count = 0;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double step = std::abs(run.motion[i + 1] - run.motion[i]);
    if (step > 0 && (count == 0 || step < count)) count = step;
  }
  const double sigma = std::max(difference_noise(run.motion, motion == Motion::position_m ? 3 : 2), count / std::sqrt(12.0));
  // The window: given, or the smallest whose acceleration noise is under 2 % of the RMS
  // acceleration the trajectory shows through a wide window (25 ms or 5 samples).
  // Half-windows in samples, counted in doubles before the cast (a log at 1e-300 s steps must not
  // overflow it), at most 0.05 s, kMaxVelocityWindow, and what keeps samples × window within
  // kMaxFilterWork.
  const auto half_window = [&](double seconds) {
    const double budget = io::kMaxFilterWork / static_cast<double>(n) / 2 - 1;
    const double most = std::min({seconds / dt, static_cast<double>(io::kMaxVelocityWindow / 2), budget});
    return static_cast<std::size_t>(std::clamp(most, 2.0, static_cast<double>(io::kMaxVelocityWindow / 2)));
  };
  const std::size_t most = half_window(0.05);
  std::size_t h = o.trajectory_window / 2;
  if (static_cast<double>(n) * static_cast<double>(o.trajectory_window) > io::kMaxFilterWork)
    throw SampleError(0, fmt::format("{} samples filtered over trajectory_window = {}: at most {:.2g} operations "
                                     "(docs/formats.md#limits); a shorter window or a shorter log",
                                     n, o.trajectory_window, io::kMaxFilterWork));
  if (h == 0) {
    // Only the wide filter's acceleration is needed (its v and F would be three times the work).
    const std::size_t wide = 2 * std::min(std::max<std::size_t>(half_window(0.025), 5), most) + 1;
    // (Its RMS from 65,536 samples or so, evenly spread, on a longer log: the wide window's
    // acceleration at every one of a million samples was a third of loading them.)
    const double a_rms = filtered_acceleration_rms(run, motion, wide, std::max<std::size_t>(1, n / kWindowScaleSamples));
    for (h = 2; h < most && filter_noise(motion, sigma, dt, h).second > 0.02 * a_rms; ++h) {
    }
  }
  Segmented s;
  s.window = 2 * h + 1;
  s.window_s = static_cast<double>(s.window) * dt;
  std::tie(s.sigma_v, s.sigma_a) = filter_noise(motion, sigma, dt, h);
  filter_trajectory(run, motion, s.window, s);
  // At rest or reversing, or within the filter's reach of it (two half-windows from positions):
  // the filtered force there mixes in static friction, or both senses.
  const double rest_m_s = std::max(o.min_speed_m_s, 3 * s.sigma_v);
  const std::size_t reach = motion == Motion::position_m ? 2 * h : h;
  s.fate.assign(n, Fate::kept);
  for (std::size_t i = 0; i < n; ++i) {
    const bool turning = i > 0 && sign_of(s.velocity_m_s[i]) != sign_of(s.velocity_m_s[i - 1]);
    if (std::abs(s.velocity_m_s[i]) >= rest_m_s && !turning) continue;
    for (std::size_t j = i >= reach ? i - reach : 0; j < std::min(n, i + reach + 1); ++j) s.fate[j] = Fate::stationary;
  }
  // And within the filter's reach of the log's first and last samples: the window is cut short
  // there, not centred, and its v, a and F are biased (a sinusoidal log that starts and ends at
  // rest kept its first and last samples at 1-2 mm/s, 2-3 N off the law).
  for (std::size_t j = 0; j < std::min(n, reach); ++j) s.fate[j] = s.fate[n - 1 - j] = Fate::stationary;
  // Pre-sliding: after rest or a reversal the first `presliding_m` of travel is a nonlinear
  // spring with hysteresis, not the sliding law (PHYSICS.md §8).
  double travelled = 0;
  for (std::size_t i = 1; i < n; ++i) {
    if (s.fate[i] == Fate::stationary) {
      travelled = 0;
      continue;
    }
    travelled += std::abs(s.velocity_m_s[i]) * (run.time_s[i] - run.time_s[i - 1]);
    if (travelled < o.presliding_m) s.fate[i] = Fate::settling;
  }
  if (motion == Motion::position_m) check_monotone(run, s, reach);
  drop_force_steps(run, reach, s);
  std::vector<double> kept_a;
  for (std::size_t i = 0; i < n; ++i)
    if (s.fate[i] == Fate::kept) kept_a.push_back(s.acceleration_m_s2[i]);
  if (kept_a.size() < 20)
    throw SampleError(0, fmt::format("{} of {} samples in motion (faster than {:.3g} m/s, away from reversals): too few "
                                     "to read as a trajectory",
                                     kept_a.size(), n, rest_m_s));
  if (rms(kept_a) < o.max_acceleration_m_s2)
    throw SampleError(0, fmt::format("the trajectory never accelerates (RMS {:.3g} m/s² in motion, under {} m/s²): its "
                                     "moving mass cannot be told from friction; read it as plateaus "
                                     "(segmentation = \"plateaus\")",
                                     rms(kept_a), o.max_acceleration_m_s2));
  return s;
}

}  // namespace

Segmented segment(const RunSamples& run, Motion motion, const RawFrictionOptions& o) {
  // The filter's cost, samples × window, before it runs.
  const double work = static_cast<double>(run.time_s.size()) * static_cast<double>(o.velocity_window);
  if (work > io::kMaxFilterWork)
    throw SampleError(0, fmt::format("{} samples filtered over velocity_window = {} take {:.2g} operations: at most {:.2g} "
                                     "(docs/formats.md#limits); a shorter window or a shorter log",
                                     run.time_s.size(), o.velocity_window, work, io::kMaxFilterWork));
  if (o.segmentation == RawSegmentation::trajectory) return segment_trajectory(run, motion, o);
  Segmented s;
  // The velocity as the classification sees it: filtered over the window either way (a drive's
  // velocity feedback is noisy too); a plateau's own velocity is the unfiltered one's mean.
  if (motion == Motion::position_m) {
    s.velocity_m_s = local_slope(run.time_s, run.motion, o.velocity_window);
    s.acceleration_m_s2 = window_difference(run.time_s, s.velocity_m_s, o.velocity_window);
  } else {
    LocalLine line = local_line(run.time_s, run.motion, o.velocity_window);
    s.velocity_m_s = std::move(line.value);
    s.acceleration_m_s2 = std::move(line.slope);
  }
  // Twice: the samples off their stretch's speed are transients, with a settling time after.
  classify(run, o, std::vector<bool>(run.time_s.size(), false), s);
  classify(run, o, off_speed(o, s), s);
  if (motion == Motion::position_m) check_monotone(run, s, o.velocity_window / 2);
  group(run, motion, o, s);
  if (s.plateaus.empty()) {
    RunSegmentation counts;
    tally(s, counts);
    throw SampleError(0, fmt::format("no constant-velocity plateau of at least {} samples in {} samples ({} accelerating, "
                                     "{} settling, {} at rest, {} in shorter plateaus): too few samples per plateau; "
                                     "lower --min-plateau or --settling, or raise --max-acceleration; a drive's log that "
                                     "never holds a speed is read whole with --segmentation trajectory",
                                     o.min_plateau_samples, run.time_s.size(), counts.dropped_acceleration,
                                     counts.dropped_settling, counts.dropped_stationary, counts.dropped_short));
  }
  return s;
}

Travel travel(const RunSamples& run, Motion motion, const Segmented& s, const RawFrictionOptions& o) {
  Travel out;
  out.position_m = motion == Motion::position_m ? run.motion : running_integral(run.time_s, run.motion);
  const std::size_t n = out.position_m.size();
  const double rest_m_s = std::max(o.min_speed_m_s, 3 * s.sigma_v);
  out.distance_since_reversal_m.resize(n);
  out.time_since_reversal_s.resize(n);
  std::size_t turn = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool turning = i > 0 && sign_of(s.velocity_m_s[i]) != sign_of(s.velocity_m_s[i - 1]);
    if (std::abs(s.velocity_m_s[i]) < rest_m_s || turning) turn = i;
    out.distance_since_reversal_m[i] = std::abs(out.position_m[i] - out.position_m[turn]);
    out.time_since_reversal_s[i] = run.time_s[i] - run.time_s[turn];
  }
  return out;
}

void tally(const Segmented& s, RunSegmentation& out) {
  out.samples = s.fate.size();
  out.kept = out.dropped_acceleration = out.dropped_settling = out.dropped_stationary = out.dropped_short = 0;
  for (Fate f : s.fate) {
    switch (f) {
      case Fate::kept: ++out.kept; break;
      case Fate::acceleration: ++out.dropped_acceleration; break;
      case Fate::settling: ++out.dropped_settling; break;
      case Fate::stationary: ++out.dropped_stationary; break;
      case Fate::short_plateau: ++out.dropped_short; break;
    }
  }
  out.plateaus = s.plateaus;
  out.filter_window = s.window;
  out.filter_window_s = s.window_s;
  out.velocity_noise_m_s = s.sigma_v;
  out.acceleration_noise_m_s2 = s.sigma_a;
}

std::vector<std::string> sign_warnings(const std::string& run, const std::string& force_column, const RunSamples& samples,
                                       const Segmented& s, const RawFrictionOptions& o) {
  const ForceSign sign = o.force_sign;
  std::vector<std::string> warnings;
  std::size_t kept = 0, negative = 0;
  // Per sense of motion: samples with a positive and a negative raw force.
  std::size_t positive_force[2] = {0, 0}, negative_force[2] = {0, 0};
  for (std::size_t i = 0; i < s.fate.size(); ++i) {
    if (s.fate[i] != Fate::kept) continue;
    ++kept;
    negative += friction_N(samples, s, o, i) < 0;
    const int sense = s.sense(i) > 0;
    positive_force[sense] += samples.force_N[i] > 0;
    negative_force[sense] += samples.force_N[i] < 0;
  }
  const auto mostly = [](std::size_t part, std::size_t whole) { return whole != 0 && part >= 0.9 * static_cast<double>(whole); };
  const std::size_t forward = positive_force[1] + negative_force[1], backward = positive_force[0] + negative_force[0];
  const bool reverses = forward != 0 && backward != 0;
  if (sign != ForceSign::magnitude && reverses &&
      ((mostly(positive_force[1], forward) && mostly(positive_force[0], backward)) ||
       (mostly(negative_force[1], forward) && mostly(negative_force[0], backward)))) {
    warnings.push_back(fmt::format("run '{}': {} keeps one sign although the motion reverses: it looks like a "
                                   "magnitude; give --force-sign magnitude (force_sign = \"magnitude\" in the "
                                   "manifest's [raw])",
                                   run, force_column));
  } else if (mostly(negative, kept)) {
    const ForceSign other = sign == ForceSign::opposes_motion ? ForceSign::follows_motion : ForceSign::opposes_motion;
    warnings.push_back(fmt::format("run '{}': the friction comes out negative on {:.0f} % of the kept samples with "
                                   "--force-sign {}: the force's sign convention looks reversed; give --force-sign {}",
                                   run, 100.0 * static_cast<double>(negative) / static_cast<double>(kept),
                                   to_string(sign), to_string(other)));
  }
  return warnings;
}

}  // namespace raw
}  // namespace lmcal
