// The friction fit itself: the parameters (the law's constants, the effects, the terms), the
// fit with its starts and, under random run offsets, its variance passes, each run held out
// and each run fitted alone. The log and options come ready from friction_prepare.cc; what the
// fitted law shows is friction_goodness.cc's, its outputs friction_output.cc's.
#include "lmcal/fit/friction_fit.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "friction_model.hpp"
#include "least_squares.hpp"
#include "parallel_slices.hpp"
#include "lmcal/error.hpp"

namespace lmcal {

using detail::FrictionData;
using detail::FrictionModel;
using detail::kConstantUnits;
using detail::run_offset_shrink;
using detail::run_offset_variance;
using detail::RunOffsetVariance;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::vector<detail::ParameterSpec> parameter_specs(const FrictionFitOptions& o, const std::vector<std::size_t>& slots) {
  std::vector<detail::ParameterSpec> specs;
  for (std::size_t j = 0; j < FrictionConstants<double>::kFittable; ++j)
    specs.push_back({kFrictionConstantNames[j], kConstantUnits[j], fittable_constant(o.start, j), o.bounds[j].first, o.bounds[j].second, o.free[j]});
  for (std::size_t m = 0; m < slots.size(); ++m) {
    const FrictionEffectInfo& e = FrictionEffectLibrary::infos[slots[m]];
    const double start = m < o.effect_start.size() ? std::clamp(o.effect_start[m], e.lower, e.upper) : e.neutral;
    specs.push_back({e.name, e.unit, start, e.lower, e.upper, true, e.scale});
  }
  for (std::size_t t = 0; t < o.terms.size(); ++t) {
    const FrictionTerm& term = o.terms[t];
    if (const std::string problem = term_form_problem(term); !problem.empty())
      throw InvalidParameter("terms", fmt::format("term {}: {}", t + 1, problem));
    // A coefficient has no natural bound; the lag's share of the temperature change is kept
    // within what a lag can mean.
    const bool lag = term.lagged_temperature();
    const double size = std::max(std::abs(term.coefficient), 1e-9), bound = 1e4 * size;
    specs.push_back({fmt::format("term{}", t + 1), term.coefficient_unit(), term.coefficient, lag ? -1.0 : -bound, lag ? 3.0 : bound, true, size});
    if (term.has_scale()) {
      if (!(term.scale_lower > 0 && term.scale_upper > term.scale_lower))
        throw InvalidParameter("terms", fmt::format("term {}: its scale needs bounds 0 < lower < upper", t + 1));
      specs.push_back({fmt::format("term{}_scale", t + 1), term.scale_unit(),
                       std::clamp(term.scale, term.scale_lower, term.scale_upper), term.scale_lower, term.scale_upper, true,
                       term.scale});
    }
  }
  return specs;
}

std::vector<std::size_t> effect_slots(const FrictionFitOptions& o) {
  std::vector<std::size_t> slots;
  for (const auto& name : o.effects) {
    const std::size_t slot = friction_effect_slot(name);
    if (std::find(slots.begin(), slots.end(), slot) != slots.end())
      throw InvalidParameter("effect", "effect '" + name + "' given twice");
    slots.push_back(slot);
  }
  return slots;
}

// The residuals before the whitening of BatchedAutoDiffCostFunction's group centring: r_i +
// c/(1 - c) · mean_g(r) per group (the inverse of r_i - c · mean_g(r)); groups with c = 1
// (a profiled offset) stay centred.
std::vector<double> unwhitened(const Eigen::VectorXd& whitened, const std::vector<std::size_t>& group,
                               const std::vector<double>& shrink) {
  std::vector<double> out(whitened.data(), whitened.data() + whitened.size());
  if (shrink.empty()) return out;
  std::vector<double> sum(shrink.size(), 0.0), count(shrink.size(), 0.0);
  for (std::size_t i = 0; i < out.size(); ++i) {
    sum[group[i]] += out[i];
    count[group[i]] += 1;
  }
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double c = shrink[group[i]];
    if (c < 1) out[i] += c / (1 - c) * sum[group[i]] / count[group[i]];
  }
  return out;
}

// A run alone at one load and one block length: k1·P/1000 and f0·Lb are both constant offsets
// there. The fit would find that after a first polish and refit without k1; k1 is held at its
// start (the pooled value) from the outset instead, and f0 carries the run's level.
std::vector<detail::ParameterSpec> one_load_holds_k1(std::vector<detail::ParameterSpec> specs, const FrictionLog& log,
                                                     const std::vector<std::size_t>& samples) {
  const auto named = [&](std::string_view name) {
    return std::find_if(specs.begin(), specs.end(), [&](const detail::ParameterSpec& s) { return s.name == name; });
  };
  const auto k1 = named("k1"), f0 = named("f0");
  if (k1 == specs.end() || f0 == specs.end() || !k1->free || !f0->free) return specs;
  for (std::size_t i : samples)
    if (log.load_N[i] != log.load_N[samples.front()] || log.block_length_mm[i] != log.block_length_mm[samples.front()])
      return specs;
  k1->free = false;
  return specs;
}


// The rows of the fit: every sample, weighted by its σ, with the run offsets asked for.
FrictionData friction_data(const FrictionLog& log, const TermSeries& series, const FrictionFitOptions& options,
                           const std::vector<double>& sigma_N, RunOffsets offsets) {
  const std::size_t runs = log.run_names.size();
  FrictionData data{&log, {}, {}, options.start.T_ref_C, {}};
  data.terms = &options.terms;
  data.series = &series;
  for (std::size_t i = 0; i < log.size(); ++i) {
    data.samples.push_back(i);
    data.inv_sigma.push_back(1.0 / sigma_N[i]);
  }
  if (offsets == RunOffsets::fixed) data.run_shrink.assign(runs, 1.0);
  // Random offsets: start from the given λ (0: without them), then λ profiled within the polish
  // (re-estimated by maximum likelihood given the constants at each of its steps: one fit, at
  // the joint optimum), unless max_variance_passes = 1 holds it at the start.
  if (offsets == RunOffsets::random) {
    std::vector<double> count(runs, 0.0);
    for (std::size_t i = 0; i < log.size(); ++i) count[log.run[i]] += 1;
    const double lambda = std::max(options.run_offset_ratio_start, 0.0);
    for (std::size_t r = 0; r < runs; ++r) data.run_shrink.push_back(run_offset_shrink(count[r], lambda));
  }
  return data;
}

// The fit, with its starts; under random run offsets, a fit whose λ still moved after it (a
// polish stopped short) is refitted from its estimate at the new λ, up to max_variance_passes
// fits. Then the deviance and the offsets' variance at the estimate.
RunOffsetVariance fit_with_variance_passes(const FrictionModel& model, const std::vector<detail::ParameterSpec>& specs,
                                           const FrictionFitOptions& options, bool random,
                                           const std::vector<std::size_t>& run_of, FrictionData& data,
                                           detail::ProfiledRunOffsets& profiled, detail::FinalState& final_state,
                                           FrictionFitResult& out) {
  const std::size_t runs = data.log->run_names.size();
  auto run_specs = specs;
  auto warm_start = [&] {
    for (std::size_t j = 0; j < run_specs.size(); ++j)
      if (run_specs[j].free && !out.fit.parameters[j].held_unidentifiable)
        run_specs[j].start = std::clamp(out.fit.parameters[j].value, run_specs[j].lower, run_specs[j].upper);
  };
  FitOptions pass_options = options.fit;
  RunOffsetVariance variance;
  SolverReport multi_start;  // the first pass's: the later ones start from its estimate
  for (int pass = 1;; ++pass) {
    profiled.profiling = data.profiled != nullptr;  // until the estimate settles (FrictionModel::estimate_settled)
    out.fit = detail::solve_least_squares(model, run_specs, pass_options, &final_state);
    profiled.profiling = false;
    out.variance_passes = pass;
    if (pass == 1) multi_start = out.fit.solver;
    if (!random || !out.fit.solver.converged) break;  // refining τ² of a fit that did not converge buys nothing
    variance = run_offset_variance(unwhitened(final_state.residuals, run_of, data.run_shrink), run_of, runs);
    std::vector<double> shrink(runs);
    double change = 0;
    for (std::size_t r = 0; r < runs; ++r) {
      shrink[r] = run_offset_shrink(variance.count[r], variance.ratio);
      change = std::max(change, std::abs(shrink[r] - data.run_shrink[r]));
    }
    if (change < 0.005 || pass >= options.max_variance_passes) break;
    data.run_shrink = std::move(shrink);
    warm_start();
    pass_options.starts = 0;
  }
  // A later pass started from the one before: each parameter's start is still the one it was given.
  for (std::size_t j = 0; j < specs.size(); ++j) out.fit.parameters[j].start = specs[j].start;
  if (out.variance_passes > 1 || out.fit.solver.starts < multi_start.starts) {
    SolverReport& s = out.fit.solver;
    s.starts = multi_start.starts, s.starts_agreed = multi_start.starts_agreed;
    s.start_costs = multi_start.start_costs, s.start_residuals = multi_start.start_residuals;
  }
  {
    const std::vector<double> raw = unwhitened(final_state.residuals, run_of, data.run_shrink);
    if (random) variance = run_offset_variance(raw, run_of, runs);
    double ss_w = 0;
    for (Eigen::Index i = 0; i < final_state.residuals.size(); ++i) ss_w += final_state.residuals[i] * final_state.residuals[i];
    out.deviance_ss = random ? variance.deviance_ss : ss_w;
    out.run_offset_ratio = random ? variance.ratio : 0.0;
  }
  return variance;
}

// Each run held out: its residuals one Gauss-Newton step from the others' fit.
void cross_validate(const FrictionLog& log, const detail::FinalState& final_state, const std::vector<std::size_t>& run_of,
                    const std::vector<double>& run_shrink, FrictionFitResult& out) {
  const std::size_t runs = log.run_names.size();
  std::vector<bool> held;
  // A parameter on its bound stays there: a held-out step must not carry it across (a drag below 0).
  for (const auto& p : out.fit.parameters) held.push_back(!p.free || p.held_unidentifiable || p.at_bound);
  std::vector<std::size_t> alone;
  const Eigen::VectorXd held_out = detail::leave_group_out_residuals(final_state, run_of, held, &alone);
  for (std::size_t r : alone) out.cv_undetermined_runs.push_back(log.run_names[r]);
  // A held-out run under random offsets is a new setup with an unknown zero: predicted
  // with the offsets' mean, 0 (its own mean is not taken out). Fixed offsets stay profiled.
  const std::vector<double> prediction_error = unwhitened(held_out, run_of, run_shrink);
  std::vector<double> shape_error = prediction_error, level(runs, 0.0), count(runs, 0.0);
  for (std::size_t i = 0; i < log.size(); ++i) level[run_of[i]] += shape_error[i], count[run_of[i]] += 1;
  for (std::size_t i = 0; i < log.size(); ++i) shape_error[i] -= level[run_of[i]] / count[run_of[i]];
  double ss = 0, ss_shape = 0;
  for (std::size_t i = 0; i < log.size(); ++i) {
    ss += std::pow(prediction_error[i] * out.sigma_N[i], 2);
    ss_shape += std::pow(shape_error[i] * out.sigma_N[i], 2);
  }
  out.cv_rmse_N = std::sqrt(ss / static_cast<double>(log.size()));
  out.cv_shape_rmse_N = std::sqrt(ss_shape / static_cast<double>(log.size()));
}

// Every run alone, from the pooled estimate, holding what the pooled fit held.
void fit_each_run(const FrictionLog& log, const TermSeries& series, const FrictionFitOptions& options,
                  const std::vector<detail::ParameterSpec>& specs, const std::vector<std::size_t>& slots,
                  const std::vector<double>& run_shrink, FrictionFitResult& out) {
  auto run_specs = specs;
  for (std::size_t j = 0; j < specs.size(); ++j) {
    run_specs[j].start = out.fit.parameters[j].value;
    run_specs[j].free = specs[j].free && !out.fit.parameters[j].held_unidentifiable;
    if (run_specs[j].free) run_specs[j].start = std::clamp(run_specs[j].start, specs[j].lower, specs[j].upper);
  }
  FitOptions run_options = options.fit;
  run_options.starts = 1;
  run_options.profile = ProfileMode::none;
  std::vector<std::vector<double>> values(specs.size(), std::vector<double>(log.run_names.size(), kNaN));
  std::vector<std::vector<double>> half_widths = values, ses = values;
  // Why a run gives no value of a parameter (RunSpread::undetermined), per parameter and run.
  std::vector<std::vector<std::string>> why_not(specs.size(), std::vector<std::string>(log.run_names.size()));
  // The runs' fits are independent: each on a free thread (its rows then on that thread alone).
  detail::for_each_index(log.run_names.size(), [&](std::size_t r) {
    FrictionData run_data{&log, {}, {}, options.start.T_ref_C, run_shrink};
    run_data.terms = &options.terms;
    run_data.series = &series;
    for (std::size_t i = 0; i < log.size(); ++i)
      if (log.run[i] == r) {
        run_data.samples.push_back(i);
        run_data.inv_sigma.push_back(1.0 / out.sigma_N[i]);
      }
    auto none = [&](const std::string& why) {
      for (auto& w : why_not) w[r] = why;
    };
    if (run_data.samples.size() <= specs.size()) return none("too few samples for its own fit");
    const FitResult run_fit =
        detail::solve_least_squares(FrictionModel(run_data, slots), one_load_holds_k1(run_specs, log, run_data.samples), run_options);
    if (!run_fit.solver.usable) return none("its own fit failed");
    for (std::size_t j = 0; j < specs.size(); ++j) {
      const ParameterEstimate& q = run_fit.parameters[j];
      if (!q.free) why_not[j][r] = "one load and block length in the run: k1 P/1000 and f0 Lb are one offset there";
      else if (q.held_unidentifiable) why_not[j][r] = "not identifiable within the run";
      else {
        values[j][r] = q.value;
        half_widths[j][r] = 0.5 * (q.ci_high - q.ci_low);
        ses[j][r] = q.se;
      }
    }
  });
  const double runs = static_cast<double>(log.run_names.size());
  for (std::size_t j = 0; j < specs.size(); ++j) {
    if (!run_specs[j].free) continue;
    RunSpread s;
    s.parameter = specs[j].name;
    s.per_run = values[j];
    s.per_run_half_width_95 = half_widths[j];
    s.per_run_se = ses[j];
    std::map<std::string, std::size_t> reasons;
    for (const std::string& w : why_not[j])
      if (!w.empty()) ++reasons[w];
    for (const auto& [why, count] : reasons)
      s.undetermined += fmt::format("{}{} of {} runs: {}", s.undetermined.empty() ? "" : "; ", count, why_not[j].size(), why);
    s.spread = spread(values[j], options.fit.confidence);
    s.pooled_se = out.fit.parameters[j].se;
    s.ratio = s.spread.sd / (s.pooled_se * std::sqrt(runs));
    for (const RunHeterogeneity& h : out.fit.uncertainty.heterogeneity)
      if (h.parameter == s.parameter) {
        s.q = h.q, s.p = h.p_value, s.p_holm = h.p_holm;
        s.wider_than_pooled = h.significant;
      }
    out.spread.push_back(s);
  }
}

}  // namespace

FrictionFitResult fit_friction(const FrictionLog& logged, const FrictionFitOptions& given) {
  if (logged.size() == 0) throw InvalidParameter("log", "the friction log has no samples");
  const FrictionFitOptions options = detail::options_for_log(logged, given);
  const bool smooth = detail::smooths_temperature(logged, options);
  FrictionLog smoothed;
  if (smooth) smoothed = with_block_mean_temperature(logged);
  const FrictionLog& log = smooth ? smoothed : logged;
  detail::check_conditions_vary(log);
  validate(options.start);
  const std::vector<std::size_t> slots = effect_slots(options);
  const auto specs = parameter_specs(options, slots);

  FrictionFitResult out;
  out.sigma_N = detail::sample_sigmas(log, options.weighting);
  const std::size_t runs = log.run_names.size();
  const RunOffsets offsets = detail::run_offsets_for(options, runs);
  out.run_offsets = offsets;
  const TermSeries series = term_series(log);
  detail::check_terms_timed(options, series);
  FrictionData data = friction_data(log, series, options, out.sigma_N, offsets);
  std::vector<std::size_t> run_of(log.size());
  for (std::size_t i = 0; i < log.size(); ++i) run_of[i] = log.run[i];
  const bool random = offsets == RunOffsets::random && runs >= 2;
  detail::ProfiledRunOffsets profiled{&data.run_shrink};
  if (random && options.max_variance_passes > 1) data.profiled = &profiled;
  const FrictionModel model(data, slots);
  detail::FinalState final_state;
  const RunOffsetVariance variance =
      fit_with_variance_passes(model, specs, options, random, run_of, data, profiled, final_state, out);
  if (options.cross_validate && runs >= 2 && options.fit.loss == RobustLoss::none && out.fit.solver.usable)
    cross_validate(log, final_state, run_of, data.run_shrink, out);

  detail::add_predictions(log, series, options, slots.size(), out);
  detail::add_run_offsets(log, offsets, random, variance, out);
  detail::add_goodness(log, out);
  out.runs = log.run_names;
  if (options.per_run_fits && log.run_names.size() >= 2 && out.fit.solver.usable)
    fit_each_run(log, series, options, specs, slots, data.run_shrink, out);
  detail::check_weight_against_mass(log, out);
  detail::add_law_combinations(log, out);
  return out;
}

}  // namespace lmcal
