// Rail FDM solver (Eqs. 11-15). The header explains the model and the scheme; this file holds
// the time loop (its pieces: rail_solver.hpp), the public solvers and the explicit
// instantiations (the inputs' functions: rail_inputs.cc).
#include "lmcal/models/rail_thermal.hpp"
#include "models/autodiff_scalars.hpp"

#include <ceres/jet.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <type_traits>
#include <optional>
#include <string>

#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"
#include "models/rail_solver.hpp"

// The templates the public header declares are defined and instantiated here: in the
// exported namespace, or a shared liblmcal would hide the instantiations.
namespace LMCAL_API lmcal {

using namespace rail_fdm;  // the solver's pieces

template <typename T>
T HeatRateSchedule<T>::at(double t) const {
  LMCAL_ASSERT(!time_s.empty() && time_s.size() == heat_rate_W.size(), "heat schedule is empty or ragged");
  const auto it = std::upper_bound(time_s.begin(), time_s.end(), t);
  if (it == time_s.begin()) return heat_rate_W.front();
  if (it == time_s.end()) return heat_rate_W.back();
  const std::size_t j = static_cast<std::size_t>(it - time_s.begin());
  const double s = (t - time_s[j - 1]) / (time_s[j] - time_s[j - 1]);
  return heat_rate_W[j - 1] + s * (heat_rate_W[j] - heat_rate_W[j - 1]);
}

template <typename T>
T HeatRateSchedule<T>::integral_J(double t0, double t1) const {
  LMCAL_ASSERT(!time_s.empty() && time_s.size() == heat_rate_W.size(), "heat schedule is empty or ragged");
  const std::size_t n = time_s.size();
  // Pieces: constant before knot 0, linear between knots j-1 and j, constant after knot n-1.
  auto value = [&](std::size_t j, double t) {  // on piece j (1 <= j < n), at t inside it
    const double s = (t - time_s[j - 1]) / (time_s[j] - time_s[j - 1]);
    return heat_rate_W[j - 1] + s * (heat_rate_W[j] - heat_rate_W[j - 1]);
  };
  T sum(0.0);
  if (t0 < time_s.front()) sum += heat_rate_W.front() * (std::min(t1, time_s.front()) - t0);
  if (t1 > time_s.back()) sum += heat_rate_W.back() * (t1 - std::max(t0, time_s.back()));
  // The first piece that can overlap [t0, t1]: the one ending after t0.
  std::size_t j = static_cast<std::size_t>(std::upper_bound(time_s.begin(), time_s.end(), t0) - time_s.begin());
  for (j = std::max<std::size_t>(j, 1); j < n && time_s[j - 1] < t1; ++j) {
    const double lo = std::max(t0, time_s[j - 1]), hi = std::min(t1, time_s[j]);
    if (hi > lo) sum += 0.5 * (value(j, lo) + value(j, hi)) * (hi - lo);  // a step has hi == lo
  }
  return sum;
}

namespace {

// RailParams::initial_profile_C at x (validated: ascending positions, one temperature each).
double initial_profile_at(const std::vector<double>& xs, const std::vector<double>& temperatures, double x) {
  if (xs.front() >= 0 && x < 0) x = -x;  // a half-rail profile, mirrored
  if (x <= xs.front()) return temperatures.front();
  if (x >= xs.back()) return temperatures.back();
  const auto hi = static_cast<std::size_t>(std::upper_bound(xs.begin(), xs.end(), x) - xs.begin());
  const double s = (x - xs[hi - 1]) / (xs[hi] - xs[hi - 1]);
  return temperatures[hi - 1] + s * (temperatures[hi] - temperatures[hi - 1]);
}

void validate(const AmbientTrace& ambient, double duration_s) {
  if (ambient.time_s.empty() || ambient.time_s.size() != ambient.temperature_C.size())
    throw InvalidParameter("ambient", "the ambient trace needs as many temperatures as times, and at least one");
  for (std::size_t i = 0; i < ambient.time_s.size(); ++i) {
    require_finite("ambient time_s", ambient.time_s[i]);
    require_in_range("ambient temperature_C", ambient.temperature_C[i], -273.15, 1000.0);
    if (i > 0 && !(ambient.time_s[i] > ambient.time_s[i - 1])) [[unlikely]]
      throw InvalidParameter("ambient time_s", ambient.time_s[i], "times increasing strictly");
  }
  if (ambient.time_s.size() > 1 && (ambient.time_s.front() > 0 || ambient.time_s.back() < duration_s))
    throw InvalidParameter("ambient", "the trace covers [" + std::to_string(ambient.time_s.front()) + ", " +
                                          std::to_string(ambient.time_s.back()) + "] s but the run needs [0, " +
                                          std::to_string(duration_s) + "] s");
}

template <typename T>
void validate(const HeatRateSchedule<T>& schedule) {
  if (schedule.time_s.size() != schedule.heat_rate_W.size())
    throw InvalidParameter("heat_schedule", "the heat schedule needs as many heat rates as times");
  for (std::size_t i = 0; i < schedule.time_s.size(); ++i) {
    require_finite("heat_schedule time_s", schedule.time_s[i]);
    require_non_negative("heat_schedule heat_rate_W", value_of(schedule.heat_rate_W[i]));
    if (i > 0 && schedule.time_s[i] < schedule.time_s[i - 1])
      throw InvalidParameter("heat_schedule time_s", schedule.time_s[i], "times in ascending order");
    if (i > 1 && schedule.time_s[i] == schedule.time_s[i - 2])
      throw InvalidParameter("heat_schedule time_s", schedule.time_s[i], "at most two knots at one time (a step)");
  }
}

void validate_times(const char* name, const std::vector<double>& times, double duration_s) {
  for (std::size_t i = 0; i < times.size(); ++i) {
    require_in_range(name, times[i], 0.0, duration_s);
    if (i > 0 && times[i] < times[i - 1]) [[unlikely]]
      throw InvalidParameter(name, times[i], "times in ascending order");
  }
}
}  // namespace

namespace {

// Rannacher start-up: Crank-Nicolson's first step is taken as kStartupSubsteps backward-Euler
// substeps, which damp the stiff modes that switching the heat on excites (CN alone would let
// them ring for hours) while keeping second order.
constexpr int kStartupSubsteps = 4;

// A step of the time stepping: from t0 with its stepper to t_next.
template <typename O>
struct TimeStep {
  double t0, t_next;
  const ThetaStepper<O>* stepper;
  bool last;
};

// The steps, in order, the last ending exactly at the duration; Crank-Nicolson's first as the
// start-up's substeps.
template <typename O>
std::vector<TimeStep<O>> time_plan(int steps, double duration_s, bool crank_nicolson, const ThetaStepper<O>& stepper,
                                   const ThetaStepper<O>& startup) {
  std::vector<TimeStep<O>> plan;
  double t = 0.0;
  for (int step = 0; step < steps; ++step) {
    const bool substeps = crank_nicolson && step == 0;
    const ThetaStepper<O>& s = substeps ? startup : stepper;
    for (int k = 0; k < (substeps ? kStartupSubsteps : 1); ++k) {
      const bool last = step + 1 == steps && (!substeps || k + 1 == kStartupSubsteps);
      const double t_next = last ? duration_s : t + s.dt();
      plan.push_back({t, t_next, &s, last});
      t = t_next;
    }
  }
  return plan;
}

// The steps' intervals as advance() takes them (from t0, its stepper's dt long).
template <typename O>
std::vector<std::pair<double, double>> intervals_of(const std::vector<TimeStep<O>>& plan) {
  std::vector<std::pair<double, double>> intervals;
  for (const TimeStep<O>& p : plan) intervals.emplace_back(p.t0, p.t0 + p.stepper->dt());
  return intervals;
}

// A solution before its first record: what it will hold, where and how it was stepped.
template <typename T>
RailSolution<T> empty_solution(const RailOutputs& outputs, const Grid& grid, double dt, int steps) {
  RailSolution<T> sol;
  sol.output_times_s = outputs.output_times_s;
  sol.sensor_positions_m = outputs.sensor_positions_m;
  sol.node_positions_m = grid.x;
  sol.time_step_s = dt;
  sol.steps = steps;
  sol.sensor_temperature_C.reserve(outputs.output_times_s.size() * outputs.sensor_positions_m.size());
  return sol;
}

// The rail at t = 0: the initial temperature, or the given profile at the grid's nodes.
template <typename T>
std::vector<T> initial_field(const RailParams<T>& params, const Grid& grid) {
  std::vector<T> field(grid.size(), params.initial_temperature_C);
  if (!params.initial_profile_C.empty())
    for (std::size_t i = 0; i < field.size(); ++i)
      field[i] = T(initial_profile_at(params.initial_profile_x_m, params.initial_profile_C, grid.x[i]));
  return field;
}

}  // namespace

// True when x carries a derivative.
bool varies(double) { return false; }
template <int N>
bool varies(const ceres::Jet<double, N>& x) {
  return !x.v.isZero();
}

// The time stepping of simulate_rail, on an operator of scalar O: T where a fitted parameter
// changes the operator (h, k, ρ, c, base loss), double where none does — the factorisation
// and every product with the operator then cost a number, not a Jet (α and the heat enter only
// the right-hand side: their derivatives are further right-hand sides through one factorisation).
template <typename O, typename T, typename Ambient>
RailSolution<T> simulate_on(const Operator<O>& op, const Prepared<T>& prep, const RailNumerics& numerics,
                            const RailOutputs& outputs, const RailParams<T>& params, const Ambient& ambient,
                            const HeatRateModel<T>& heat_rate) {
  const Grid& grid = prep.grid;
  const std::size_t n = grid.size();

  const double step_count = std::ceil(outputs.duration_s / numerics.time_step_s - 1e-9);
  if (!(step_count <= kMaxTimeSteps))
    throw InvalidParameter("time_step_s", numerics.time_step_s,
                           fmt::format("at most {:.0e} steps over {:.3g} s: a longer step or a shorter run", kMaxTimeSteps,
                                       outputs.duration_s));
  const int steps = static_cast<int>(step_count);
  const double dt = outputs.duration_s / steps;
  const bool crank_nicolson = numerics.scheme == TimeScheme::crank_nicolson;
  const ThetaStepper<O> stepper(op, n, crank_nicolson ? 0.5 : 1.0, dt);
  const ThetaStepper<O> startup(op, n, 1.0, dt / kStartupSubsteps);

  const HeatRateSchedule<T>& schedule = params.heat_schedule;
  validate(schedule);
  if (!schedule.empty() && heat_rate)
    throw InvalidParameter("heat_schedule", "a heat schedule cannot also follow the rail temperature (coupling)");
  const std::vector<TimeStep<O>> plan = time_plan(steps, outputs.duration_s, crank_nicolson, stepper, startup);
  std::shared_ptr<const StepSweeps> sweeps;
  if (numerics.source == SourceModel::moving) sweeps = moving_sweeps(prep.motion, grid.faces, intervals_of(plan));
  SourceTerm<T> source(numerics.source, prep.motion, grid, params.heat_partition * params.heat_rate_W, sweeps);
  // Q_f for the step starting from `field`: constant, or from the coupling model.
  auto heat_rate_for = [&](const std::vector<T>& field) {
    return heat_rate ? heat_rate(source.source_temperature(field)) : params.heat_rate_W;
  };
  // The mean Q_f over [t0, t0 + dt]: the schedule's exact integral, else the step's Q_f.
  auto mean_heat_rate = [&](double t0, double dt, const T& q) {
    return schedule.empty() ? q : schedule.integral_J(t0, t0 + dt) / dt;
  };

  RailSolution<T> sol = empty_solution<T>(outputs, grid, dt, steps);
  std::vector<T> current = initial_field(params, grid), next(n);
  const std::vector<T> initial = outputs.energy_balance ? current : std::vector<T>();
  std::size_t next_output = 0, next_profile = 0;
  std::optional<T> carried_source_temperature;  // of the last interval's end, when computed
  // Records the outputs that fall in (t_before, t_after], interpolating linearly in time.
  auto emit = [&](double t_before, double t_after, const std::vector<T>& before, const std::vector<T>& after,
                  const T& q_before, const T& q_after, bool last) {
    auto within = [&](double t) { return last || t <= t_after + 1e-9 * dt; };
    auto share = [&](double t) {
      return t_after > t_before ? std::clamp((t - t_before) / (t_after - t_before), 0.0, 1.0) : 1.0;
    };
    // The temperature under the block at both ends, once per interval with outputs (the start's
    // carried over from the previous interval when it was computed there).
    const bool any = outputs.source_temperature && next_output < outputs.output_times_s.size() &&
                     within(outputs.output_times_s[next_output]);
    std::optional<T> ts_before, ts_after;
    if (any) {
      ts_before = carried_source_temperature ? *carried_source_temperature : source.source_temperature(before);
      ts_after = source.source_temperature(after);
    }
    carried_source_temperature = ts_after;
    for (; next_output < outputs.output_times_s.size() && within(outputs.output_times_s[next_output]); ++next_output) {
      const double s = share(outputs.output_times_s[next_output]);
      record_sensors(prep.probes, before, after, s, sol.sensor_temperature_C);
      if (outputs.source_temperature) sol.source_temperature_C.push_back(*ts_before + s * (*ts_after - *ts_before));
      sol.heat_rate_W.push_back(schedule.empty() ? q_before + s * (q_after - q_before)
                                                 : schedule.at(outputs.output_times_s[next_output]));
    }
    for (; next_profile < outputs.profile_times_s.size() && within(outputs.profile_times_s[next_profile]);
         ++next_profile) {
      const double s = share(outputs.profile_times_s[next_profile]);
      std::vector<T> profile(n);
      for (std::size_t i = 0; i < n; ++i) profile[i] = before[i] + s * (after[i] - before[i]);
      sol.profiles_C.push_back(std::move(profile));
    }
  };
  T q = heat_rate_for(current);
  emit(0.0, 0.0, current, current, q, q, false);

  RailEnergy<T> energy;
  RailEnergy<T>* tally = outputs.energy_balance ? &energy : nullptr;
  const auto ambient_now = ambient_reader(ambient);
  for (const TimeStep<O>& p : plan) {
    source.set_power(params.heat_partition * mean_heat_rate(p.t0, p.stepper->dt(), q));
    p.stepper->advance(current, next, p.t0, ambient_now, source, tally);
    const T q_next = heat_rate ? heat_rate_for(next) : q;
    emit(p.t0, p.t_next, current, next, q, q_next, p.last);
    q = q_next;
    std::swap(current, next);
  }

  if (tally) {
    for (std::size_t i = 0; i < n; ++i) energy.stored_J += op.capacity[i] * (current[i] - initial[i]);
    const double f = grid.symmetry_factor();
    sol.energy = {f * energy.injected_J, f * energy.stored_J, f * energy.convected_side_J, f * energy.convected_end_J,
                  f * energy.base_J};
  }
  return sol;
}

template <typename T>
RailSolution<T> simulate_rail(const RailGeometry& geometry, const RailNumerics& numerics,
                              const RailOutputs& outputs, const RailParams<T>& params,
                              const AmbientTrace& ambient, const HeatRateModel<T>& heat_rate) {
  require_positive("duration_s", outputs.duration_s);
  validate(ambient, outputs.duration_s);
  validate_times("output_times_s", outputs.output_times_s, outputs.duration_s);
  validate_times("profile_times_s", outputs.profile_times_s, outputs.duration_s);
  const Prepared<T> prep = prepare(geometry, numerics, outputs.sensor_positions_m, params);
  if constexpr (!std::is_same_v<T, double>) {
    if (!varies(params.h_W_m2K) && !varies(params.conductivity_W_mK) && !varies(params.density_kg_m3) &&
        !varies(params.specific_heat_J_kgK) && !varies(params.base_loss_W_mK))
      return simulate_on(make_operator(prep.grid, geometry, values_of(params)), prep, numerics, outputs, params, ambient,
                         heat_rate);
  }
  return simulate_on(prep.op, prep, numerics, outputs, params, ambient, heat_rate);
}

std::vector<RailSolution<double>> simulate_rails(const RailGeometry& geometry, const RailNumerics& numerics,
                                                 const RailOutputs& outputs, const std::vector<RailParams<double>>& params,
                                                 const std::vector<AmbientTrace>& ambients) {
  constexpr int L = 4;
  if (ambients.size() != params.size())
    throw InvalidParameter("ambients", "one ambient trace per run (" + std::to_string(params.size()) + " runs, " +
                                           std::to_string(ambients.size()) + " traces)");
  if (numerics.source == SourceModel::moving)
    throw InvalidParameter("source", "runs in lanes take a static source (paper or averaged); simulate_rail takes the moving block");
  if (outputs.energy_balance) throw InvalidParameter("energy_balance", "runs in lanes keep no energy balance; simulate_rail does");
  for (const auto& p : params)
    if (!p.initial_profile_C.empty())
      throw InvalidParameter("initial_profile_C", "runs in lanes start uniform; simulate_rail continues from a profile");
  require_positive("duration_s", outputs.duration_s);
  validate_times("output_times_s", outputs.output_times_s, outputs.duration_s);
  validate_times("profile_times_s", outputs.profile_times_s, outputs.duration_s);
  for (std::size_t r = 0; r < params.size(); ++r) {
    validate(params[r]);
    validate(ambients[r], outputs.duration_s);
    if (!params[r].heat_schedule.empty())
      throw InvalidParameter("heat_schedule", "runs in lanes take a constant heat rate; simulate_rail takes a schedule");
  }
  std::vector<RailSolution<double>> out;
  for (std::size_t first = 0; first < params.size(); first += L) {
    // Lane l holds run first + l; a last, partial sweep repeats its last run in the spare lanes.
    auto run_of = [&](int l) { return std::min(first + static_cast<std::size_t>(l), params.size() - 1); };
    auto lanes = [&](double RailParams<double>::*field) {
      Lanes<L> x;
      for (int l = 0; l < L; ++l) x.v[l] = params[run_of(l)].*field;
      return x;
    };
    RailParams<Lanes<L>> p{.heat_partition = lanes(&RailParams<double>::heat_partition),
                           .heat_rate_W = lanes(&RailParams<double>::heat_rate_W),
                           .h_W_m2K = lanes(&RailParams<double>::h_W_m2K),
                           .conductivity_W_mK = lanes(&RailParams<double>::conductivity_W_mK),
                           .density_kg_m3 = lanes(&RailParams<double>::density_kg_m3),
                           .specific_heat_J_kgK = lanes(&RailParams<double>::specific_heat_J_kgK),
                           .initial_temperature_C = lanes(&RailParams<double>::initial_temperature_C),
                           .base_loss_W_mK = lanes(&RailParams<double>::base_loss_W_mK),
                           .heat_schedule = {}};
    LaneAmbient<L> ambient{};
    for (int l = 0; l < L; ++l) ambient.traces[l] = &ambients[run_of(l)], ambient.places[l] = 1;
    const Prepared<Lanes<L>> prep = prepare(geometry, numerics, outputs.sensor_positions_m, p);
    // Runs on one rail usually share its operator (h, k, ρ, c, base loss): then it is one set
    // of numbers for every lane, and the sweep's arrays stay in the first-level cache.
    auto shared = [&](double RailParams<double>::*field) {
      for (int l = 1; l < L; ++l)
        if (params[run_of(l)].*field != params[run_of(0)].*field) return false;
      return true;
    };
    const bool one_operator = shared(&RailParams<double>::h_W_m2K) && shared(&RailParams<double>::conductivity_W_mK) &&
                              shared(&RailParams<double>::density_kg_m3) &&
                              shared(&RailParams<double>::specific_heat_J_kgK) && shared(&RailParams<double>::base_loss_W_mK);
    const RailSolution<Lanes<L>> sol =
        one_operator ? simulate_on(make_operator(prep.grid, geometry, params[run_of(0)]), prep, numerics, outputs, p, ambient,
                                   HeatRateModel<Lanes<L>>{})
                     : simulate_on(prep.op, prep, numerics, outputs, p, ambient, HeatRateModel<Lanes<L>>{});
    for (int l = 0; l < L && first + static_cast<std::size_t>(l) < params.size(); ++l) {
      RailSolution<double> one;
      one.output_times_s = sol.output_times_s;
      one.sensor_positions_m = sol.sensor_positions_m;
      one.node_positions_m = sol.node_positions_m;
      one.time_step_s = sol.time_step_s;
      one.steps = sol.steps;
      auto lane = [&](const std::vector<Lanes<L>>& xs) {
        std::vector<double> values(xs.size());
        for (std::size_t k = 0; k < xs.size(); ++k) values[k] = xs[k].v[l];
        return values;
      };
      one.sensor_temperature_C = lane(sol.sensor_temperature_C);
      one.heat_rate_W = lane(sol.heat_rate_W);
      one.source_temperature_C = lane(sol.source_temperature_C);
      for (const auto& profile : sol.profiles_C) one.profiles_C.push_back(lane(profile));
      out.push_back(std::move(one));
    }
  }
  return out;
}

template <typename T>
RailSolution<T> steady_rail(const RailGeometry& geometry, const RailNumerics& numerics,
                            const std::vector<double>& sensor_positions_m, const RailParams<T>& params,
                            double ambient_C) {
  require_in_range("ambient_C", ambient_C, -273.15, 1000.0);
  const Prepared<T> prep = prepare(geometry, numerics, sensor_positions_m, params);
  const Grid& grid = prep.grid;
  const std::size_t n = grid.size();
  // `moving` has no steady state; its cycle average is the averaged source.
  const std::vector<double> weights = static_source_weights(static_shape(numerics.source), prep.motion, grid.faces);
  const T power = params.heat_partition * params.heat_rate_W;

  std::vector<T> diagonal(n), solution(n);
  for (std::size_t i = 0; i < n; ++i) {
    const T convective = prep.op.convective(i, n);
    diagonal[i] = prep.op.link * double(neighbours(i, n)) + convective;
    solution[i] = power * weights[i] + convective * ambient_C;
  }
  TridiagonalFactor<T>(diagonal, -prep.op.link).solve(solution);

  RailSolution<T> sol;
  sol.output_times_s = {0.0};
  sol.sensor_positions_m = sensor_positions_m;
  sol.node_positions_m = grid.x;
  record_sensors(prep.probes, solution, solution, 0.0, sol.sensor_temperature_C);
  sol.profiles_C.push_back(std::move(solution));
  return sol;
}

#define LMCAL_INSTANTIATE_RAIL(T)                                                                        \
  template struct HeatRateSchedule<T>;                                                                    \
  template RailSolution<T> simulate_rail<T>(const RailGeometry&, const RailNumerics&, const RailOutputs&, \
                                            const RailParams<T>&, const AmbientTrace&,                   \
                                            const HeatRateModel<T>&);                                    \
  template RailSolution<T> steady_rail<T>(const RailGeometry&, const RailNumerics&,                      \
                                          const std::vector<double>&, const RailParams<T>&, double);

LMCAL_FOR_EACH_AUTODIFF_SCALAR(LMCAL_INSTANTIATE_RAIL)

}  // namespace lmcal
