// The thermal fit itself: the parameters and their layout, the joint fit of all runs and each
// run's alone, and what the fitted model shows (goodness per sensor, the α curve, the end
// states, the sensitivities). The runs come prepared from thermal_prepare.cc, the heat's
// uncertainty from thermal_uncertainty.cc; thermal_output.cc writes the result.
#include "lmcal/fit/thermal_fit.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"
#include "parallel_slices.hpp"
#include "thermal_model.hpp"
#include "thermal_terms.hpp"

namespace lmcal {

using detail::ParameterSpec;
using detail::PreparedRun;
using detail::ThermalLayout;
using detail::ThermalModel;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

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
  return {.source = detail::source_of(o), .scheme = o.scheme, .half_rail_segments = o.half_rail_segments, .time_step_s = o.time_step_s};
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

// Step 2 of the two-stage fit: the heat's uncertainty into the joint fit's covariance.
void add_heat_uncertainty(const ThermalDataSet& data, const std::vector<PreparedRun>& runs, const ThermalModel& model,
                          const detail::FinalState& state, const ThermalFitOptions& o, ThermalFitResult& result) {
  const detail::HeatUncertainty heat = detail::heat_uncertainty(runs, result.runs, data, o);
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

// The terms' regressors (or, with `sum`, their fitted sum) at every sample of `fit`.
std::vector<std::vector<double>> term_values_at_samples(const ThermalDataSet& data, const ThermalFitOptions& o,
                                                        const ThermalFitResult& fit, const std::vector<double>& theta_given,
                                                        const std::vector<ThermalSensorTerm>* terms) {
  const std::vector<PreparedRun> runs = detail::prepared_runs(data, o);
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

// Checks the options that bound every residual evaluation.
void check_options(const ThermalDataSet& data, const ThermalFitOptions& o) {
  if (data.runs.empty()) throw InvalidParameter("runs", "the data set has no runs");
  // Every residual evaluation steps every run's rail: bounded before the first.
  if (o.half_rail_segments > io::kMaxRailSegments)
    throw InvalidParameter("half_rail_segments", o.half_rail_segments,
                           fmt::format("at most {} for a fit (docs/formats.md#limits)", io::kMaxRailSegments));
  validate(numerics_of(o));
}

// Every run prepared (result.runs: what is reported of each; `spans`: each sensor's span).
std::vector<PreparedRun> prepare_runs(const ThermalDataSet& data, const ThermalFitOptions& o, ThermalFitResult& result,
                                      std::vector<std::vector<double>>& spans) {
  std::vector<PreparedRun> runs;
  for (const auto& run : data.runs) {
    detail::PreparedRunInfo p = detail::prepare_run(run, o);
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
  return runs;
}

// Every run fitted alone: α's spread across the runs, their random effects, the widened SEs
// and the repeats' differences.
void fit_each_run(const ThermalDataSet& data, const std::vector<PreparedRun>& runs, const ThermalFitOptions& o,
                  ThermalFitResult& result) {
  std::vector<double> alphas;
  ThermalFitOptions one_run = o;  // for the spread across runs: estimates and SEs, no profiles
  one_run.fit.profile = ProfileMode::none;
  // Independent fits (each its own model): one thread each, kept in run order.
  result.per_run.resize(runs.size());
  detail::for_each_index(runs.size(), [&](std::size_t r) { result.per_run[r] = fit_runs({runs[r]}, one_run); });
  for (const FitResult& run : result.per_run) alphas.push_back(run.parameter("alpha").value);
  result.alpha_spread = spread(alphas, o.fit.confidence);
  std::vector<Estimate> estimates;
  std::vector<double> se;
  for (const FitResult& run : result.per_run) {
    const ParameterEstimate& a = run.parameter("alpha");
    se.push_back(a.se);
    if (std::isfinite(a.value) && std::isfinite(a.se) && a.se > 0) estimates.push_back({a.value, a.se});
  }
  if (estimates.size() >= 2) result.alpha_runs = random_effects(estimates, o.fit.confidence);
  if (o.fit.runs_replicate && o.fit.covariance == CovarianceMethod::automatic) detail::widen_to_the_runs(result, o.fit.confidence);
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
void compare_sources(const std::vector<PreparedRun>& runs, const ThermalFitOptions& o, ThermalFitResult& result) {
  ThermalFitOptions other = o;
  other.source = o.source == SourceModel::paper ? SourceModel::averaged : SourceModel::paper;
  other.per_run_fits = other.compare_sources = false;
  other.fit.bootstrap = 0;  // only its α is read
  other.fit.profile = ProfileMode::none;
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

// Every data row's error (measured − model) and its slope in α.
struct RowErrors {
  std::vector<double> error, d_alpha;
};

// Measured against the model, per sensor, from the final residuals r = measured - model
// (σ = 1). The model is linear in α, so the α error curve (the paper's Fig. 11) follows from
// the Jacobian column of α: r(α) = r(α̂) + ∂r/∂α · (α - α̂). With a robust loss the residuals
// are transformed, so the model is simulated again instead.
RowErrors row_errors(const ThermalModel& model, const std::vector<double>& theta, const detail::FinalState& final_state,
                     const ThermalFitOptions& o) {
  const std::vector<PreparedRun>& runs = model.runs();
  const ThermalLayout& layout = model.layout();
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
  return {std::move(error), std::move(d_alpha)};
}

// The goodness of every sensor and the samples (measured, simulated); returns the data row of
// every sample. A sensor's max error against its own span, or a tenth of the largest span of
// any sensor if more (a sensor far from the heat barely moves: its span is mostly noise).
std::vector<std::size_t> add_goodness(const ThermalModel& model, const std::vector<std::vector<double>>& spans,
                                      const std::vector<double>& error, ThermalFitResult& result) {
  const std::vector<PreparedRun>& runs = model.runs();
  const auto& rows = model.rows();
  std::vector<std::size_t> sample_rows;  // the data row of every sample
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
  return sample_rows;
}

// ∂ reading / ∂ θ of the global parameters at every sample: −∂r/∂θ (r = measured − reading).
void add_sensitivities(const ThermalLayout& layout, const std::vector<ParameterSpec>& specs,
                       const detail::FinalState& final_state, const std::vector<std::size_t>& sample_rows,
                       ThermalFitResult& result) {
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

// The rail's temperature at the sensors' last records: the readings less their offsets and terms.
void add_end_states(const ThermalModel& model, const std::vector<double>& theta, ThermalFitResult& result) {
  const std::vector<PreparedRun>& runs = model.runs();
  const ThermalLayout& layout = model.layout();
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
}

// The error of every run's first thermocouple against α (the paper's Fig. 11).
void add_alpha_curve(const ThermalModel& model, const RowErrors& errors, double alpha_hat, const ThermalFitOptions& o,
                     ThermalFitResult& result) {
  const std::vector<PreparedRun>& runs = model.runs();
  const auto& rows = model.rows();
  const std::vector<double>& error = errors.error;
  const std::vector<double>& d_alpha = errors.d_alpha;
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
}

}  // namespace

namespace detail {

// The source model: the option's, unless an extension switches it.
SourceModel source_of(const ThermalFitOptions& o) {
  SourceModel source = o.source;
  for (const auto& name : o.extensions)
    if (const auto switched = detail::thermal_extension(name).source) source = *switched;
  return source;
}

}  // namespace detail

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

std::vector<AmbientTrace> thermal_fit_ambients(const ThermalDataSet& data, const ThermalFitOptions& options) {
  std::vector<AmbientTrace> out;
  for (const auto& run : detail::prepared_runs(data, options)) out.push_back(run.ambient);
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
  check_options(data, o);
  ThermalFitResult result;
  std::vector<std::vector<double>> spans;
  const std::vector<PreparedRun> runs = prepare_runs(data, o, result, spans);

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
  if (usable && o.per_run_fits && runs.size() >= 2) fit_each_run(data, runs, o, result);
  if (usable && o.compare_sources && detail::source_of(o) == o.source && o.source != SourceModel::moving)
    compare_sources(runs, o, result);

  // What the fitted model shows.
  const std::vector<double> theta = result.joint.values();
  const RowErrors errors = row_errors(model, theta, final_state, o);
  const std::vector<std::size_t> sample_rows = add_goodness(model, spans, errors.error, result);
  if (o.sensitivities && o.fit.loss == RobustLoss::none) add_sensitivities(layout, specs, final_state, sample_rows, result);
  for (std::size_t j = 0; j < layout.terms.size(); ++j) {
    std::vector<std::size_t> indices{static_cast<std::size_t>(layout.term_coefficient[j])};
    if (layout.term_scale[j] >= 0) indices.push_back(static_cast<std::size_t>(layout.term_scale[j]));
    result.sensor_term_parameters.push_back(indices);
  }
  add_end_states(model, theta, result);
  add_alpha_curve(model, errors, theta[static_cast<std::size_t>(layout.alpha)], o, result);
  for (const auto& pr : runs) result.sensor_names.push_back(pr.sensor_names);
  return result;
}

}  // namespace lmcal
