// The friction fit's inputs made ready: the options for the log (a drive's effects, the law's
// conditions), the log's checks and its block-mean temperatures, the samples grouped by
// condition and their weights, the run offsets asked for.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numeric>
#include <span>
#include <tuple>
#include <unordered_map>

#include "friction_steps.hpp"
#include "lmcal/error.hpp"
#include "lmcal/fit/statistics.hpp"
#include "parallel_slices.hpp"

namespace lmcal {

using detail::ConditionGroups;
using detail::ConditionKey;
using detail::condition_key;

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


// Blocks: the samples of one run at one setting. Within a run, guide, preload and load, the
// logged temperatures sorted fall into set points wherever they are more than
// max(kSetPointGap_K, 5σ) apart, σ the thermometer's noise (from the median difference of
// successive samples, robust to the set points' steps). A set point spanning more than
// max(kSetPointWidth_K, 8σ) drifts beyond its noise: it is cut into 1 K bins, so that no sample
// is more than 0.5 K from what its bin's mean stands for.

constexpr double kSetPointGap_K = 1.0, kSetPointWidth_K = 3.0;

double successive_noise(std::span<const std::size_t> in_time, const std::vector<double>& T, std::vector<double>& step) {
  step.clear();
  for (std::size_t k = 1; k < in_time.size(); ++k) step.push_back(std::abs(T[in_time[k]] - T[in_time[k - 1]]));
  if (step.empty()) return 0;
  std::nth_element(step.begin(), step.begin() + static_cast<std::ptrdiff_t>(step.size() / 2), step.end());
  return 1.4826 * step[step.size() / 2] / std::sqrt(2.0);  // |N(0, 2σ²)|'s median is 0.954σ
}


}  // namespace

namespace detail {

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

FrictionFitOptions options_for_log(const FrictionLog& logged, const FrictionFitOptions& given) {
  // A trajectory's drive force carries its inertia (and an incline's weight): fitted with the law.
  FrictionFitOptions options = given;
  with_effect_parts(options.effects, &options.effect_start);  // an effect's shape is fitted with it
  for (const std::string& name : drive_effects(logged))
    if (std::find(options.effects.begin(), options.effects.end(), name) == options.effects.end()) {
      options.effect_start.resize(std::min(options.effect_start.size(), options.effects.size()));  // it starts neutral
      options.effects.push_back(name);
    }
  prepare_law(logged, options);
  return options;
}

bool smooths_temperature(const FrictionLog& logged, const FrictionFitOptions& options) {
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
  return options.temperature == FrictionTemperature::block_mean && !constant_within_runs(logged);
}

void check_conditions_vary(const FrictionLog& log) {
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
}

RunOffsets run_offsets_for(const FrictionFitOptions& options, std::size_t runs) {
  const RunOffsets offsets = options.run_offsets != RunOffsets::automatic ? options.run_offsets
                             : runs >= 2 && options.fit.loss == RobustLoss::none ? RunOffsets::random
                                                                                  : RunOffsets::none;
  if (offsets != RunOffsets::none && options.fit.loss != RobustLoss::none)
    throw InvalidParameter("run_offsets", "per-run offsets and a robust loss cannot be combined");
  return offsets;
}

void check_terms_timed(const FrictionFitOptions& options, const TermSeries& series) {
  for (const auto& term : options.terms)
    for (const auto& f : term.factors)
      if (!series.timed && (f.covariate == TermCovariate::time_in_run_s || f.covariate == TermCovariate::sliding_distance_m ||
                            f.covariate == TermCovariate::campaign_time_s || f.transform == TermTransform::lagged_temperature))
        throw InvalidParameter("terms", "a term in time, sliding distance or a lagged temperature needs a time_s column");
}

}  // namespace detail

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
  // The settings' samples are disjoint: each setting on a free thread, the same sums as in turn.
  detail::for_each_index(offset.size(), [&](std::size_t s) {
    std::vector<double> steps;
    std::vector<std::pair<double, std::size_t>> by_T;
    const std::span<std::size_t> members(grouped.data() + begin_of[s], begin_of[s + 1] - begin_of[s]);
    const double noise = successive_noise(members, T, steps);  // members in time (log) order
    const double gap = std::max(kSetPointGap_K, 5 * noise), width = std::max(kSetPointWidth_K, 8 * noise);
    // By temperature, sorted as (T, sample) pairs held together (ties are equal values: their
    // order changes no mean).
    by_T.reserve(members.size());
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
  });
  return out;
}

}  // namespace lmcal
