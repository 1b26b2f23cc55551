// The thermal fit's inputs: every run prepared for the rail model (ambient, sensors, records,
// initial temperature, heat and its prior), and the friction fit a two-stage fit reads.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "io/json_input.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/io/limits.hpp"
#include "lmcal/io/units.hpp"
#include "thermal_prepared.hpp"

namespace lmcal {

using detail::PreparedRun;
using detail::PreparedRunInfo;
using detail::kGivenHeat;
using detail::kMeasuredMeanFriction;
using detail::kMeasuredStartFriction;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double mean_of_finite(const std::vector<double>& values, std::size_t from, std::size_t to) {
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t i = from; i < std::min(to, values.size()); ++i)
    if (!std::isnan(values[i])) {
      sum += values[i];
      ++n;
    }
  return n ? sum / static_cast<double>(n) : kNaN;
}

// The change of a channel over the run: mean of its last ten records minus its first ten.
double rise(const std::vector<double>& values) {
  const std::size_t n = values.size(), k = std::min<std::size_t>(10, n);
  return mean_of_finite(values, n - k, n) - mean_of_finite(values, 0, k);
}

// The scale of a channel's signal: the span of its ten-record means over the run (highest minus
// lowest). A run that heats and cools back rises by about 0 from start to end, but spans its
// whole excursion; the means keep the thermocouple's noise out of the span.
double span(const std::vector<double>& values) {
  const std::size_t n = values.size(), k = std::min<std::size_t>(10, n);
  double low = std::numeric_limits<double>::infinity(), high = -low;
  for (std::size_t first = 0; first + k <= n; first += k) {
    const double m = mean_of_finite(values, first, first + k);
    if (std::isfinite(m)) low = std::min(low, m), high = std::max(high, m);
  }
  return high >= low ? high - low : kNaN;
}

// Whether run's thermocouple offsets are fitted (ThermalOffsets); `note` says why not.
bool offsets_determined(const ThermalRun& run, double ambient_start_C, const ThermalFitOptions& o, std::string& note) {
  if (o.offsets == ThermalOffsets::fitted) return true;
  if (o.offsets == ThermalOffsets::held) {
    note = "offsets held at 0 (asked)";
    return false;
  }
  const ThermalTrace& trace = run.trace;
  for (const auto& channel : trace.rail) {
    std::size_t end = 0;
    while (end < trace.size() && trace.time_s[end] - trace.time_s.front() <= 60.0) ++end;
    const double start = mean_of_finite(channel.values, 0, std::max<std::size_t>(end, 1));
    if (!(std::abs(start - ambient_start_C) <= o.isothermal_tolerance_K)) {
      note = fmt::format("offsets held at 0: {} starts {:.2f} K from the ambient (more than {} K), so the run does not "
                         "start isothermal and its offsets cannot be told from the rail's own temperature",
                         channel.name, start - ambient_start_C, o.isothermal_tolerance_K);
      return false;
    }
  }
  return true;
}

// Whether the manifest gives the whole heat (no phase of it is friction × speed).
bool heat_given(const ThermalRun& run) {
  if (run.heat_rate_W || !run.trace.heat_rate_W.empty()) return true;
  return !run.schedule.empty() &&
         std::all_of(run.schedule.begin(), run.schedule.end(), [](const ThermalPhase& p) { return p.heat_rate_W.has_value(); });
}

// The block's speed for the geometry (the `moving` source, the velocity regressors): the run's,
// else the fastest phase's. A `moving` block cannot change speed: a schedule of speeds is refused.
double run_velocity_m_s(const ThermalRun& run, SourceModel source) {
  double fastest = 0;
  for (const ThermalPhase& p : run.schedule) fastest = std::max(fastest, p.velocity_m_s.value_or(0.0));
  const double V = run.velocity_m_s > 0 ? run.velocity_m_s : fastest;
  for (const ThermalPhase& p : run.schedule)
    if (source == SourceModel::moving && p.velocity_m_s && *p.velocity_m_s != V)
      throw InvalidParameter(run.id, "the moving source keeps the block at one speed; a schedule of speeds (here "
                                     "a phase at " + fmt::format("{} m/s", *p.velocity_m_s) +
                                     ") needs the averaged or paper source");
  return V;
}

// Q_f(t) of a run with a schedule or a measured power (empty otherwise), t since the first
// record; `friction_heat_W(V)` is friction × speed for the phases that give a speed.
template <typename FrictionHeat>
HeatRateSchedule<double> heat_schedule_of(const ThermalRun& run, const FrictionHeat& friction_heat_W) {
  HeatRateSchedule<double> schedule;
  for (std::size_t i = 0; i < run.trace.heat_rate_W.size(); ++i)
    schedule.add(run.trace.time_s[i] - run.trace.time_s.front(), run.trace.heat_rate_W[i]);
  std::vector<double> from_s, heat_W;
  for (const ThermalPhase& p : run.schedule) {
    from_s.push_back(p.from_s);
    heat_W.push_back(p.heat_rate_W ? *p.heat_rate_W : friction_heat_W(*p.velocity_m_s));
  }
  if (!from_s.empty()) schedule = HeatRateSchedule<double>::steps(from_s, heat_W);
  return schedule;
}

// Fewer records cannot tell the rail's heating course (hours) from the sensors' noise.
// A record counts when some thermocouple has a value in it.
void check_records(const ThermalRun& run, const ThermalFitOptions& o) {
  const ThermalTrace& trace = run.trace;
  if (o.every < 1) throw InvalidParameter("every", 0.0, "at least 1");
  constexpr std::size_t kMinRecords = 10;
  std::size_t records = 0;
  for (std::size_t i = 0; i < trace.size(); i += o.every)
    records += std::any_of(trace.rail.begin(), trace.rail.end(), [&](const TemperatureChannel& c) { return std::isfinite(c.values[i]); });
  if (records < kMinRecords)
    throw InvalidParameter(run.id, fmt::format("{} records with a thermocouple value{} to fit: a thermal run needs at least {} "
                                               "to follow the rail's heating",
                                               records, o.every > 1 ? " kept (--every)" : "", kMinRecords));
}

// Ambient: the mean of the ambient sensors (NaN left out), or the one named; the manifest's
// constant ambient_C for a CSV without ambient columns.
AmbientTrace ambient_of(const ThermalRun& run, const ThermalFitOptions& o) {
  const ThermalTrace& trace = run.trace;
  AmbientTrace ambient;
  const double t0 = trace.time_s.front();
  if (trace.ambient.empty() && run.ambient_C) ambient = AmbientTrace::constant(*run.ambient_C);
  for (std::size_t i = 0; i < trace.size() && !trace.ambient.empty(); ++i) {
    double T = kNaN;
    if (o.ambient == "mean") {
      double sum = 0;
      int count = 0;
      for (const auto& c : trace.ambient)
        if (!std::isnan(c.values[i])) {
          sum += c.values[i];
          ++count;
        }
      if (count) T = sum / count;
    } else {
      const auto it = std::find_if(trace.ambient.begin(), trace.ambient.end(), [&](auto& c) { return c.name == o.ambient; });
      if (it == trace.ambient.end())
        throw InvalidParameter("ambient", fmt::format("run {} has no ambient column '{}'", run.id, o.ambient));
      T = it->values[i];
    }
    if (std::isnan(T)) continue;
    ambient.time_s.push_back(trace.time_s[i] - t0);
    ambient.temperature_C.push_back(T);
  }
  const bool constant_ambient = ambient.time_s.size() == 1 && trace.ambient.empty();
  if (!constant_ambient && (ambient.time_s.empty() || ambient.time_s.front() > 0 ||
                            ambient.time_s.back() < trace.time_s.back() - t0))
    throw InvalidParameter(run.id, "the ambient record must cover the run from its first to its last record");
  return ambient;
}

// The sensors' names, positions and spans, and their readings at the fitted records.
void add_sensors_and_records(const ThermalRun& run, const ThermalFitOptions& o, PreparedRunInfo& out) {
  const ThermalTrace& trace = run.trace;
  PreparedRun& pr = out.run;
  const double t0 = trace.time_s.front();
  for (const auto& channel : trace.rail) {
    // Labelled by name, not by the unit its column was written in: "tc1" beside values in °C,
    // not "tc1_K" (the header stays where two columns would share a name).
    const auto split = split_unit(channel.name, Quantity::temperature);
    const bool shared = split && std::any_of(trace.rail.begin(), trace.rail.end(), [&](const TemperatureChannel& other) {
      const auto o = split_unit(other.name, Quantity::temperature);
      return &other != &channel && o && o->name == split->name;
    });
    pr.sensor_names.push_back(split && !shared ? split->name : channel.name);
    pr.sensor_positions_m.push_back(run.sensor_position_m.at(channel.name));
    out.span_K.push_back(span(channel.values));
  }
  for (std::size_t i = 0; i < trace.size(); i += o.every) {
    pr.times_s.push_back(trace.time_s[i] - t0);
    if (i < trace.line.size()) pr.lines.push_back(trace.line[i]);
    std::vector<double> row;
    for (const auto& channel : trace.rail) row.push_back(channel.values[i]);
    pr.measured.push_back(std::move(row));
  }
}

// Initial rail temperature: the thermocouples' first reading, or (offsets fitted) the
// ambient at the start, averaged over the first minute: one noisy sample would start the
// rail off its equilibrium by the sensors' noise, a transient of the rail's time constant.
// Decides whether the run's offsets are fitted too (they take the ambient's start).
double initial_temperature_C(const ThermalRun& run, const ThermalFitOptions& o, PreparedRunInfo& out) {
  const ThermalTrace& trace = run.trace;
  PreparedRun& pr = out.run;
  std::vector<double> first;
  for (const auto& channel : trace.rail) first.push_back(channel.values.front());
  double T0 = mean_of_finite(first, 0, first.size());
  double ambient_start = 0;
  {
    std::size_t n = 0;
    for (std::size_t i = 0; i < pr.ambient.time_s.size() && (n == 0 || pr.ambient.time_s[i] <= 60.0); ++i, ++n)
      ambient_start += pr.ambient.temperature_C[i];
    ambient_start /= static_cast<double>(n);
  }
  out.info.offsets_fitted = offsets_determined(run, ambient_start, o, out.info.offsets_note);
  pr.fit_offsets = out.info.offsets_fitted;
  if (std::isnan(T0) || pr.fit_offsets) T0 = ambient_start;
  return T0;
}

// Heat: given in the manifest (a heater, a measured power: it wins over o.heat), or friction ×
// speed: the friction law at the start (the rail and grease at the ambient, which the two
// ambient sensors measure better than one biased thermocouple), or the measured friction:
// at the start temperature when the manifest gives it, else the run's mean (and a
// temperature-following heat then keeps that mean). A schedule's speed phases take the same
// friction, at their own speed. Returns the heat input taken (o.heat, `automatic` resolved).
HeatInput choose_heat_source(const ThermalRun& run, const GuideSpec& spec, const ThermalFitOptions& o, bool given,
                             PreparedRunInfo& out) {
  PreparedRun& pr = out.run;
  HeatInput heat = o.heat;
  const bool measured = run.mean_friction_N || run.start_friction_N;
  if (heat == HeatInput::automatic) heat = o.friction || !measured ? HeatInput::friction_law : HeatInput::measured_friction;
  if (!given && heat == HeatInput::measured_friction) {
    if (!measured)
      throw InvalidParameter(run.id, "the run has no mean_friction_N or start_friction_N in the manifest; give a friction "
                                     "fit (--friction)");
    pr.heat_is_run_mean = !run.start_friction_N && run.schedule.empty();
    out.info.heat_source = run.start_friction_N ? kMeasuredStartFriction : kMeasuredMeanFriction;
  }
  if (!given) {
    FrictionConstants<double> k = o.friction ? *o.friction : paper_friction_constants();
    if (run.viscosity40_mm2_s) {  // the run's oil: ν at 40 °C
      k.nu_ref_mm2_s = *run.viscosity40_mm2_s;
      k.T_ref_C = 40.0;
    }
    const FrictionConditions<double> c{
        .load_N = run.load_N,
        .preload_um = run.preload_um ? *run.preload_um : require(spec, &GuideSpec::preload_um, "preload_um"),
        .block_length_mm = run.block_length_mm ? *run.block_length_mm : require(spec, &GuideSpec::block_length_mm, "block_length_mm"),
        .velocity_m_s = pr.geometry.velocity_m_s,
        .temperature_C = pr.ambient.temperature_C.front()};
    pr.friction = k;
    pr.friction_effects = o.friction_effects;
    pr.conditions = c;  // the coupling extension scales Q_f by the law's change from here
    if (heat != HeatInput::measured_friction) {
      out.info.heat_source = o.friction ? "friction law (fitted constants)" : "friction law (the paper's constants)";
      if (!run.heat_rate_W) {  // with a schedule too: the law at the run's speed (phases at other speeds: approximately)
        out.info.heat_conditions = c;
        out.info.heat_viscosity40_mm2_s = k.nu_ref_mm2_s;
      }
    }
  } else {
    out.info.heat_source = kGivenHeat;
  }
  return heat;
}

// Friction × speed at the speed V: the measured friction, or the law at the run's conditions.
double friction_heat_W(const ThermalRun& run, const PreparedRun& pr, HeatInput heat, double V) {
  if (heat == HeatInput::measured_friction) return (run.start_friction_N ? *run.start_friction_N : *run.mean_friction_N) * V;
  FrictionConditions<double> c = pr.conditions;
  c.velocity_m_s = V;
  return heat_rate_with_effects_W(pr.friction, pr.friction_effects, c);
}

// The rail's parameters (material, α's start, h, T0) and its heat: the constant Q, or a
// schedule's (Q then its mean over the run, what RunInfo reports). Returns Q.
double set_rail_parameters(const ThermalRun& run, const GuideSpec& spec, const ThermalFitOptions& o, HeatInput heat,
                           double T0, PreparedRunInfo& out) {
  const ThermalTrace& trace = run.trace;
  PreparedRun& pr = out.run;
  const auto heat_W = [&](double V) { return friction_heat_W(run, pr, heat, V); };
  const HeatRateSchedule<double> schedule = heat_schedule_of(run, heat_W);
  const double duration_s = trace.time_s.back() - trace.time_s.front();
  const double Q = !schedule.empty() ? schedule.integral_J(0.0, duration_s) / duration_s
                   : run.heat_rate_W ? *run.heat_rate_W
                                     : heat_W(pr.geometry.velocity_m_s);
  // A heat no rail takes (friction constants far off, a law giving negative friction) would
  // only make the rail model's numbers leave the doubles.
  if (!kHeatRateRange.contains(Q)) {
    throw InvalidParameter(run.id, fmt::format("its heat rate is {} (from the {}): beyond the {:g} to {:g} W a rig's rail "
                                               "takes; check the friction constants{}",
                                               std::isfinite(Q) ? fmt::format("{:g} W", Q) : "not finite", out.info.heat_source, kHeatRateRange.low, kHeatRateRange.high,
                                               o.friction ? " (--friction)" : " and the run's conditions"));
  }
  if (!schedule.empty() && std::find(o.extensions.begin(), o.extensions.end(), "coupling") != o.extensions.end())
    throw InvalidParameter(run.id, "the coupling extension cannot follow a heat schedule or a measured power");
  pr.params = rail_material_of(spec);
  pr.params.heat_partition = o.alpha_start;
  pr.params.heat_rate_W = Q;
  pr.params.h_W_m2K = run.h_W_m2K ? *run.h_W_m2K : o.h_W_m2K;  // the run's own h wins where h is not fitted
  pr.params.initial_temperature_C = T0;
  pr.params.heat_schedule = schedule;
  return Q;
}

// The heat scale's prior: σ_Q from the temperature Q_f was evaluated at and the law's own
// uncertainty; σ_T from the thermocouples' second differences (insensitive to the warm-up).
void set_heat_prior(const ThermalRun& run, const ThermalFitOptions& o, bool given, PreparedRun& pr) {
  const ThermalTrace& trace = run.trace;
  if (o.fit_heat_scales && given) {  // the stated uncertainty of the given heat, else the law's share
    const double sigma_Q = run.heat_rate_uncertainty_W ? *run.heat_rate_uncertainty_W / detail::given_heat_reference_W(run)
                                                       : o.heat_law_uncertainty;
    if (!(sigma_Q > 0)) throw InvalidParameter("heat_rate_uncertainty_W", "the heat rate's uncertainty must be positive");
    pr.heat_prior_sigma_K = std::max(thermocouple_noise_K(trace), 1e-3);
    pr.heat_prior_weight = pr.heat_prior_sigma_K / sigma_Q;
  } else if (o.fit_heat_scales) {
    const double dT = 0.5;
    FrictionConditions<double> lo = pr.conditions, hi = pr.conditions;
    lo.temperature_C -= dT;
    hi.temperature_C += dT;
    const double dlnQ = std::log(heat_rate_with_effects_W(pr.friction, pr.friction_effects, hi) /
                                 heat_rate_with_effects_W(pr.friction, pr.friction_effects, lo)) / (2 * dT);
    const double sigma_Q = std::hypot(dlnQ * o.heat_temperature_uncertainty_K, o.heat_law_uncertainty);
    const double sigma_T = std::max(thermocouple_noise_K(trace), 1e-3);
    if (!(sigma_Q > 0)) throw InvalidParameter("heat_law_uncertainty", "the heat rate's uncertainty must be positive");
    pr.heat_prior_weight = sigma_T / sigma_Q;
    pr.heat_prior_sigma_K = sigma_T;
  }
}

// The estimates and covariance of a friction fit JSON (se and correlation), for the two-stage
// uncertainty; its bootstrap replicates are not in the file.
// The friction fit's estimates, SEs and covariance (from its correlation matrix and SEs), each
// field checked: a document of the wrong shape is refused naming the field.
FitResult friction_fit_uncertainty(const io::JsonFile& f) {
  FitResult fit;
  const nlohmann::json& parameters = f.array(f.root, "parameters", "");
  for (std::size_t i = 0; i < parameters.size(); ++i) {
    const std::string at = fmt::format("parameters[{}]", i);
    ParameterEstimate e;
    e.name = f.text(parameters[i], "name", at);
    e.value = f.number(parameters[i], "value", at, true);  // null: not estimated
    e.se = f.number(parameters[i], "se", at, true);
    if (e.se < 0) f.fail(at + ".se", "expected a standard error >= 0");
    e.free = f.flag(parameters[i], "free", at, false) && !f.flag(parameters[i], "held_unidentifiable", at, false);
    fit.parameters.push_back(e);
  }
  // The law's seven constants must all be there: a fit without them is no fit of this law.
  for (const char* name : kFrictionConstantNames) {
    const auto p = std::find_if(fit.parameters.begin(), fit.parameters.end(), [&](const ParameterEstimate& q) { return q.name == name; });
    if (p == fit.parameters.end() || !std::isfinite(p->value))
      f.fail("parameters", fmt::format("the friction law's {} has no value: expected all of {}", name, fmt::join(kFrictionConstantNames, ", ")));
  }
  const auto n = static_cast<Eigen::Index>(fit.parameters.size());
  fit.covariance = Eigen::MatrixXd::Zero(n, n);
  const nlohmann::json& matrix = f.array(f.object(f.root, "correlation", ""), "matrix", "correlation");
  if (matrix.size() != parameters.size())
    f.fail("correlation.matrix", fmt::format("expected {} rows, one per parameter, found {}", n, matrix.size()));
  for (Eigen::Index a = 0; a < n; ++a) {
    const nlohmann::json& row = matrix[static_cast<std::size_t>(a)];
    const std::string at = fmt::format("correlation.matrix[{}]", a);
    if (!row.is_array() || row.size() != parameters.size())
      f.fail(at, fmt::format("expected an array of {} numbers, found {}", n, io::json_type(row)));
    for (Eigen::Index b = 0; b < n; ++b) {
      const nlohmann::json& c = row[static_cast<std::size_t>(b)];
      if (!c.is_null() && !c.is_number()) f.fail(fmt::format("{}[{}]", at, b), "expected a number or null, found " + io::json_type(c));
      const double sa = fit.parameters[static_cast<std::size_t>(a)].se, sb = fit.parameters[static_cast<std::size_t>(b)].se;
      if (c.is_number() && std::isfinite(sa) && std::isfinite(sb)) {
        fit.covariance(a, b) = c.get<double>() * sa * sb;
        if (!std::isfinite(fit.covariance(a, b)))
          f.fail(fmt::format("{}[{}]", at, b), "the covariance it gives with the SEs (correlation × SE × SE) overflows");
      }
    }
  }
  return fit;
}

}  // namespace

namespace detail {

// The given heat its heat_rate_uncertainty_W is stated at: the run's, else the largest given.
double given_heat_reference_W(const ThermalRun& run) {
  if (run.heat_rate_W) return *run.heat_rate_W;
  double largest = 0;
  for (double q : run.trace.heat_rate_W) largest = std::max(largest, q);
  for (const ThermalPhase& p : run.schedule) largest = std::max(largest, p.heat_rate_W.value_or(0.0));
  return largest;
}

PreparedRunInfo prepare_run(const ThermalRun& run, const ThermalFitOptions& o) {
  check_records(run, o);
  const GuideSpec spec = resolved_guide(run);
  PreparedRunInfo out;
  PreparedRun& pr = out.run;
  pr.id = run.id;
  const double Lb1 = run.contact_length_mm ? *run.contact_length_mm : require(spec, &GuideSpec::contact_length_mm, "contact_length_mm");
  pr.geometry = rail_geometry_of(spec, run.rail_length_m, run.stroke_m, Lb1 * 1e-3, run_velocity_m_s(run, source_of(o)));
  pr.ambient = ambient_of(run, o);
  add_sensors_and_records(run, o, out);
  const double T0 = initial_temperature_C(run, o, out);
  const bool given = heat_given(run);
  const HeatInput heat = choose_heat_source(run, spec, o, given, out);
  const double Q = set_rail_parameters(run, spec, o, heat, T0, out);
  set_heat_prior(run, o, given, pr);
  out.info.id = run.id;
  out.info.velocity_m_s = pr.geometry.velocity_m_s;
  out.info.load_N = run.load_N;
  out.info.heat_rate_W = Q;
  out.info.initial_temperature_C = T0;
  out.info.ambient_difference_percent =
      run.trace.ambient.size() >= 2 ? percent_difference(rise(run.trace.ambient[0].values), rise(run.trace.ambient[1].values))
                                    : kNaN;
  return out;
}

std::vector<PreparedRun> prepared_runs(const ThermalDataSet& data, const ThermalFitOptions& o) {
  std::vector<PreparedRun> runs;
  for (const auto& run : data.runs) runs.push_back(prepare_run(run, o).run);
  return runs;
}

}  // namespace detail

double thermocouple_noise_K(const ThermalTrace& trace, double spacing_s, std::size_t* differences) {
  std::size_t k = 1;
  if (trace.size() >= 2 && spacing_s > 0) {
    const double step = (trace.time_s.back() - trace.time_s.front()) / static_cast<double>(trace.size() - 1);
    k = std::max<std::size_t>(1, static_cast<std::size_t>(spacing_s / step + 1e-9));
  }
  double ss = 0;
  std::size_t n = 0;
  for (const auto& channel : trace.rail)
    for (std::size_t i = k; i + k < channel.values.size(); ++i) {
      const double d2 = channel.values[i + k] - 2 * channel.values[i] + channel.values[i - k];
      if (!std::isnan(d2)) {
        ss += d2 * d2;
        ++n;
      }
    }
  if (differences) *differences = n;
  return n ? std::sqrt(ss / (6.0 * static_cast<double>(n))) : std::numeric_limits<double>::quiet_NaN();
}

void read_friction_fit(const std::string& json_file, ThermalFitOptions& options) {
  const io::JsonFile f = io::read_json_file(
      json_file, "a friction fit JSON (friction.json of lmcal fit friction, or calibrated_friction.json of lmcal calibrate)");
  if (f.root.value("kind", nlohmann::json()) != "friction fit")
    throw InputError(json_file, 0, 0, "expected a friction fit (\"kind\": \"friction fit\") written by lmcal fit friction");
  FitResult fit = friction_fit_uncertainty(f);
  FrictionConstants<double> k = paper_friction_constants();
  FrictionEffects<double> e;
  for (const ParameterEstimate& p : fit.parameters)
    if (double* law = find_law_parameter(k, e, p.name); law && std::isfinite(p.value)) *law = p.value;
  try {
    validate(k);
  } catch (const InvalidParameter& bad) {
    f.fail("parameters", bad.what());
  }
  options.friction = k;
  options.friction_effects = e;
  options.friction_fit = std::move(fit);
}

}  // namespace lmcal
