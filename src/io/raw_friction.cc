#include "io/raw_friction.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"

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
}

namespace raw {

namespace {

// f(i, lo, hi) at every sample i, over the window [lo, hi) of `window` samples centred on it
// (shorter at the ends).
template <typename F>
std::vector<double> over_windows(std::size_t n, std::size_t window, F f) {
  std::vector<double> out(n);
  const std::size_t half = window / 2;
  for (std::size_t i = 0; i < n; ++i) out[i] = f(i, i >= half ? i - half : 0, std::min(n, i + half + 1));
  return out;
}

}  // namespace

LocalLine local_line(const std::vector<double>& t, const std::vector<double>& y, std::size_t window) {
  LocalLine line;
  line.value.resize(t.size());
  line.slope = over_windows(t.size(), window, [&](std::size_t i, std::size_t lo, std::size_t hi) {
    // Offsets from sample i, for round-off (times may be epoch seconds); one pass of sums.
    double st = 0, sy = 0, stt = 0, sty = 0;
    for (std::size_t j = lo; j < hi; ++j) {
      const double dt = t[j] - t[i], dy = y[j] - y[i];
      st += dt;
      sy += dy;
      stt += dt * dt;
      sty += dt * dy;
    }
    const double count = static_cast<double>(hi - lo);
    const double var = stt - st * st / count;
    const double slope = var > 0 ? (sty - st * sy / count) / var : 0.0;
    line.value[i] = y[i] + sy / count - slope * st / count;  // the line at t_i
    return slope;
  });
  return line;
}

std::vector<double> local_slope(const std::vector<double>& t, const std::vector<double>& y, std::size_t window) {
  return local_line(t, y, window).slope;
}

std::vector<double> window_difference(const std::vector<double>& t, const std::vector<double>& y, std::size_t window) {
  return over_windows(t.size(), window, [&](std::size_t, std::size_t lo, std::size_t hi) {
    return hi - 1 > lo ? (y[hi - 1] - y[lo]) / (t[hi - 1] - t[lo]) : 0.0;
  });
}

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
void check_monotone(const RunSamples& run, const Segmented& s) {
  double count_m = 0;
  for (std::size_t j = 1; j < run.motion.size(); ++j) {
    if (s.fate[j] != Fate::stationary || s.fate[j - 1] != Fate::stationary) continue;
    const double step = std::abs(run.motion[j] - run.motion[j - 1]);
    if (step > 0 && (count_m == 0 || step < count_m)) count_m = step;
  }
  const double jitter_m = 2.5 * count_m;  // two counts, and the rounding of the logged numbers
  for (std::size_t j = 1; j < s.fate.size(); ++j) {
    if (s.fate[j] == Fate::stationary || s.fate[j - 1] == Fate::stationary) continue;
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

double friction_N(const RunSamples& run, const Segmented& s, const RawFrictionOptions& o, std::size_t i) {
  const double sense = s.fate[i] == Fate::kept ? sign_of(s.plateaus[s.plateau[i]].velocity_m_s) : sign_of(s.velocity_m_s[i]);
  const double inertia_N = o.moving_mass_kg * s.acceleration_m_s2[i];
  const double f = run.force_N[i];
  switch (o.force_sign) {
    case ForceSign::follows_motion: return sense * (f - inertia_N);
    case ForceSign::opposes_motion: return sense * (-f - inertia_N);
    case ForceSign::magnitude: return f - sense * inertia_N;
  }
  return f;
}

Segmented segment(const RunSamples& run, Motion motion, const RawFrictionOptions& o) {
  // The filter's cost, samples × window, before it runs.
  const double work = static_cast<double>(run.time_s.size()) * static_cast<double>(o.velocity_window);
  if (work > io::kMaxFilterWork)
    throw SampleError(0, fmt::format("{} samples filtered over velocity_window = {} take {:.2g} operations: at most {:.2g} "
                                     "(docs/formats.md#limits); a shorter window or a shorter log",
                                     run.time_s.size(), o.velocity_window, work, io::kMaxFilterWork));
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
  if (motion == Motion::position_m) check_monotone(run, s);
  group(run, motion, o, s);
  if (s.plateaus.empty()) {
    RunSegmentation counts;
    tally(s, counts);
    throw SampleError(0, fmt::format("no constant-velocity plateau of at least {} samples in {} samples ({} accelerating, "
                                     "{} settling, {} at rest, {} in shorter plateaus): too few samples per plateau; "
                                     "lower --min-plateau or --settling, or raise --max-acceleration",
                                     o.min_plateau_samples, run.time_s.size(), counts.dropped_acceleration,
                                     counts.dropped_settling, counts.dropped_stationary, counts.dropped_short));
  }
  return s;
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
    const int sense = s.plateaus[s.plateau[i]].velocity_m_s > 0;
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
