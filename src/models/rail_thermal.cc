// Rail FDM solver (Eqs. 11-15). The header explains the model and the scheme;
// this file holds the definitions and the explicit instantiations.
#include "lmcal/models/rail_thermal.hpp"
#include "models/autodiff_scalars.hpp"

#include <ceres/jet.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <type_traits>
#include <optional>
#include <string>

#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"

// The templates the public header declares are defined and instantiated here: in the
// exported namespace, or a shared liblmcal would hide the instantiations.
namespace LMCAL_API lmcal {

std::string_view to_string(TimeScheme scheme) {
  return scheme == TimeScheme::backward_euler ? "backward-euler" : "crank-nicolson";
}

TimeScheme parse_time_scheme(std::string_view name) {
  if (name == "backward-euler" || name == "be") return TimeScheme::backward_euler;
  if (name == "crank-nicolson" || name == "cn") return TimeScheme::crank_nicolson;
  throw InvalidParameter("scheme", "unknown time scheme '" + std::string(name) +
                                       "'; expected backward-euler (be) or crank-nicolson (cn)");
}

double AmbientTrace::at(double t) const {
  LMCAL_ASSERT(!time_s.empty() && time_s.size() == temperature_C.size(), "ambient trace is empty or ragged");
  if (time_s.size() == 1 || t <= time_s.front()) return temperature_C.front();
  if (t >= time_s.back()) return temperature_C.back();
  const auto it = std::upper_bound(time_s.begin(), time_s.end(), t);
  const std::size_t j = static_cast<std::size_t>(it - time_s.begin());
  const double s = (t - time_s[j - 1]) / (time_s[j] - time_s[j - 1]);
  return temperature_C[j - 1] + s * (temperature_C[j] - temperature_C[j - 1]);
}

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

void validate(const RailGeometry& g) {
  require_positive("rail_length_m", g.rail_length_m);
  require_positive("area_m2", g.area_m2);
  require_positive("perimeter_m", g.perimeter_m);
  require_positive("stroke_m", g.stroke_m);
  require_positive("contact_length_m", g.contact_length_m);
  require_non_negative("velocity_m_s", g.velocity_m_s);
  if (g.stroke_m + g.contact_length_m > g.rail_length_m)
    throw InvalidParameter("rail_length_m", g.rail_length_m,
                           "at least stroke_m + contact_length_m = " +
                               std::to_string(g.stroke_m + g.contact_length_m) + " (the block must stay on the rail)");
}

void validate(const RailNumerics& n) {
  if (n.half_rail_segments < 1 || n.half_rail_segments > io::kMaxRailModelSegments)
    throw InvalidParameter("half_rail_segments", n.half_rail_segments,
                           fmt::format("from 1 to {} segments (docs/formats.md#limits)", io::kMaxRailModelSegments));
  require_positive("time_step_s", n.time_step_s);
}

RailGeometry rail_geometry_of(const GuideSpec& spec, double rail_length_m, double stroke_m, double contact_length_m,
                              double velocity_m_s) {
  return {.rail_length_m = rail_length_m,
          .area_m2 = require(spec, &GuideSpec::area_m2, "area_m2"),
          .perimeter_m = require(spec, &GuideSpec::perimeter_m, "perimeter_m"),
          .stroke_m = stroke_m,
          .contact_length_m = contact_length_m,
          .velocity_m_s = velocity_m_s};
}

RailParams<double> rail_material_of(const GuideSpec& spec) {
  RailParams<double> p;
  p.conductivity_W_mK = require(spec, &GuideSpec::conductivity_W_mK, "conductivity_W_mK");
  p.density_kg_m3 = require(spec, &GuideSpec::density_kg_m3, "density_kg_m3");
  p.specific_heat_J_kgK = require(spec, &GuideSpec::specific_heat_J_kgK, "specific_heat_J_kgK");
  return p;
}

void validate(const RailParams<double>& p) {
  require_in_range("heat_partition", p.heat_partition, 0.0, 1.0);
  require_non_negative("heat_rate_W", p.heat_rate_W);
  require_positive("h_W_m2K", p.h_W_m2K);
  require_positive("conductivity_W_mK", p.conductivity_W_mK);
  require_positive("density_kg_m3", p.density_kg_m3);
  require_positive("specific_heat_J_kgK", p.specific_heat_J_kgK);
  require_in_range("initial_temperature_C", p.initial_temperature_C, -273.15, 1000.0);
  require_non_negative("base_loss_W_mK", p.base_loss_W_mK);
  if (p.initial_profile_x_m.size() != p.initial_profile_C.size())
    throw InvalidParameter("initial_profile_C", "needs one temperature per position of initial_profile_x_m");
  for (std::size_t i = 0; i < p.initial_profile_C.size(); ++i) {
    require_in_range("initial_profile_C", p.initial_profile_C[i], -273.15, 1000.0);
    require_finite("initial_profile_x_m", p.initial_profile_x_m[i]);
    if (i > 0 && !(p.initial_profile_x_m[i] > p.initial_profile_x_m[i - 1]))
      throw InvalidParameter("initial_profile_x_m", p.initial_profile_x_m[i], "ascending positions");
  }
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


double value_of(double x) { return x; }
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

// L ambient traces, read at once.
template <int L>
struct LaneAmbient {
  const AmbientTrace* traces[L];
  Lanes<L> at(double t) const {
    Lanes<L> out;
    for (int l = 0; l < L; ++l) out.v[l] = traces[l]->at(t);
    return out;
  }
};

template <int L>
double value_of(const Lanes<L>& x) {
  return x.v[0];
}

void validate(const AmbientTrace& ambient, double duration_s) {
  if (ambient.time_s.empty() || ambient.time_s.size() != ambient.temperature_C.size())
    throw InvalidParameter("ambient", "the ambient trace needs as many temperatures as times, and at least one");
  for (std::size_t i = 0; i < ambient.time_s.size(); ++i) {
    require_finite("ambient time_s", ambient.time_s[i]);
    require_in_range("ambient temperature_C", ambient.temperature_C[i], -273.15, 1000.0);
    if (i > 0 && !(ambient.time_s[i] > ambient.time_s[i - 1]))
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
    if (i > 0 && times[i] < times[i - 1]) throw InvalidParameter(name, times[i], "times in ascending order");
  }
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

Grid make_grid(const RailGeometry& g, const RailNumerics& n, bool full_rail) {
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

Probe make_probe(const Grid& grid, const RailGeometry& g, double position_m) {
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
  template <typename V>
  void solve(std::vector<V>& r) const {
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

std::size_t neighbours(std::size_t i, std::size_t n) { return (i == 0 || i + 1 == n) ? 1 : 2; }

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
SourceModel static_shape(SourceModel model) {
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

std::shared_ptr<const StepSweeps> moving_sweeps(const BlockMotion& motion, const std::vector<double>& faces,
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
  void advance(const std::vector<V>& current, std::vector<V>& next, double t0, const Ambient& ambient,
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
  for (const TimeStep<O>& p : plan) {
    source.set_power(params.heat_partition * mean_heat_rate(p.t0, p.stepper->dt(), q));
    p.stepper->advance(current, next, p.t0, ambient, source, tally);
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
    for (int l = 0; l < L; ++l) ambient.traces[l] = &ambients[run_of(l)];
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
