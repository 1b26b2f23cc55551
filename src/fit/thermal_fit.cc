#include "lmcal/fit/thermal_fit.hpp"

#include "lmcal/version.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>

#include "io/file_kind.hpp"
#include "io/json_input.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/io/csv_writer.hpp"
#include "lmcal/io/limits.hpp"
#include "lmcal/io/units.hpp"
#include "bounded_interval.hpp"
#include "fit_json.hpp"
#include "friction_model.hpp"
#include "lmcal/fit/friction_fit.hpp"
#include "thermal_model.hpp"
#include "thermal_terms.hpp"

namespace lmcal {

using detail::number;

using detail::ParameterSpec;
using detail::PreparedRun;
using detail::ThermalLayout;
using detail::ThermalModel;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// RunInfo::heat_source of a heat from the manifest's friction force.
constexpr const char* kMeasuredMeanFriction = "measured mean friction";
constexpr const char* kMeasuredStartFriction = "measured friction at the start temperature";
// ... and of a heat the manifest gives (heat_rate_W, a schedule's heats, the CSV's column).
constexpr const char* kGivenHeat = "given heat rate";

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

// The source model: the option's, unless an extension switches it.
SourceModel source_of(const ThermalFitOptions& o) {
  SourceModel source = o.source;
  for (const auto& name : o.extensions)
    if (const auto switched = detail::thermal_extension(name).source) source = *switched;
  return source;
}

// Whether the manifest gives the whole heat (no phase of it is friction × speed).
bool heat_given(const ThermalRun& run) {
  if (run.heat_rate_W || !run.trace.heat_rate_W.empty()) return true;
  return !run.schedule.empty() &&
         std::all_of(run.schedule.begin(), run.schedule.end(), [](const ThermalPhase& p) { return p.heat_rate_W.has_value(); });
}

// The given heat its heat_rate_uncertainty_W is stated at: the run's, else the largest given.
double given_heat_reference_W(const ThermalRun& run) {
  if (run.heat_rate_W) return *run.heat_rate_W;
  double largest = 0;
  for (double q : run.trace.heat_rate_W) largest = std::max(largest, q);
  for (const ThermalPhase& p : run.schedule) largest = std::max(largest, p.heat_rate_W.value_or(0.0));
  return largest;
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

struct Prepared {
  PreparedRun run;
  RunInfo info;
  std::vector<double> span_K;  // measured span of every sensor (the scale of its max error)
};

Prepared prepare_run(const ThermalRun& run, const ThermalFitOptions& o) {
  const ThermalTrace& trace = run.trace;
  if (o.every < 1) throw InvalidParameter("every", 0.0, "at least 1");
  // Fewer records cannot tell the rail's heating course (hours) from the sensors' noise.
  // A record counts when some thermocouple has a value in it.
  constexpr std::size_t kMinRecords = 10;
  std::size_t records = 0;
  for (std::size_t i = 0; i < trace.size(); i += o.every)
    records += std::any_of(trace.rail.begin(), trace.rail.end(), [&](const TemperatureChannel& c) { return std::isfinite(c.values[i]); });
  if (records < kMinRecords)
    throw InvalidParameter(run.id, fmt::format("{} records with a thermocouple value{} to fit: a thermal run needs at least {} "
                                               "to follow the rail's heating",
                                               records, o.every > 1 ? " kept (--every)" : "", kMinRecords));
  const GuideSpec spec = resolved_guide(run);
  Prepared out;
  PreparedRun& pr = out.run;
  pr.id = run.id;
  const double Lb1 = run.contact_length_mm ? *run.contact_length_mm : require(spec, &GuideSpec::contact_length_mm, "contact_length_mm");
  pr.geometry = rail_geometry_of(spec, run.rail_length_m, run.stroke_m, Lb1 * 1e-3, run_velocity_m_s(run, source_of(o)));

  // Ambient: the mean of the ambient sensors (NaN left out), or the one named; the manifest's
  // constant ambient_C for a CSV without ambient columns.
  const double t0 = trace.time_s.front();
  if (trace.ambient.empty() && run.ambient_C) pr.ambient = AmbientTrace::constant(*run.ambient_C);
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
    pr.ambient.time_s.push_back(trace.time_s[i] - t0);
    pr.ambient.temperature_C.push_back(T);
  }
  const bool constant_ambient = pr.ambient.time_s.size() == 1 && trace.ambient.empty();
  if (!constant_ambient && (pr.ambient.time_s.empty() || pr.ambient.time_s.front() > 0 ||
                            pr.ambient.time_s.back() < trace.time_s.back() - t0))
    throw InvalidParameter(run.id, "the ambient record must cover the run from its first to its last record");

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

  // Initial rail temperature: the thermocouples' first reading, or (offsets fitted) the
  // ambient at the start, averaged over the first minute: one noisy sample would start the
  // rail off its equilibrium by the sensors' noise, a transient of the rail's time constant.
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

  // Heat: given in the manifest (a heater, a measured power: it wins over o.heat), or friction ×
  // speed: the friction law at the start (the rail and grease at the ambient, which the two
  // ambient sensors measure better than one biased thermocouple), or the measured friction:
  // at the start temperature when the manifest gives it, else the run's mean (and a
  // temperature-following heat then keeps that mean). A schedule's speed phases take the same
  // friction, at their own speed.
  const bool given = heat_given(run);
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
  const auto friction_heat_W = [&](double V) {
    if (heat == HeatInput::measured_friction) return (run.start_friction_N ? *run.start_friction_N : *run.mean_friction_N) * V;
    FrictionConditions<double> c = pr.conditions;
    c.velocity_m_s = V;
    return heat_rate_with_effects_W(pr.friction, pr.friction_effects, c);
  };
  const HeatRateSchedule<double> schedule = heat_schedule_of(run, friction_heat_W);
  const double duration_s = trace.time_s.back() - t0;
  // Q: the constant heat, or a schedule's mean over the run (what RunInfo reports).
  const double Q = !schedule.empty() ? schedule.integral_J(0.0, duration_s) / duration_s
                   : run.heat_rate_W ? *run.heat_rate_W
                                     : friction_heat_W(pr.geometry.velocity_m_s);
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
  // The heat scale's prior: σ_Q from the temperature Q_f was evaluated at and the law's own
  // uncertainty; σ_T from the thermocouples' second differences (insensitive to the warm-up).
  if (o.fit_heat_scales && given) {  // the stated uncertainty of the given heat, else the law's share
    const double sigma_Q = run.heat_rate_uncertainty_W ? *run.heat_rate_uncertainty_W / given_heat_reference_W(run)
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
  out.info.id = run.id;
  out.info.velocity_m_s = pr.geometry.velocity_m_s;
  out.info.load_N = run.load_N;
  out.info.heat_rate_W = Q;
  out.info.initial_temperature_C = T0;
  out.info.ambient_difference_percent =
      trace.ambient.size() >= 2 ? percent_difference(rise(trace.ambient[0].values), rise(trace.ambient[1].values)) : kNaN;
  return out;
}

// Parameters and their layout for the runs given.
std::pair<ThermalLayout, std::vector<ParameterSpec>> layout_for(const std::vector<PreparedRun>& runs,
                                                                const ThermalFitOptions& o) {
  ThermalLayout layout;
  std::vector<ParameterSpec> specs = {{"alpha", "1", o.alpha_start, o.alpha_lower, o.alpha_upper, true}};
  layout.alpha = 0;
  if (o.fit_h) {
    layout.h = static_cast<int>(specs.size());
    specs.push_back({"h_W_m2K", "W/m2K", o.h_W_m2K, o.h_lower, o.h_upper, true});
  }
  for (const auto& name : o.extensions) {
    const detail::ThermalExtension& e = detail::thermal_extension(name);
    if (std::find(layout.extensions.begin(), layout.extensions.end(), &e) != layout.extensions.end())
      throw InvalidParameter("extension", fmt::format("'{}' is given twice", name));
    layout.extensions.push_back(&e);
    layout.extension_first.push_back(static_cast<int>(specs.size()));
    for (const auto& p : e.parameters) specs.push_back({p.name, p.unit, p.start, p.lower, p.upper, true, p.scale});
  }
  // The sensor terms: a coefficient each, sized so that 1 typical unit moves the readings by
  // 0.1 K; one period for the ambient-periodic terms, one τ per lag.
  std::vector<std::pair<double, int>> periods;  // start period -> its parameter
  for (std::size_t j = 0; j < o.sensor_terms.size(); ++j) {
    const ThermalSensorTerm& term = o.sensor_terms[j];
    double ss = 0, count = 0;
    for (const auto& run : runs)
      for (double phi : detail::sensor_term_regressor<double>(term.kind, term.scale_s, run.times_s, run.ambient,
                                                              run.geometry.velocity_m_s)) {
        const double rise = term.kind == ThermalTermKind::rise_time ? 10.0 : 1.0;  // a typical rise, K
        ss += phi * phi * rise * rise;
        count += 1;
      }
    const double rms = count > 0 ? std::sqrt(ss / count) : 0.0;
    const double typical = rms > 0 ? 0.1 / rms : 1.0;
    layout.terms.push_back(term);
    layout.term_coefficient.push_back(static_cast<int>(specs.size()));
    specs.push_back({fmt::format("c{} {}", j + 1, to_string(term.kind)), term_coefficient_unit(term.kind),
                     term.coefficient, -1e4 * typical, 1e4 * typical, true, typical});
    int scale = -1;
    if (term_has_scale(term.kind) && term.fit_scale) {
      const bool periodic = term.kind == ThermalTermKind::ambient_in_phase || term.kind == ThermalTermKind::ambient_quadrature;
      const auto shared = std::find_if(periods.begin(), periods.end(), [&](auto& p) { return p.first == term.scale_s; });
      if (periodic && shared != periods.end()) {
        scale = shared->second;
      } else {
        if (!(term.scale_s > 0) || !(term.scale_lower_s > 0) || !(term.scale_upper_s > term.scale_lower_s))
          throw InvalidParameter("sensor_terms", fmt::format("term {} ({}) needs a scale inside 0 < lower < upper", j + 1,
                                                             to_string(term.kind)));
        scale = static_cast<int>(specs.size());
        const std::string name = !periodic       ? fmt::format("tau{}_s", j + 1)
                                 : periods.empty() ? std::string("P_s")
                                                   : fmt::format("P{}_s", periods.size() + 1);
        specs.push_back({name, "s", std::clamp(term.scale_s, term.scale_lower_s, term.scale_upper_s), term.scale_lower_s,
                         term.scale_upper_s, true});
        if (periodic) periods.emplace_back(term.scale_s, scale);
      }
    }
    layout.term_scale.push_back(scale);
  }
  for (const auto& run : runs) {
    std::vector<int> offsets(run.sensor_names.size(), -1);
    for (std::size_t s = 0; s < offsets.size() && run.fit_offsets; ++s) {
      offsets[s] = static_cast<int>(specs.size());
      specs.push_back({fmt::format("offset {} {}", run.id, run.sensor_names[s]), "K", 0.0, -5.0, 5.0, true, 1.0, true});
    }
    layout.offsets.push_back(offsets);
    int initial = -1;
    if (o.fit_initial_temperature) {
      initial = static_cast<int>(specs.size());
      const double T0 = run.params.initial_temperature_C;
      specs.push_back({fmt::format("T0 {}", run.id), "C", T0, T0 - 10, T0 + 10, true, 1.0, true});
    }
    layout.initial.push_back(initial);
    int scale = -1;
    if (o.fit_heat_scales) {
      scale = static_cast<int>(specs.size());
      specs.push_back({fmt::format("heat_scale {}", run.id), "1", 1.0, 0.5, 2.0, true, 0.0, true});
    }
    layout.heat_scale.push_back(scale);
  }
  layout.size = static_cast<int>(specs.size());
  for (auto& spec : specs)
    for (const auto& [name, value] : o.parameter_start)
      if (name == spec.name) spec.start = std::clamp(value, spec.lower, spec.upper);
  return {layout, specs};
}

RailNumerics numerics_of(const ThermalFitOptions& o) {
  return {.source = source_of(o), .scheme = o.scheme, .half_rail_segments = o.half_rail_segments, .time_step_s = o.time_step_s};
}

void check_jet_size(const ThermalModel& model) {
  if (model.max_local_parameters() > 8)
    throw InvalidParameter("thermal fit", fmt::format("one run's simulation would depend on {} fitted parameters; at most 8 "
                                                      "(fewer extensions, or no offsets or initial temperatures)",
                                                      model.max_local_parameters()));
}

FitResult fit_runs(const std::vector<PreparedRun>& runs, const ThermalFitOptions& o) {
  auto [layout, specs] = layout_for(runs, o);
  const ThermalModel model(runs, layout, numerics_of(o));
  check_jet_size(model);
  return detail::solve_least_squares(model, specs, o.fit);
}

// Each run predicted by the global parameters (α, h, extensions) fitted to the others (one
// Gauss-Newton step from the joint optimum, with the run's own parameters held), its own
// nuisance parameters (offsets, T0, heat scale within its prior) then re-estimated from its
// records. What is scored is what the others teach about this run: its course over time,
// and its level through the heat scale's prior row (a scale far from 1 counts as error);
// not its thermocouples' biases.
double leave_one_run_out_rmse(const ThermalModel& model, const FitResult& joint, const detail::FinalState& state) {
  const auto& rows = model.rows();
  const ThermalLayout& layout = model.layout();
  const std::size_t runs = model.runs().size();
  std::vector<std::size_t> group(model.num_residuals(), runs);  // priors: never left out
  for (std::size_t k = 0; k < rows.size(); ++k) group[k] = rows[k].run;
  // A parameter on its bound stays there: the step is unconstrained, and would take a base
  // loss that the data push below 0 to a negative value, scoring a physics the fit refused.
  std::vector<bool> held;
  for (const auto& p : joint.parameters) held.push_back(!p.free || p.held_unidentifiable || p.at_bound);
  const detail::GroupNormalEquations sums = detail::group_normal_equations(state, group);
  double ss = 0;
  for (std::size_t r = 0; r < runs; ++r) {
    std::vector<int> own;
    for (int o : layout.offsets[r]) own.push_back(o);
    own.push_back(layout.initial[r]);
    own.push_back(layout.heat_scale.empty() ? -1 : layout.heat_scale[r]);
    std::erase_if(own, [&](int i) { return i < 0 || held[static_cast<std::size_t>(i)]; });
    std::vector<bool> held_r = held;
    for (int i : own) held_r[static_cast<std::size_t>(i)] = true;
    const Eigen::VectorXd step = detail::leave_group_out_step(sums, r, held_r);
    // The run's rows (and its heat-scale prior row), and its own parameters re-estimated.
    std::vector<Eigen::Index> mine;
    for (std::size_t k = model.first_row(r); k < rows.size() && rows[k].run == r; ++k) mine.push_back(static_cast<Eigen::Index>(k));
    const std::size_t data_rows = mine.size();
    for (std::size_t k = 0; k < model.prior_runs().size(); ++k)
      if (model.prior_runs()[k] == r) mine.push_back(static_cast<Eigen::Index>(rows.size() + k));
    Eigen::VectorXd e(static_cast<Eigen::Index>(mine.size()));
    Eigen::MatrixXd N(static_cast<Eigen::Index>(mine.size()), static_cast<Eigen::Index>(own.size()));
    for (std::size_t i = 0; i < mine.size(); ++i) {
      e[static_cast<Eigen::Index>(i)] =
          i < data_rows ? state.residuals[mine[i]] + state.jacobian.row(mine[i]).dot(step) : state.residuals[mine[i]];
      for (std::size_t j = 0; j < own.size(); ++j)
        N(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = state.jacobian(mine[i], own[j]);
    }
    if (!own.empty()) e += N * N.colPivHouseholderQr().solve(-e);
    ss += e.squaredNorm();  // with the prior row: a heat scale far from 1 counts against the model
  }
  return std::sqrt(ss / static_cast<double>(rows.size()));
}

// The heat's uncertainty (two-stage): the covariance of the runs' ln Q_f, and, when the
// friction fit brought bootstrap replicates, each replicate's ln Q* − ln Q̂.
struct HeatUncertainty {
  Eigen::MatrixXd covariance;          // runs × runs
  std::vector<Eigen::VectorXd> draws;
  std::string description;             // how it was counted; empty: not counted
  std::string missing;                 // what is not counted, and why
};

// ∂ ln Q_f(run) / ∂θ over the friction fit's parameters (central differences of the one law).
Eigen::RowVectorXd log_heat_gradient(const PreparedRun& run, const FitResult& friction) {
  const auto p = static_cast<Eigen::Index>(friction.parameters.size());
  Eigen::RowVectorXd g = Eigen::RowVectorXd::Zero(p);
  auto log_q = [&](std::size_t j, double value) {
    FrictionConstants<double> k = run.friction;
    FrictionEffects<double> e = run.friction_effects;
    if (double* law = find_law_parameter(k, e, friction.parameters[j].name)) *law = value;
    return std::log(heat_rate_with_effects_W(k, e, run.conditions));
  };
  for (std::size_t j = 0; j < friction.parameters.size(); ++j) {
    const ParameterEstimate& q = friction.parameters[j];
    if (!std::isfinite(q.se) || !(q.se > 0)) continue;
    const double h = 1e-3 * q.se;
    g[static_cast<Eigen::Index>(j)] = (log_q(j, q.value + h) - log_q(j, q.value - h)) / (2 * h);
  }
  return g;
}

HeatUncertainty heat_uncertainty(const std::vector<PreparedRun>& runs, const std::vector<RunInfo>& infos,
                                 const ThermalDataSet& data, const ThermalFitOptions& o) {
  const auto G = static_cast<Eigen::Index>(runs.size());
  HeatUncertainty h;
  h.covariance = Eigen::MatrixXd::Zero(G, G);
  std::vector<std::string> counted, missing;
  // Friction law: V₁ through ∇ ln Q_f, the replicates likewise.
  Eigen::MatrixXd gradient = Eigen::MatrixXd::Zero(G, o.friction_fit ? static_cast<Eigen::Index>(o.friction_fit->parameters.size()) : 0);
  // Measured mean friction: its stated uncertainty, one systematic error common to all runs.
  Eigen::VectorXd measured = Eigen::VectorXd::Zero(G);
  for (Eigen::Index r = 0; r < G; ++r) {
    const auto i = static_cast<std::size_t>(r);
    if (infos[i].heat_source == kMeasuredMeanFriction || infos[i].heat_source == kMeasuredStartFriction) {
      // Relative: a load cell's error is mostly its gain, the same for the start and the mean.
      const auto& run = data.runs[i];
      if (run.mean_friction_uncertainty_N) measured[r] = *run.mean_friction_uncertainty_N / *run.mean_friction_N;
      else missing.push_back(run.id + ": no mean_friction_uncertainty_N in the manifest");
    } else if (infos[i].heat_source == kGivenHeat) {
      // Relative at the largest given heat: a power meter's (or heater's) error is mostly its gain.
      const auto& run = data.runs[i];
      if (run.heat_rate_uncertainty_W) measured[r] = *run.heat_rate_uncertainty_W / given_heat_reference_W(run);
      else missing.push_back(run.id + ": no heat_rate_uncertainty_W in the manifest");
    } else if (o.friction_fit && o.friction_fit->covariance.allFinite()) {
      gradient.row(r) = log_heat_gradient(runs[i], *o.friction_fit);
    } else {
      missing.push_back(runs[i].id + (o.friction ? ": the friction fit's covariance is not known" : ": the paper's constants"));
    }
  }
  if (gradient.cols() > 0 && !gradient.isZero()) {
    h.covariance += gradient * o.friction_fit->covariance * gradient.transpose();
    counted.push_back("the friction fit's covariance through the law (delta method)");
    const Eigen::MatrixXd& d = o.friction_fit->uncertainty.bootstrap_draws;
    for (Eigen::Index b = 0; b < d.rows() && d.cols() == gradient.cols(); ++b)
      h.draws.push_back(gradient * d.row(b).transpose().unaryExpr([](double x) { return std::isnan(x) ? 0.0 : x; }));
  }
  if (!measured.isZero()) {
    h.covariance += measured * measured.transpose();
    counted.push_back("the measured friction's or given heat's stated uncertainty, as one systematic error of all runs");
    h.draws.clear();  // a mixture: the bootstrap draws from the covariance instead
  }
  h.description = fmt::format("{}", fmt::join(counted, "; "));
  if (!missing.empty()) h.missing = fmt::format("the heat's uncertainty is not counted for {}", fmt::join(missing, ", "));
  return h;
}

// E = ∂r/∂ln Q_f per run (rows × runs): the heat-scale columns of the Jacobian (data rows;
// a prior row does not depend on Q), from an auxiliary model with one held scale per run when
// the fit has none.
std::optional<Eigen::MatrixXd> heat_jacobian(const ThermalModel& model, const std::vector<double>& theta,
                                             const detail::FinalState& state) {
  const ThermalLayout& layout = model.layout();
  const auto G = static_cast<Eigen::Index>(model.runs().size());
  const auto data_rows = static_cast<Eigen::Index>(model.rows().size());
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(model.num_residuals()), G);
  const bool scaled = !layout.heat_scale.empty() && layout.heat_scale.front() >= 0;
  Eigen::MatrixXd J_aux;
  std::vector<int> column(static_cast<std::size_t>(G));
  if (scaled) {
    for (Eigen::Index r = 0; r < G; ++r) column[static_cast<std::size_t>(r)] = layout.heat_scale[static_cast<std::size_t>(r)];
  } else {
    ThermalLayout aux_layout = layout;
    aux_layout.heat_scale.clear();
    std::vector<double> aux_theta = theta;
    for (Eigen::Index r = 0; r < G; ++r) {
      column[static_cast<std::size_t>(r)] = aux_layout.size;
      aux_layout.heat_scale.push_back(aux_layout.size++);
      aux_theta.push_back(1.0);
    }
    const ThermalModel aux(model.runs(), aux_layout, model.numerics());
    if (aux.max_local_parameters() > 8) return std::nullopt;
    detail::evaluate_residuals(aux, aux_theta, {}, &J_aux);
  }
  const Eigen::MatrixXd& J = scaled ? state.jacobian : J_aux;
  for (Eigen::Index k = 0; k < data_rows; ++k) {
    const auto r = static_cast<Eigen::Index>(model.rows()[static_cast<std::size_t>(k)].run);
    const int c = column[static_cast<std::size_t>(r)];
    E(k, r) = J(k, c) * (scaled ? theta[static_cast<std::size_t>(c)] : 1.0);
  }
  return E;
}

// A global parameter's variance as the runs make it (α above all: the heat reaching each rail
// has its own error, which no record of the run sees). The joint fit weighs each run by its
// information (1/SE² of the run's own i.i.d. fit): θ̂ ≈ Σ c_r θ_r, and θ_r = θ + u_r + e_r, where
// e_r is the run's own error (its quoted SE, without an error common to all runs) and u_r what
// differs between runs unseen by any record (τ, REML, of the per-run θ). So
// Var(θ̂) = Σ c_r² (SE_r² + τ²), plus what is common to all runs (the heat's stated
// uncertainty), with t(runs − 1). A cluster-robust covariance estimates the same, but with a
// few runs carrying most of the information it falls well short (α: SD/SE 1.8 at 8 runs).
// Replaces a parameter's SE (the correlations kept) only where it is larger than the quoted
// one; a parameter that some run's own fit did not estimate keeps the quoted one.
void widen_to_the_runs(ThermalFitResult& result, double confidence) {
  FitResult& joint = result.joint;
  const std::size_t runs = result.per_run.size();
  if (runs < 3 || joint.covariance.rows() == 0) return;
  Uncertainty& u = joint.uncertainty;
  std::vector<std::string> widened;
  for (std::size_t a = 0; a < joint.parameters.size(); ++a) {
    ParameterEstimate& p = joint.parameters[a];
    if (p.per_run || !p.free || p.held_unidentifiable || p.interval == "none") continue;
    std::vector<Estimate> estimates;
    std::vector<double> info, own;
    for (const FitResult& run : result.per_run) {
      std::size_t j = 0;
      while (j < run.parameters.size() && run.parameters[j].name != p.name) ++j;
      const CovarianceSummary* iid = run.uncertainty.find("iid");
      if (j == run.parameters.size() || run.parameters[j].held_unidentifiable || !iid || !(iid->se[j] > 0)) break;
      const ParameterEstimate& q = run.parameters[j];
      if (!std::isfinite(q.value) || !(q.se > 0)) break;
      const Eigen::MatrixXd& given = run.uncertainty.covariance_given_input;
      const auto k = static_cast<Eigen::Index>(j);
      own.push_back(given.rows() > k ? given(k, k) : q.se * q.se);
      info.push_back(1 / (iid->se[j] * iid->se[j]));
      estimates.push_back({q.value, q.se});
    }
    if (estimates.size() != runs) continue;
    const RandomEffects re = random_effects(estimates, confidence);
    if (!std::isfinite(re.tau)) continue;
    const double total_info = std::accumulate(info.begin(), info.end(), 0.0);
    double runs_variance = 0;
    for (std::size_t r = 0; r < runs; ++r) runs_variance += std::pow(info[r] / total_info, 2) * (own[r] + re.tau * re.tau);
    const auto ja = static_cast<Eigen::Index>(a);
    const double quoted = joint.covariance(ja, ja);
    const double given = u.covariance_given_input.rows() > ja ? u.covariance_given_input(ja, ja) : quoted;
    const double common = std::max(quoted - given, 0.0);  // the heat's stated, common uncertainty
    if (!(runs_variance > given) || !(quoted > 0)) continue;
    const double variance = runs_variance + common, dof = static_cast<double>(runs - 1);
    const double d = std::sqrt(variance / quoted);
    joint.covariance.row(ja) *= d;
    joint.covariance.col(ja) *= d;
    p.se = std::sqrt(variance);
    // Welch-Satterthwaite with the common part known (ν = ∞).
    p.dof = std::min(1e7, variance * variance / (runs_variance * runs_variance / dof));
    const double t = student_t_quantile(1 - (1 - confidence) / 2, p.dof);
    // Within the bounds (α below 0 is no heat partition): where the wider t interval would cross
    // one, on the log scale of the distance to it (logit between two), bounded_interval.hpp.
    const detail::BoundedInterval bounded = detail::bounded_interval(p.value, p.se, t, p.lower, p.upper);
    p.ci_low = bounded.low;
    p.ci_high = bounded.high;
    if (p.interval == "linear" && bounded.method != "linear") {
      p.interval = bounded.method;
      u.notes.push_back(fmt::format("{}'s interval on the {} scale of its distance to its bounds [{:.4g}, {:.4g}]: the t "
                                    "interval, [{:.4g}, {:.4g}], would cross one",
                                    p.name, bounded.method == "clipped" ? "linear" : bounded.method, p.lower, p.upper,
                                    p.value - t * p.se, p.value + t * p.se));
    }
    // A profile interval (a bound inside it) widens about the estimate by the same factor, and
    // stays within the bounds.
    if (p.interval == "profile") {
      if (std::isfinite(p.profile_low)) p.profile_low = std::max(p.lower, p.value - d * (p.value - p.profile_low));
      if (std::isfinite(p.profile_high)) p.profile_high = std::min(p.upper, p.value + d * (p.profile_high - p.value));
    }
    widened.push_back(fmt::format("{} {:.3g} (tau {:.3g}, t with {:.1f} dof)", p.name, p.se, re.tau, p.dof));
    u.from_replicates.push_back(p.name);
  }
  if (widened.empty()) return;  // (scaling a row and column keeps the correlations)
  u.reason += fmt::format("; the SE of {} from the runs as replicates (notes)", widened.size() == 1 ? "one parameter" : "some parameters");
  u.notes.push_back(fmt::format(
      "SEs from the runs as replicates, sqrt(sum c_r^2 (SE_r^2 + tau^2)) plus any uncertainty common to all runs (c_r: each "
      "run's share of the joint fit's information; tau: the spread of the {} runs' own estimates beyond their SEs, REML): {}; "
      "the others quote {}",
      runs, fmt::join(widened, "; "), u.method));
}

// Step 2 of the two-stage fit: the heat's uncertainty into the joint fit's covariance.
void add_heat_uncertainty(const ThermalDataSet& data, const std::vector<PreparedRun>& runs, const ThermalModel& model,
                          const detail::FinalState& state, const ThermalFitOptions& o, ThermalFitResult& result) {
  const HeatUncertainty heat = heat_uncertainty(runs, result.runs, data, o);
  for (std::size_t r = 0; r < runs.size(); ++r) result.runs[r].heat_relative_se = std::sqrt(heat.covariance(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(r)));
  if (!heat.missing.empty()) result.joint.uncertainty.notes.push_back(heat.missing + ": alpha's interval may be too narrow");
  if (heat.description.empty()) return;
  if (o.fit.loss != RobustLoss::none) {
    result.joint.uncertainty.notes.push_back("the heat's uncertainty is not propagated through a robust loss");
    return;
  }
  const auto E = heat_jacobian(model, state.theta, state);
  if (!E) {
    result.joint.uncertainty.notes.push_back("the heat's uncertainty is not propagated: the runs depend on too many parameters");
    return;
  }
  detail::add_input_uncertainty(model.row_structure(), o.fit, state, *E, heat.covariance, heat.draws.empty() ? nullptr : &heat.draws,
                                "heat", result.joint);
  result.heat_uncertainty = heat.description;
}

}  // namespace

const char* to_string(ThermalOffsets offsets) {
  switch (offsets) {
    case ThermalOffsets::automatic: return "auto";
    case ThermalOffsets::fitted: return "fit";
    case ThermalOffsets::held: return "hold";
  }
  return "?";
}

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

const char* to_string(ThermalTermKind kind) {
  switch (kind) {
    case ThermalTermKind::time: return "t";
    case ThermalTermKind::time_squared: return "t^2";
    case ThermalTermKind::ambient_in_phase: return "a_P";
    case ThermalTermKind::ambient_quadrature: return "b_P";
    case ThermalTermKind::ambient_lag: return "lag_tau(Tamb)-Tamb";
    case ThermalTermKind::ambient_change: return "Tamb-Tamb0";
    case ThermalTermKind::rise_time: return "rise*t";
    case ThermalTermKind::velocity_time: return "V*t";
  }
  return "?";
}

bool term_has_scale(ThermalTermKind kind) {
  return kind == ThermalTermKind::ambient_in_phase || kind == ThermalTermKind::ambient_quadrature ||
         kind == ThermalTermKind::ambient_lag;
}

const char* term_coefficient_unit(ThermalTermKind kind) {
  switch (kind) {
    case ThermalTermKind::time: return "K/h";
    case ThermalTermKind::time_squared: return "K/h2";
    case ThermalTermKind::rise_time: return "1/h";
    case ThermalTermKind::velocity_time: return "K/(h m/s)";
    default: return "1";  // K per K of the ambient
  }
}

std::vector<ThermalExtensionInfo> thermal_extension_library() {
  std::vector<ThermalExtensionInfo> library;
  for (const auto& e : detail::thermal_extensions()) {
    ThermalExtensionInfo info{e.name, e.description, e.measure, {}, e.source, e.heat_follows_rail, {}, {}};
    for (const auto& p : e.parameters) {
      info.parameters.push_back(p.name);
      info.parameter_scale.push_back(p.scale);
      info.parameter_bounds.emplace_back(p.lower, p.upper);
    }
    library.push_back(std::move(info));
  }
  return library;
}

namespace {

std::vector<PreparedRun> prepared_runs(const ThermalDataSet& data, const ThermalFitOptions& o) {
  std::vector<PreparedRun> runs;
  for (const auto& run : data.runs) runs.push_back(prepare_run(run, o).run);
  return runs;
}

// The terms' regressors (or, with `sum`, their fitted sum) at every sample of `fit`.
std::vector<std::vector<double>> term_values_at_samples(const ThermalDataSet& data, const ThermalFitOptions& o,
                                                        const ThermalFitResult& fit, const std::vector<double>& theta_given,
                                                        const std::vector<ThermalSensorTerm>* terms) {
  const std::vector<PreparedRun> runs = prepared_runs(data, o);
  auto [layout, specs] = layout_for(runs, o);
  std::vector<double> theta = theta_given.empty() ? fit.joint.values() : theta_given;
  if (theta.size() != specs.size())
    throw InvalidParameter("fit", "the fit's parameters do not match the options it is said to be made with");
  const ThermalModel model(runs, layout, numerics_of(o));
  const auto simulated = model.simulate(theta);
  auto T0 = [&](std::size_t r) {
    return layout.initial[r] >= 0 ? theta[static_cast<std::size_t>(layout.initial[r])] : runs[r].params.initial_temperature_C;
  };
  // The time index of every sample (samples keep the fitted records' times).
  auto time_index = [&](const ThermalFitResult::Sample& sample) {
    const auto& times = runs[sample.run].times_s;
    return static_cast<std::size_t>(std::lower_bound(times.begin(), times.end(), sample.time_s - 1e-9) - times.begin());
  };
  std::vector<std::vector<double>> out;
  if (!terms) {
    const auto sums = model.term_sums(theta, simulated);
    std::vector<double> column;
    for (const auto& sample : fit.samples) column.push_back(sums[sample.run][time_index(sample)][sample.sensor]);
    out.push_back(std::move(column));
    return out;
  }
  for (const ThermalSensorTerm& term : *terms) {
    std::vector<std::vector<double>> phi;
    for (const auto& run : runs)
      phi.push_back(detail::sensor_term_regressor<double>(term.kind, term.scale_s, run.times_s, run.ambient, run.geometry.velocity_m_s));
    std::vector<double> column;
    for (const auto& sample : fit.samples) {
      const std::size_t t = time_index(sample);
      const double by = term.kind == ThermalTermKind::rise_time ? simulated[sample.run][t][sample.sensor] - T0(sample.run) : 1.0;
      column.push_back(phi[sample.run][t] * by);
    }
    out.push_back(std::move(column));
  }
  return out;
}

}  // namespace

std::vector<AmbientTrace> thermal_fit_ambients(const ThermalDataSet& data, const ThermalFitOptions& options) {
  std::vector<AmbientTrace> out;
  for (const auto& run : prepared_runs(data, options)) out.push_back(run.ambient);
  return out;
}

std::vector<std::vector<double>> thermal_sensor_term_values(const ThermalDataSet& data, const ThermalFitOptions& options,
                                                            const ThermalFitResult& fit,
                                                            const std::vector<ThermalSensorTerm>& terms) {
  return term_values_at_samples(data, options, fit, {}, &terms);
}

std::vector<double> thermal_sensor_term_sum(const ThermalDataSet& data, const ThermalFitOptions& options,
                                            const ThermalFitResult& fit, const std::vector<double>& theta) {
  return term_values_at_samples(data, options, fit, theta, nullptr).front();
}

ThermalFitResult fit_thermal(const ThermalDataSet& data, const ThermalFitOptions& o) {
  if (data.runs.empty()) throw InvalidParameter("runs", "the data set has no runs");
  // Every residual evaluation steps every run's rail: bounded before the first.
  if (o.half_rail_segments > io::kMaxRailSegments)
    throw InvalidParameter("half_rail_segments", o.half_rail_segments,
                           fmt::format("at most {} for a fit (docs/formats.md#limits)", io::kMaxRailSegments));
  validate(numerics_of(o));
  ThermalFitResult result;
  std::vector<PreparedRun> runs;
  std::vector<std::vector<double>> spans;
  for (const auto& run : data.runs) {
    Prepared p = prepare_run(run, o);
    runs.push_back(std::move(p.run));
    result.runs.push_back(p.info);
    spans.push_back(std::move(p.span_K));
  }
  // α is the share of a heat: with none in any run, nothing tells it (and every search for it
  // ran to its bounds).
  if (std::all_of(result.runs.begin(), result.runs.end(), [](const RunInfo& r) { return r.heat_rate_W == 0; })) {
    throw InvalidParameter("alpha", fmt::format("not identifiable: no heat (every run's heat rate is 0 W, from the {}); "
                                                "α is the share of the friction heat that enters the rail",
                                                result.runs.front().heat_source));
  }

  // Joint fit, and every run alone.
  auto [layout, specs] = layout_for(runs, o);
  const ThermalModel model(runs, layout, numerics_of(o));
  check_jet_size(model);
  detail::FinalState final_state;
  result.joint = detail::solve_least_squares(model, specs, o.fit, &final_state);
  result.sum_of_squares_K2 = final_state.residuals.squaredNorm();
  // An unusable fit (it says why) gets nothing built on its estimate.
  const bool usable = result.joint.solver.usable;
  if (usable) add_heat_uncertainty(data, runs, model, final_state, o, result);
  if (usable && o.cross_validate && runs.size() >= 2 && o.fit.loss == RobustLoss::none)
    result.cv_rmse_K = leave_one_run_out_rmse(model, result.joint, final_state);
  std::vector<double> alphas;
  if (usable && o.per_run_fits && runs.size() >= 2) {
    ThermalFitOptions one_run = o;  // for the spread across runs: estimates and SEs, no profiles
    one_run.fit.profile = ProfileMode::none;
    for (const auto& run : runs) {
      result.per_run.push_back(fit_runs({run}, one_run));
      alphas.push_back(result.per_run.back().parameter("alpha").value);
    }
    result.alpha_spread = spread(alphas, o.fit.confidence);
    std::vector<Estimate> estimates;
    std::vector<double> se;
    for (const FitResult& run : result.per_run) {
      const ParameterEstimate& a = run.parameter("alpha");
      se.push_back(a.se);
      if (std::isfinite(a.value) && std::isfinite(a.se) && a.se > 0) estimates.push_back({a.value, a.se});
    }
    if (estimates.size() >= 2) result.alpha_runs = random_effects(estimates, o.fit.confidence);
    if (o.fit.runs_replicate && o.fit.covariance == CovarianceMethod::automatic) widen_to_the_runs(result, o.fit.confidence);
    const double tau2 = std::isfinite(result.alpha_runs.tau) ? result.alpha_runs.tau * result.alpha_runs.tau : 0.0;
    // Eq. 2 between repeated runs at the same conditions, and how far apart they are against
    // what a run's α is known to.
    for (std::size_t a = 0; a < runs.size(); ++a)
      for (std::size_t b = a + 1; b < runs.size(); ++b)
        if (data.runs[a].velocity_m_s == data.runs[b].velocity_m_s && data.runs[a].load_N == data.runs[b].load_N &&
            data.runs[a].guide == data.runs[b].guide) {
          const double d = alphas[a] - alphas[b], within = se[a] * se[a] + se[b] * se[b];
          result.repeat_differences.push_back({runs[a].id + "/" + runs[b].id, percent_difference(alphas[a], alphas[b]),
                                               d / std::sqrt(within + 2 * tau2), d / std::sqrt(within)});
        }
  }

  // Source-model dependence: the same data with `paper` against `averaged`.
  if (usable && o.compare_sources && source_of(o) == o.source && o.source != SourceModel::moving) {
    ThermalFitOptions other = o;
    other.source = o.source == SourceModel::paper ? SourceModel::averaged : SourceModel::paper;
    other.per_run_fits = other.compare_sources = false;
    auto [other_layout, other_specs] = layout_for(runs, other);
    const ThermalModel other_model(runs, other_layout, numerics_of(other));
    const FitResult other_fit = detail::solve_least_squares(other_model, other_specs, other.fit);
    result.other_source = std::string(to_string(other.source));
    result.other_source_alpha = other_fit.parameter("alpha").value;
    const double own = result.joint.parameter("alpha").value;
    result.alpha_ratio_paper_over_averaged =
        o.source == SourceModel::paper ? own / result.other_source_alpha : result.other_source_alpha / own;
    result.contact_over_stroke = runs[0].geometry.contact_length_m / runs[0].geometry.stroke_m;
  }

  // Measured against the model, per sensor, from the final residuals r = measured - model
  // (σ = 1). The model is linear in α, so the α error curve (the paper's Fig. 11) follows from
  // the Jacobian column of α: r(α) = r(α̂) + ∂r/∂α · (α - α̂). With a robust loss the residuals
  // are transformed, so the model is simulated again instead.
  const std::vector<double> theta = result.joint.values();
  const auto& rows = model.rows();
  std::vector<double> error(rows.size()), d_alpha(rows.size());
  if (o.fit.loss == RobustLoss::none) {
    for (std::size_t k = 0; k < rows.size(); ++k) {
      error[k] = final_state.residuals[static_cast<Eigen::Index>(k)];
      d_alpha[k] = final_state.jacobian(static_cast<Eigen::Index>(k), layout.alpha);
    }
  } else {
    std::vector<double> at_zero = theta, at_one = theta;
    at_zero[static_cast<std::size_t>(layout.alpha)] = 0.0;
    at_one[static_cast<std::size_t>(layout.alpha)] = 1.0;
    const auto fitted = model.simulate(theta), zero = model.simulate(at_zero), one = model.simulate(at_one);
    const auto terms = model.term_sums(theta, fitted);
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const auto& w = rows[k];
      const int offset = layout.offsets[w.run][w.sensor];
      error[k] = runs[w.run].measured[w.time][w.sensor] - fitted[w.run][w.time][w.sensor] -
                 (offset >= 0 ? theta[static_cast<std::size_t>(offset)] : 0.0) - terms[w.run][w.time][w.sensor];
      d_alpha[k] = -(one[w.run][w.time][w.sensor] - zero[w.run][w.time][w.sensor]);
    }
  }
  std::vector<std::size_t> sample_rows;  // the data row of every sample
  // A sensor's max error against its own span, or a tenth of the largest span of any sensor if
  // more (a sensor far from the heat barely moves: its span is mostly noise).
  double widest_K = 0;
  for (const auto& run_spans : spans)
    for (double v : run_spans)
      if (std::isfinite(v)) widest_K = std::max(widest_K, v);
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const auto& pr = runs[r];
    for (std::size_t s = 0; s < pr.sensor_names.size(); ++s) {
      SensorGoodness g{pr.id, pr.sensor_names[s], pr.sensor_positions_m[s], 0, 0, 0, 0};
      double ss = 0;
      for (std::size_t k = model.first_row(r); k < rows.size() && rows[k].run == r; ++k) {  // the run's rows
        if (rows[k].sensor != s) continue;
        const double measured = pr.measured[rows[k].time][s];
        ss += error[k] * error[k];
        g.max_error_K = std::max(g.max_error_K, std::abs(error[k]));
        ++g.n;
        const std::size_t t = rows[k].time;
        result.samples.push_back({r, s, pr.times_s[t], measured, measured - error[k], t < pr.lines.size() ? pr.lines[t] : 0u});
        sample_rows.push_back(k);
      }
      g.rmse_K = g.n ? std::sqrt(ss / static_cast<double>(g.n)) : kNaN;
      g.max_error_percent = 100 * g.max_error_K / std::max({std::isfinite(spans[r][s]) ? spans[r][s] : 0.0, 0.1 * widest_K, 1e-9});
      result.max_error_percent = std::max(result.max_error_percent, g.max_error_percent);
      result.goodness.push_back(g);
    }
  }
  // ∂ reading / ∂ θ of the global parameters: −∂r/∂θ (r = measured − reading).
  if (o.sensitivities && o.fit.loss == RobustLoss::none) {
    std::vector<int> global{layout.alpha};
    if (layout.h >= 0) global.push_back(layout.h);
    for (std::size_t e = 0; e < layout.extensions.size(); ++e)
      for (std::size_t j = 0; j < layout.extensions[e]->parameters.size(); ++j)
        global.push_back(layout.extension_first[e] + static_cast<int>(j));
    for (std::size_t j = 0; j < layout.terms.size(); ++j) {
      global.push_back(layout.term_coefficient[j]);
      if (layout.term_scale[j] >= 0 && std::find(global.begin(), global.end(), layout.term_scale[j]) == global.end())
        global.push_back(layout.term_scale[j]);
    }
    for (int scale : layout.heat_scale)
      if (scale >= 0) global.push_back(scale);  // per run: the search takes them out run by run
    for (int g : global) {
      std::vector<double> column;
      for (std::size_t k : sample_rows) column.push_back(-final_state.jacobian(static_cast<Eigen::Index>(k), g));
      result.sensitivities.emplace_back(specs[static_cast<std::size_t>(g)].name, std::move(column));
    }
  }
  for (std::size_t j = 0; j < layout.terms.size(); ++j) {
    std::vector<std::size_t> indices{static_cast<std::size_t>(layout.term_coefficient[j])};
    if (layout.term_scale[j] >= 0) indices.push_back(static_cast<std::size_t>(layout.term_scale[j]));
    result.sensor_term_parameters.push_back(indices);
  }
  // The rail's temperature at the sensors' last records: the readings less their offsets and terms.
  const auto profiles = model.end_profiles(theta);
  const auto term_sums = layout.terms.empty() ? decltype(model.simulate(theta)){} : model.term_sums(theta, model.simulate(theta));
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const auto& pr = runs[r];
    ThermalFitResult::EndState end{profiles[r], pr.sensor_positions_m, {}};
    for (std::size_t s = 0; s < pr.sensor_names.size(); ++s) {
      const int offset = layout.offsets[r][s];
      end.measured_C.push_back(pr.measured.back()[s] - (offset >= 0 ? theta[static_cast<std::size_t>(offset)] : 0.0) -
                               (term_sums.empty() ? 0.0 : term_sums[r].back()[s]));
    }
    result.end_states.push_back(std::move(end));
  }
  const double alpha_hat = theta[static_cast<std::size_t>(layout.alpha)];
  for (std::size_t r = 0; r < runs.size(); ++r) {
    std::vector<std::size_t> first_sensor;  // the run's rows of its first thermocouple
    for (std::size_t k = model.first_row(r); k < rows.size() && rows[k].run == r; ++k)
      if (rows[k].sensor == 0) first_sensor.push_back(k);
    for (int c = 0; c < o.curve_points; ++c) {
      const double alpha = o.curve_from + (o.curve_to - o.curve_from) * c / std::max(1, o.curve_points - 1);
      double ss = 0, worst = 0;
      std::size_t n = 0;
      for (std::size_t k : first_sensor) {
        const double e = error[k] + d_alpha[k] * (alpha - alpha_hat);
        ss += e * e;
        worst = std::max(worst, std::abs(e));
        ++n;
      }
      result.alpha_curve.push_back({runs[r].id, alpha, n ? std::sqrt(ss / static_cast<double>(n)) : kNaN, worst});
    }
  }
  for (const auto& pr : runs) result.sensor_names.push_back(pr.sensor_names);
  return result;
}

namespace {

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

// ---- output ---------------------------------------------------------------------------------


std::string thermal_fit_json(const ThermalFitResult& r, const ThermalFitOptions& o,
                             const std::vector<std::pair<std::string, std::string>>& inputs,
                             const std::vector<std::string>& command, const std::string& name) {
  nlohmann::json runs = nlohmann::json::array();
  for (std::size_t i = 0; i < r.runs.size(); ++i) {
    const auto& info = r.runs[i];
    nlohmann::json run = {{"id", info.id},
                          {"velocity_m_s", info.velocity_m_s},
                          {"load_N", info.load_N},
                          {"heat_rate_W", info.heat_rate_W},
                          {"heat_source", info.heat_source},
                          {"initial_temperature_C", info.initial_temperature_C},
                          {"ambient_sensors_percent_difference_eq2", number(info.ambient_difference_percent)}};
    if (i < r.per_run.size()) run["fit"] = detail::fit_json(r.per_run[i]);
    runs.push_back(run);
  }
  nlohmann::json goodness = nlohmann::json::array();
  for (const auto& g : r.goodness)
    goodness.push_back({{"run", g.run},
                        {"sensor", g.sensor},
                        {"position_m", g.position_m},
                        {"n", g.n},
                        {"rmse_K", number(g.rmse_K)},
                        {"max_error_K", number(g.max_error_K)},
                        {"max_error_percent", number(g.max_error_percent)}});
  nlohmann::json repeats = nlohmann::json::array();
  for (const auto& d : r.repeat_differences)
    repeats.push_back({{"runs", d.runs},
                       {"alpha_percent_difference_eq2", number(d.percent)},
                       {"z", number(d.z)},
                       {"z_within_run_se_only", number(d.z_within)}});
  const RandomEffects& re = r.alpha_runs;
  const nlohmann::json random_effects_json = {{"runs", re.k},
                                              {"mean", number(re.mean)},
                                              {"se", number(re.mean_se)},
                                              {"ci95", {number(re.mean_low), number(re.mean_high)}},
                                              {"tau", number(re.tau)},
                                              {"tau_ci95", {number(re.tau_low), number(re.tau_high)}},
                                              {"cochran_q", number(re.q)},
                                              {"q_p", number(re.q_p)},
                                              {"i_squared", number(re.i2)},
                                              {"method", re.method}};
  nlohmann::json in = nlohmann::json::array();
  for (const auto& [file, hash] : inputs) in.push_back({{"file", file}, {"sha256", hash}});
  const auto& s = r.alpha_spread;
  nlohmann::json j = {{"kind", "thermal fit"},
                      {"name", name},
                      {"lmcal_version", LMCAL_VERSION}, {"schema_version", kOutputSchemaVersion},
                      {"command", command},
                      {"inputs", in},
                      {"options",
                       {{"source", to_string(o.source)},
                        {"scheme", to_string(o.scheme)},
                        {"half_rail_segments", o.half_rail_segments},
                        {"time_step_s", o.time_step_s},
                        {"every", o.every},
                        {"ambient", o.ambient},
                        {"fit_h", o.fit_h},
                        {"offsets", to_string(o.offsets)},
                        {"fit_initial_temperature", o.fit_initial_temperature},
                        {"extensions", o.extensions}}},
                      {"cv_rmse_K", number(r.cv_rmse_K)},
                      {"joint", detail::fit_json(r.joint)},
                      {"alpha_across_runs",
                       {{"n", s.n},
                        {"mean", number(s.mean)},
                        {"sd_eq1", number(s.sd)},
                        {"ci95", {number(s.low), number(s.high)}},
                        {"half_width", number(s.half_width)},
                        {"min", number(s.min)},
                        {"max", number(s.max)},
                        {"random_effects", random_effects_json}}},
                      {"repeats", repeats},
                      {"source_comparison",
                       {{"other_source", r.other_source},
                        {"other_source_alpha", number(r.other_source_alpha)},
                        {"alpha_paper_over_averaged", number(r.alpha_ratio_paper_over_averaged)},
                        {"contact_over_stroke", number(r.contact_over_stroke)}}},
                      {"runs", runs},
                      {"goodness", goodness},
                      {"max_error_percent", number(r.max_error_percent)}};
  if (!o.sensor_terms.empty()) {  // empirical terms (a diagnosis's); absent otherwise, so plain fits keep their bytes
    nlohmann::json terms = nlohmann::json::array();
    for (const auto& t : o.sensor_terms) {
      terms.push_back({{"kind", to_string(t.kind)}, {"coefficient_unit", term_coefficient_unit(t.kind)}});
      if (term_has_scale(t.kind)) terms.back()["scale_s"] = t.scale_s;
    }
    j["options"]["sensor_terms"] = terms;
  }
  return j.dump(2) + "\n";
}

std::string thermal_fit_samples_csv(const ThermalFitResult& r) {
  CsvText csv({"run", "line", "sensor", "time_s", "measured_C", "simulated_C", "residual_K"});
  csv.expect_rows(r.samples.size());
  for (const auto& s : r.samples) {
    csv.cell(r.runs[s.run].id).cell(s.line > 0 ? std::to_string(s.line) : "");
    csv.cell(r.sensor_names[s.run][s.sensor]).cell(s.time_s).cell(s.measured_C);
    csv.cell(s.simulated_C).cell(s.measured_C - s.simulated_C).end_row();
  }
  return csv.str();
}

std::vector<std::pair<std::string, std::string>> thermal_fit_files(const ThermalFitResult& result,
                                                                   const ThermalFitOptions& options,
                                                                   const std::vector<std::pair<std::string, std::string>>& inputs,
                                                                   const std::vector<std::string>& command,
                                                                   const std::string& name) {
  return {{name + ".json", thermal_fit_json(result, options, inputs, command, name)},
          {name + "_samples.csv", thermal_fit_samples_csv(result)},
          {name + "_alpha_curve.csv", thermal_fit_curve_csv(result)}};
}

std::string thermal_fit_curve_csv(const ThermalFitResult& r) {
  CsvText csv({"run", "alpha", "rmse_K", "max_error_K"});
  for (const auto& p : r.alpha_curve) csv.cell(p.run).cell(p.alpha).cell(p.rmse_K).cell(p.max_error_K).end_row();
  return csv.str();
}

std::string thermal_fit_summary(const ThermalFitResult& r) {
  std::string s;
  s += fmt::format("{} runs, {} records; joint fit over all runs:\n", r.runs.size(), r.joint.residuals);
  for (const auto& p : r.joint.parameters) {
    const std::string interval = p.interval == "profile" ? fmt::format("[{:.4g}, {:.4g}] profile", p.profile_low, p.profile_high)
                                 : p.interval == "linear" ? fmt::format("[{:.4g}, {:.4g}]", p.ci_low, p.ci_high)
                                 : p.interval != "none" ? fmt::format("[{:.4g}, {:.4g}] {} scale", p.ci_low, p.ci_high, p.interval)
                                                          : std::string("held");
    s += fmt::format("  {:<24} {:>10.5g} ± {:<9.3g} {:<9} {}{}\n", p.name, p.value, p.se, shown_unit(p.unit), interval,
                     p.at_bound ? "  at a bound" : "");
  }
  s += fmt::format("  residual sigma {:.3f} K; {}\n", std::sqrt(r.joint.residual_variance), r.joint.solver.termination);
  s += detail::uncertainty_summary(r.joint);
  if (!r.heat_uncertainty.empty()) s += "  the heat's uncertainty: " + r.heat_uncertainty + "\n";
  for (const auto& run : r.runs)
    if (!run.offsets_note.empty()) s += fmt::format("  {}: {}\n", run.id, run.offsets_note);
  if (std::isfinite(r.cv_rmse_K)) s += fmt::format("  leave-one-run-out prediction RMSE {:.4f} K\n", r.cv_rmse_K);
  for (const auto& issue : r.joint.identifiability.issues)
    s += fmt::format("  NOT IDENTIFIABLE: {} -> held {}; {}\n", issue.why, fmt::join(issue.held, ", "), issue.measure);
  if (!r.per_run.empty()) {
    s += "per run:\n";
    for (std::size_t i = 0; i < r.per_run.size(); ++i) {
      const auto& p = r.per_run[i].parameter("alpha");
      const double ambient = r.runs[i].ambient_difference_percent;
      s += fmt::format("  {:<10} V {:.3f} m/s  Q {:.2f} W  alpha {:.4f} ± {:.4f}{}\n", r.runs[i].id, r.runs[i].velocity_m_s,
                       r.runs[i].heat_rate_W, p.value, p.se,
                       std::isfinite(ambient) ? fmt::format("  ambient sensors differ {:.1f} % (Eq. 2)", ambient)
                                              : "  one ambient sensor (no comparison)");
    }
    const auto& sp = r.alpha_spread;
    if (sp.n < 2)
      s += fmt::format("alpha {}\n", across_runs(sp));
    else
      s += fmt::format("alpha across runs: {:.3f} ± {:.3f} (mean ± 95 % t half-width; spread of runs (Eq. 1 sigma) {:.4f}, n {}, min {:.3f}, max {:.3f})\n",
                       sp.mean, sp.half_width, sp.sd, sp.n, sp.min, sp.max);
    const RandomEffects& re = r.alpha_runs;
    if (re.k >= 2 && re.tau > 0)
      s += fmt::format("  the runs' alpha differ beyond their own SEs by tau = {:.3g} (REML; Cochran's Q = {:.3g} on {} runs, p = "
                       "{:.2g}, I2 = {:.0f} %): a run's alpha is known to sqrt(SE^2 + tau^2), not to its own SE; random-effects "
                       "mean {:.4f}, 95 % [{:.4f}, {:.4f}] (Hartung-Knapp)\n",
                       re.tau, re.q, re.k, re.q_p, 100 * re.i2, re.mean, re.mean_low, re.mean_high);
    for (const auto& d : r.repeat_differences)
      s += fmt::format("  repeats {}: alpha differs {:.1f} % (Eq. 2); z = {:.2f} against sqrt(SE1^2 + SE2^2 + 2 tau^2) ({:.2f} "
                       "against their own SEs alone)\n",
                       d.runs, d.percent, d.z, d.z_within);
  }
  s += "goodness per sensor (joint fit):\n";
  for (const auto& g : r.goodness)
    s += fmt::format("  {:<10} {:<8} x {:.3f} m  RMSE {:.3f} K  max error {:.3f} K ({:.1f} % of the span)\n", g.run, g.sensor,
                     g.position_m, g.rmse_K, g.max_error_K, g.max_error_percent);
  s += fmt::format("max error {:.1f} % of the measured span (each sensor's highest minus lowest 10-record mean, at least a "
                   "tenth of the widest sensor's; the paper reports 12 % of the rise)\n",
                   r.max_error_percent);
  if (!r.other_source.empty())
    s += fmt::format(
        "source model: alpha with `{}` is {:.4f}; alpha(paper) / alpha(averaged) = {:.3f} (Lb1/L1 = {:.3f}: the paper's "
        "source puts L1/Lb1 times the block's power into the rail, so its alpha is smaller by about that factor)\n",
        r.other_source, r.other_source_alpha, r.alpha_ratio_paper_over_averaged, r.contact_over_stroke);
  for (const auto& w : r.joint.warnings) s += "warning: " + w + "\n";
  return s;
}

}  // namespace lmcal
