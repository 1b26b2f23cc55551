// Transient temperature of an LM rail heated by its block: the fin model of
// Cheng et al. (2017), Eqs. 11-15; see shared/PHYSICS.md §4.
//
//   ρ c A ∂T/∂t = k A ∂²T/∂x² + g(x, t) - (h p + b) (T - T∞(t))
//   -k A ∂T/∂x = h A (T - T∞)  at the rail ends,   T(x, 0) = T_initial
//
// b is an optional heat loss through the rail base (W/mK per metre of rail; 0 in the
// paper, whose symmetric rig has no bed). g is the heat input per unit length from one of the source models of
// heat_source.hpp, carrying P = α·Q_f in total (`paper`: P·L1/Lb1). `paper` and
// `averaged` are symmetric and solved on the half rail 0 <= x <= L/2 with
// ∂T/∂x = 0 at x = 0; `moving` is solved on the full rail -L/2 <= x <= L/2.
//
// Discretisation: vertex-centred finite volumes (nodes at x_i = i·Δx, half
// volumes at the ends; equivalent to the paper's central differences with ghost
// nodes), so conduction conserves energy exactly and the source is integrated
// exactly over every volume. Time: θ-scheme, backward Euler (θ = 1, the paper's)
// or Crank-Nicolson (θ = 1/2); one tridiagonal factorisation per run, O(n) per
// step (CN starts with four backward-Euler substeps, see the trap below). The ambient enters θ-weighted between step ends; the moving source as the
// exact energy of the block's sweep over each step.
//
// Templated on the scalar: double for simulation, ceres::Jet for derivatives with
// respect to α, Q_f (hence the friction constants), h, k, ρ, c and T_initial.
// Instantiated in src/models/rail_thermal.cc for double and ceres::Jet<double, N>,
// N = 1, 2, 4, 8: the list of src/models/autodiff_scalars.hpp, the one place to add another N.
//
// Example: SRN 35C at 0.11 m/s, 6 h, the paper's numerics:
//   lmcal::RailGeometry g{.rail_length_m = 0.6, .area_m2 = 8.88e-4, .perimeter_m = 0.14,
//                         .stroke_m = 0.2, .contact_length_m = 0.0822, .velocity_m_s = 0.11};
//   lmcal::RailNumerics n{.source = lmcal::SourceModel::paper,
//                         .scheme = lmcal::TimeScheme::backward_euler,
//                         .half_rail_segments = 50, .time_step_s = 600};
//   lmcal::RailOutputs o{.duration_s = 21600, .sensor_positions_m = {0.0},
//                        .output_times_s = {0, 3600, 21600}};
//   lmcal::RailParams<double> p{.heat_partition = 0.6, .heat_rate_W = 4.86};
//   auto sol = lmcal::simulate_rail(g, n, o, p, lmcal::AmbientTrace::constant(26.0));
//
// Trap: Crank-Nicolson does not damp the fastest modes: with Δt far above Δx²·ρc/k,
// a sudden change rings for hours. The solver therefore takes CN's first step as four
// backward-Euler substeps (Rannacher start-up), which damps the start (heat switched
// on, rail and ambient apart); a measured ambient that jumps mid-run can still ring,
// so give such traces backward Euler or a step near the jump's time scale.
#pragma once

#include "lmcal/export.hpp"

#include <cstddef>
#include <functional>
#include <string_view>
#include <vector>

#include "lmcal/io/catalog.hpp"
#include "lmcal/models/heat_source.hpp"

namespace LMCAL_API lmcal {

enum class TimeScheme { backward_euler, crank_nicolson };
std::string_view to_string(TimeScheme scheme);
// Accepts "backward-euler"/"be" and "crank-nicolson"/"cn"; throws InvalidParameter otherwise.
TimeScheme parse_time_scheme(std::string_view name);

// Geometry of one rail and its block's motion. SI units.
struct RailGeometry {
  double rail_length_m = 0;     // L (not reported by the paper; an input of every run)
  double area_m2 = 0;           // A, rail cross-section
  double perimeter_m = 0;       // p, convecting perimeter
  double stroke_m = 0;          // L1
  double contact_length_m = 0;  // Lb1
  double velocity_m_s = 0;      // V (moving source)
};

// The most time steps a simulation takes (an InvalidParameter beyond): 10^8, minutes of work.
inline constexpr double kMaxTimeSteps = 1e8;

struct RailNumerics {
  SourceModel source = SourceModel::averaged;
  TimeScheme scheme = TimeScheme::crank_nicolson;
  int half_rail_segments = 50;  // Δx = (L/2) / segments; `moving` uses 2× over the full rail
  double time_step_s = 600;     // shortened so that a whole number of steps fills the run
};

struct RailOutputs {
  double duration_s = 0;
  std::vector<double> sensor_positions_m;  // from the rail centre; |x| <= L/2
  std::vector<double> output_times_s;      // ascending, within [0, duration]
  std::vector<double> profile_times_s;     // ascending; whole temperature profile at these times
  bool energy_balance = false;             // account injected / stored / convected energy
  // RailSolution::source_temperature_C at every output (false: left empty — a fit that needs
  // only the sensors saves a weighted sum over the rail per record).
  bool source_temperature = true;
};

// Q_f(t) for a heat that changes during the run (a heater switched off, a block that stops, a
// measured power trace), t from the run's start (s): linear between knots, constant before the
// first knot and after the last; a time given twice is a step (the earlier value up to it, the
// later one from it). The solver takes the exact integral ∫ Q dt over every step, so a step
// that switches the heat off part way injects exactly the energy before the switch.
// Example, a 10 W heater switched off after 2 h:
//   auto q = lmcal::HeatRateSchedule<double>::steps({0, 7200}, {10.0, 0.0});
template <typename T>
struct HeatRateSchedule {
  std::vector<double> time_s;  // non-decreasing; at most two equal times (a step)
  std::vector<T> heat_rate_W;  // Q_f at each knot, >= 0

  bool empty() const { return time_s.empty(); }
  // Piecewise constant: heat_rate_W[i] from from_s[i] until from_s[i + 1], the last to the end.
  static HeatRateSchedule steps(const std::vector<double>& from_s, const std::vector<T>& heat_rate_W) {
    HeatRateSchedule s;
    for (std::size_t i = 0; i < from_s.size(); ++i) {
      if (i > 0) s.add(from_s[i], heat_rate_W[i - 1]);
      s.add(from_s[i], heat_rate_W[i]);
    }
    return s;
  }
  void add(double t, const T& q) {
    time_s.push_back(t);
    heat_rate_W.push_back(q);
  }
  T at(double t) const;                   // the later value at a step
  T integral_J(double t0, double t1) const;  // ∫_{t0}^{t1} Q dt, exact for the linear pieces, t0 <= t1
};

// The physical parameters, of the scalar type: everything a fit may free.
template <typename T>
struct RailParams {
  T heat_partition{0.6};            // α, share of the frictional heat entering the rail, [0, 1]
  T heat_rate_W{0.0};               // Q_f, frictional heat of the block, W
  T h_W_m2K{5.3};                   // convection coefficient on sides and ends
  T conductivity_W_mK{18.0};        // k
  T density_kg_m3{7800.0};          // ρ
  T specific_heat_J_kgK{461.0};     // c
  T initial_temperature_C{26.0};    // uniform T(x, 0)
  T base_loss_W_mK{0.0};            // b, conductance to the ambient through the base, W/K per m of rail
  HeatRateSchedule<T> heat_schedule;  // Q_f(t); when given it replaces heat_rate_W (which is then unused)
  // A non-uniform T(x, 0), to continue an earlier simulation from its end (a duty cycle's next
  // segment): temperatures at ascending positions from the rail centre, linear between them
  // onto the solver's nodes, the end values beyond; a profile of x >= 0 only is mirrored (the
  // half-rail models'). Empty: the uniform initial_temperature_C. Not in simulate_rails.
  std::vector<double> initial_profile_x_m, initial_profile_C;
};

// Two-way coupling: Q_f as a function of the rail temperature under the block (the source-
// weighted mean of the temperature field), evaluated at the start of every step (explicit,
// first order in Δt: keep Δt well below the time constant when it is used). Empty = the
// constant RailParams::heat_rate_W. Not together with a heat schedule (InvalidParameter).
template <typename T>
using HeatRateModel = std::function<T(const T& source_temperature_C)>;

// Measured or assumed ambient temperature, linearly interpolated between samples.
// One sample means a constant ambient; otherwise the trace must cover the run.
struct AmbientTrace {
  std::vector<double> time_s;
  std::vector<double> temperature_C;
  static AmbientTrace constant(double temperature_C) { return {{0.0}, {temperature_C}}; }
  double at(double time_s) const;
  // at(time_s) for a loop that reads nearby times in turn: `place` (start it at 1) keeps where
  // the last read ended, and the search steps from there instead of bisecting the whole trace.
  double at(double time_s, std::size_t& place) const;
};

// Energy over the run, for the whole rail (the half-rail models count both halves), J.
template <typename T>
struct RailEnergy {
  T injected_J{};        // heat put in by the source
  T stored_J{};          // ∫ ρ c A (T_end - T_0) dx
  T convected_side_J{};  // ∫∫ h p (T - T∞) dx dt
  T convected_end_J{};   // ∫ h A (T_end_face - T∞) dt over both ends
  T base_J{};            // ∫∫ b (T - T∞) dx dt
  T imbalance_J() const { return injected_J - stored_J - convected_side_J - convected_end_J - base_J; }
};

template <typename T>
struct RailSolution {
  std::vector<double> output_times_s;
  std::vector<double> sensor_positions_m;
  std::vector<T> sensor_temperature_C;  // [time][sensor], row-major
  std::vector<T> heat_rate_W;           // Q_f at each output time (varies with a HeatRateModel)
  std::vector<T> source_temperature_C;  // rail temperature under the block at each output time
  std::vector<double> node_positions_m;
  std::vector<std::vector<T>> profiles_C;  // one per profile time, at node_positions_m
  RailEnergy<T> energy;
  double time_step_s = 0;  // the step actually used
  int steps = 0;

  const T& temperature_C(std::size_t time_index, std::size_t sensor_index) const {
    return sensor_temperature_C[time_index * sensor_positions_m.size() + sensor_index];
  }
};

// Runs the transient model. Throws InvalidParameter, naming the parameter and its
// value, for non-physical input (lengths <= 0, α outside [0, 1], segments < 1,
// Δt <= 0, NaN anywhere, a sensor off the rail, a stroke + contact longer than the rail,
// a heat schedule with a negative heat or times out of order).
// With a heat schedule, every step gets α·∫Q dt exactly (RailOutputs::energy_balance closes
// to round-off) and RailSolution::heat_rate_W holds the schedule at the output times. The
// `moving` block keeps moving at velocity_m_s: a schedule changes its power, not its speed (a
// block that stops is the caller's to refuse, or to model with a static source).
template <typename T>
RailSolution<T> simulate_rail(const RailGeometry& geometry, const RailNumerics& numerics,
                              const RailOutputs& outputs, const RailParams<T>& params,
                              const AmbientTrace& ambient, const HeatRateModel<T>& heat_rate = {});

// Several runs at once, in SIMD lanes (four per sweep): runs on one rail, grid, time plan and
// outputs (`geometry`, `numerics`, `outputs` shared), each with its own parameters (α, heat
// rate, h, k, ρ, c, T0, base loss) and ambient trace. A static source (paper or averaged);
// no heat schedule, coupling or energy balance (simulate_rail, run by run, has them).
// The same numbers as simulate_rail run by run: every lane does the same arithmetic.
std::vector<RailSolution<double>> simulate_rails(const RailGeometry& geometry, const RailNumerics& numerics,
                                                 const RailOutputs& outputs, const std::vector<RailParams<double>>& params,
                                                 const std::vector<AmbientTrace>& ambients);

// Steady state under a constant ambient and the constant RailParams::heat_rate_W, at the
// nodes of the model's grid (`moving` gives the cycle-averaged steady state, i.e. that of
// `averaged` on the full rail).
template <typename T>
RailSolution<T> steady_rail(const RailGeometry& geometry, const RailNumerics& numerics,
                            const std::vector<double>& sensor_positions_m, const RailParams<T>& params,
                            double ambient_C);

// The same checks simulate_rail applies, for callers that want to fail early.
// The rail of a catalog guide: its section (A, p) from `spec`, the rest as given; its material
// (k, ρ, c) from `spec`, every other parameter at its default for the caller to set. A field the
// catalog lacks is an InvalidParameter naming it and how to supply it (require()).
RailGeometry rail_geometry_of(const GuideSpec& spec, double rail_length_m, double stroke_m, double contact_length_m,
                              double velocity_m_s);
RailParams<double> rail_material_of(const GuideSpec& spec);

void validate(const RailGeometry& geometry);
void validate(const RailNumerics& numerics);
void validate(const RailParams<double>& params);

}  // namespace lmcal
