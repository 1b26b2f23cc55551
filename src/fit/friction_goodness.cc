// What the fitted friction law shows: every sample's prediction, the runs' offsets, the
// errors against the signal's scale and per condition, the weight an incline's fit gives
// against its mass, and a combination law's combinations.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <tuple>

#include "friction_steps.hpp"
#include "parallel_slices.hpp"
#include "lmcal/error.hpp"

namespace lmcal {

using detail::ConditionKey;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The temperature a combination law is quoted at: the logged mean (to 0.1 K), else T_i.
double law_temperature_C(const FrictionLog& log) {
  if (!log.law.temperature || log.size() == 0) return FrictionLawConditions::kUnloggedTemperature_C;
  double sum = 0;
  for (double t : log.temperature_C) sum += t;
  return std::round(10 * sum / static_cast<double>(log.size())) / 10;
}

// The combinations a combination law's fit determines (LawCombination), at temperature T.
std::vector<LawCombination> law_combinations(const FitResult& fit, const FrictionLog& log, double T) {
  using Law = FrictionLawConditions;
  const auto& p = fit.parameters;
  double nu40 = 0;
  for (double v : log.viscosity40_mm2_s) nu40 += v / static_cast<double>(log.size());
  FrictionConstants<double> fitted = paper_friction_constants();
  fitted.nu_ref_mm2_s = nu40;
  fitted.beta_per_K = p[5].value;
  const double shift = T - fitted.T_ref_C;
  const double nu = viscosity_mm2_s(fitted, T);  // Eq. 6 at T
  const double load = Law::kNeutralLoad_N * 1e-3, pc = Law::kNeutralPreload_um, lb = Law::kNeutralBlockLength_mm;
  struct Row {
    const char* name;
    const char* unit;
    std::size_t constant;
    double factor;          // combination = factor · constant
    double per_beta;        // d(combination)/dβ / combination
    const char* meaning;
  };
  const Row rows[] = {
      {detail::kLawCombinationNames[0], "N", 0, load, 0, "the Coulomb level: (k1 - k2·pc)·P·1e-3 + Lb·f0"},
      {detail::kLawCombinationNames[2], "N", 2, pc * lb / nu, shift, "the Stribeck amplitude at rest: mu_st·pc·Lb/ν(T)"},
      {detail::kLawCombinationNames[3], "m/s", 3, 1, 0, "the Stribeck speed: V_St"},
      {detail::kLawCombinationNames[4], "N·s/m", 4, lb * pc * nu, -shift, "the viscous slope: Lb·mu_v·pc·ν(T)"},
  };
  std::vector<LawCombination> out;
  for (const Row& row : rows) {
    const ParameterEstimate& k = p[row.constant];
    ParameterEstimate c = k;
    c.name = row.name;
    c.unit = row.unit;
    const auto scale = [&](double& v) { v *= row.factor; };
    for (double* v : {&c.value, &c.start, &c.lower, &c.upper, &c.se, &c.ci_low, &c.ci_high, &c.profile_low,
                      &c.profile_high, &c.boot_low, &c.boot_high})
      scale(*v);
    for (ProfilePoint& q : c.profile_curve) scale(q.value);
    // With β fitted and T away from T_i the combination leans on β too: the delta method.
    const bool with_beta = row.per_beta != 0 && p[5].free && !p[5].held_unidentifiable && std::isfinite(p[5].se);
    if (with_beta && fit.covariance.rows() > 5) {
      const double g0 = row.factor, g5 = c.value * row.per_beta;
      const auto j = static_cast<Eigen::Index>(row.constant);
      const double variance = g0 * g0 * fit.covariance(j, j) + 2 * g0 * g5 * fit.covariance(j, 5) +
                              g5 * g5 * fit.covariance(5, 5);
      c.se = std::sqrt(std::max(variance, 0.0));
      const double half = (k.se > 0 ? (k.ci_high - k.ci_low) / (2 * k.se) : 0) * c.se;
      c.ci_low = c.value - half, c.ci_high = c.value + half;
      c.profile_low = c.profile_high = c.boot_low = c.boot_high = std::numeric_limits<double>::quiet_NaN();
      c.profile_curve.clear();
      if (c.interval != "none") c.interval = "linear";
    }
    out.push_back({std::move(c), row.meaning});
  }
  return out;
}

}  // namespace

FrictionConstants<double> FrictionFitResult::constants() const {
  const auto& p = fit.parameters;
  LMCAL_ASSERT(p.size() >= FrictionConstants<double>::kFittable, "a friction fit has seven constants");
  FrictionConstants<double> k = paper_friction_constants();
  for (std::size_t j = 0; j < FrictionConstants<double>::kFittable; ++j) fittable_constant(k, j) = p[j].value;
  return k;
}

FrictionEffects<double> FrictionFitResult::effects() const {
  FrictionEffects<double> e;
  for (std::size_t j = FrictionConstants<double>::kFittable; j < fit.parameters.size(); ++j)
    if (const auto slot = find_friction_effect(fit.parameters[j].name)) e[*slot] = fit.parameters[j].value;  // not the terms
  return e;
}

namespace detail {

// The combination that stands for constant j in a combination law's outputs (nullptr: none).
const LawCombination* combination_of(const FrictionFitResult& r, std::size_t j) {
  static constexpr std::array<int, 7> kCombination{0, -1, 1, 2, 3, -1, -1};  // k1, mu_st, v_st, mu_v
  if (r.combinations.empty() || j >= kCombination.size() || kCombination[j] < 0) return nullptr;
  return &r.combinations[static_cast<std::size_t>(kCombination[j])];
}

// The weight fitted along a stated incline against M g sin θ with the mass fitted beside it.
// axis_gravity is + G·direction in the motion's sense, the shape of any constant offset of the
// drive's force (a current offset, a sensor zero): it carries both. Where they differ beyond
// 3 SE and by over 1 % of the weight, the fit says which of the two the difference may be.
void check_weight_against_mass(const FrictionLog& log, FrictionFitResult& out) {
  const auto index = [&](std::string_view name) -> std::optional<std::size_t> {
    for (std::size_t j = 0; j < out.fit.parameters.size(); ++j)
      if (out.fit.parameters[j].name == name) return j;
    return std::nullopt;
  };
  const auto g = index(AxisGravity::info.name), m = index(MovingMass::info.name);
  if (!log.incline_stated || !g || !m || out.fit.covariance.rows() != static_cast<Eigen::Index>(out.fit.parameters.size())) return;
  const ParameterEstimate &G = out.fit.parameters[*g], &M = out.fit.parameters[*m];
  if (!G.free || !M.free || !std::isfinite(G.se) || !std::isfinite(M.se)) return;
  const double per_kg = axis_weight_N(1.0, log.axis_incline_deg), weight = M.value * per_kg, difference = G.value - weight;
  const auto gi = static_cast<Eigen::Index>(*g), mi = static_cast<Eigen::Index>(*m);
  const double variance = out.fit.covariance(gi, gi) + per_kg * per_kg * out.fit.covariance(mi, mi) -
                          2 * per_kg * out.fit.covariance(gi, mi);
  const double se = std::sqrt(std::max(variance, 0.0));
  if (!(std::abs(difference) > 3 * se && std::abs(difference) > 0.01 * std::abs(weight))) return;
  out.fit.warnings.push_back(fmt::format(
      "axis_gravity {:.5g} N is {:+.3g} ± {:.2g} N off the weight the fitted mass gives along the stated incline, "
      "M g sin θ = {:.5g} N ({:.5g} kg at {:g}°): a constant offset in the drive's force (a current offset, a "
      "sensor's zero) or an incline other than stated; axis_gravity carries both",
      G.value, difference, se, weight, M.value, log.axis_incline_deg));
}

// Predictions and goodness of fit, in newtons: the law's with its effects (`effects` of them)
// and terms.
void add_predictions(const FrictionLog& log, const TermSeries& series, const FrictionFitOptions& options,
                     std::size_t effects, FrictionFitResult& out) {
  const FrictionConstants<double> k = out.constants();
  const FrictionEffects<double> e = out.effects();
  out.terms = options.terms;
  std::vector<double> term_values;
  {
    std::size_t j = FrictionConstants<double>::kFittable + effects;
    for (auto& term : out.terms) {
      term_values.push_back(term.coefficient = out.fit.parameters[j++].value);
      if (term.has_scale()) term_values.push_back(term.scale = out.fit.parameters[j++].value);
    }
  }
  std::vector<double> lag_change;
  for (std::size_t t = 0, at = 0; t < out.terms.size(); at += out.terms[t].has_scale() ? 2 : 1, ++t)
    if (out.terms[t].lagged_temperature()) lag_change = lagged_temperature_change(log, series, term_values[at + 1]);
  // Each sample's prediction on its own: slices of the samples on the threads, the same bits.
  out.predicted_N.resize(log.size());
  detail::for_each_slice(log.size(), detail::slice_threads(log.size(), 16384), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      FrictionConstants<double> ki = k;
      ki.nu_ref_mm2_s = log.viscosity40_mm2_s[i];
      ki.T_ref_C = options.start.T_ref_C;
      out.predicted_N[i] =
          !out.terms.empty()
              ? friction_with_terms_N(ki, e, log, series, i, out.terms, term_values.data(), lag_change.empty() ? nullptr : &lag_change)
          : effects == 0 ? friction_force_N(ki, log.conditions(i))
                        : friction_force_with_effects_N(ki, e, log.conditions(i));
    }
  });
}

// Per run: the mean residual of the law, and the zero offset the predictions carry.
void add_run_offsets(const FrictionLog& log, RunOffsets offsets, bool random, const RunOffsetVariance& variance,
                     FrictionFitResult& out) {
  const std::size_t runs = log.run_names.size();
  std::vector<double> run_sum(runs, 0.0), run_count(runs, 0.0);
  for (std::size_t i = 0; i < log.size(); ++i) {
    run_sum[log.run[i]] += log.friction_N[i] - out.predicted_N[i];
    run_count[log.run[i]] += 1;
  }
  for (std::size_t r = 0; r < runs; ++r) {
    const double mean = run_count[r] > 0 ? run_sum[r] / run_count[r] : kNaN;
    out.run_mean_residual_N.push_back(mean);
    const double share = offsets == RunOffsets::fixed ? 1.0
                         : random ? run_count[r] * variance.ratio / (1 + run_count[r] * variance.ratio)
                                  : 0.0;
    out.run_offset_N.push_back(share * mean);
  }
  if (random) {
    double sigma2 = 0;
    for (double s : out.sigma_N) sigma2 += s * s;
    out.run_offset_sd_N = std::sqrt(variance.ratio * variance.sigma2 * sigma2 / static_cast<double>(log.size()));
  }
}

// Relative errors against the signal's scale, not each sample's own force (a force near zero,
// a slow light condition or a torque crossing 0, turned a small error into 10³ %): the
// measured force's range, 1st to 99th percentile (a spike moves neither), at least a tenth of
// its median magnitude (a log at nearly one force).
// Then the goodness per condition (guide, preload, load, temperature, speed, direction).
void add_goodness(const FrictionLog& log, FrictionFitResult& out) {
  std::vector<double> magnitudes(log.size()), sorted = log.friction_N;
  for (std::size_t i = 0; i < log.size(); ++i) magnitudes[i] = std::abs(log.friction_N[i]);
  std::nth_element(magnitudes.begin(), magnitudes.begin() + static_cast<std::ptrdiff_t>(magnitudes.size() / 2), magnitudes.end());
  const auto percentile = [&](double q) {  // a selection, not a sort of all the forces
    const auto k = static_cast<std::ptrdiff_t>(std::round(q * static_cast<double>(sorted.size() - 1)));
    std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
    return sorted[static_cast<std::size_t>(k)];
  };
  const double scale_N = std::max({percentile(0.99) - percentile(0.01), 0.1 * magnitudes[magnitudes.size() / 2], 1e-9});
  double ss = 0;
  for (std::size_t i = 0; i < log.size(); ++i) {
    if (!out.run_offset_N.empty() && std::isfinite(out.run_offset_N[log.run[i]])) out.predicted_N[i] += out.run_offset_N[log.run[i]];
    const double r = log.friction_N[i] - out.predicted_N[i];
    ss += r * r;
    const double relative = std::abs(r) / scale_N;
    if (relative > out.max_relative_error) {
      out.max_relative_error = relative;
      out.max_relative_error_sample = i;
    }
  }
  out.rmse_N = std::sqrt(ss / static_cast<double>(log.size()));

  const ConditionGroups groups = group_conditions(log);
  for (std::size_t g = 0; g < groups.keys.size(); ++g) {
    const ConditionKey& key = groups.keys[g];
    const auto members = groups.members(g);
    ConditionResidual c{log.guide_names.empty() ? "" : log.guide_names[std::get<0>(key)],
                        std::get<1>(key), std::get<2>(key), std::get<3>(key), std::get<4>(key), std::get<5>(key),
                        members.size(), 0, 0, 0, 0, 0};
    double ss_c = 0;
    for (std::size_t i : members) {
      c.measured_N += log.friction_N[i];
      c.predicted_N += out.predicted_N[i];
      ss_c += (log.friction_N[i] - out.predicted_N[i]) * (log.friction_N[i] - out.predicted_N[i]);
    }
    const double m = static_cast<double>(members.size());
    c.measured_N /= m;
    c.predicted_N /= m;
    c.bias_N = c.measured_N - c.predicted_N;
    c.rmse_N = std::sqrt(ss_c / m);
    c.relative_error = std::abs(c.bias_N) / std::max(std::abs(c.measured_N), 1e-9);
    out.conditions.push_back(c);
  }
}

// A combination law's combinations, and the runs' spread in them, at the pooled fit's factor (and β).
void add_law_combinations(const FrictionLog& log, FrictionFitResult& out) {
  out.law = log.law;
  if (log.law.combination()) {
    out.law_temperature_C = law_temperature_C(log);
    out.combinations = law_combinations(out.fit, log, out.law_temperature_C);
    // The runs' spread in the combinations, at the pooled fit's factor (and β).
    for (RunSpread& sp : out.spread) {
      const std::optional<std::size_t> j = find_friction_constant(sp.parameter);
      const LawCombination* c = j ? combination_of(out, *j) : nullptr;
      if (!c || out.fit.parameters[*j].value == 0) continue;
      const double factor = c->estimate.value / out.fit.parameters[*j].value;
      for (std::vector<double>* v : {&sp.per_run, &sp.per_run_half_width_95, &sp.per_run_se})
        for (double& x : *v) x *= factor;
      for (double* x : {&sp.spread.mean, &sp.spread.sd, &sp.spread.low, &sp.spread.high, &sp.spread.min, &sp.spread.max,
                        &sp.pooled_se})
        *x *= factor;
      sp.parameter = c->estimate.name;
    }
  }
}

}  // namespace detail

}  // namespace lmcal
