// The rail FDM solver's pieces (private to models/, included by rail_thermal.cc alone): the
// scalars it steps (a number, a Jet, or several runs side by side in SIMD lanes), the grid and
// its probes, the operator of Eqs. 11-13 and its tridiagonal factorisation, the heat source's
// spread over the grid (averaged or moving with the block) and the θ-scheme's step. The time
// loop that puts them together, and the public functions, are in rail_thermal.cc.
#pragma once

#include <ceres/jet.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <type_traits>
#include <vector>

#include "lmcal/error.hpp"
#include "lmcal/models/rail_thermal.hpp"

namespace lmcal::rail_fdm {

inline double value_of(double x) { return x; }
template <int N>
double value_of(const ceres::Jet<double, N>& x) { return x.a; }

template <typename T>
RailParams<double> values_of(const RailParams<T>& p) {
  RailParams<double> v{value_of(p.heat_partition),      value_of(p.heat_rate_W),         value_of(p.h_W_m2K),
                       value_of(p.conductivity_W_mK),   value_of(p.density_kg_m3),       value_of(p.specific_heat_J_kgK),
                       value_of(p.initial_temperature_C), value_of(p.base_loss_W_mK)};
  v.initial_profile_x_m = p.initial_profile_x_m;
  v.initial_profile_C = p.initial_profile_C;
  return v;
}

// Several runs' numbers side by side (SIMD lanes): the solver's arithmetic lane by lane, so
// one sweep advances L runs (simulate_rails). The loops over a fixed L vectorise, and the L
// elimination chains of a tridiagonal solve run interleaved.
template <int L>
struct Lanes {
  double v[L];
  Lanes() : v{} {}
  Lanes(double x) {  // NOLINT(google-explicit-constructor): a number in every lane, as a Jet takes one
    for (int l = 0; l < L; ++l) v[l] = x;
  }
  template <typename F>
  Lanes& apply(const Lanes& b, F f) {
    for (int l = 0; l < L; ++l) v[l] = f(v[l], b.v[l]);
    return *this;
  }
  Lanes& operator+=(const Lanes& b) { return apply(b, std::plus<>()); }
  Lanes& operator-=(const Lanes& b) { return apply(b, std::minus<>()); }
  Lanes& operator*=(const Lanes& b) { return apply(b, std::multiplies<>()); }
  Lanes& operator/=(const Lanes& b) { return apply(b, std::divides<>()); }
  friend Lanes operator+(Lanes a, const Lanes& b) { return a += b; }
  friend Lanes operator-(Lanes a, const Lanes& b) { return a -= b; }
  friend Lanes operator*(Lanes a, const Lanes& b) { return a *= b; }
  friend Lanes operator/(Lanes a, const Lanes& b) { return a /= b; }
  // With a number (the operator's coefficients when they are shared, weights, Δt).
  friend Lanes operator+(Lanes a, double b) { return a += Lanes(b); }
  friend Lanes operator-(Lanes a, double b) { return a -= Lanes(b); }
  friend Lanes operator*(Lanes a, double b) { return a *= Lanes(b); }
  friend Lanes operator/(Lanes a, double b) { return a /= Lanes(b); }
  friend Lanes operator+(double a, const Lanes& b) { return Lanes(a) += b; }
  friend Lanes operator-(double a, const Lanes& b) { return Lanes(a) -= b; }
  friend Lanes operator*(double a, const Lanes& b) { return Lanes(a) *= b; }
  friend Lanes operator/(double a, const Lanes& b) { return Lanes(a) /= b; }
};

// L ambient traces, read at once. A time loop reads a copy (ambient_reader), which keeps each
// trace's place as AmbientCursor does.
template <int L>
struct LaneAmbient {
  const AmbientTrace* traces[L];
  mutable std::size_t places[L];
  Lanes<L> at(double t) const {
    Lanes<L> out;
    for (int l = 0; l < L; ++l) out.v[l] = traces[l]->at(t, places[l]);
    return out;
  }
};

// One ambient trace read by a time loop (twice a step, at nearby times), keeping its place.
// Local to one simulation.
class AmbientCursor {
 public:
  explicit AmbientCursor(const AmbientTrace& trace) : trace_(trace) {}
  double at(double t) const { return trace_.at(t, place_); }

 private:
  const AmbientTrace& trace_;
  mutable std::size_t place_ = 1;
};
inline AmbientCursor ambient_reader(const AmbientTrace& trace) { return AmbientCursor(trace); }
template <int L>
LaneAmbient<L> ambient_reader(const LaneAmbient<L>& lanes) {
  return lanes;
}

template <int L>
double value_of(const Lanes<L>& x) {
  return x.v[0];
}

// Vertex-centred grid: nodes x_i, control volume i = [faces[i], faces[i+1]].
struct Grid {
  bool full_rail;
  double dx;
  std::vector<double> x;
  std::vector<double> faces;
  double symmetry_factor() const { return full_rail ? 1.0 : 2.0; }  // energies for the whole rail
  std::size_t size() const { return x.size(); }
};

inline Grid make_grid(const RailGeometry& g, const RailNumerics& n, bool full_rail) {
  Grid grid;
  grid.full_rail = full_rail;
  const int segments = full_rail ? 2 * n.half_rail_segments : n.half_rail_segments;
  const double start = full_rail ? -0.5 * g.rail_length_m : 0.0;
  grid.dx = (full_rail ? g.rail_length_m : 0.5 * g.rail_length_m) / segments;
  grid.x.resize(static_cast<std::size_t>(segments) + 1);
  for (std::size_t i = 0; i < grid.x.size(); ++i) grid.x[i] = start + static_cast<double>(i) * grid.dx;
  grid.x.back() = start + (full_rail ? g.rail_length_m : 0.5 * g.rail_length_m);
  grid.faces.resize(grid.x.size() + 1);
  grid.faces.front() = grid.x.front();
  grid.faces.back() = grid.x.back();
  for (std::size_t i = 1; i < grid.x.size(); ++i) grid.faces[i] = 0.5 * (grid.x[i - 1] + grid.x[i]);
  return grid;
}

// Linear interpolation weights of a sensor between two nodes.
struct Probe {
  std::size_t node;
  double weight;  // share of node + 1
};

inline Probe make_probe(const Grid& grid, const RailGeometry& g, double position_m) {
  require_in_range("sensor position_m", position_m, -0.5 * g.rail_length_m, 0.5 * g.rail_length_m);
  const double x = grid.full_rail ? position_m : std::abs(position_m);
  const double s = (x - grid.x.front()) / grid.dx;
  const auto last = grid.size() - 2;
  const std::size_t j = std::min(static_cast<std::size_t>(std::max(0.0, std::floor(s))), last);
  return {j, std::clamp(s - static_cast<double>(j), 0.0, 1.0)};
}

template <typename T>
T probe_value(const Probe& p, const std::vector<T>& field) {
  return field[p.node] + p.weight * (field[p.node + 1] - field[p.node]);
}

// The discrete operator: capacity C_i (J/K), side conductance h p ΔV_i and base
// conductance b ΔV_i (W/K), end conductance h A at the convective end nodes, and the
// inter-node conductance k A / Δx.
template <typename T>
struct Operator {
  std::vector<T> capacity;
  std::vector<T> side;
  std::vector<T> base;
  T end{};
  bool left_end_convects = false;  // the full rail convects at both ends; the half rail is symmetric at x = 0
  T link{};

  T convective(std::size_t i, std::size_t n) const {
    T c = side[i] + base[i];
    if ((i == 0 && left_end_convects) || i + 1 == n) c += end;
    return c;
  }
};

template <typename T>
Operator<T> make_operator(const Grid& grid, const RailGeometry& g, const RailParams<T>& p) {
  Operator<T> op;
  const std::size_t n = grid.size();
  op.capacity.resize(n);
  op.side.resize(n);
  op.base.resize(n);
  const T rho_c_A = p.density_kg_m3 * p.specific_heat_J_kgK * g.area_m2;
  const T h_p = p.h_W_m2K * g.perimeter_m;
  for (std::size_t i = 0; i < n; ++i) {
    const double length = grid.faces[i + 1] - grid.faces[i];
    op.capacity[i] = rho_c_A * length;
    op.side[i] = h_p * length;
    op.base[i] = p.base_loss_W_mK * length;
  }
  op.end = p.h_W_m2K * g.area_m2;
  op.left_end_convects = grid.full_rail;
  op.link = p.conductivity_W_mK * g.area_m2 / grid.dx;
  return op;
}

// Tridiagonal matrix with diagonal d_i and constant off-diagonal e, factorised once;
// solve() overwrites the right-hand side with the solution.
//
// A step's cost is the latency of the elimination's dependency chain, so the matrix
// is factorised from both ends at once and the two halves meet at a twist row k
// ("burn at both ends"): rows above k are eliminated downwards, rows below upwards,
// and the two independent chains run interleaved in one loop.
//   top    i < k:  x_i + m_i x_{i+1} = y_i,   y_i = r_i / p_i - m_i y_{i-1},  m_i = e / p_i
//   bottom i > k:  x_i + m_i x_{i-1} = y_i,   y_i = r_i / p_i - m_i y_{i+1}
//   twist  i = k:  (d_k - e m_{k-1} - e m_{k+1}) x_k = r_k - e y_{k-1} - e y_{k+1}
template <typename T>
class TridiagonalFactor {
 public:
  TridiagonalFactor(const std::vector<T>& diagonal, const T& off)
      : n_(diagonal.size()), twist_(n_ / 2), off_(off), inv_(n_), m_(n_) {
    for (std::size_t i = 0; i < twist_; ++i) {
      const T pivot = i == 0 ? diagonal[0] : diagonal[i] - off * m_[i - 1];
      inv_[i] = T(1.0) / pivot;
      m_[i] = off * inv_[i];
    }
    for (std::size_t i = n_ - 1; i > twist_; --i) {
      const T pivot = i == n_ - 1 ? diagonal[i] : diagonal[i] - off * m_[i + 1];
      inv_[i] = T(1.0) / pivot;
      m_[i] = off * inv_[i];
    }
    T pivot = diagonal[twist_];
    if (twist_ > 0) pivot -= off * m_[twist_ - 1];
    if (twist_ + 1 < n_) pivot -= off * m_[twist_ + 1];
    inv_[twist_] = T(1.0) / pivot;
  }

  // The right-hand side may carry derivatives the matrix does not (V a Jet, T double): each
  // operation is then a Jet times a number, not a Jet times a Jet.
  // Flattened (everything it calls inlined), as is advance(): GCC otherwise leaves a Jet's
  // Eigen arithmetic as calls, 40 % of a thermal Jacobian's time.
  template <typename V>
  [[gnu::flatten]] void solve(std::vector<V>& r) const {
    LMCAL_ASSERT(r.size() == n_, "right-hand side of the wrong size");
    V* x = r.data();
    const T* inv = inv_.data();
    const T* m = m_.data();
    const std::size_t k = twist_, last = n_ - 1;
    const std::size_t top = k, bottom = last - k;  // rows eliminated from each end
    // The running values live in locals: reloading x[i - 1] from memory would put a
    // store-to-load round trip on the dependency chain.
    V up = top > 0 ? V(x[0] * inv[0]) : V(0.0);
    V down = bottom > 0 ? V(x[last] * inv[last]) : V(0.0);
    if (top > 0) x[0] = up;
    if (bottom > 0) x[last] = down;
    const std::size_t both = std::min(top, bottom);
    for (std::size_t j = 1; j < both; ++j) {
      up = x[j] * inv[j] - m[j] * up;
      down = x[last - j] * inv[last - j] - m[last - j] * down;
      x[j] = up;
      x[last - j] = down;
    }
    for (std::size_t j = std::max<std::size_t>(both, 1); j < top; ++j) x[j] = up = x[j] * inv[j] - m[j] * up;
    for (std::size_t j = std::max<std::size_t>(both, 1); j < bottom; ++j)
      x[last - j] = down = x[last - j] * inv[last - j] - m[last - j] * down;
    V centre = x[k];
    if (k > 0) centre -= off_ * x[k - 1];
    if (k < last) centre -= off_ * x[k + 1];
    centre *= inv[k];
    x[k] = centre;
    up = down = centre;
    for (std::size_t j = 1; j <= both; ++j) {
      up = x[k - j] - m[k - j] * up;
      down = x[k + j] - m[k + j] * down;
      x[k - j] = up;
      x[k + j] = down;
    }
    for (std::size_t j = both + 1; j <= top; ++j) x[k - j] = up = x[k - j] - m[k - j] * up;
    for (std::size_t j = both + 1; j <= bottom; ++j) x[k + j] = down = x[k + j] - m[k + j] * down;
  }

 private:
  std::size_t n_, twist_;
  T off_;
  std::vector<T> inv_;  // 1 / pivot_i
  std::vector<T> m_;    // e / pivot_i
};

inline std::size_t neighbours(std::size_t i, std::size_t n) { return (i == 0 || i + 1 == n) ? 1 : 2; }

template <typename T>
struct Prepared {
  Grid grid;
  Operator<T> op;
  BlockMotion motion;
  std::vector<Probe> probes;
};

template <typename T>
Prepared<T> prepare(const RailGeometry& geometry, const RailNumerics& numerics,
                    const std::vector<double>& sensors, const RailParams<T>& params) {
  validate(geometry);
  validate(numerics);
  validate(values_of(params));
  if (numerics.source == SourceModel::moving) require_positive("velocity_m_s", geometry.velocity_m_s);
  Prepared<T> prep{make_grid(geometry, numerics, numerics.source == SourceModel::moving), {},
                   {geometry.stroke_m, geometry.contact_length_m, geometry.velocity_m_s}, {}};
  prep.op = make_operator(prep.grid, geometry, params);
  for (double x : sensors) prep.probes.push_back(make_probe(prep.grid, geometry, x));
  return prep;
}

template <typename T>
void record_sensors(const std::vector<Probe>& probes, const std::vector<T>& before, const std::vector<T>& after,
                    double s, std::vector<T>& out) {
  for (const Probe& p : probes) {
    const T a = probe_value(p, before), b = probe_value(p, after);
    out.push_back(a + s * (b - a));
  }
}

// The time-independent shape a source model spreads P with (`moving`: its cycle average).
inline SourceModel static_shape(SourceModel model) {
  return model == SourceModel::moving ? SourceModel::averaged : model;
}

// The moving block's sweep over each step of a run, in step order. It depends on the motion,
// the grid and the step times only, so the many simulations of one run in a fit share it: a
// small process-wide cache of the last few runs' sweeps (the same numbers as computing afresh).
struct StepSweep {
  double t0 = 0, t1 = 0;
  SweepEnergy energy;
};
using StepSweeps = std::vector<StepSweep>;

inline std::shared_ptr<const StepSweeps> moving_sweeps(const BlockMotion& motion, const std::vector<double>& faces,
                                                const std::vector<std::pair<double, double>>& steps) {
  struct Entry {
    BlockMotion motion;
    std::vector<double> faces;
    std::vector<std::pair<double, double>> steps;
    std::shared_ptr<const StepSweeps> sweeps;
  };
  constexpr std::size_t kEntries = 16;  // more runs than a data set holds
  static std::mutex mutex;
  static std::deque<Entry> cache;
  const auto same = [&](const Entry& e) {
    return e.motion.stroke_m == motion.stroke_m && e.motion.contact_length_m == motion.contact_length_m &&
           e.motion.velocity_m_s == motion.velocity_m_s && e.faces == faces && e.steps == steps;
  };
  {
    const std::lock_guard lock(mutex);
    if (const auto it = std::find_if(cache.begin(), cache.end(), same); it != cache.end()) return it->sweeps;
  }
  auto sweeps = std::make_shared<StepSweeps>(steps.size());
  for (std::size_t k = 0; k < steps.size(); ++k) {
    (*sweeps)[k].t0 = steps[k].first;
    (*sweeps)[k].t1 = steps[k].second;
    moving_source_energy(motion, faces, steps[k].first, steps[k].second, (*sweeps)[k].energy);
  }
  const std::lock_guard lock(mutex);
  if (cache.size() == kEntries) cache.pop_front();
  cache.push_back({motion, faces, steps, sweeps});
  return sweeps;
}

// Heat input per step: P times the static weights, or the moving block's exact sweep.
// P may change from step to step (two-way coupling).
template <typename T>
class SourceTerm {
 public:
  // `sweeps`: the moving block's sweep of every step, in the order add() is called (moving only).
  SourceTerm(SourceModel model, const BlockMotion& motion, const Grid& grid, const T& power,
             std::shared_ptr<const StepSweeps> sweeps = nullptr)
      : model_(model), power_(power), weights_(static_source_weights(static_shape(model), motion, grid.faces)),
        sweeps_(std::move(sweeps)) {
    for (double w : weights_) weight_total_ += w;
    // The nodes the block heats (the weights are 0 elsewhere: adding nothing there is skipped).
    while (heated_begin_ < weights_.size() && weights_[heated_begin_] == 0.0) ++heated_begin_;
    heated_end_ = weights_.size();
    while (heated_end_ > heated_begin_ && weights_[heated_end_ - 1] == 0.0) --heated_end_;
    LMCAL_ASSERT(model != SourceModel::moving || sweeps_, "the moving source needs its sweeps");
  }

  void set_power(const T& power) { power_ = power; }

  // The rail temperature under the block: the source-weighted mean of the field (the cycle
  // average for the moving block).
  T source_temperature(const std::vector<T>& field) const {
    T sum{};
    for (std::size_t i = heated_begin_; i < heated_end_; ++i)
      if (weights_[i] != 0.0) sum += weights_[i] * field[i];
    return sum / weight_total_;
  }

  // Adds the mean power over [t0, t1] to `rhs` (W per volume); returns the energy injected, J.
  T add(double t0, double t1, std::vector<T>& rhs) {
    const double dt = t1 - t0;
    if (model_ == SourceModel::moving) {
      LMCAL_ASSERT(next_sweep_ < sweeps_->size(), "more steps than sweeps");
      const StepSweep& sweep = (*sweeps_)[next_sweep_++];
      LMCAL_ASSERT(sweep.t0 == t0 && sweep.t1 == t1, "the sweeps follow the steps");
      double total_s = 0;
      for (std::size_t k = 0; k < sweep.energy.energy_s.size(); ++k) {
        rhs[sweep.energy.first + k] += power_ * (sweep.energy.energy_s[k] / dt);
        total_s += sweep.energy.energy_s[k];
      }
      return power_ * total_s;
    }
    for (std::size_t i = heated_begin_; i < heated_end_; ++i) rhs[i] += power_ * weights_[i];
    return power_ * (weight_total_ * dt);
  }

 private:
  SourceModel model_;
  T power_;
  std::vector<double> weights_;  // share of P per volume (the averaged shape for `moving`)
  double weight_total_ = 0;
  std::size_t heated_begin_ = 0, heated_end_ = 0;  // the nodes with a weight
  std::shared_ptr<const StepSweeps> sweeps_;
  std::size_t next_sweep_ = 0;
};

// One θ-scheme step of fixed length, factorised once:
//   (C/Δt + θK) T^{n+1} = (C/Δt - (1-θ)K) T^n + s̄ + conv·T∞_θ,   K = link·(graph Laplacian) + conv.
template <typename T>
class ThetaStepper {
 public:
  ThetaStepper(const Operator<T>& op, std::size_t n, double theta, double dt)
      : op_(op), theta_(theta), dt_(dt), explicit_diagonal_(n), convective_(n),
        explicit_link_((1.0 - theta) * op.link), factor_(implicit_diagonal(op, n, theta, dt), -theta * op.link) {
    for (std::size_t i = 0; i < n; ++i) {
      convective_[i] = op.convective(i, n);
      explicit_diagonal_[i] = op.capacity[i] / dt - (1.0 - theta) * (op.link * double(neighbours(i, n)) + convective_[i]);
    }
  }

  double dt() const { return dt_; }

  // current (at t0) -> next (at t0 + Δt). Accumulates the energy terms when `energy` is given.
  // V, the field's scalar, may carry derivatives the operator (T) does not.
  template <typename V, typename Ambient>
  [[gnu::flatten]] void advance(const std::vector<V>& current, std::vector<V>& next, double t0, const Ambient& ambient,
               SourceTerm<V>& source, RailEnergy<V>* energy) const {
    const std::size_t n = current.size();
    const double t1 = t0 + dt_;
    const auto ambient_theta = theta_ * ambient.at(t1) + (1.0 - theta_) * ambient.at(t0);
    for (std::size_t i = 0; i < n; ++i) next[i] = explicit_diagonal_[i] * current[i] + convective_[i] * ambient_theta;
    if (theta_ < 1.0) {
      next[0] += explicit_link_ * current[1];
      for (std::size_t i = 1; i + 1 < n; ++i) next[i] += explicit_link_ * (current[i - 1] + current[i + 1]);
      next[n - 1] += explicit_link_ * current[n - 2];
    }
    const V injected = source.add(t0, t1, next);
    factor_.solve(next);
    if (energy == nullptr) return;
    // The scheme's own quadrature of the losses, so the balance closes to round-off.
    auto excess = [&](std::size_t i) { return theta_ * next[i] + (1.0 - theta_) * current[i] - ambient_theta; };
    energy->injected_J += injected;
    for (std::size_t i = 0; i < n; ++i) {
      const V e = excess(i) * dt_;
      energy->convected_side_J += op_.side[i] * e;
      energy->base_J += op_.base[i] * e;
    }
    energy->convected_end_J += op_.end * excess(n - 1) * dt_;
    if (op_.left_end_convects) energy->convected_end_J += op_.end * excess(0) * dt_;
  }

 private:
  static std::vector<T> implicit_diagonal(const Operator<T>& op, std::size_t n, double theta, double dt) {
    std::vector<T> d(n);
    for (std::size_t i = 0; i < n; ++i)
      d[i] = op.capacity[i] / dt + theta * (op.link * double(neighbours(i, n)) + op.convective(i, n));
    return d;
  }

  const Operator<T>& op_;
  double theta_, dt_;
  std::vector<T> explicit_diagonal_, convective_;
  T explicit_link_;
  TridiagonalFactor<T> factor_;
};

}  // namespace lmcal::rail_fdm
