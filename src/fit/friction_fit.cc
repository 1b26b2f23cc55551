#include "lmcal/fit/friction_fit.hpp"

#include "lmcal/version.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <set>
#include <span>
#include <tuple>
#include <unordered_map>

#include "fit_json.hpp"
#include "friction_model.hpp"
#include "least_squares.hpp"
#include "parallel_slices.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/csv_writer.hpp"

namespace lmcal {

using detail::fit_json;
using detail::number;

using detail::ConditionKey;
using detail::condition_key;
using detail::FrictionData;
using detail::FrictionModel;
using detail::kConstantUnits;
using detail::run_offset_shrink;
using detail::run_offset_variance;
using detail::RunOffsetVariance;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct ConditionKeyHash {
  std::size_t operator()(const ConditionKey& k) const {
    std::size_t h = std::get<0>(k);
    // A value's bits, multiplied and folded (std::hash<double> hashes its bytes, a tenth of
    // a 10⁵-sample fit); 0.0 and -0.0 are one key.
    auto mix = [&](double v) {
      const auto bits = v == 0 ? std::uint64_t{0} : std::bit_cast<std::uint64_t>(v);
      h = (h ^ bits) * 0x9e3779b97f4a7c15ULL;
      h ^= h >> 29;
    };
    mix(std::get<1>(k)), mix(std::get<2>(k)), mix(std::get<3>(k)), mix(std::get<4>(k)), mix(std::get<5>(k));
    return h;
  }
};

// Samples grouped by condition (guide, preload, load, temperature to 1 K, speed, direction),
// groups in key order; each group's samples in log order, stored one group after the other (a
// trajectory's samples are each a condition of their own: a vector per group cost a heap
// allocation per sample).
struct ConditionGroups {
  std::vector<ConditionKey> keys;
  std::vector<std::size_t> first;     // per group: where its samples start in `samples` (and a last entry: the end)
  std::vector<std::size_t> samples;   // group by group
  std::vector<std::size_t> group_of;  // per sample
  std::span<const std::size_t> members(std::size_t g) const { return {samples.data() + first[g], first[g + 1] - first[g]}; }
};

ConditionGroups group_conditions(const FrictionLog& log) {
  std::unordered_map<ConditionKey, std::size_t, ConditionKeyHash> index;
  std::vector<ConditionKey> keys;  // in the order they first appear
  std::vector<std::size_t> first_group(log.size()), count;
  std::size_t group = 0;
  for (std::size_t i = 0; i < log.size(); ++i) {
    // A log holds each condition for a stretch of samples: look up only where it changes.
    const ConditionKey key = condition_key(log, i);
    if (i == 0 || !(key == keys[group])) {
      const auto [it, inserted] = index.try_emplace(key, keys.size());
      if (inserted) {
        keys.push_back(it->first);
        count.push_back(0);
      }
      group = it->second;
    }
    ++count[group];
    first_group[i] = group;
  }
  // Key order, so that outputs do not depend on the hash.
  std::vector<std::size_t> order(keys.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return keys[a] < keys[b]; });
  std::vector<std::size_t> rank(order.size());
  ConditionGroups sorted;
  sorted.first.assign(order.size() + 1, 0);
  for (std::size_t r = 0; r < order.size(); ++r) {
    rank[order[r]] = r;
    sorted.keys.push_back(keys[order[r]]);
    sorted.first[r + 1] = sorted.first[r] + count[order[r]];
  }
  // The samples into their groups' places in log order (a counting sort).
  sorted.group_of.resize(log.size());
  sorted.samples.resize(log.size());
  std::vector<std::size_t> next(sorted.first.begin(), sorted.first.end() - 1);
  for (std::size_t i = 0; i < log.size(); ++i) {
    const std::size_t g = rank[first_group[i]];
    sorted.group_of[i] = g;
    sorted.samples[next[g]++] = i;
  }
  return sorted;
}

// σ per sample from the spread of repeats (see FrictionWeighting).
std::vector<double> sample_sigmas(const FrictionLog& log, FrictionWeighting weighting) {
  const std::size_t n = log.size();
  std::vector<double> sigma(n, 1.0);
  if (weighting == FrictionWeighting::none) return sigma;
  const ConditionGroups groups = group_conditions(log);
  std::vector<double> deviation(n, kNaN);
  std::vector<double> group_sd(groups.keys.size(), kNaN);
  for (std::size_t g = 0; g < groups.keys.size(); ++g) {
    const auto members = groups.members(g);
    if (members.size() < 2) continue;
    double mean = 0;
    for (std::size_t i : members) mean += log.friction_N[i];
    mean /= static_cast<double>(members.size());
    const double correction = std::sqrt(static_cast<double>(members.size()) / static_cast<double>(members.size() - 1));
    for (std::size_t i : members) deviation[i] = (log.friction_N[i] - mean) * correction;
    if (members.size() >= 3) {
      std::vector<double> values;
      for (std::size_t i : members) values.push_back(log.friction_N[i]);
      group_sd[g] = sample_standard_deviation(values);
    }
  }
  std::vector<double> all;
  for (double d : deviation)
    if (!std::isnan(d)) all.push_back(d);
  if (all.size() < 3)
    throw InvalidParameter("weighting", "weights from the spread of repeats need conditions measured at least twice");
  const double pooled = std::sqrt(std::inner_product(all.begin(), all.end(), all.begin(), 0.0) / static_cast<double>(all.size()));
  if (weighting == FrictionWeighting::per_run) {
    std::map<std::uint32_t, std::pair<double, std::size_t>> by_run;
    for (std::size_t i = 0; i < n; ++i)
      if (!std::isnan(deviation[i])) {
        by_run[log.run[i]].first += deviation[i] * deviation[i];
        by_run[log.run[i]].second += 1;
      }
    for (std::size_t i = 0; i < n; ++i) {
      const auto it = by_run.find(log.run[i]);
      sigma[i] = it == by_run.end() || it->second.second < 3 ? pooled
                                                             : std::sqrt(it->second.first / static_cast<double>(it->second.second));
    }
  } else {
    // A condition's own σ from >= 3 repeats, floored at a quarter of the pooled σ (a few
    // repeats can agree by chance), the pooled σ where it has fewer repeats.
    for (std::size_t i = 0; i < n; ++i) {
      const double sd = group_sd[groups.group_of[i]];
      sigma[i] = std::isnan(sd) ? pooled : std::max(sd, 0.25 * pooled);
    }
  }
  for (double& s : sigma)
    if (!(s > 0)) s = pooled > 0 ? pooled : 1.0;
  return sigma;
}

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

}  // namespace

const std::vector<std::string>& friction_effect_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const auto& e : FrictionEffectLibrary::infos) v.emplace_back(e.name);
    return v;
  }();
  return names;
}

const std::vector<std::string>& friction_cause_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const auto& e : FrictionEffectLibrary::infos)
      if (!e.dynamics && !is_friction_effect_part(e)) v.emplace_back(e.name);
    return v;
  }();
  return names;
}

std::vector<std::string> drive_effects(const FrictionLog& log) {
  std::vector<std::string> names;
  if (log.trajectory) names.emplace_back(MovingMass::info.name);
  if (log.trajectory && std::isfinite(log.axis_incline_deg) && log.axis_incline_deg != 0)
    names.emplace_back(AxisGravity::info.name);
  return names;
}

namespace {

// What a log without some of the law's conditions (FrictionLawConditions) can determine.
// Without a temperature β is held (the law sits at T_i). A combination law holds k2 and f0 at
// 0, so that k1 carries the Coulomb level, and starts and bounds k1, mu_st and mu_v from the
// data's own scale (the paper's values are for its guide, not for an unknown drive).
void prepare_law(const FrictionLog& log, FrictionFitOptions& o) {
  constexpr std::size_t kK1 = 0, kK2 = 1, kMuSt = 2, kMuV = 4, kBeta = 5, kF0 = 6;
  if (!log.law.temperature) o.free[kBeta] = false;
  if (!log.law.combination()) return;
  for (std::size_t j : {kK2, kF0}) {
    o.free[j] = false;
    fittable_constant(o.start, j) = 0;
  }
  double force_max = 0, speed_max = 0, nu = 0;
  for (std::size_t i = 0; i < log.size(); ++i) {
    force_max = std::max(force_max, std::abs(log.friction_N[i]));
    speed_max = std::max(speed_max, log.velocity_m_s[i]);
    nu += log.viscosity40_mm2_s[i] / static_cast<double>(log.size());
  }
  // At the neutral conditions the Coulomb level is k1, the Stribeck amplitude mu_st / ν and the
  // viscous slope mu_v · ν; none can exceed ten times the largest force.
  const double force = std::max(force_max, 1e-9);
  const auto scaled = [&](std::size_t j, double start, double upper) {
    o.bounds[j] = {0, upper};
    if (o.free[j]) fittable_constant(o.start, j) = start;
  };
  scaled(kK1, 0.5 * force, 10 * force);
  scaled(kMuSt, 0.2 * force * nu, 10 * force * nu);
  scaled(kMuV, 0.3 * force / std::max(speed_max, 1e-12) / nu, 10 * force / std::max(speed_max, 1e-12) / nu);
}

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

// The combination that stands for constant j in a combination law's outputs (nullptr: none).
const LawCombination* combination_of(const FrictionFitResult& r, std::size_t j) {
  static constexpr std::array<int, 7> kCombination{0, -1, 1, 2, 3, -1, -1};  // k1, mu_st, v_st, mu_v
  if (r.combinations.empty() || j >= kCombination.size() || kCombination[j] < 0) return nullptr;
  return &r.combinations[static_cast<std::size_t>(kCombination[j])];
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

const char* to_string(RunOffsets offsets) {
  switch (offsets) {
    case RunOffsets::automatic: return "auto";
    case RunOffsets::none: return "none";
    case RunOffsets::fixed: return "fixed";
    case RunOffsets::random: return "random";
  }
  return "?";
}

const char* to_string(FrictionTemperature temperature) {
  return temperature == FrictionTemperature::block_mean ? "block-mean" : "logged";
}

const char* to_string(FrictionWeighting w) {
  switch (w) {
    case FrictionWeighting::none: return "none";
    case FrictionWeighting::per_run: return "per-run";
    case FrictionWeighting::per_condition: return "per-condition";
  }
  return "?";
}

// Blocks: the samples of one run at one setting. Within a run, guide, preload and load, the
// logged temperatures sorted fall into set points wherever they are more than
// max(kSetPointGap_K, 5σ) apart, σ the thermometer's noise (from the median difference of
// successive samples, robust to the set points' steps). A set point spanning more than
// max(kSetPointWidth_K, 8σ) drifts beyond its noise: it is cut into 1 K bins, so that no sample
// is more than 0.5 K from what its bin's mean stands for.
namespace {

constexpr double kSetPointGap_K = 1.0, kSetPointWidth_K = 3.0;

double successive_noise(std::span<const std::size_t> in_time, const std::vector<double>& T, std::vector<double>& step) {
  step.clear();
  for (std::size_t k = 1; k < in_time.size(); ++k) step.push_back(std::abs(T[in_time[k]] - T[in_time[k - 1]]));
  if (step.empty()) return 0;
  std::nth_element(step.begin(), step.begin() + static_cast<std::ptrdiff_t>(step.size() / 2), step.end());
  return 1.4826 * step[step.size() / 2] / std::sqrt(2.0);  // |N(0, 2σ²)|'s median is 0.954σ
}

}  // namespace

FrictionLog with_block_mean_temperature(const FrictionLog& logged) {
  // Each sample's setting, looked up only where it changes (a log holds one for a stretch),
  // then the samples grouped by setting in one index array (a counting sort: log order kept).
  using Setting = std::tuple<std::uint32_t, std::uint32_t, double, double>;
  const std::size_t n = logged.size();
  std::map<Setting, std::size_t> index;
  std::vector<std::size_t> setting_of(n), offset;
  for (std::size_t i = 0; i < n; ++i) {
    const Setting setting{logged.run[i], logged.guide.empty() ? 0 : logged.guide[i], logged.preload_um[i], logged.load_N[i]};
    if (i == 0 || !(logged.run[i] == logged.run[i - 1] && (logged.guide.empty() || logged.guide[i] == logged.guide[i - 1]) &&
                    logged.preload_um[i] == logged.preload_um[i - 1] && logged.load_N[i] == logged.load_N[i - 1])) {
      const auto [it, inserted] = index.try_emplace(setting, offset.size());
      if (inserted) offset.push_back(0);
      setting_of[i] = it->second;
    } else {
      setting_of[i] = setting_of[i - 1];
    }
    ++offset[setting_of[i]];
  }
  std::vector<std::size_t> begin_of(offset.size() + 1, 0);
  for (std::size_t s = 0; s < offset.size(); ++s) begin_of[s + 1] = begin_of[s] + offset[s];
  std::vector<std::size_t> grouped(n), fill(begin_of.begin(), begin_of.end() - 1);
  for (std::size_t i = 0; i < n; ++i) grouped[fill[setting_of[i]]++] = i;
  FrictionLog out = logged;
  const auto& T = logged.temperature_C;
  const auto assign_mean = [&](std::span<const std::size_t> members) {
    double sum = 0;
    for (std::size_t i : members) sum += T[i];
    for (std::size_t i : members) out.temperature_C[i] = sum / static_cast<double>(members.size());
  };
  std::vector<double> steps;
  std::vector<std::pair<double, std::size_t>> by_T;
  for (std::size_t s = 0; s < offset.size(); ++s) {
    const std::span<std::size_t> members(grouped.data() + begin_of[s], begin_of[s + 1] - begin_of[s]);
    const double noise = successive_noise(members, T, steps);  // members in time (log) order
    const double gap = std::max(kSetPointGap_K, 5 * noise), width = std::max(kSetPointWidth_K, 8 * noise);
    // By temperature, sorted as (T, sample) pairs held together (ties are equal values: their
    // order changes no mean).
    by_T.clear();
    for (std::size_t i : members) by_T.emplace_back(T[i], i);
    std::sort(by_T.begin(), by_T.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    for (std::size_t k = 0; k < members.size(); ++k) members[k] = by_T[k].second;
    for (std::size_t begin = 0; begin < members.size();) {
      std::size_t end = begin + 1;
      while (end < members.size() && T[members[end]] - T[members[end - 1]] <= gap) ++end;
      const std::span<const std::size_t> point(members.data() + begin, end - begin);
      if (T[point.back()] - T[point.front()] <= width) {
        assign_mean(point);
      } else {
        for (std::size_t k = 0; k < point.size();) {
          std::size_t j = k + 1;
          while (j < point.size() && std::round(T[point[j]]) == std::round(T[point[k]])) ++j;
          assign_mean(point.subspan(k, j - k));
          k = j;
        }
      }
      begin = end;
    }
  }
  return out;
}

namespace {

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

}  // namespace

namespace {

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

}  // namespace

std::string held_out_caveat(const FrictionFitResult& fit) {
  if (fit.cv_undetermined_runs.empty()) return {};
  return fmt::format("{} {} alone what the law needs (the only {} at a load, preload or temperature): held out, that "
                     "part of the law stays at the full data's estimate, so {} held-out error is optimistic",
                     fmt::join(fit.cv_undetermined_runs, ", "), fit.cv_undetermined_runs.size() == 1 ? "varies" : "each vary",
                     fit.cv_undetermined_runs.size() == 1 ? "run" : "runs",
                     fit.cv_undetermined_runs.size() == 1 ? "its" : "their");
}

FrictionFitResult fit_friction(const FrictionLog& logged, const FrictionFitOptions& given) {
  if (logged.size() == 0) throw InvalidParameter("log", "the friction log has no samples");
  // A trajectory's drive force carries its inertia (and an incline's weight): fitted with the law.
  FrictionFitOptions options = given;
  with_effect_parts(options.effects, &options.effect_start);  // an effect's shape is fitted with it
  for (const std::string& name : drive_effects(logged))
    if (std::find(options.effects.begin(), options.effects.end(), name) == options.effects.end()) {
      options.effect_start.resize(std::min(options.effect_start.size(), options.effects.size()));  // it starts neutral
      options.effects.push_back(name);
    }
  prepare_law(logged, options);
  // A temperature constant within each run (a manifest's, or none logged) is its own block
  // mean: the log is used as it is, not copied.
  const auto constant_within_runs = [](const FrictionLog& l) {
    std::vector<double> first(l.run_names.size(), kNaN);
    for (std::size_t i = 0; i < l.size(); ++i) {
      double& T = first[l.run[i]];
      if (std::isnan(T)) T = l.temperature_C[i];
      else if (l.temperature_C[i] != T) return false;
    }
    return true;
  };
  const bool smooth = options.temperature == FrictionTemperature::block_mean && !constant_within_runs(logged);
  FrictionLog smoothed;
  if (smooth) smoothed = with_block_mean_temperature(logged);
  const FrictionLog& log = smooth ? smoothed : logged;
  // The law is friction in motion against the conditions: with nothing moving, or nothing
  // varied, none of it can be fitted (the fit would report an exact, meaningless agreement).
  const auto varies = [&](const std::vector<double>& column) {
    const auto [low, high] = std::minmax_element(column.begin(), column.end());
    return *low != *high;
  };
  if (*std::max_element(log.velocity_m_s.begin(), log.velocity_m_s.end()) <= 0)
    throw InvalidParameter("velocity_m_s", "no sample in motion (every speed 0): the friction law describes sliding; "
                                           "log the block moving");
  if (!varies(log.velocity_m_s) && !varies(log.load_N) && !varies(log.preload_um) && !varies(log.temperature_C))
    throw InvalidParameter("conditions", "every sample at one condition (speed, load, preload and temperature constant): the "
                                         "law's constants cannot be told apart; log at least two speeds");
  validate(options.start);
  const std::vector<std::size_t> slots = effect_slots(options);
  const auto specs = parameter_specs(options, slots);

  FrictionFitResult out;
  out.sigma_N = sample_sigmas(log, options.weighting);
  const std::size_t runs = log.run_names.size();
  const RunOffsets offsets = options.run_offsets != RunOffsets::automatic ? options.run_offsets
                             : runs >= 2 && options.fit.loss == RobustLoss::none ? RunOffsets::random
                                                                                  : RunOffsets::none;
  if (offsets != RunOffsets::none && options.fit.loss != RobustLoss::none)
    throw InvalidParameter("run_offsets", "per-run offsets and a robust loss cannot be combined");
  out.run_offsets = offsets;
  const TermSeries series = term_series(log);
  for (const auto& term : options.terms)
    for (const auto& f : term.factors)
      if (!series.timed && (f.covariate == TermCovariate::time_in_run_s || f.covariate == TermCovariate::sliding_distance_m ||
                            f.covariate == TermCovariate::campaign_time_s || f.transform == TermTransform::lagged_temperature))
        throw InvalidParameter("terms", "a term in time, sliding distance or a lagged temperature needs a time_s column");
  FrictionData data{&log, {}, {}, options.start.T_ref_C, {}};
  data.terms = &options.terms;
  data.series = &series;
  for (std::size_t i = 0; i < log.size(); ++i) {
    data.samples.push_back(i);
    data.inv_sigma.push_back(1.0 / out.sigma_N[i]);
  }
  std::vector<std::size_t> run_of(log.size());
  for (std::size_t i = 0; i < log.size(); ++i) run_of[i] = log.run[i];
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
  const bool random = offsets == RunOffsets::random && runs >= 2;
  detail::ProfiledRunOffsets profiled{&data.run_shrink};
  if (random && options.max_variance_passes > 1) data.profiled = &profiled;
  const FrictionModel model(data, slots);
  detail::FinalState final_state;
  auto run_specs = specs;
  auto warm_start = [&] {
    for (std::size_t j = 0; j < run_specs.size(); ++j)
      if (run_specs[j].free && !out.fit.parameters[j].held_unidentifiable)
        run_specs[j].start = std::clamp(out.fit.parameters[j].value, run_specs[j].lower, run_specs[j].upper);
  };
  // A fit whose λ still moved after it (a polish stopped short) is refitted from its estimate at
  // the new λ, up to max_variance_passes fits.
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
  if (options.cross_validate && runs >= 2 && options.fit.loss == RobustLoss::none && out.fit.solver.usable) {
    std::vector<bool> held;
    // A parameter on its bound stays there: a held-out step must not carry it across (a drag below 0).
    for (const auto& p : out.fit.parameters) held.push_back(!p.free || p.held_unidentifiable || p.at_bound);
    std::vector<std::size_t> alone;
    const Eigen::VectorXd held_out = detail::leave_group_out_residuals(final_state, run_of, held, &alone);
    for (std::size_t r : alone) out.cv_undetermined_runs.push_back(log.run_names[r]);
    // A held-out run under random offsets is a new setup with an unknown zero: predicted
    // with the offsets' mean, 0 (its own mean is not taken out). Fixed offsets stay profiled.
    const std::vector<double> prediction_error = unwhitened(held_out, run_of, data.run_shrink);
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

  // Predictions and goodness of fit, in newtons.
  const FrictionConstants<double> k = out.constants();
  const FrictionEffects<double> e = out.effects();
  out.terms = options.terms;
  std::vector<double> term_values;
  {
    std::size_t j = FrictionConstants<double>::kFittable + slots.size();
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
          : slots.empty() ? friction_force_N(ki, log.conditions(i))
                          : friction_force_with_effects_N(ki, e, log.conditions(i));
    }
  });
  // Per run: the mean residual of the law, and the zero offset the predictions carry.
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
  // Relative errors against the signal's scale, not each sample's own force (a force near zero,
  // a slow light condition or a torque crossing 0, turned a small error into 10³ %): the
  // measured force's range, 1st to 99th percentile (a spike moves neither), at least a tenth of
  // its median magnitude (a log at nearly one force).
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

  // Every run alone, from the pooled estimate, holding what the pooled fit held.
  out.runs = log.run_names;
  if (options.per_run_fits && log.run_names.size() >= 2 && out.fit.solver.usable) {
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
      FrictionData run_data{&log, {}, {}, options.start.T_ref_C, data.run_shrink};
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
  check_weight_against_mass(log, out);
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
  return out;
}

// ---- output ---------------------------------------------------------------------------------

namespace {

const char* to_string(RobustLoss l) {
  switch (l) {
    case RobustLoss::none: return "none";
    case RobustLoss::huber: return "huber";
    case RobustLoss::cauchy: return "cauchy";
  }
  return "?";
}

nlohmann::json run_offsets_json(const FrictionFitResult& r, const FrictionFitOptions& o) {
  const std::string model = fmt::format("{}{}",
                                        r.run_offsets == RunOffsets::random  ? "random (a run intercept of variance tau^2, ML, GLS)"
                                        : r.run_offsets == RunOffsets::fixed ? "fixed (one free offset per run, profiled)"
                                                                             : "none",
                                        o.run_offsets == RunOffsets::automatic ? "; chosen automatically" : "");
  nlohmann::json per_run = nlohmann::json::object();
  for (std::size_t k = 0; k < r.runs.size() && k < r.run_offset_N.size(); ++k)
    per_run[r.runs[k]] = {{"offset_N", number(r.run_offset_N[k])}, {"mean_residual_N", number(r.run_mean_residual_N[k])}};
  return {{"model", model}, {"sd_N", number(r.run_offset_sd_N)}, {"ratio_to_noise_variance", number(r.run_offset_ratio)},
          {"fits", r.variance_passes}, {"per_run", per_run}};
}

}  // namespace

namespace {

// Whether the summary's table shows parameter j: not the constants a combination law held at
// 0, nor β without a logged temperature (its value would be the paper's, not this log's).
bool shown(const FrictionFitResult& r, std::size_t j) {
  constexpr std::size_t kK2 = 1, kBeta = 5, kF0 = 6;
  return (r.combinations.empty() || (j != kK2 && j != kF0)) && (r.law.temperature || j != kBeta);
}

// What the log gave and what the fit could therefore determine.
std::string law_summary(const FrictionFitResult& r) {
  if (!r.law.combination() && r.law.temperature) return "";
  if (!r.law.combination())
    return "law: no temperature logged: evaluated at the oil's ν40 (T_i = 40 °C), beta_per_K held; log the "
           "temperature to fit it\n";
  std::string s = fmt::format("law: not given: {} ({}); fitted in the combinations one setup determines, at {}\n",
                              fmt::join(r.law.not_logged(), ", "), r.law.stated(),
                              r.law.temperature ? fmt::format("the mean logged temperature, {:g} °C", r.law_temperature_C)
                                                : std::string("the log's own (unlogged) temperature"));
  for (const LawCombination& c : r.combinations) s += fmt::format("  {:<20} {}\n", c.estimate.name, c.meaning);
  s += "  to separate the paper's constants: give load_N, preload_um (or preload_class) and block_length_mm, with runs "
       "at two loads or more (k1 from f0), two preloads (k2) and temperatures over 10 K or more (beta)\n";
  return s;
}

nlohmann::json law_json(const FrictionFitResult& r) {
  nlohmann::json j = {{"form", r.law.combination() ? "combinations" : "constants"},
                      {"not_given", r.law.not_logged()}};
  if (!r.law.combination()) return j;
  nlohmann::json combinations = nlohmann::json::array();
  for (const LawCombination& c : r.combinations) {
    const ParameterEstimate& e = c.estimate;
    combinations.push_back({{"name", e.name}, {"unit", e.unit}, {"meaning", c.meaning}, {"value", number(e.value)},
                            {"se", number(e.se)}, {"interval", e.interval},
                            {"ci95", {number(e.interval == "profile" ? e.profile_low : e.ci_low),
                                      number(e.interval == "profile" ? e.profile_high : e.ci_high)}}});
  }
  j["stated"] = r.law.stated();
  j["temperature_C"] = r.law_temperature_C;
  j["combinations"] = combinations;
  return j;
}

}  // namespace

FitResult friction_fit_as_shown(const FrictionFitResult& r) {
  FitResult f = r.fit;
  for (std::size_t j = 0; j < f.parameters.size(); ++j) {
    if (!shown(r, j)) f.parameters[j].interval = "none", f.parameters[j].listed = false;
    const LawCombination* c = combination_of(r, j);
    if (!c) continue;
    const double ratio = r.fit.parameters[j].se > 0 ? c->estimate.se / r.fit.parameters[j].se : 0;
    for (CovarianceSummary& m : f.uncertainty.methods)
      if (j < m.se.size()) m.se[j] *= ratio;
    for (RunHeterogeneity& h : f.uncertainty.heterogeneity)
      if (h.parameter == f.parameters[j].name) h.parameter = c->estimate.name;
    f.parameters[j] = c->estimate;
  }
  return f;
}

std::string friction_fit_json(const FrictionFitResult& r, const FrictionFitOptions& o, const FitProvenance& prov) {
  nlohmann::json spread = nlohmann::json::array();
  for (const auto& s : r.spread) {
    nlohmann::json per_run = nlohmann::json::array();
    nlohmann::json per_run_se = nlohmann::json::array();
    for (double v : s.per_run) per_run.push_back(number(v));
    for (double v : s.per_run_se) per_run_se.push_back(number(v));
    nlohmann::json row = {{"parameter", s.parameter},
                          {"per_run", per_run},
                          {"per_run_se", per_run_se},
                          {"n", s.spread.n},
                          {"mean", number(s.spread.mean)},
                          {"sd_eq1", number(s.spread.sd)},
                          {"ci95", {number(s.spread.low), number(s.spread.high)}},
                          {"min", number(s.spread.min)},
                          {"max", number(s.spread.max)},
                          {"pooled_se", number(s.pooled_se)},
                          {"ratio_to_pooled", number(s.ratio)},
                          {"cochran_q", number(s.q)},
                          {"p", number(s.p)},
                          {"p_holm", number(s.p_holm)},
                          {"wider_than_pooled", s.wider_than_pooled}};
    if (!s.undetermined.empty()) row["undetermined"] = s.undetermined;  // why per_run has NaN
    spread.push_back(std::move(row));
  }
  nlohmann::json inputs = nlohmann::json::array();
  for (const auto& [file, hash] : prov.inputs) inputs.push_back({{"file", file}, {"sha256", hash}});
  nlohmann::json j = {
      {"kind", "friction fit"},
      {"name", prov.name},
      {"lmcal_version", LMCAL_VERSION}, {"schema_version", kOutputSchemaVersion},
      {"command", prov.command},
      {"inputs", inputs},
      {"seed", o.fit.seed},
      {"options",
       {{"weighting", to_string(o.weighting)},
        {"loss", to_string(o.fit.loss)},
        {"loss_scale", o.fit.loss_scale},
        {"starts", o.fit.starts},
        {"effects", o.effects},
        {"temperature", to_string(o.temperature)},
        {"reference_temperature_C", o.start.T_ref_C}}},
      {"runs", r.runs},
      {"run_offsets", run_offsets_json(r, o)},
      {"goodness",
       {{"rmse_N", r.rmse_N},
        {"max_relative_error", r.max_relative_error},
        {"max_relative_error_sample", r.max_relative_error_sample},
        {"conditions", r.conditions.size()}}},
      {"spread_across_runs", spread},
      {"law", law_json(r)}};
  j.update(fit_json(r.fit));
  if (!r.terms.empty()) {
    nlohmann::json terms = nlohmann::json::array();
    for (std::size_t t = 0; t < r.terms.size(); ++t)
      terms.push_back({{"symbol", r.terms[t].symbol(t + 1)},
                       {"covariates", r.terms[t].covariates()},
                       {"coefficient", r.terms[t].coefficient},
                       {"coefficient_unit", r.terms[t].coefficient_unit()},
                       {"scale", r.terms[t].has_scale() ? nlohmann::json(r.terms[t].scale) : nlohmann::json()},
                       {"scale_unit", r.terms[t].scale_unit()}});
    j["empirical_terms"] = terms;
  }
  return j.dump(2) + "\n";
}

std::string friction_fit_samples_csv(const FrictionFitResult& r, const FrictionLog& log) {
  // Only the conditions the log gave: a combination law's neutral values are not data.
  const bool setup = !log.law.combination(), temperature = log.law.temperature;
  std::vector<std::string> header{"run", "line", "time_s", "guide", "velocity_m_s"};
  if (setup) header.insert(header.end(), {"load_N", "preload_um", "block_length_mm"});
  if (temperature) header.push_back("temperature_C");
  header.insert(header.end(), {"direction", "measured_N", "predicted_N", "residual_N", "sigma_N"});
  CsvText csv(header);
  csv.expect_rows(log.size());
  for (std::size_t i = 0; i < log.size(); ++i) {
    csv.cell(log.run_names[log.run[i]]).cell(i < log.line.size() && log.line[i] > 0 ? std::to_string(log.line[i]) : "");
    csv.cell(i < log.time_s.size() ? log.time_s[i] : NAN);  // nan: the log has no time
    csv.cell(log.guide_names.empty() ? "" : log.guide_names[log.guide[i]]);
    csv.cell(log.velocity_m_s[i]);
    if (setup) csv.cell(log.load_N[i]).cell(log.preload_um[i]).cell(log.block_length_mm[i]);
    if (temperature) csv.cell(log.temperature_C[i]);
    csv.cell(double(log.direction[i])).cell(log.friction_N[i]).cell(r.predicted_N[i]);
    csv.cell(log.friction_N[i] - r.predicted_N[i]).cell(r.sigma_N[i]).end_row();
  }
  return csv.str();
}

std::vector<std::pair<std::string, std::string>> friction_fit_files(const FrictionFitResult& result, const FrictionLog& log,
                                                                    const FrictionFitOptions& options,
                                                                    const FitProvenance& provenance) {
  return {{provenance.name + ".json", friction_fit_json(result, options, provenance)},
          {provenance.name + "_samples.csv", friction_fit_samples_csv(result, log)},
          {provenance.name + "_conditions.csv", friction_fit_conditions_csv(result)}};
}

std::string friction_fit_conditions_csv(const FrictionFitResult& r) {
  const bool setup = !r.law.combination(), temperature = r.law.temperature;
  std::vector<std::string> header{"guide"};
  if (setup) header.insert(header.end(), {"preload_um", "load_N"});
  if (temperature) header.push_back("temperature_C");
  header.insert(header.end(), {"velocity_m_s", "direction", "n", "measured_N", "predicted_N", "bias_N", "rmse_N",
                               "relative_error"});
  CsvText csv(header);
  for (const auto& c : r.conditions) {
    csv.cell(c.guide);
    if (setup) csv.cell(c.preload_um).cell(c.load_N);
    if (temperature) csv.cell(c.temperature_C);
    csv.cell(c.velocity_m_s).cell(c.direction);
    csv.cell(double(c.n)).cell(c.measured_N).cell(c.predicted_N).cell(c.bias_N).cell(c.rmse_N).cell(c.relative_error);
    csv.end_row();
  }
  return csv.str();
}

std::string friction_fit_summary(const FrictionFitResult& r) {
  const FitResult f = friction_fit_as_shown(r);
  std::string s;
  std::size_t free = 0;
  for (const auto& p : f.parameters) free += p.free ? 1 : 0;
  s += fmt::format("{} samples, {} runs, {} of {} parameters asked free\n", f.residuals, r.runs.size(), free,
                   f.parameters.size());
  s += law_summary(r);
  s += fmt::format("  {:<20} {:>12} {:>11}  {:<19} {:<27} {}\n", "parameter", "value", "SE", "unit", "95% interval", "note");
  for (std::size_t j = 0; j < f.parameters.size(); ++j) {
    if (!shown(r, j)) continue;
    const ParameterEstimate& p = f.parameters[j];
    std::string note;
    if (!p.free) note = "held (given)";
    else if (p.held_unidentifiable) note = "held: not identifiable";
    else if (p.at_bound) note = "at a bound";
    std::string interval = "";
    if (p.interval == "profile") interval = fmt::format("[{:.5g}, {:.5g}] profile", p.profile_low, p.profile_high);
    else if (p.interval == "linear") interval = fmt::format("[{:.5g}, {:.5g}]", p.ci_low, p.ci_high);
    s += fmt::format("  {:<20} {:>12.6g} {:>11.3g}  {:<19} {:<27} {}\n", p.name, p.value, p.se, shown_unit(p.unit), interval, note);
  }
  s += detail::uncertainty_summary(f);
  if (f.identifiability.identifiable) {
    s += fmt::format("identifiability: all requested parameters determined (condition number {:.3g})\n",
                     f.identifiability.condition_number);
  } else {
    for (const auto& issue : f.identifiability.issues)
      s += fmt::format("NOT IDENTIFIABLE: {}\n  -> held {}; to separate them: {}\n", issue.why,
                       fmt::join(issue.held, ", "), issue.measure);
  }
  // The strongest correlations among fitted parameters.
  std::vector<std::tuple<double, double, std::string, std::string>> pairs;
  for (std::size_t i = 0; i < f.parameters.size(); ++i)
    for (std::size_t j = i + 1; j < f.parameters.size(); ++j) {
      const double c = f.correlation(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
      if (std::isfinite(c)) pairs.emplace_back(std::abs(c), c, f.parameters[i].name, f.parameters[j].name);
    }
  std::sort(pairs.rbegin(), pairs.rend());
  if (!pairs.empty()) {
    s += "strongest correlations:";
    for (std::size_t k = 0; k < std::min<std::size_t>(3, pairs.size()); ++k)
      s += fmt::format(" {}/{} {:+.3f};", std::get<2>(pairs[k]), std::get<3>(pairs[k]), std::get<1>(pairs[k]));
    s += "\n";
  }
  s += fmt::format("solver: {} after {} iterations{}; {} of {} starts reached the best minimum of a {}-residual subsample{}; "
                   "covariance {}\n",
                   f.solver.termination, f.solver.iterations, f.solver.converged ? "" : " (not converged)", f.solver.starts_agreed,
                   f.solver.starts, f.solver.start_residuals, f.solver.restarted ? " (polished again from the best on all data)" : "",
                   f.solver.covariance_ok ? "ok" : "FAILED");
  s += fmt::format("goodness: RMSE {:.3f} N, max error {:.1f} % of the measured force's range (sample {}), residual sigma {:.3g}\n", r.rmse_N,
                   100 * r.max_relative_error, r.max_relative_error_sample, std::sqrt(f.residual_variance));
  if (r.variance_passes > 0 && r.run_offset_ratio > 0)
    s += fmt::format("run offsets: random, tau = {:.3g} N (variance {:.3g} x the noise's, ML with the constants{})\n",
                     r.run_offset_sd_N, r.run_offset_ratio,
                     r.variance_passes > 1 ? fmt::format(", {} fits", r.variance_passes) : std::string());
  if (!r.spread.empty()) {
    s += fmt::format("spread across {} runs (Eq. 1 sigma; ratio = sigma / (pooled SE * sqrt(runs)), ~1 if only noise; "
                     "p: the pooled fit's test of heterogeneity between runs, Holm across the constants):\n",
                     r.runs.size());
    for (const auto& sp : r.spread) {
      if (sp.spread.n < 2) {  // fewer than two runs' own values (the report's rule too)
        s += fmt::format("  {:<20} no spread: not determined run by run ({})\n", sp.parameter,
                         sp.undetermined.empty() ? "fewer than two runs' own fits gave it" : sp.undetermined);
        continue;
      }
      s += fmt::format("  {:<20} mean {:>11.5g}  sigma {:>9.3g}  [{:.5g}, {:.5g}]  min {:.5g} max {:.5g}  ratio {:.2f}  p {:.2g}{}{}\n",
                       sp.parameter, sp.spread.mean, sp.spread.sd, sp.spread.low, sp.spread.high, sp.spread.min,
                       sp.spread.max, sp.ratio, sp.p_holm,
                       sp.wider_than_pooled ? "  WIDER: the runs differ beyond what the model explains" : "",
                       sp.undetermined.empty() ? "" : "  (without " + sp.undetermined + ")");
    }
  }
  for (const auto& w : f.warnings) s += "warning: " + w + "\n";
  return s;
}

}  // namespace lmcal
