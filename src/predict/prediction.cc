// `lmcal predict`: the calibrated model over a duty cycle, with bands (prediction.hpp).

#include "lmcal/predict/prediction.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <limits>
#include <cmath>
#include <exception>
#include <map>

#include "fit/covariance/covariance.hpp"
#include "lmcal/error.hpp"
#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/io/units.hpp"
#include "lmcal/models/friction_effects.hpp"
#include "parallel_slices.hpp"

namespace lmcal {

namespace {

// w with ∫_a^b rise dx = Σ w_i rise_i for the rise linear between the nodes x (a <= b), the
// end values beyond them, and a half-rail profile (x >= 0 only) mirrored: the integral is
// linear in the nodes' values, so one set of weights serves every time of a segment.
std::vector<double> elongation_weights(const std::vector<double>& x, double a, double b) {
  LMCAL_ASSERT(!x.empty() && a <= b, "nodes, and a <= b");
  const bool half = x.front() >= 0;
  std::vector<double> w(x.size(), 0.0);
  // Adds `share` of the rise at `at` to the weights (the interpolation's two nodes).
  const auto add = [&](double at, double share) {
    if (half) at = std::abs(at);
    if (at <= x.front()) {
      w.front() += share;
      return;
    }
    if (at >= x.back()) {
      w.back() += share;
      return;
    }
    const auto hi = static_cast<std::size_t>(std::upper_bound(x.begin(), x.end(), at) - x.begin());
    const double s = (at - x[hi - 1]) / (x[hi] - x[hi - 1]);
    w[hi - 1] += (1 - s) * share;
    w[hi] += s * share;
  };
  // The rise is linear between nodes (and their mirror images): the trapezoid rule over those
  // break points is exact for it.
  std::vector<double> points{a, b};
  for (double xi : x)
    for (double p : {xi, -xi})
      if (p > a && p < b && (half || p == xi)) points.push_back(p);
  std::sort(points.begin(), points.end());
  for (std::size_t i = 1; i < points.size(); ++i) {
    const double half_width = 0.5 * (points[i] - points[i - 1]);
    add(points[i - 1], half_width);
    add(points[i], half_width);
  }
  return w;
}

// Σ w_i (T_i − ref_i) α_th.
double weighted_rise(const std::vector<double>& w, const std::vector<double>& T, const std::vector<double>& ref,
                     double expansion_per_K) {
  double sum = 0;
  for (std::size_t i = 0; i < w.size(); ++i) sum += w[i] * (T[i] - ref[i]);
  return expansion_per_K * sum;
}

}  // namespace

double thermal_elongation_m(const std::vector<double>& x, const std::vector<double>& T, const std::vector<double>& ref,
                            double expansion_per_K, double a, double b) {
  LMCAL_ASSERT(x.size() == T.size() && x.size() == ref.size() && !x.empty(), "one temperature per node");
  if (b < a) return -thermal_elongation_m(x, T, ref, expansion_per_K, b, a);
  return weighted_rise(elongation_weights(x, a, b), T, ref, expansion_per_K);
}

std::string runaway_of(const RailSolution<double>& sol, const std::string& inputs) {
  const PhysicalRange range = physical_range(Quantity::temperature);
  // The common case first, in one branch-free pass: every value finite (0·x stays 0) and
  // within the range. Otherwise the pass below finds the value to name.
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, zero = 0;
  const auto span = [&](const std::vector<double>& values) {
    for (double x : values) lo = std::min(lo, x), hi = std::max(hi, x), zero += 0 * x;
  };
  for (const auto& profile : sol.profiles_C) span(profile);
  span(sol.sensor_temperature_C);
  span(sol.source_temperature_C);
  for (double q : sol.heat_rate_W) zero += 0 * q;
  if (zero == 0 && (lo > hi || (range.contains(lo) && range.contains(hi)))) return "";
  double worst = 0;
  bool finite = true;
  const auto see = [&](double T) {
    finite = finite && std::isfinite(T);
    if (std::isfinite(T) && std::abs(T) > std::abs(worst)) worst = T;
  };
  for (const auto& profile : sol.profiles_C)
    for (double T : profile) see(T);
  for (double T : sol.sensor_temperature_C) see(T);
  for (double T : sol.source_temperature_C) see(T);
  for (double q : sol.heat_rate_W) finite = finite && std::isfinite(q);
  if (finite && range.contains(worst)) return "";
  return fmt::format("{} drives the rail to {}, beyond the temperatures of a rig ({:g} to {:g} °C): the model's heat runs "
                     "away there (the friction law's Stribeck term grows as the oil thins), so it predicts nothing real; "
                     "lower the speed or the load, or check the oil's viscosity",
                     inputs, finite ? fmt::format("{:.4g} °C", worst) : std::string("no finite temperature"), range.low,
                     range.high);
}

namespace {

// One set of the model's parameters.
struct Draw {
  FrictionConstants<double> constants;
  FrictionEffects<double> effects;
  double alpha = 0, h_W_m2K = 0;
  std::vector<std::pair<std::string, double>> mechanism_values;
};

// What one simulated duty gives.
struct Trajectory {
  std::vector<std::vector<double>> temperature_C;  // [position][time]
  std::vector<double> elongation_um;
  std::vector<std::vector<double>> scale_error_um;  // [scale position][time]
  std::vector<double> friction_N, heat_rate_W;
  std::vector<double> profile_x_m, profile_C;  // at the end
  double max_rail_C = -INFINITY;
};

Draw point_draw(const ModelFile& m) {
  Draw d{m.constants, m.effects, m.alpha, m.h_W_m2K.value_or(5.3), m.mechanism_parameters};
  return d;
}

// The parameter called `name` of `d` (a friction constant, an effect, α, h or a mechanism's);
// null for one a prediction does not use (an empirical term of the load cell's log).
double* find_parameter(Draw& d, const std::string& name) {
  if (double* law = find_law_parameter(d.constants, d.effects, name)) return law;
  if (name == "alpha") return &d.alpha;
  if (name == "h_W_m2K") return &d.h_W_m2K;
  for (auto& [n, v] : d.mechanism_values)
    if (n == name) return &v;
  return nullptr;
}

// Adds the draw's deviations `delta` of the covariance's parameters to `d`. The parameters the
// prediction does not use are skipped: the others' draws keep their joint (marginal) law.
void add_deviations(Draw& d, const std::vector<std::string>& parameters, const Eigen::VectorXd& delta) {
  for (std::size_t j = 0; j < parameters.size(); ++j)
    if (double* p = find_parameter(d, parameters[j])) *p += delta(static_cast<Eigen::Index>(j));
}

// A square root of a covariance that also serves a singular one: V diag(√λ₊).
Eigen::MatrixXd square_root(const Eigen::MatrixXd& c) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(c);
  return eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
}

// The heat the calibration runs put in with the friction law of `d`, summed.
double reference_heat_W(const ModelFile& m, const Draw& d) {
  double q = 0;
  for (const HeatReference& r : m.heat_references) {
    FrictionConstants<double> k = d.constants;
    k.nu_ref_mm2_s = r.viscosity40_mm2_s;
    q += heat_rate_with_effects_W(k, d.effects, r.conditions);
  }
  return q;
}

// The draws (the first is the model at its estimates), and how they were made.
struct DrawSet {
  std::vector<Draw> draws;
  std::string method;
  std::vector<std::string> notes;
};

DrawSet make_draws(const ModelFile& m, const PredictionOptions& o) {
  DrawSet s;
  const Draw point = point_draw(m);
  s.draws.push_back(point);
  const ModelCovariance& f = m.friction_covariance_matrix;
  const ModelCovariance& t = m.thermal_covariance_matrix;
  const bool rescale = !f.empty() && !m.heat_references.empty() && m.thermal_covariance_given_heat.size() > 0;
  const Eigen::MatrixXd Lf = f.empty() ? Eigen::MatrixXd() : square_root(f.matrix);
  const Eigen::MatrixXd Lt = t.empty() ? Eigen::MatrixXd() : square_root(rescale ? m.thermal_covariance_given_heat : t.matrix);
  const double q_point = rescale ? reference_heat_W(m, point) : 0;
  const auto nf = static_cast<Eigen::Index>(f.parameters.size()), nt = static_cast<Eigen::Index>(t.parameters.size());
  const auto z = detail::standard_normal_draws(o.samples, nf + nt + 1, o.seed);
  for (std::size_t i = 0; i < o.samples; ++i) {
    Draw d = point;
    if (nf > 0) {
      add_deviations(d, f.parameters, Lf * z[i].head(nf));
    }
    if (nt > 0) {
      add_deviations(d, t.parameters, Lt * z[i].segment(nf, nt));
    }
    // The rail saw α·Q: with this draw's heat at the calibration runs, α is the one that gives the same.
    if (rescale) d.alpha *= q_point / reference_heat_W(m, d);
    d.alpha = std::clamp(d.alpha + m.alpha_between_run_sd * z[i](nf + nt), 0.0, 1.0);
    d.h_W_m2K = std::max(d.h_W_m2K, 1e-3);
    s.draws.push_back(std::move(d));
  }
  std::string thermal_part = t.empty() ? "none in the model file"
                             : rescale ? fmt::format("the '{}' covariance less the heat's share, α rescaled with each "
                                                     "draw's heat at the {} calibration runs so that α·Q stays as fitted",
                                                     m.thermal_covariance, m.heat_references.size())
                                       : fmt::format("'{}'", m.thermal_covariance);
  s.method = fmt::format(
      "{} draws of the model's parameters from a multivariate normal with their covariance (friction: {}; thermal: {}){}; "
      "the duty simulated for each; the band is the {:g} % central interval of the draws",
      o.samples, f.empty() ? "none in the model file" : "'" + m.friction_covariance + "'", thermal_part,
      m.alpha_between_run_sd > 0 ? fmt::format(", plus α's run-to-run spread (sd {:.3g})", m.alpha_between_run_sd) : "",
      100 * o.confidence);
  if (f.empty() || t.empty())
    s.notes.push_back("the model file has no covariance for some parameters: their uncertainty is not in the band");
  if (!f.empty() && !rescale)
    s.notes.push_back("the heat of the calibration is not known as the friction law's (measured or given): the "
                      "friction constants' and α's draws are independent, which may widen the band");
  if (!m.friction_terms.empty())
    s.notes.push_back("the friction model's empirical terms describe the load cell's log and are not applied to the heat");
  s.notes.push_back("not in the band: the thermocouples' noise and lag, model error beyond the calibrated mechanisms, "
                    "and the duty's own uncertainty (ambient, load)");
  return s;
}

// The global output times: every output_every_s from 0, and the end.
std::vector<double> output_times(const DutyCycle& duty) {
  std::vector<double> t;
  const double end = duty.duration_s();
  for (std::size_t i = 0;; ++i) {
    const double ti = static_cast<double>(i) * duty.output_every_s;
    if (ti >= end - 1e-9 * end) break;
    t.push_back(ti);
  }
  t.push_back(end);
  return t;
}

// The ambient over [t0, t1] of the duty, from t0.
AmbientTrace segment_ambient(const AmbientTrace& a, double t0, double t1) {
  if (a.time_s.size() == 1) return a;
  AmbientTrace out;
  out.time_s.push_back(0);
  out.temperature_C.push_back(a.at(t0));
  for (std::size_t i = 0; i < a.time_s.size(); ++i)
    if (a.time_s[i] > t0 && a.time_s[i] < t1) {
      out.time_s.push_back(a.time_s[i] - t0);
      out.temperature_C.push_back(a.temperature_C[i]);
    }
  out.time_s.push_back(t1 - t0);
  out.temperature_C.push_back(a.at(t1));
  return out;
}

// Refuses a segment whose rail predicts nothing real (runaway_of), at its table in the duty file.
void require_physical(const DutyCycle& duty, const DutySegment& s, const RailSolution<double>& sol) {
  const std::string message =
      runaway_of(sol, fmt::format("{} (velocity_m_s = {}, load_N = {}, stroke_m = {}, viscosity40_mm2_s = {})", s.name,
                                  s.velocity_m_s, s.load_N, s.stroke_m, s.viscosity40_mm2_s));
  if (message.empty()) return;
  if (s.line > 0) throw InputError(duty.file, s.line, s.column, message);
  throw InvalidParameter("duty", message);
}

Trajectory simulate_duty(const ModelFile& m, const DutyCycle& duty, const Draw& d, const PredictionOptions& o,
                         const std::vector<double>& times, std::vector<std::string>* segment_at) {
  const GuideSpec& g = duty.guide;
  const std::vector<ThermalExtensionInfo> library = thermal_extension_library();
  const double initial_C = duty.initial_C.value_or(duty.ambient.at(0.0));
  Trajectory tr;
  tr.temperature_C.assign(duty.positions_m.size(), {});
  tr.scale_error_um.assign(duty.scale.positions_m.size(), {});
  std::vector<double> carried_x, carried_C;  // the rail at the end of the last segment
  double source_C = initial_C;               // the rail under the block at the segment's start
  double t0 = 0;
  std::size_t next = 0;  // index into times
  for (std::size_t k = 0; k < duty.segments.size(); ++k) {
    const DutySegment& s = duty.segments[k];
    const double t1 = t0 + s.duration_s;
    const bool last = k + 1 == duty.segments.size();
    RailOutputs outputs{.duration_s = s.duration_s, .sensor_positions_m = duty.positions_m};
    const std::size_t first = next;
    for (; next < times.size() && (times[next] <= t1 + 1e-9 * std::max(1.0, t1) || last); ++next) {
      outputs.output_times_s.push_back(std::clamp(times[next] - t0, 0.0, s.duration_s));
      if (segment_at) segment_at->push_back(s.name);
    }
    outputs.profile_times_s = outputs.output_times_s;
    if (outputs.profile_times_s.empty() || outputs.profile_times_s.back() < s.duration_s) outputs.profile_times_s.push_back(s.duration_s);
    const RailGeometry geometry = rail_geometry_of(g, duty.rail_length_m, s.stroke_m, *g.contact_length_mm * 1e-3, s.velocity_m_s);
    RailNumerics numerics{.source = s.velocity_m_s > 0 ? m.source : SourceModel::averaged,
                          .scheme = TimeScheme::crank_nicolson,
                          .half_rail_segments = o.half_rail_segments,
                          .time_step_s = o.time_step_s};
    RailParams<double> params = rail_material_of(g);
    params.heat_partition = d.alpha;
    params.h_W_m2K = d.h_W_m2K;
    params.initial_temperature_C = initial_C;
    params.initial_profile_x_m = carried_x;
    params.initial_profile_C = carried_C;
    FrictionConstants<double> constants = d.constants;
    constants.nu_ref_mm2_s = s.viscosity40_mm2_s;
    const FrictionConditions<double> conditions{.load_N = s.load_N,
                                                .preload_um = s.preload_um,
                                                .block_length_mm = s.block_length_mm,
                                                .velocity_m_s = s.velocity_m_s,
                                                .temperature_C = source_C};
    const double law_heat_W = heat_rate_with_effects_W(constants, d.effects, conditions);
    const AmbientTrace ambient = segment_ambient(duty.ambient, t0, t1);
    // At rest there is no heat: the mechanisms of the heat (a coupling, a source model) are
    // idle too; those of the rail (a base loss, the convection) are not.
    std::vector<std::string> mechanisms = m.mechanisms;
    if (s.velocity_m_s == 0)
      std::erase_if(mechanisms, [&](const std::string& name) {
        return std::any_of(library.begin(), library.end(),
                           [&](const ThermalExtensionInfo& e) { return e.name == name && (e.source || e.heat_follows_rail); });
      });
    RailSolution<double> sol;
    if (mechanisms.empty()) {
      params.heat_rate_W = law_heat_W;
      sol = simulate_rail(geometry, numerics, outputs, params, ambient);
    } else {
      sol = simulate_rail_with_mechanisms(geometry, numerics, outputs, params, ambient, constants, d.effects, conditions,
                                          mechanisms, d.mechanism_values);
    }
    require_physical(duty, s, sol);
    // The reference of the elongation: the rail at the duty's start (uniform). The integrals'
    // weights on this segment's grid, once (a scale position before the fixed point: negative).
    const std::vector<double> reference(sol.node_positions_m.size(), initial_C);
    const std::vector<double>& x = sol.node_positions_m;
    const std::vector<double> whole = elongation_weights(x, -0.5 * duty.rail_length_m, 0.5 * duty.rail_length_m);
    std::vector<std::vector<double>> to_scale;
    std::vector<double> sense;
    const double fixed = duty.scale.fixed_point_m();
    for (double at : duty.scale.positions_m) {
      to_scale.push_back(elongation_weights(x, std::min(fixed, at), std::max(fixed, at)));
      sense.push_back(at < fixed ? -1.0 : 1.0);
    }
    const std::size_t n_out = outputs.output_times_s.size();
    for (std::size_t i = 0; i < n_out; ++i) {
      for (std::size_t p = 0; p < duty.positions_m.size(); ++p) tr.temperature_C[p].push_back(sol.temperature_C(i, p));
      const std::vector<double>& profile = sol.profiles_C[i];
      tr.elongation_um.push_back(1e6 * weighted_rise(whole, profile, reference, duty.scale.expansion_per_K));
      for (std::size_t q = 0; q < duty.scale.positions_m.size(); ++q)
        tr.scale_error_um[q].push_back(1e6 * sense[q] * weighted_rise(to_scale[q], profile, reference, duty.scale.expansion_per_K));
      const double heat = s.velocity_m_s > 0 ? sol.heat_rate_W[i] : 0.0;
      tr.heat_rate_W.push_back(heat);
      tr.friction_N.push_back(s.velocity_m_s > 0 ? heat / s.velocity_m_s : 0.0);
      for (double T : profile) tr.max_rail_C = std::max(tr.max_rail_C, T);
    }
    (void)first;
    carried_x = sol.node_positions_m;
    carried_C = sol.profiles_C.back();
    for (double T : carried_C) tr.max_rail_C = std::max(tr.max_rail_C, T);
    if (!sol.source_temperature_C.empty()) source_C = sol.source_temperature_C.back();
    else source_C = carried_C[carried_C.size() / 2];
    t0 = t1;
  }
  tr.profile_x_m = carried_x;
  tr.profile_C = carried_C;
  return tr;
}

// The q-quantile of `v` (sorted in place), linear between order statistics.
double quantile(std::vector<double>& v, double q) {
  std::sort(v.begin(), v.end());
  const double at = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(at));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (at - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

// The band of one quantity: `get(trajectory)` is its series over time.
template <class Get>
Band band_of(const Trajectory& point, const std::vector<Trajectory>& draws, double confidence, Get&& get) {
  Band b;
  b.value = get(point);
  const std::size_t n = b.value.size();
  b.low.resize(n);
  b.high.resize(n);
  std::vector<double> column(draws.size());
  for (std::size_t t = 0; t < n; ++t) {
    for (std::size_t i = 0; i < draws.size(); ++i) column[i] = get(draws[i])[t];
    b.low[t] = quantile(column, 0.5 * (1 - confidence));
    b.high[t] = quantile(column, 0.5 * (1 + confidence));
  }
  return b;
}

void flag_ranges(const ModelFile& m, const DutyCycle& duty, double max_rail_C, Prediction& p) {
  const auto check = [&](const CalibratedRange* r, const std::string& segment, const char* quantity, double value,
                         const char* what) {
    const double slack = 1e-9 * std::max(1.0, std::abs(value));
    if (r && (value < r->low - slack || value > r->high + slack)) p.outside.push_back({segment, quantity, value, r->low, r->high, what});
  };
  for (const DutySegment& s : duty.segments) {
    if (s.velocity_m_s <= 0) continue;
    if (std::any_of(p.outside.begin(), p.outside.end(), [&](auto& f) { return f.segment == s.name; })) continue;
    check(m.friction_range_of("velocity_m_s"), s.name, "velocity_m_s", s.velocity_m_s, "friction");
    check(m.friction_range_of("load_N"), s.name, "load_N", s.load_N, "friction");
    check(m.thermal_range_of("velocity_m_s"), s.name, "velocity_m_s", s.velocity_m_s, "thermal");
    check(m.thermal_range_of("load_N"), s.name, "load_N", s.load_N, "thermal");
  }
  check(m.thermal_range_of("temperature_C"), "the duty", "temperature_C", max_rail_C, "thermal");
  check(m.friction_range_of("temperature_C"), "the duty", "temperature_C", max_rail_C, "friction");
}

// The last check before a prediction leaves: every number of every band finite (a draw or a
// segment that was not is refused or left out above; this one names what slipped through).
void require_finite_bands(const Prediction& p) {
  const auto check = [](const Band& b, const std::string& quantity) {
    for (const std::vector<double>* v : {&b.value, &b.low, &b.high})
      for (double x : *v)
        if (!std::isfinite(x)) throw InvalidParameter(quantity, x, "a finite prediction (the model gave none here)");
  };
  for (const Band& b : p.temperature_C) check(b, "temperature_C");
  for (const Band& b : p.scale_error_um) check(b, "scale_error_um");
  check(p.elongation_um, "elongation_um");
  check(p.friction_N, "friction_N");
  check(p.heat_rate_W, "heat_rate_W");
  check(p.profile_C, "end profile temperature_C");
}

}  // namespace

Prediction predict(const ModelFile& m, const DutyCycle& duty, const PredictionOptions& o) {
  if (!m.has_thermal) throw InvalidParameter("model", "has no [thermal] part: a prediction needs the calibrated rail model");
  if (!m.has_friction) throw InvalidParameter("model", "has no [friction] part: a prediction needs the friction law for the heat");
  m.require_friction_scalings("a duty's prediction");
  if (m.friction_covariance_matrix.empty() && m.thermal_covariance_matrix.empty())
    throw InvalidParameter("model", "has no covariance matrix (written by lmcal before 0.2?): recalibrate to get bands");
  if (o.samples < 20) throw InvalidParameter("samples", static_cast<double>(o.samples), "at least 20 draws for a band");
  require_in_range("confidence", o.confidence, 0.5, 0.999);
  if (o.half_rail_segments < 4) throw InvalidParameter("half_rail_segments", o.half_rail_segments, "at least 4");
  check_prediction_size(duty, o);  // before any draw is allocated
  require_positive("time_step_s", o.time_step_s);

  const bool other_guide = !m.guide.empty() && m.guide != duty.guide.model;
  // The names as JSON strings: quoted, a control character escaped (they reach a terminal).
  const auto quoted = [](const std::string& name) { return nlohmann::json(name).dump(); };
  if (other_guide && !o.any_guide)
    throw InvalidParameter("guide", fmt::format("the duty runs on {} but the model was calibrated on {}: its α, h and friction "
                                                "constants are that guide's rail and block; calibrate on {}, or predict anyway "
                                                "with --any-guide",
                                                quoted(duty.guide.model), quoted(m.guide), quoted(duty.guide.model)));

  const DrawSet set = make_draws(m, o);
  const std::vector<double> times = output_times(duty);
  Prediction p;
  p.time_s = times;
  p.positions_m = duty.positions_m;
  p.scale_positions_m = duty.scale.positions_m;
  const Trajectory point = simulate_duty(m, duty, set.draws[0], o, times, &p.segment);

  std::vector<Trajectory> draws(set.draws.size() - 1);
  std::vector<std::string> failed(draws.size());
  // Each draw on a free thread; anything but a draw's physics (out of memory) is rethrown.
  detail::for_each_index(draws.size(), [&](std::size_t i) {
    try {
      draws[i] = simulate_duty(m, duty, set.draws[i + 1], o, times, nullptr);
    } catch (const InputError& e) {
      failed[i] = e.what();
    } catch (const InvalidParameter& e) {
      failed[i] = e.what();
    }
  });
  std::vector<Trajectory> ran;
  std::size_t n_failed = 0;
  std::string first_failure;
  for (std::size_t i = 0; i < draws.size(); ++i) {
    if (failed[i].empty()) ran.push_back(std::move(draws[i]));
    else if (n_failed++ == 0) first_failure = failed[i];
  }
  if (ran.size() < 20) throw InvalidParameter("model", "too few parameter draws could be simulated: " + first_failure);
  p.samples = ran.size();
  p.method = set.method;
  p.notes = set.notes;
  if (other_guide)
    p.notes.push_back(fmt::format("the model was calibrated on {}, the duty runs on {} (--any-guide): its α, h and friction "
                                  "constants are carried over to a guide they were not fitted on",
                                  quoted(m.guide), quoted(duty.guide.model)));
  if (n_failed > 0)
    p.notes.push_back(fmt::format("{} of {} draws were not physical and were left out (first: {})", n_failed, draws.size(), first_failure));

  for (std::size_t q = 0; q < duty.positions_m.size(); ++q)
    p.temperature_C.push_back(band_of(point, ran, o.confidence, [q](const Trajectory& t) -> const std::vector<double>& { return t.temperature_C[q]; }));
  p.elongation_um = band_of(point, ran, o.confidence, [](const Trajectory& t) -> const std::vector<double>& { return t.elongation_um; });
  for (std::size_t q = 0; q < duty.scale.positions_m.size(); ++q)
    p.scale_error_um.push_back(band_of(point, ran, o.confidence, [q](const Trajectory& t) -> const std::vector<double>& { return t.scale_error_um[q]; }));
  p.friction_N = band_of(point, ran, o.confidence, [](const Trajectory& t) -> const std::vector<double>& { return t.friction_N; });
  p.heat_rate_W = band_of(point, ran, o.confidence, [](const Trajectory& t) -> const std::vector<double>& { return t.heat_rate_W; });
  p.profile_x_m = point.profile_x_m;
  p.profile_C = band_of(point, ran, o.confidence, [](const Trajectory& t) -> const std::vector<double>& { return t.profile_C; });
  flag_ranges(m, duty, point.max_rail_C, p);
  require_finite_bands(p);
  return p;
}

}  // namespace lmcal
