// `lmcal plan thermal`: the next thermal runs for a calibrated rail model (plan.hpp).

#include "lmcal/version.hpp"
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

#include "lmcal/error.hpp"
#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/predict/plan.hpp"
#include "predict/design.hpp"

namespace lmcal {

namespace {

// The model's rail parameters a plan is for, and the mechanisms it simulates with.
struct ThermalParameters {
  std::vector<std::string> names;
  std::vector<double> values, scales;
  std::vector<double> lower;            // a forward step from a lower bound stays inside
  std::vector<std::string> mechanisms;  // the model's and the separated ones
  std::vector<std::size_t> separated;   // indices into names: the separated mechanisms' first parameters
};

ThermalParameters parameters_of(const ModelFile& m, const std::vector<std::string>& separate) {
  ThermalParameters p;
  const auto library = thermal_extension_library();
  const auto info_of = [&](const std::string& mechanism) {
    const auto e = std::find_if(library.begin(), library.end(), [&](auto& x) { return x.name == mechanism; });
    if (e == library.end()) throw InvalidParameter("separate", fmt::format("unknown mechanism '{}'", mechanism));
    if (e->parameters.empty()) throw InvalidParameter("separate", fmt::format("'{}' is a switch, without a parameter to compare", mechanism));
    return *e;
  };
  for (const auto& mp : m.thermal_parameters) {
    if (mp.held) continue;
    double scale = std::abs(mp.value), lower = -std::numeric_limits<double>::infinity();
    for (const auto& e : library)
      for (std::size_t k = 0; k < e.parameters.size(); ++k)
        if (e.parameters[k] == mp.name) {
          scale = std::max(scale, e.parameter_scale[k]);
          lower = e.parameter_bounds[k].first;
        }
    if (mp.name == "alpha") lower = 0;
    p.names.push_back(mp.name);
    p.values.push_back(mp.name == "alpha" ? m.alpha : mp.value);
    p.scales.push_back(std::max(scale, 1e-6));
    p.lower.push_back(lower);
  }
  p.mechanisms = m.mechanisms;
  if (!separate.empty() && separate.size() != 2)
    throw InvalidParameter("separate", "two mechanisms to tell apart, e.g. base_loss,convection_velocity");
  for (const auto& mechanism : separate) {
    const ThermalExtensionInfo e = info_of(mechanism);
    const bool in_model = std::find(m.mechanisms.begin(), m.mechanisms.end(), mechanism) != m.mechanisms.end();
    if (!in_model) {  // at its neutral value: none of it (0, or its lower bound)
      p.mechanisms.push_back(mechanism);
      for (std::size_t k = 0; k < e.parameters.size(); ++k) {
        const auto [lo, hi] = e.parameter_bounds[k];
        p.names.push_back(e.parameters[k]);
        p.values.push_back(lo <= 0 && 0 <= hi ? 0.0 : lo);
        p.scales.push_back(e.parameter_scale[k]);
        p.lower.push_back(lo);
      }
    }
    const auto at = std::find(p.names.begin(), p.names.end(), e.parameters.front());
    if (at == p.names.end()) throw InvalidParameter("separate", fmt::format("'{}' is held in the model", mechanism));
    p.separated.push_back(static_cast<std::size_t>(at - p.names.begin()));
  }
  if (p.names.empty()) throw InvalidParameter("model", "its rail model has no free parameter to plan for");
  return p;
}

// One run as the plan simulates it.
struct RunShape {
  RailGeometry geometry;
  RailParams<double> params;
  FrictionConditions<double> conditions;
  double ambient_C = 24, duration_s = 0;
  std::vector<double> sensors_m;
};

RunShape shape_of(const ThermalRun& run, const ModelFile& m) {
  const GuideSpec g = resolved_guide(run);
  RunShape s;
  double ambient = run.ambient_C.value_or(NAN);
  if (std::isnan(ambient)) {
    double sum = 0;
    for (const auto& c : run.trace.ambient) sum += c.values.empty() ? 0 : c.values.front();
    ambient = run.trace.ambient.empty() ? 24.0 : sum / static_cast<double>(run.trace.ambient.size());
  }
  s.ambient_C = ambient;
  s.duration_s = run.trace.size() > 1 ? run.trace.time_s.back() - run.trace.time_s.front() : 0;
  const double contact_mm = run.contact_length_mm ? *run.contact_length_mm : require(g, &GuideSpec::contact_length_mm, "contact_length_mm");
  s.geometry = rail_geometry_of(g, run.rail_length_m, run.stroke_m, contact_mm * 1e-3, run.velocity_m_s);
  s.params = rail_material_of(g);
  s.params.heat_partition = m.alpha;
  s.params.h_W_m2K = m.h_W_m2K.value_or(5.3);
  s.params.initial_temperature_C = ambient;
  s.conditions = {.load_N = run.load_N,
                  .preload_um = run.preload_um ? *run.preload_um : require(g, &GuideSpec::preload_um, "preload_um"),
                  .block_length_mm = run.block_length_mm ? *run.block_length_mm : require(g, &GuideSpec::block_length_mm, "block_length_mm"),
                  .velocity_m_s = run.velocity_m_s,
                  .temperature_C = ambient};
  for (const auto& [sensor, x] : run.sensor_position_m) s.sensors_m.push_back(x);
  return s;
}

// The readings of a run at θ, every record_every_s, sensor by sensor.
Eigen::VectorXd readings(const RunShape& s, const ModelFile& m, const ThermalParameters& p, const std::vector<double>& theta,
                         double record_every_s) {
  RailParams<double> params = s.params;
  std::vector<std::pair<std::string, double>> values = m.mechanism_parameters;
  for (std::size_t j = 0; j < p.names.size(); ++j) {
    if (p.names[j] == "alpha") params.heat_partition = std::clamp(theta[j], 0.0, 1.0);
    else if (p.names[j] == "h_W_m2K") params.h_W_m2K = theta[j];
    else {
      const auto at = std::find_if(values.begin(), values.end(), [&](auto& v) { return v.first == p.names[j]; });
      if (at == values.end()) values.emplace_back(p.names[j], theta[j]);
      else at->second = theta[j];
    }
  }
  RailOutputs outputs{.duration_s = s.duration_s, .sensor_positions_m = s.sensors_m, .source_temperature = false};
  for (double t = record_every_s; t <= s.duration_s + 1e-9; t += record_every_s) outputs.output_times_s.push_back(t);
  const RailNumerics numerics{.source = m.source, .scheme = TimeScheme::crank_nicolson, .half_rail_segments = 50,
                              .time_step_s = std::min(60.0, record_every_s)};
  const RailSolution<double> sol = simulate_rail_with_mechanisms(s.geometry, numerics, outputs, params,
                                                                 AmbientTrace::constant(s.ambient_C), m.constants, m.effects,
                                                                 s.conditions, p.mechanisms, values);
  return Eigen::Map<const Eigen::VectorXd>(sol.sensor_temperature_C.data(), static_cast<Eigen::Index>(sol.sensor_temperature_C.size()));
}

// The run's information, SᵀS/σ², S the sensitivities with each sensor's mean taken out.
Eigen::MatrixXd information(const RunShape& s, const ModelFile& m, const ThermalParameters& p, double record_every_s,
                            double noise_K) {
  const Eigen::VectorXd y0 = readings(s, m, p, p.values, record_every_s);
  const auto n = y0.size(), k = static_cast<Eigen::Index>(p.names.size());
  const auto sensors = static_cast<Eigen::Index>(s.sensors_m.size());
  Eigen::MatrixXd S(n, k);
  for (Eigen::Index j = 0; j < k; ++j) {
    std::vector<double> theta = p.values;
    const double h = 1e-3 * p.scales[static_cast<std::size_t>(j)];
    theta[static_cast<std::size_t>(j)] += h;
    S.col(j) = (readings(s, m, p, theta, record_every_s) - y0) / h;
  }
  for (Eigen::Index q = 0; q < sensors; ++q) {  // rows are [time][sensor]
    for (Eigen::Index j = 0; j < k; ++j) {
      double mean = 0;
      for (Eigen::Index r = q; r < n; r += sensors) mean += S(r, j);
      mean /= static_cast<double>(n / sensors);
      for (Eigen::Index r = q; r < n; r += sensors) S(r, j) -= mean;
    }
  }
  const Eigen::VectorXd scale = Eigen::Map<const Eigen::VectorXd>(p.scales.data(), k);
  S = S * scale.asDiagonal();  // in units of the parameters' sizes
  return S.transpose() * S / (noise_K * noise_K);
}


double correlation(const Eigen::MatrixXd& cov, std::size_t a, std::size_t b) {
  const auto i = static_cast<Eigen::Index>(a), j = static_cast<Eigen::Index>(b);
  return cov(i, j) / std::sqrt(cov(i, i) * cov(j, j));
}

}  // namespace

std::vector<ThermalCandidate> thermal_candidates(const ThermalDataSet& data, const ThermalCandidateGrid& grid) {
  if (data.runs.empty()) throw InvalidParameter("runs", "no thermal runs to plan from");
  std::vector<double> v, P;
  double duration = 0;
  for (const ThermalRun& r : data.runs) {
    v.push_back(r.velocity_m_s);
    P.push_back(r.load_N);
    if (r.trace.size() > 1) duration = std::max(duration, r.trace.time_s.back() - r.trace.time_s.front());
  }
  const auto own = [](const std::vector<double>& given, std::vector<double> fallback) {
    std::vector<double> out = given.empty() ? std::move(fallback) : given;
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  };
  std::vector<ThermalCandidate> out;
  for (double vi : own(grid.velocity_m_s, v))
    for (double Pi : own(grid.load_N, P))
      for (double T : own(grid.duration_s, {duration})) {
        require_positive("velocity_m_s", vi);
        require_non_negative("load_N", Pi);
        require_positive("duration_s", T);
        out.push_back({vi, Pi, T});
      }
  return out;
}

namespace {

// The greedy design: `count` times, the candidate run whose information (`candidate_info`)
// raises `criterion` of the covariance most, added to `info` and the plan; the covariance after
// (`cov`: the one before, `info`'s).
template <class Criterion>
Eigen::MatrixXd pick_runs(const std::vector<ThermalCandidate>& candidates, const std::vector<Eigen::MatrixXd>& candidate_info,
                          std::size_t count, double ridge, const Criterion& criterion, Eigen::MatrixXd& info, Eigen::MatrixXd cov,
                          ThermalPlan& plan) {
  std::vector<bool> taken(candidates.size(), false);
  for (std::size_t r = 0; r < count; ++r) {
    const double now = criterion(cov);
    double best = -std::numeric_limits<double>::infinity();
    std::size_t best_c = 0;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      if (taken[c]) continue;
      const double gain = criterion(detail::ridge_inverse(info + candidate_info[c], ridge)) - now;
      if (gain > best) {
        best = gain;
        best_c = c;
      }
    }
    taken[best_c] = true;
    info += candidate_info[best_c];
    cov = detail::ridge_inverse(info, ridge);
    plan.picks.push_back({candidates[best_c], best});
  }
  return cov;
}

// Each parameter's SE before (the model's quoted one, else from the runs' information, variances
// `before`; `before_own` those of the model's own parameters alone) and after the planned runs
// (`cov`, with their information `info`); a note for one the rail's temperature does not show.
void expected_parameters(const ModelFile& m, const ThermalParameters& p, const Eigen::MatrixXd& info, const Eigen::VectorXd& before,
                         const Eigen::VectorXd& before_own, const Eigen::MatrixXd& cov, ThermalPlan& plan) {
  const auto k = static_cast<Eigen::Index>(p.names.size());
  for (Eigen::Index j = 0; j < k; ++j) {
    const auto js = static_cast<std::size_t>(j);
    if (!(info(j, j) > 1e-12 * info.diagonal().maxCoeff())) {  // nothing in the rail's temperature depends on it
      plan.notes.push_back(fmt::format("{}: the rail's temperature does not depend on it (a sensor's property): not planned for",
                                       p.names[js]));
      continue;
    }
    const ModelParameter* quoted = m.find(p.names[js]);
    PlannedParameter r{p.names[js], quoted ? quoted->unit : "", p.values[js]};
    r.determined_before = quoted && !quoted->held && std::isfinite(quoted->se) && quoted->se > 0;
    const double s = p.scales[js];
    r.se_before = r.determined_before ? quoted->se : s * std::sqrt(before(j));
    // Scaled as the information's variance changes; it may grow where a separated mechanism
    // now shares what the model's parameter explained alone.
    r.se_after = r.determined_before ? quoted->se * std::sqrt(cov(j, j) / before_own(j)) : s * std::sqrt(cov(j, j));
    plan.parameters.push_back(r);
  }
}

}  // namespace

ThermalPlan plan_thermal(const ModelFile& m, const ThermalDataSet& data, const std::vector<ThermalCandidate>& candidates,
                         const ThermalPlanOptions& o) {
  if (!m.has_thermal || !m.has_friction)
    throw InvalidParameter("model", "a thermal plan needs the calibrated model's [thermal] and [friction] (the heat)");
  if (candidates.empty()) throw InvalidParameter("candidates", "no candidate runs to choose from");
  require_positive("record_every_s", o.record_every_s);
  const ThermalParameters p = parameters_of(m, o.separate);
  const auto k = static_cast<Eigen::Index>(p.names.size());
  ThermalPlan plan;
  plan.noise_K = o.noise_K;
  if (!(plan.noise_K > 0)) {
    double sum = 0;
    for (const ThermalRun& r : data.runs) sum += thermocouple_noise_K(r.trace, 120);
    plan.noise_K = std::max(sum / static_cast<double>(data.runs.size()), 1e-3);
  }
  std::vector<Eigen::Index> named;
  for (const auto& name : o.parameters) {
    const auto at = std::find(p.names.begin(), p.names.end(), name);
    if (at == p.names.end()) throw InvalidParameter("parameters", fmt::format("'{}' is not a free parameter of the rail model", name));
    named.push_back(at - p.names.begin());
  }
  plan.criterion = !p.separated.empty() ? fmt::format("Ds-optimal: separate {} from {}", o.separate[0], o.separate[1])
                   : named.empty()      ? "D-optimal (all parameters)"
                                        : fmt::format("A-optimal for {}", fmt::join(o.parameters, ", "));

  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(k, k);
  for (const ThermalRun& run : data.runs) info += information(shape_of(run, m), m, p, o.record_every_s, plan.noise_K);
  const double ridge = 1e-10 * std::max(info.trace(), 1e-30) / static_cast<double>(k);
  const Eigen::MatrixXd before_cov = detail::ridge_inverse(info, ridge);
  const Eigen::VectorXd before = before_cov.diagonal();
  // The model's quoted SEs are those of its own parameters, without the separated mechanism it
  // lacks: their variance before from the information of those alone.
  std::vector<Eigen::Index> own;
  for (Eigen::Index j = 0; j < k; ++j)
    if (m.find(p.names[static_cast<std::size_t>(j)])) own.push_back(j);
  const Eigen::VectorXd before_own = detail::variances_holding_others(info, own, ridge);
  const RunShape base = shape_of(data.runs.front(), m);
  const auto shape_for = [&](const ThermalCandidate& c) {
    RunShape s = base;
    s.geometry.velocity_m_s = s.conditions.velocity_m_s = c.velocity_m_s;
    s.conditions.load_N = c.load_N;
    s.duration_s = c.duration_s;
    return s;
  };
  std::vector<Eigen::MatrixXd> candidate_info(candidates.size());
  for (std::size_t c = 0; c < candidates.size(); ++c)
    candidate_info[c] = information(shape_for(candidates[c]), m, p, o.record_every_s, plan.noise_K);
  const auto criterion = [&](const Eigen::MatrixXd& cov) {
    if (!p.separated.empty()) {  // log det of the separated pair's covariance: smaller is better
      Eigen::Matrix2d pair;
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) pair(a, b) = cov(static_cast<Eigen::Index>(p.separated[a]), static_cast<Eigen::Index>(p.separated[b]));
      return -std::log(pair.determinant());
    }
    if (!named.empty()) {
      double sum = 0;
      for (Eigen::Index j : named) sum += cov(j, j) / before(j);
      return -sum;
    }
    return -std::log(cov.determinant());
  };
  const Eigen::MatrixXd cov = pick_runs(candidates, candidate_info, std::min(o.runs, candidates.size()), ridge, criterion, info,
                                        before_cov, plan);
  plan.correlation_before = p.separated.empty() ? NAN : correlation(before_cov, p.separated[0], p.separated[1]);
  plan.correlation_after = p.separated.empty() ? NAN : correlation(cov, p.separated[0], p.separated[1]);
  expected_parameters(m, p, info, before, before_own, cov, plan);
  if (!p.separated.empty())
    plan.notes.push_back(fmt::format("{} and {} (at its neutral value where the model lacks it): correlation of their estimates "
                                     "{:.3f} with the runs logged, {:.3f} with the planned ones too",
                                     o.separate[0], o.separate[1], plan.correlation_before, plan.correlation_after));
  if (!p.separated.empty() && std::abs(plan.correlation_after) > 0.99) {
    std::vector<std::string> measures;
    for (const auto& e : thermal_extension_library())
      if ((e.name == o.separate[0] || e.name == o.separate[1]) && !e.measure.empty()) measures.push_back(e.name + ": " + e.measure);
    plan.notes.push_back(fmt::format("no candidate run separates them (their effects have the same shape at every speed, load and "
                                     "duration given); what would: {}",
                                     fmt::join(measures, "; ")));
  }
  plan.notes.push_back(fmt::format("each run's readings every {} s with noise {:.3g} K, its thermocouple offsets fitted; a "
                                   "mechanism not in the model: its SE from that information alone",
                                   o.record_every_s, plan.noise_K));
  return plan;
}

std::string thermal_plan_json(const ThermalPlan& plan, const std::vector<std::string>& command) {
  nlohmann::json runs = nlohmann::json::array(), parameters = nlohmann::json::array();
  for (const auto& r : plan.picks)
    runs.push_back({{"velocity_m_s", r.candidate.velocity_m_s}, {"load_N", r.candidate.load_N},
                    {"duration_s", r.candidate.duration_s}, {"gain", r.gain}});
  const auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  for (const auto& p : plan.parameters)
    parameters.push_back({{"name", p.name}, {"unit", p.unit}, {"value", p.value}, {"se_before", number(p.se_before)},
                          {"se_after", number(p.se_after)}, {"in_model", p.determined_before}});
  return nlohmann::json({{"kind", "thermal plan"}, {"lmcal_version", LMCAL_VERSION}, {"schema_version", kOutputSchemaVersion}, {"command", command},
                         {"criterion", plan.criterion}, {"noise_K", plan.noise_K}, {"runs", runs}, {"parameters", parameters},
                         {"correlation_before", number(plan.correlation_before)},
                         {"correlation_after", number(plan.correlation_after)}, {"notes", plan.notes}})
             .dump(1) +
         "\n";
}

std::string thermal_plan_manifest_toml(const ThermalPlan& plan, const ThermalDataSet& data) {
  const ThermalRun& first = data.runs.front();
  std::string out = fmt::format("# lmcal plan: the next thermal runs, {}. Log each run into its file (time_s, the\n"
                                "# ambient and tc columns as before), then calibrate with the old runs.\n",
                                plan.criterion);
  for (std::size_t r = 0; r < plan.picks.size(); ++r) {
    const ThermalCandidate& c = plan.picks[r].candidate;
    out += fmt::format("\n[[run]]\nid = \"plan{0}\"\nfile = \"thermal/plan{0}.csv\"\nguide = \"{1}\"\nvelocity_m_s = {2}\n"
                       "load_N = {3}\nstroke_m = {4}\nrail_length_m = {5}\n# duration: {6} h\n[run.sensors_m]\n",
                       r + 1, first.guide, c.velocity_m_s, c.load_N, first.stroke_m, first.rail_length_m, c.duration_s / 3600);
    for (const auto& [sensor, x] : first.sensor_position_m) out += fmt::format("{} = {}\n", sensor, x);
  }
  return out;
}

std::string thermal_plan_summary(const ThermalPlan& plan) {
  std::string out = fmt::format("plan: the next {} thermal runs, {}:\n", plan.picks.size(), plan.criterion);
  for (std::size_t r = 0; r < plan.picks.size(); ++r)
    out += fmt::format("  {:>2}. V = {:g} m/s  P = {:g} N  {:g} h\n", r + 1, plan.picks[r].candidate.velocity_m_s,
                       plan.picks[r].candidate.load_N, plan.picks[r].candidate.duration_s / 3600);
  out += "expected standard errors, now -> after:\n";
  for (const auto& p : plan.parameters) out += detail::expected_se_line(p, p.determined_before ? "" : " (not in the model)");
  for (const auto& n : plan.notes) out += "  note: " + n + "\n";
  return out;
}

}  // namespace lmcal
