#include "thermal_model.hpp"

#include <ceres/jet.h>
#include <fmt/format.h>

#include <algorithm>
#include <exception>
#include <cmath>
#include <limits>

#include "lmcal/error.hpp"
#include "lmcal/models/thermal_effects.hpp"
#include "parallel_slices.hpp"
#include "thermal_terms.hpp"

namespace lmcal::detail {

namespace {

// The global parameters run r's simulation depends on: α, h, the extensions', its T0. Its
// sensors' offsets enter the residuals only, with derivative -1 (through the robust loss):
// they are not carried through the solver.
std::vector<int> local_parameters(const ThermalLayout& layout, std::size_t r) {
  std::vector<int> local{layout.alpha};
  if (layout.h >= 0) local.push_back(layout.h);
  for (std::size_t e = 0; e < layout.extensions.size(); ++e)
    for (std::size_t j = 0; j < layout.extensions[e]->parameters.size(); ++j)
      local.push_back(layout.extension_first[e] + static_cast<int>(j));
  if (layout.initial[r] >= 0) local.push_back(layout.initial[r]);
  if (!layout.heat_scale.empty() && layout.heat_scale[r] >= 0) local.push_back(layout.heat_scale[r]);
  return local;
}

template <typename T>
double value_of(const T& x) {
  if constexpr (std::is_same_v<T, double>) return x;
  else return x.a;
}

// The time mean of a quantity given at the output times (trapezoids; the value when there is one).
template <typename T>
T time_mean(const std::vector<double>& time_s, const std::vector<T>& values) {
  if (values.size() < 2 || !(time_s.back() > time_s.front())) return values.front();
  T sum(0.0);
  for (std::size_t i = 0; i + 1 < values.size(); ++i) sum += 0.5 * (values[i] + values[i + 1]) * (time_s[i + 1] - time_s[i]);
  return sum / (time_s.back() - time_s.front());
}

// The rail with a temperature-following heat rate scaled so that its mean over the run (the
// outputs, which span it) is params.heat_rate_W, the measured run mean: Q(t) = c · model(T_s),
// with c the root of ln mean(c) = ln Q_mean. The mean grows more slowly than c (a larger heat
// warms the rail, and the friction falls), so secant steps on ln c converge in a few
// simulations; a Jet's derivatives converge with its value.
template <typename T>
RailSolution<T> simulate_rail_keeping_mean_heat(const RailGeometry& geometry, const RailNumerics& numerics,
                                                const RailOutputs& outputs, const RailParams<T>& params,
                                                const AmbientTrace& ambient, const HeatRateModel<T>& heat_rate) {
  using std::exp, std::log;
  if (!(value_of(params.heat_rate_W) > 0)) return simulate_rail(geometry, numerics, outputs, params, ambient, heat_rate);
  constexpr int kMaxSimulations = 12;
  constexpr double kTolerance = 1e-9;  // of ln(mean / target)
  const T log_target = log(params.heat_rate_W);
  T log_c(0.0), previous_log_c(0.0), previous_miss(0.0);
  RailSolution<T> sol;
  for (int k = 0; k < kMaxSimulations; ++k) {
    const T c = exp(log_c);
    sol = simulate_rail<T>(geometry, numerics, outputs, params, ambient, [&](const T& source_C) { return c * heat_rate(source_C); });
    const T miss = log(time_mean(sol.output_times_s, sol.heat_rate_W)) - log_target;
    if (std::abs(value_of(miss)) < kTolerance) break;
    // d ln mean / d ln c: 1 for the first step, then the secant's (kept within reason).
    double slope = 1.0;
    if (k > 0 && value_of(log_c) != value_of(previous_log_c))
      slope = std::clamp(value_of(miss - previous_miss) / value_of(log_c - previous_log_c), 0.2, 5.0);
    previous_log_c = log_c;
    previous_miss = miss;
    log_c = log_c - miss / slope;
  }
  return sol;
}

// Simulated temperatures of run r, [time][sensor], with the parameters given by `param`
// (global index -> scalar) and the run's fixed values elsewhere; with `end_profile`, also the
// rail's temperature profile at the last record.
template <typename T, typename Param>
std::vector<std::vector<T>> simulate_run(const PreparedRun& run, const RailNumerics& numerics,
                                         const ThermalLayout& layout, std::size_t r, const Param& param,
                                         RailProfile* end_profile = nullptr, std::vector<T>* end_field = nullptr) {
  const bool scaled = !layout.heat_scale.empty() && layout.heat_scale[r] >= 0;
  const T heat_scale = scaled ? param(layout.heat_scale[r]) : T(1.0);
  // A schedule's phase heats carry the run's heat scale too (and with it its derivative).
  HeatRateSchedule<T> schedule;
  for (std::size_t k = 0; k < run.params.heat_schedule.time_s.size(); ++k)
    schedule.add(run.params.heat_schedule.time_s[k], run.params.heat_schedule.heat_rate_W[k] * heat_scale);
  RailParams<T> p{.heat_partition = param(layout.alpha),
                  .heat_rate_W = scaled ? run.params.heat_rate_W * heat_scale : T(run.params.heat_rate_W),
                  .h_W_m2K = layout.h >= 0 ? param(layout.h) : T(run.params.h_W_m2K),
                  .conductivity_W_mK = T(run.params.conductivity_W_mK),
                  .density_kg_m3 = T(run.params.density_kg_m3),
                  .specific_heat_J_kgK = T(run.params.specific_heat_J_kgK),
                  .initial_temperature_C = layout.initial[r] >= 0 ? param(layout.initial[r])
                                                                  : T(run.params.initial_temperature_C),
                  .base_loss_W_mK = T(run.params.base_loss_W_mK),
                  .heat_schedule = std::move(schedule)};
  ThermalRunSetup<T> setup{.velocity_m_s = run.geometry.velocity_m_s,
                           .friction = &run.friction,
                           .friction_effects = &run.friction_effects,
                           .conditions = run.conditions,
                           .params = p,
                           .heat_rate_is_run_mean = run.heat_is_run_mean};
  for (std::size_t e = 0; e < layout.extensions.size(); ++e) {
    std::vector<T> values;
    for (std::size_t j = 0; j < layout.extensions[e]->parameters.size(); ++j)
      values.push_back(param(layout.extension_first[e] + static_cast<int>(j)));
    layout.extensions[e]->apply(setup, values.data());
  }
  const RailOutputs outputs{.duration_s = run.times_s.back(),
                            .sensor_positions_m = run.sensor_positions_m,
                            .output_times_s = run.times_s,
                            .profile_times_s = end_profile || end_field ? std::vector<double>{run.times_s.back()}
                                                                        : std::vector<double>{},
                            .source_temperature = false};  // only the sensors are compared
  const RailSolution<T> sol =
      setup.heat_rate && setup.heat_rate_is_run_mean
          ? simulate_rail_keeping_mean_heat(run.geometry, numerics, outputs, setup.params, run.ambient, setup.heat_rate)
          : simulate_rail(run.geometry, numerics, outputs, setup.params, run.ambient, setup.heat_rate);
  if (end_profile) {
    std::vector<double> values;
    for (const T& x : sol.profiles_C.front()) values.push_back(value_of(x));
    *end_profile = {run.times_s.back(), sol.node_positions_m, std::move(values)};
  }
  if (end_field) *end_field = sol.profiles_C.front();
  std::vector<std::vector<T>> out(run.times_s.size(), std::vector<T>(run.sensor_positions_m.size()));
  for (std::size_t s = 0; s < run.sensor_positions_m.size(); ++s) {
    std::vector<T> series(run.times_s.size());
    for (std::size_t t = 0; t < run.times_s.size(); ++t) series[t] = sol.temperature_C(t, s);
    if (setup.lagged) series = first_order_lag(run.times_s, series, setup.sensor_lag_s);
    for (std::size_t t = 0; t < run.times_s.size(); ++t) out[t][s] = series[t];
  }
  return out;
}

// The sensor terms of a run at its records: φ_j(t), and ∂φ_j/∂scale where the scale is fitted
// (and derivatives are asked for). They enter the residuals only, not the solver.
struct RunTerms {
  std::vector<std::vector<double>> phi, dphi;  // [term][time]; dphi empty without a fitted scale
};

RunTerms run_terms(const PreparedRun& run, const ThermalLayout& layout, const double* theta, bool derivatives) {
  RunTerms out;
  for (std::size_t j = 0; j < layout.terms.size(); ++j) {
    const ThermalSensorTerm& term = layout.terms[j];
    const int scale = layout.term_scale[j];
    const double s = scale >= 0 ? theta[scale] : term.scale_s;
    std::vector<double> phi, dphi;
    if (derivatives && scale >= 0) {
      using Jet1 = ceres::Jet<double, 1>;
      for (const Jet1& x : sensor_term_regressor<Jet1>(term.kind, Jet1(s, 0), run.times_s, run.ambient, run.geometry.velocity_m_s)) {
        phi.push_back(x.a);
        dphi.push_back(x.v[0]);
      }
    } else {
      phi = sensor_term_regressor<double>(term.kind, s, run.times_s, run.ambient, run.geometry.velocity_m_s);
    }
    out.phi.push_back(std::move(phi));
    out.dphi.push_back(std::move(dphi));
  }
  return out;
}

// The global parameters run r's rows depend on (its simulation's, its sensors' offsets and the
// sensor terms'), ascending: the only nonzero columns of its Jacobian rows.
std::vector<int> run_columns(const ThermalLayout& layout, std::size_t r) {
  std::vector<int> columns = local_parameters(layout, r);
  for (int o : layout.offsets[r])
    if (o >= 0) columns.push_back(o);
  for (std::size_t j = 0; j < layout.terms.size(); ++j) {
    columns.push_back(layout.term_coefficient[j]);
    if (layout.term_scale[j] >= 0) columns.push_back(layout.term_scale[j]);
  }
  std::sort(columns.begin(), columns.end());
  columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
  return columns;
}

// Where rows go: row k's residual at r[k - first]; with J, its slope over global parameter j
// at J[(k - first) · stride + column(j)], column(j) = j or, for a run's own block, its place
// among the run's columns.
struct RowSink {
  double* r;
  double* J = nullptr;
  std::size_t first = 0, stride = 0;
  const std::vector<int>* column = nullptr;  // global -> block column; null: the global index
  double& slope(std::size_t row, int j) const {
    return J[(row - first) * stride + static_cast<std::size_t>(column ? (*column)[static_cast<std::size_t>(j)] : j)];
  }
};

class ThermalCost final : public ceres::CostFunction, public NormalEquationsCost {
 public:
  ThermalCost(const ThermalModel& model, std::vector<std::size_t> rows, RowLoss loss)
      : model_(model), rows_(std::move(rows)), loss_(loss) {
    mutable_parameter_block_sizes()->push_back(model.layout().size);
    set_num_residuals(static_cast<int>(rows_.empty() ? model.num_residuals() : rows_.size()));
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const double* theta = parameters[0];
    const std::size_t n = model_.num_residuals();
    const auto P = static_cast<std::size_t>(model_.layout().size);
    const bool subset = !rows_.empty();
    std::vector<double> all_r, all_J;
    double* r = residuals;
    double* J = jacobians && jacobians[0] ? jacobians[0] : nullptr;
    if (subset) {
      all_r.resize(n);
      r = all_r.data();
      if (J) {
        all_J.resize(n * P);
        J = all_J.data();
      }
    }
    if (J) std::fill(J, J + n * P, 0.0);
    const bool ok = evaluate_runs(theta, J != nullptr, [&](std::size_t) { return RowSink{r, J, 0, P}; });
    if (!ok) return false;
    for (std::size_t k = 0; k < model_.prior_runs().size(); ++k) {
      const std::size_t row = model_.rows().size() + k;
      const Prior prior = prior_row(theta, k);
      r[row] = prior.residual;
      if (J) J[row * P + prior.index] = prior.weight;
    }
    if (subset) {
      for (std::size_t k = 0; k < rows_.size(); ++k) {
        residuals[k] = all_r[rows_[k]];
        if (J) std::copy_n(all_J.data() + rows_[k] * P, P, jacobians[0] + k * P);
      }
    }
    return true;
  }

  // A residual pass costs 40 % of the normal equations' (the simulation dominates both) and
  // nearly every step of a thermal polish is taken.
  bool normal_equations_at_trials() const override { return true; }

  // Each run's JᵀJ over its own columns (a handful of the parameters: its simulation's, its
  // offsets, the terms'), scattered into the whole in run order: the same bits on any thread
  // count. The runs' rows are kept in the model for residuals_and_jacobian at the same θ.
  bool normal_equations(const double* theta, const std::vector<bool>& held, double& cost, Eigen::MatrixXd& JtJ,
                        Eigen::VectorXd& Jtr) const override {
    const auto P = static_cast<Eigen::Index>(model_.layout().size);
    JtJ.setZero(P, P);
    Jtr.setZero(P);
    cost = 0;
    if (!rows_.empty()) {  // a subset of rows: through the stored Jacobian
      Eigen::VectorXd r;
      Eigen::MatrixXd J;
      if (!residuals_and_jacobian(theta, held, r, J)) return false;
      JtJ.noalias() = J.transpose() * J;
      Jtr.noalias() = J.transpose() * r;
      cost = 0.5 * r.squaredNorm();
      return true;
    }
    struct Sums {
      Eigen::MatrixXd H;
      Eigen::VectorXd g;
      double cost = 0;
    };
    std::vector<Sums> sums(model_.runs().size());
    std::vector<ThermalRunRows> blocks;
    const bool ok = run_blocks(theta, blocks, [&](std::size_t run, const ThermalRunRows& b) {
      sums[run] = {b.J.transpose() * b.J, b.J.transpose() * b.r, 0.5 * b.r.squaredNorm()};
    });
    if (!ok) return false;
    model_.remember_rows(theta, loss_, std::move(blocks));
    for (std::size_t run = 0; run < sums.size(); ++run) {
      const std::vector<int> columns = run_columns(model_.layout(), run);
      for (std::size_t a = 0; a < columns.size(); ++a) {
        Jtr[columns[a]] += sums[run].g[static_cast<Eigen::Index>(a)];
        for (std::size_t b = 0; b < columns.size(); ++b)
          JtJ(columns[a], columns[b]) += sums[run].H(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
      }
      cost += sums[run].cost;
    }
    for (std::size_t k = 0; k < model_.prior_runs().size(); ++k) {
      const Prior prior = prior_row(theta, k);
      JtJ(prior.index, prior.index) += prior.weight * prior.weight;
      Jtr[prior.index] += prior.weight * prior.residual;
      cost += 0.5 * prior.residual * prior.residual;
    }
    return true;
  }

  bool residuals_and_jacobian(const double* theta, const std::vector<bool>&, Eigen::VectorXd& r,
                              Eigen::MatrixXd& J) const override {
    const auto P = static_cast<Eigen::Index>(model_.layout().size);
    if (!rows_.empty()) {
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rowwise(num_residuals(), P);
      r.resize(num_residuals());
      double* jacobians[] = {rowwise.data()};
      if (!Evaluate(&theta, r.data(), jacobians)) return false;
      J = rowwise;
      return true;
    }
    const auto n = static_cast<Eigen::Index>(model_.num_residuals());
    r.resize(n);
    J.setZero(n, P);
    auto place = [&](std::size_t run, const ThermalRunRows& b) {
      const auto first = static_cast<Eigen::Index>(model_.first_row(run));
      r.segment(first, b.r.size()) = b.r;
      for (std::size_t a = 0; a < b.columns.size(); ++a)
        J.col(b.columns[a]).segment(first, b.r.size()) = b.J.col(static_cast<Eigen::Index>(a));
    };
    if (const std::vector<ThermalRunRows>* kept = model_.rows_at(theta, loss_)) {
      for (std::size_t run = 0; run < kept->size(); ++run) place(run, (*kept)[run]);
    } else {
      std::vector<ThermalRunRows> blocks;
      if (!run_blocks(theta, blocks, place)) return false;
    }
    for (std::size_t k = 0; k < model_.prior_runs().size(); ++k) {
      const auto row = static_cast<Eigen::Index>(model_.rows().size() + k);
      const Prior prior = prior_row(theta, k);
      r[row] = prior.residual;
      J(row, static_cast<Eigen::Index>(prior.index)) = prior.weight;
    }
    return true;
  }

 private:
  // The prior row of the k-th fitted heat scale (after the data rows): weight · (scale - 1).
  struct Prior {
    std::size_t index;
    double weight, residual;
  };
  Prior prior_row(const double* theta, std::size_t k) const {
    const std::size_t run = model_.prior_runs()[k];
    const auto index = static_cast<std::size_t>(model_.layout().heat_scale[run]);
    const double weight = model_.runs()[run].heat_prior_weight;
    return {index, weight, weight * (theta[index] - 1.0)};
  }

  // Every run's data rows with derivatives, one block per run, handed to `use(run, block)` on
  // the thread that built it.
  template <class Use>
  bool run_blocks(const double* theta, std::vector<ThermalRunRows>& blocks, const Use& use) const {
    const auto P = static_cast<std::size_t>(model_.layout().size);
    blocks.assign(model_.runs().size(), {});
    std::vector<std::vector<int>> column(blocks.size());
    const bool ok = evaluate_runs(theta, true, [&](std::size_t run) {
      ThermalRunRows& b = blocks[run];
      b.columns = run_columns(model_.layout(), run);
      column[run].assign(P, -1);
      for (std::size_t a = 0; a < b.columns.size(); ++a) column[run][static_cast<std::size_t>(b.columns[a])] = static_cast<int>(a);
      const std::size_t first = model_.first_row(run);
      const std::size_t end = run + 1 < blocks.size() ? model_.first_row(run + 1) : model_.rows().size();
      b.r.resize(static_cast<Eigen::Index>(end - first));
      b.J.setZero(b.r.size(), static_cast<Eigen::Index>(b.columns.size()));
      return RowSink{b.r.data(), b.J.data(), first, b.columns.size(), &column[run]};
    }, [&](std::size_t run) { use(run, blocks[run]); });
    return ok;
  }

  // Each run simulated and its rows written where sink(run) says; then, on the same thread,
  // done(run). Runs are independent simulations writing disjoint rows: one thread each
  // (parallel_slices.hpp); anything but a rejected step (std::bad_alloc) is rethrown.
  template <class Sink, class Done = void (*)(std::size_t)>
  bool evaluate_runs(const double* theta, bool derivatives, const Sink& sink, const Done& done = [](std::size_t) {}) const {
    std::vector<char> ok(model_.runs().size(), 1);
    for_each_index(ok.size(), [&](std::size_t run) {
      const std::vector<int> local = local_parameters(model_.layout(), run);
      const RowSink out = sink(run);
      // A trial step outside the physical range (α(V) outside [0, 1], h <= 0) is rejected,
      // not thrown through Ceres.
      try {
        bool good = true;
        // The smallest Jet of AutodiffScalars that holds the run's parameters (at most 8: checked by the fit).
        if (!derivatives) good = evaluate_run<double>(run, theta, local, out);
#define LMCAL_EVALUATE_WITH_JET(N) \
        else if (local.size() <= N) good = evaluate_run<ceres::Jet<double, N>>(run, theta, local, out);
        LMCAL_FOR_EACH_JET_SIZE(LMCAL_EVALUATE_WITH_JET)
#undef LMCAL_EVALUATE_WITH_JET
        else LMCAL_ASSERT(false, "a thermal run depends on more parameters than the largest Jet holds");
        ok[run] = good;
      } catch (const InvalidParameter&) {
        ok[run] = 0;
      }
      if (ok[run]) done(run);
    });
    return std::find(ok.begin(), ok.end(), 0) == ok.end();
  }

  // θ_global as a T: a Jet carrying the derivative in its slot when the parameter is one of
  // the run's `local` ones.
  template <typename T>
  static auto parameter(const double* theta, [[maybe_unused]] const std::vector<int>& local) {
    if constexpr (std::is_same_v<T, double>) {
      return [theta](int global) { return theta[global]; };
    } else {
      return [theta, &local](int global) {
        for (std::size_t k = 0; k < local.size(); ++k)
          if (local[k] == global) return T(theta[global], static_cast<int>(k));
        return T(theta[global]);
      };
    }
  }

  template <typename T>
  bool evaluate_run(std::size_t run, const double* theta, const std::vector<int>& local, const RowSink& out) const {
    const ThermalLayout& layout = model_.layout();
    const auto param = parameter<T>(theta, local);
    const PreparedRun& pr = model_.runs()[run];
    if constexpr (std::is_same_v<T, double>) {
      return evaluate_rows(run, theta, local, out, simulate_run<T>(pr, model_.numerics(), layout, run, param));
    } else {  // with the end profile and its slopes, for end_profiles()
      RailProfile end;
      std::vector<T> end_field;
      auto simulated = simulate_run<T>(pr, model_.numerics(), layout, run, param, &end, &end_field);
      std::vector<std::vector<double>> slope(local.size(), std::vector<double>(end_field.size()));
      for (std::size_t j = 0; j < local.size(); ++j)
        for (std::size_t i = 0; i < end_field.size(); ++i) slope[j][i] = end_field[i].v[static_cast<Eigen::Index>(j)];
      model_.remember_end_profile(run, theta, local, std::move(end), std::move(slope));
      return evaluate_rows(run, theta, local, out, simulated);
    }
  }

  template <typename T>
  bool evaluate_rows(std::size_t run, const double* theta, const std::vector<int>& local, const RowSink& out,
                     const std::vector<std::vector<T>>& simulated) const {
    const ThermalLayout& layout = model_.layout();
    const auto param = parameter<T>(theta, local);
    const PreparedRun& pr = model_.runs()[run];
    const RunTerms terms = run_terms(pr, layout, theta, out.J != nullptr);
    const T T0 = layout.initial[run] >= 0 ? param(layout.initial[run]) : T(pr.params.initial_temperature_C);
    const auto& rows = model_.rows();
    for (std::size_t row = model_.first_row(run); row < rows.size() && rows[row].run == run; ++row) {
      const auto& w = rows[row];
      const int offset_index = layout.offsets[run][w.sensor];
      T raw = pr.measured[w.time][w.sensor] - simulated[w.time][w.sensor];
      if (offset_index >= 0) raw -= theta[offset_index];
      // The sensor terms (a rise_time term carries the simulation's derivatives with it).
      const T rise = simulated[w.time][w.sensor] - T0;
      for (std::size_t j = 0; j < layout.terms.size(); ++j) {
        const double c = theta[layout.term_coefficient[j]], phi = terms.phi[j][w.time];
        if (layout.terms[j].kind == ThermalTermKind::rise_time) raw -= c * phi * rise;
        else raw -= c * phi;
      }
      const T residual = robust_residual(raw, loss_);
      double& r = out.r[row - out.first];
      if constexpr (std::is_same_v<T, double>) {
        r = residual;
        if (!std::isfinite(r)) return false;
      } else {
        r = residual.a;
        if (!std::isfinite(r)) return false;
        for (std::size_t k = 0; k < local.size(); ++k) out.slope(row, local[k]) = residual.v[k];
        const double slope = robust_residual(ceres::Jet<double, 1>(raw.a, 0), loss_).v[0];  // ∂residual/∂raw
        if (offset_index >= 0) out.slope(row, offset_index) = -slope;
        for (std::size_t j = 0; j < layout.terms.size(); ++j) {
          const double by = layout.terms[j].kind == ThermalTermKind::rise_time ? rise.a : 1.0;
          out.slope(row, layout.term_coefficient[j]) = -slope * terms.phi[j][w.time] * by;
          if (const int scale = layout.term_scale[j]; scale >= 0)  // shared by the periodic terms: summed
            out.slope(row, scale) -= slope * theta[layout.term_coefficient[j]] * terms.dphi[j][w.time] * by;
        }
      }
    }
    return true;
  }

  const ThermalModel& model_;
  std::vector<std::size_t> rows_;
  RowLoss loss_;
};

}  // namespace

std::unique_ptr<ceres::CostFunction> ThermalModel::cost_function(const std::vector<std::size_t>& rows,
                                                                 const RowLoss& loss) const {
  return std::make_unique<ThermalCost>(*this, rows, loss);
}

std::size_t ThermalModel::max_local_parameters() const {
  std::size_t most = 0;
  for (std::size_t r = 0; r < runs_.size(); ++r) most = std::max(most, local_parameters(layout_, r).size());
  return most;
}

// f(r) for every run, one thread each (the runs are independent simulations, as in the cost
// function); the exception of the lowest run that threw is rethrown here.
template <class F>
void for_each_run(std::size_t count, const F& f) {
  for_each_index(count, f);
}

std::vector<std::vector<std::vector<double>>> ThermalModel::simulate(const std::vector<double>& theta) const {
  std::vector<std::vector<std::vector<double>>> out(runs_.size());
  for_each_run(runs_.size(), [&](std::size_t r) {
    out[r] = simulate_run<double>(runs_[r], numerics_, layout_, r, [&](int g) { return theta[g]; });
  });
  return out;
}

std::vector<std::vector<std::vector<double>>> ThermalModel::term_sums(
    const std::vector<double>& theta, const std::vector<std::vector<std::vector<double>>>& simulated) const {
  std::vector<std::vector<std::vector<double>>> out;
  for (std::size_t r = 0; r < runs_.size(); ++r) {
    const PreparedRun& run = runs_[r];
    const RunTerms terms = run_terms(run, layout_, theta.data(), false);
    const double T0 = layout_.initial[r] >= 0 ? theta[static_cast<std::size_t>(layout_.initial[r])] : run.params.initial_temperature_C;
    std::vector<std::vector<double>> sums(run.times_s.size(), std::vector<double>(run.sensor_positions_m.size(), 0.0));
    for (std::size_t t = 0; t < run.times_s.size(); ++t)
      for (std::size_t s = 0; s < run.sensor_positions_m.size(); ++s)
        for (std::size_t j = 0; j < layout_.terms.size(); ++j)
          sums[t][s] += theta[static_cast<std::size_t>(layout_.term_coefficient[j])] * terms.phi[j][t] *
                        (layout_.terms[j].kind == ThermalTermKind::rise_time ? simulated[r][t][s] - T0 : 1.0);
    out.push_back(std::move(sums));
  }
  return out;
}

void ThermalModel::remember_rows(const double* theta, const RowLoss& loss, std::vector<ThermalRunRows> runs) const {
  rows_memo_.theta.assign(theta, theta + layout_.size);
  rows_memo_.loss = loss;
  rows_memo_.runs = std::move(runs);
}

const std::vector<ThermalRunRows>* ThermalModel::rows_at(const double* theta, const RowLoss& loss) const {
  const RowsMemo& m = rows_memo_;
  const bool same = !m.theta.empty() && std::equal(m.theta.begin(), m.theta.end(), theta) && m.loss.kind == loss.kind &&
                    m.loss.scale == loss.scale;
  return same ? &m.runs : nullptr;
}

void ThermalModel::remember_end_profile(std::size_t r, const double* theta, const std::vector<int>& local,
                                        RailProfile profile, std::vector<std::vector<double>> slope) const {
  EndProfileMemo& m = end_memo_[r];
  m.theta.assign(theta, theta + layout_.size);
  m.local = local;
  m.profile = std::move(profile);
  m.slope = std::move(slope);
}

std::vector<RailProfile> ThermalModel::end_profiles(const std::vector<double>& theta) const {
  std::vector<RailProfile> out(runs_.size());
  for_each_run(runs_.size(), [&](std::size_t r) {
    const EndProfileMemo& m = end_memo_[r];
    if (m.theta.size() == theta.size()) {
      std::vector<bool> unchanged(theta.size());
      for (std::size_t k = 0; k < theta.size(); ++k) unchanged[k] = theta[k] == m.theta[k];
      const bool same = std::find(unchanged.begin(), unchanged.end(), false) == unchanged.end();
      if (same || linear(unchanged)) {  // exact: T(θ) = T(θ_m) + Σ ∂T/∂θ_k (θ_k - θ_m,k)
        out[r] = m.profile;
        for (std::size_t j = 0; j < m.local.size(); ++j) {
          const auto k = static_cast<std::size_t>(m.local[j]);
          if (unchanged[k]) continue;
          for (std::size_t i = 0; i < out[r].temperature_C.size(); ++i)
            out[r].temperature_C[i] += m.slope[j][i] * (theta[k] - m.theta[k]);
        }
        return;
      }
    }
    simulate_run<double>(runs_[r], numerics_, layout_, r, [&](int g) { return theta[g]; }, &out[r]);
  });
  return out;
}

}  // namespace lmcal::detail

namespace lmcal {

RailSolution<double> simulate_rail_with_mechanisms(const RailGeometry& geometry, RailNumerics numerics,
                                                   const RailOutputs& outputs, const RailParams<double>& params,
                                                   const AmbientTrace& ambient, const FrictionConstants<double>& friction,
                                                   const FrictionEffects<double>& effects,
                                                   const FrictionConditions<double>& conditions,
                                                   const std::vector<std::string>& mechanisms,
                                                   const std::vector<std::pair<std::string, double>>& values) {
  ThermalRunSetup<double> setup{.velocity_m_s = geometry.velocity_m_s,
                                        .friction = &friction,
                                        .friction_effects = &effects,
                                        .conditions = conditions,
                                        .params = params};
  if (!(setup.params.heat_rate_W > 0)) setup.params.heat_rate_W = heat_rate_with_effects_W(friction, effects, conditions);
  for (const auto& name : mechanisms) {
    const detail::ThermalExtension& e = detail::thermal_extension(name);
    if (e.source) numerics.source = *e.source;
    std::vector<double> v;
    for (const auto& p : e.parameters) {
      const auto it = std::find_if(values.begin(), values.end(), [&](auto& nv) { return nv.first == p.name; });
      if (it == values.end()) throw InvalidParameter(name, fmt::format("mechanism '{}' needs a value for '{}'", name, p.name));
      v.push_back(it->second);
    }
    e.apply(setup, v.data());
  }
  return simulate_rail(geometry, numerics, outputs, setup.params, ambient, setup.heat_rate);
}

}  // namespace lmcal
