// A raw friction log's samples gathered per run, each run cut into plateaus (raw_friction.hpp)
// and its kept samples put into the log.
#include "friction_file_loader.hpp"

#include <algorithm>
#include <cmath>

#include "lmcal/error.hpp"

namespace lmcal::detail::friction_reading {

void FileLoader::read_raw_row(std::uint32_t run_index, std::uint32_t guide_index, double t, const FrictionConditions<double>& c,
                              double nu40) {
  const double motion = reader_.number(*motion_, false);
  const double force = reader_.number(*column(kForce), true);
  if (std::isnan(force)) {
    ++skipped_;
    return;
  }
  const bool merge = check_time_order(run_index, t, true);
  if (raw_index_.size() <= run_index) raw_index_.resize(run_index + 1, kNone);
  if (raw_index_[run_index] == kNone) {
    raw_index_[run_index] = raw_runs_.size();
    raw_runs_.push_back({.run = run_index});
    if (raw_runs_.size() == 1) raw_runs_.back().reserve(reader_.estimated_rows());  // most raw files hold one run
  }
  RawRun& r = raw_runs_[raw_index_[run_index]];
  if (merge && !r.line.empty()) {
    const double k = r.last_merged;
    r.samples.motion.back() = (r.samples.motion.back() * k + motion) / (k + 1);
    r.samples.force_N.back() = (r.samples.force_N.back() * k + force) / (k + 1);
    ++r.last_merged;
    ++r.merged;
    ++merged_;
    return;
  }
  r.samples.time_s.push_back(t);
  r.samples.motion.push_back(motion);
  r.samples.force_N.push_back(force);
  r.line.push_back(reader_.line());
  r.last_merged = 1;
  r.add_setup({guide_index, c, nu40});
}

void FileLoader::segment_raw_runs() {
  RunSegmentation total;
  for (RawRun& r : raw_runs_) {
    const std::string& name = log_.run_names[r.run];
    raw::Segmented s;
    try {
      s = raw::segment(r.samples, motion_kind_, raw_);
    } catch (const raw::SampleError& e) {
      csv::fail_at_cell(file_.path, r.line[e.sample], motion_->cell, fmt::format("run '{}': {}", name, e.what()));
    }
    RunSegmentation seg{.run = name, .file = report_.file};
    raw::tally(s, seg);
    seg.averaged_duplicates = r.merged;
    // On an inclined axis the drive holds the weight: its force may keep one sign both ways.
    if (!(s.trajectory() && raw_.axis_incline_deg != 0))
      for (const std::string& w : raw::sign_warnings(name, column(kForce)->header, r.samples, s, raw_))
        report_.warnings.push_back(w);
    if (!s.trajectory() && 3 * seg.kept < 2 * seg.samples)
      report_.warnings.push_back(fmt::format(
          "run '{}': the plateau reader kept {} of {} samples ({:.0f} %): a drive's log that never holds a speed is "
          "read whole with --segmentation trajectory (segmentation = \"trajectory\" in the manifest's [raw]), which "
          "fits the moving mass with the law; or shorten --settling ({} s)",
          name, seg.kept, seg.samples, 100.0 * static_cast<double>(seg.kept) / static_cast<double>(std::max<std::size_t>(seg.samples, 1)),
          raw_.settling_s));
    const raw::Travel travel = raw::travel(r.samples, motion_kind_, s, raw_);
    for (std::size_t i = 0; i < s.fate.size(); ++i) {
      if (s.fate[i] != raw::Fate::kept) continue;
      // A plateau's sample takes its plateau's speed; a trajectory's, its own filtered one.
      const double v = s.trajectory() ? s.velocity_m_s[i] : s.plateaus[s.plateau[i]].velocity_m_s;
      // A plateau's speed comes from positions over time: held to the range a column's is.
      if (const PhysicalRange range = physical_range(Quantity::velocity); !range.contains(v)) {
        csv::fail_at_cell(file_.path, r.line[i], motion_->cell,
                          fmt::format("run '{}': {}", name,
                                      out_of_range_message("the plateau's velocity_m_s", fmt::format("{:g}", v), range)));
      }
      const SampleSetup& setup = r.setups[r.setup[i]];
      FrictionConditions<double> c = setup.conditions;
      c.velocity_m_s = std::abs(v);
      c.direction = v < 0 ? -1.0 : 1.0;
      c.acceleration_m_s2 = s.trajectory() ? s.acceleration_m_s2[i] : 0.0;
      c.position_m = travel.position_m[i];
      c.distance_since_reversal_m = travel.distance_since_reversal_m[i];
      log_.append(r.run, setup.guide, r.samples.time_s[i], c, raw::friction_N(r.samples, s, raw_, i),
                  setup.viscosity40, static_cast<std::uint32_t>(r.line[i]));
      log_.time_since_reversal_s.back() = travel.time_since_reversal_s[i];
    }
    log_.raw_traces.push_back(thin_trace(name, r.samples, s));
    total.kept += seg.kept;
    total.dropped_acceleration += seg.dropped_acceleration;
    total.dropped_settling += seg.dropped_settling;
    total.dropped_stationary += seg.dropped_stationary;
    total.dropped_short += seg.dropped_short;
    log_.segmentation.push_back(std::move(seg));
  }
  const auto skip = [&](std::size_t count, const std::string& reason) {
    if (count != 0) report_.skipped[reason] = count;
  };
  skip(skipped_, column(kForce)->header + " empty or NaN");
  skip(merged_, "merged into a sample at the same time");
  skip(total.dropped_acceleration,
       raw_.segmentation == RawSegmentation::trajectory
           ? std::string("at a step of the drive force (a jump 5 σ out of its trend, or within the filter's reach of "
                         "one: where in the sample interval it fell is unknown)")
           : fmt::format("accelerating (|a| > {} m/s²)", raw_.max_acceleration_m_s2));
  if (raw_.segmentation == RawSegmentation::trajectory) {
    log_.trajectory = true;
    log_.axis_incline_deg = raw_.axis_incline_deg;
    skip(total.dropped_stationary, "at rest or reversing (slower than max(min_speed, 3 σ_v), or within the filter's "
                                   "reach of such a sample: static friction, not the sliding law) or within the "
                                   "filter's reach of the log's ends (a window cut short)");
    skip(total.dropped_settling, fmt::format("pre-sliding (the first {} mm of travel after rest or a reversal)",
                                             raw_.presliding_m * 1e3));
  } else {
    skip(total.dropped_settling, fmt::format("settling ({} s after an acceleration)", raw_.settling_s));
    skip(total.dropped_stationary, fmt::format("at rest (speed < {} m/s)", raw_.min_speed_m_s));
  }
  skip(total.dropped_short, fmt::format("in plateaus shorter than {} samples", raw_.min_plateau_samples));
  report_.rows_kept = total.kept;
}

RawTrace FileLoader::thin_trace(const std::string& run, const raw::RunSamples& samples, const raw::Segmented& s) {
  RawTrace trace{.run = run};
  const std::size_t n = samples.time_s.size();
  const std::size_t stride = std::max<std::size_t>(1, (n + RawTrace::kMaxPoints - 1) / RawTrace::kMaxPoints);
  for (std::size_t i = 0; i < n; i += stride) {
    trace.time_s.push_back(samples.time_s[i]);
    trace.velocity_m_s.push_back(s.velocity_m_s[i]);
    trace.force_N.push_back(samples.force_N[i]);
  }
  return trace;
}

}  // namespace lmcal::detail::friction_reading
