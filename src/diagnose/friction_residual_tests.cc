// The tests of a friction fit's residuals: the covariates within and between runs, along the
// travel, their interactions, and the lack of fit against pure error or the noise (Holm over
// all); and what they say of a fit (diagnose_friction_residuals, warn_of_missed_structure).
#include "friction_residual_tests.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <tuple>

#include "lmcal/fit/statistics.hpp"
#include "fit/friction_condition.hpp"
#include "selection.hpp"

namespace lmcal {

namespace detail {

// Whether the log's accelerations are large enough to matter beside friction (RMS).
bool accelerates(const FrictionLog& log) {
  double sum2 = 0;
  for (double a : log.acceleration_m_s2) sum2 += a * a;
  return log.size() > 0 && std::sqrt(sum2 / static_cast<double>(log.size())) >= kMinCauseAcceleration_m_s2;
}

// Whether a log column varies enough for a cause that needs it (FrictionEffectInfo::varies):
// both directions, or a spread beyond the column's resolution (a condition a combination law
// did not log is constant at its neutral value).
bool varies_in(const FrictionLog& log, std::string_view column) {
  if (column.empty() || log.size() == 0) return true;
  if (column == "direction")
    return std::any_of(log.direction.begin(), log.direction.end(), [](auto d) { return d > 0; }) &&
           std::any_of(log.direction.begin(), log.direction.end(), [](auto d) { return d < 0; });
  const auto spread = [](const std::vector<double>& v) {
    const auto [low, high] = std::minmax_element(v.begin(), v.end());
    return *high - *low;
  };
  if (column == "temperature_C") {  // a thermometer's noise spreads one set point too: the SD, not the range
    if (!log.law.temperature) return false;
    double sum = 0, sum2 = 0;
    for (double t : log.temperature_C) sum += t, sum2 += t * t;
    const double n = static_cast<double>(log.size()), mean = sum / n;
    return std::sqrt(std::max(sum2 / n - mean * mean, 0.0)) >= 0.5;
  }
  if (column == "load_N") return log.law.load && !log.law.combination() && spread(log.load_N) > 1e-6 * log.load_N.front();
  // A raw log's travel: over more than a few encoder counts (a tidy log has none: all 0).
  if (column == "position_m") return spread(log.position_m) > 1e-3;
  if (column == "distance_since_reversal_m") return spread(log.distance_since_reversal_m) > 1e-3;
  // Accelerations that matter beside friction, on a log whose moving mass is not fitted anyway
  // (a trajectory fits it with the law: moving_mass).
  if (column == "acceleration_m_s2") return !log.trajectory && accelerates(log);
  return true;
}

// `tolerance`: values within it of a run's first are that value (condition_tolerance).
std::vector<Covariate> covariates_of(const FrictionLog& log, double tolerance) {
  std::vector<Covariate> c = {{"velocity_m_s", log.velocity_m_s}, {"load_N", log.load_N},
                              {"preload_um", log.preload_um},     {"block_length_mm", log.block_length_mm},
                              {"temperature_C", {}},              {"direction", {}}};
  for (std::size_t i = 0; i < log.size(); ++i) {
    c[4].value.push_back(std::round(log.temperature_C[i]));
    c[5].value.push_back(log.direction[i]);
  }
  // Not on a trajectory: its speed bins recur over the whole run, so their mean times are alike
  // and a test of them would be one of speed. Within conditions, time on a drive's log follows
  // the moves (position, speed's order) too closely to stand for a drift of its own; the
  // temperature and the run order are the drift's covariates there.
  if (!log.trajectory && std::any_of(log.time_s.begin(), log.time_s.end(), [](double t) { return !std::isnan(t); }))
    c.push_back({"time_s", log.time_s});
  for (auto& cov : c) {
    std::vector<double> first(log.run_names.size(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t i = 0; i < log.size() && cov.run_level; ++i) {
      double& f = first[log.run[i]];
      if (std::isnan(f)) f = cov.value[i];
      else if (!detail::same_to_resolution(cov.value[i], f, tolerance)) cov.run_level = false;
    }
  }
  return c;
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Along the travel: position, distance and time since the last reversal and acceleration change
// within a condition (a condition's mean says nothing about them), and neighbouring samples'
// residuals are correlated. So the run-centred residuals are averaged in cells (run, tenth of the
// run's samples, sense, speed bin, covariate bin); the stretches of a run and the runs are the
// replicates. F test: do the covariate's bins explain more of the cell means than the speed bins
// (in each sense) already do? Ten quantile bins each: a trend or a feature a tenth of the travel
// wide, not a short ripple (position_ripple's own fit finds those). Only the covariates that
// vary (a tidy log has none: all 0).
std::vector<CovariateTest> along_the_travel(const FrictionLog& log, const std::vector<double>& centred) {
  constexpr std::size_t kStretches = 10;
  constexpr std::size_t kLabels = 12;  // value_bins' labels are below its max_groups, 12
  std::vector<std::pair<std::string, const std::vector<double>*>> along;
  if (varies_in(log, "position_m")) along.emplace_back("position_m (along the travel)", &log.position_m);
  if (varies_in(log, "distance_since_reversal_m")) {
    along.emplace_back("distance_since_reversal_m", &log.distance_since_reversal_m);
    if (std::none_of(log.time_since_reversal_s.begin(), log.time_since_reversal_s.end(), [](double t) { return std::isnan(t); }))
      along.emplace_back("time_since_reversal_s", &log.time_since_reversal_s);
  }
  if (accelerates(log)) along.emplace_back("acceleration_m_s2 (within conditions)", &log.acceleration_m_s2);
  if (along.empty()) return {};
  const std::size_t n = log.size();
  const std::vector<std::size_t> speed = detail::value_bins(log.velocity_m_s);
  std::vector<std::size_t> count(log.run_names.size(), 0), seen(log.run_names.size(), 0), stretch(n);
  for (std::size_t i = 0; i < n; ++i) ++count[log.run[i]];
  for (std::size_t i = 0; i < n; ++i) stretch[i] = seen[log.run[i]]++ * kStretches / count[log.run[i]];
  std::vector<CovariateTest> tests;
  for (const auto& [name, values] : along) {
    const std::vector<std::size_t> bin = detail::value_bins(*values);
    // cell -> (sum, count); the cell's label for the speed alone and for speed and covariate
    std::map<std::tuple<std::uint32_t, std::size_t, int, std::size_t, std::size_t>, std::pair<double, double>> cells;
    for (std::size_t i = 0; i < n; ++i) {
      auto& c = cells[{log.run[i], stretch[i], log.direction[i] > 0 ? 1 : 0, speed[i], bin[i]}];
      c.first += centred[i];
      c.second += 1;
    }
    std::vector<double> means;
    std::vector<std::size_t> coarse, fine;
    for (const auto& [key, sum] : cells) {
      const auto& [run, part, sense, v, b] = key;
      means.push_back(sum.first / sum.second);
      coarse.push_back(2 * v + static_cast<std::size_t>(sense));
      fine.push_back(coarse.back() * kLabels + b);
    }
    tests.push_back(detail::nested_anova(name, coarse, fine, means));
  }
  return tests;
}

// The law's residuals (measured - law, no offsets) per sample, and per run their mean.
struct LawResiduals {
  std::vector<double> raw, centred;  // centred: the run's mean taken out
  std::vector<double> run_mean;
};

LawResiduals law_residuals(const FrictionLog& log, const FrictionFitResult& fit) {
  LawResiduals r;
  const std::size_t runs = log.run_names.size();
  std::vector<double> count(runs, 0.0);
  r.run_mean.assign(runs, 0.0);
  for (std::size_t i = 0; i < log.size(); ++i) {
    r.raw.push_back(log.friction_N[i] - (fit.predicted_N[i] - fit.run_offset_N[log.run[i]]));
    r.run_mean[log.run[i]] += r.raw.back();
    count[log.run[i]] += 1;
  }
  for (std::size_t g = 0; g < runs; ++g) r.run_mean[g] /= std::max(count[g], 1.0);
  for (std::size_t i = 0; i < log.size(); ++i) r.centred.push_back(r.raw[i] - r.run_mean[log.run[i]]);
  return r;
}

// Means of `values` per group key: the covariates' and the values' means, in key order.
template <class Key>
std::pair<std::vector<std::vector<double>>, std::vector<double>> group_means(const std::vector<Key>& key,
                                                                             const std::vector<Covariate>& covariates,
                                                                             const std::vector<double>& values) {
  std::map<Key, std::vector<double>> sums;  // per group: covariates..., value, count
  const std::size_t k = covariates.size();
  for (std::size_t i = 0; i < values.size(); ++i) {
    auto& g = sums[key[i]];
    g.resize(k + 2, 0.0);
    for (std::size_t c = 0; c < k; ++c) g[c] += covariates[c].value[i];
    g[k] += values[i];
    g[k + 1] += 1;
  }
  std::vector<std::vector<double>> columns(k);
  std::vector<double> means;
  for (const auto& [key_value, g] : sums) {
    for (std::size_t c = 0; c < k; ++c) columns[c].push_back(g[c] / g[k + 1]);
    means.push_back(g[k] / g[k + 1]);
  }
  return {columns, means};
}

// "speed, load and preload matched within 1 % of their value, temperature to 1 K"
std::string matched_words(double tolerance) {
  return fmt::format("speed, load and preload matched within {:g} % of their value, temperature to 1 K", 100 * tolerance);
}

// The residuals' noise from their high-frequency differences: within each run, the samples of
// one setup and direction (every condition but the speed) in time order, second differences k
// samples apart, e(i+k) - 2 e(i) + e(i-k) (variance 6σ² for white noise: a run's level and a
// misfit smooth over neighbouring samples cancel). k = 1, or a trajectory's filter window (its
// filtered samples share their noise over the window, so neighbours differ by little of it).
// Noise correlated over more than k samples is seen only in part (the margin's trap).
detail::NoiseFloor residual_noise(const FrictionLog& log, const std::vector<detail::ConditionKey>& keys,
                                  const std::vector<double>& residual, std::size_t& lag) {
  std::map<std::pair<std::uint32_t, detail::ConditionKey>, std::vector<std::size_t>> series;
  for (std::size_t i = 0; i < log.size(); ++i) {
    detail::ConditionKey setup = keys[i];
    std::get<4>(setup) = 0;  // the speed sweeps along a series
    series[{log.run[i], setup}].push_back(i);
  }
  std::vector<std::size_t> run_lag(log.run_names.size(), 1);
  for (const RunSegmentation& s : log.segmentation)
    for (std::size_t r = 0; r < log.run_names.size(); ++r)
      if (log.trajectory && log.run_names[r] == s.run && s.filter_window > 1) run_lag[r] = s.filter_window;
  lag = *std::max_element(run_lag.begin(), run_lag.end());
  double ss = 0, count = 0, independent = 0;
  for (const auto& [where, at] : series) {
    const std::size_t k = run_lag[where.first];
    double m = 0;
    for (std::size_t j = k; j + k < at.size(); ++j) {
      ss += std::pow(residual[at[j + k]] - 2 * residual[at[j]] + residual[at[j - k]], 2);
      m += 1;
    }
    count += m;
    independent += m / static_cast<double>(k);  // k apart: k interleaved series of differences
  }
  if (count == 0) return {};
  return {std::sqrt(ss / (6 * count)), independent * detail::kSecondDifferenceDofShare};
}

// Lack of fit against the noise of the residuals' consecutive differences (residual_noise): the
// run-centred residuals' variance, every parameter and run level counted, against it, with
// o.noise_margin. `why` says why not against pure error.
LackOfFit noise_lack_of_fit(const FrictionLog& log, const std::vector<detail::ConditionKey>& keys,
                            const std::vector<double>& centred, std::size_t parameters, const std::string& why,
                            const FrictionDiagnosisOptions& o) {
  double ss = 0;
  for (double e : centred) ss += e * e;
  std::size_t lag = 1;
  const detail::NoiseFloor noise = residual_noise(log, keys, centred, lag);
  const auto n = static_cast<double>(log.size());
  LackOfFit l = detail::lack_of_fit_against_noise(
      ss, n, n, parameters + log.run_names.size(), noise, o.structure_p, o.noise_margin,
      fmt::format("the noise of consecutive residuals (second differences {} sample{} apart within each run's setup and "
                  "direction; {}; {}), structure when the residual RMS exceeds {:g} times it",
                  lag, lag == 1 ? "" : "s", why, matched_words(o.condition_tolerance), o.noise_margin));
  l.condition_tolerance = o.condition_tolerance;
  return l;
}

// Lack of fit. Against pure error where the design repeats conditions across runs: the cell
// means (run × condition; repeated samples of a cell averaged, so serially correlated samples
// count once) fitted by run + condition (backfitting), against run alone. What the conditions
// add beyond the runs' levels is the model's lack of fit; the run × condition remainder is the
// pure error — the spread of a condition repeated in other runs. Conditions match within
// o.condition_tolerance (their resolution), not as exact doubles. A few conditions coinciding by
// chance (continuous speeds) make no pure error: at least half the conditions must recur in
// another run. Otherwise the residuals are judged against the noise of their high-frequency
// differences (residual_noise), with o.noise_margin.
LackOfFit lack_of_fit(const FrictionLog& log, const std::vector<detail::ConditionKey>& keys, const std::vector<double>& centred,
                      std::size_t parameters, const FrictionDiagnosisOptions& o) {
  // Each sample's condition, numbered in order of first appearance (a stretch of samples at one
  // condition looked up once).
  const std::size_t n = log.size();
  std::map<detail::ConditionKey, std::size_t> condition_index;
  std::vector<std::size_t> condition_of(n);
  for (std::size_t i = 0; i < n; ++i)
    condition_of[i] = i > 0 && keys[i] == keys[i - 1] ? condition_of[i - 1]
                                                      : condition_index.try_emplace(keys[i], condition_index.size()).first->second;
  const std::size_t R = log.run_names.size(), C = condition_index.size();
  // The (run, condition) cells in that order, each with its samples' sum in log order: the
  // samples sorted by condition, then stably by run (two counting sorts), and summed in turn.
  struct Cell {
    std::size_t run, condition;
    double sum = 0, count = 0;
  };
  const auto counting_sort = [n](const std::vector<std::size_t>& order, std::size_t groups, auto group_of) {
    std::vector<std::size_t> start(groups + 1, 0), sorted(n);
    for (std::size_t i : order) ++start[group_of(i) + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    for (std::size_t i : order) sorted[start[group_of(i)]++] = i;
    return sorted;
  };
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  order = counting_sort(order, C, [&](std::size_t i) { return condition_of[i]; });
  order = counting_sort(order, R, [&](std::size_t i) { return std::size_t{log.run[i]}; });
  std::vector<Cell> cells;
  for (std::size_t i : order) {
    if (cells.empty() || cells.back().run != log.run[i] || cells.back().condition != condition_of[i])
      cells.push_back({.run = log.run[i], .condition = condition_of[i]});
    cells.back().sum += centred[i];
    cells.back().count += 1;
  }
  const std::size_t N = cells.size();
  std::vector<std::size_t> runs_of_condition(C, 0);
  for (const Cell& cell : cells) ++runs_of_condition[cell.condition];
  const auto repeated = static_cast<std::size_t>(std::count_if(runs_of_condition.begin(), runs_of_condition.end(),
                                                               [](std::size_t runs) { return runs >= 2; }));
  // Connected components of the run-condition graph: the additive model's rank is R + C - components.
  std::vector<std::size_t> parent(R + C);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const Cell& cell : cells) parent[find(cell.run)] = find(R + cell.condition);
  std::set<std::size_t> roots;
  for (const Cell& cell : cells) roots.insert(find(cell.run));
  const double df_pure = static_cast<double>(N) - static_cast<double>(R + C) + static_cast<double>(roots.size());
  const double df_lack = static_cast<double>(C) - static_cast<double>(roots.size()) - static_cast<double>(parameters);
  if (df_pure < 3 || df_lack < 1 || 2 * repeated < C)
    return noise_lack_of_fit(log, keys, centred, parameters,
                             fmt::format("{} of {} conditions recur in another run, too few for a pure error", repeated, C), o);
  std::vector<double> run_effect(R, 0.0), condition_effect(C, 0.0);
  auto sweep = [&](bool runs) {
    std::vector<double> sum(runs ? R : C, 0.0), count(runs ? R : C, 0.0);
    for (const Cell& cell : cells) {
      const double m = cell.sum / cell.count;
      if (runs) sum[cell.run] += m - condition_effect[cell.condition], count[cell.run] += 1;
      else sum[cell.condition] += m - run_effect[cell.run], count[cell.condition] += 1;
    }
    auto& effect = runs ? run_effect : condition_effect;
    for (std::size_t g = 0; g < effect.size(); ++g) effect[g] = count[g] > 0 ? sum[g] / count[g] : 0.0;
  };
  auto ss = [&](bool with_conditions) {
    double total = 0;
    for (const Cell& cell : cells)
      total += std::pow(cell.sum / cell.count - run_effect[cell.run] - (with_conditions ? condition_effect[cell.condition] : 0.0), 2);
    return total;
  };
  sweep(true);
  const double ss_runs = ss(false);
  for (int it = 0; it < 500; ++it) {
    const double before = ss(true);
    sweep(false);
    sweep(true);
    if (before - ss(true) < 1e-14 * std::max(before, 1e-300)) break;
  }
  const double ss_pure = ss(true);
  LackOfFit l;
  l.tested = true;
  l.against = "pure error";
  l.condition_tolerance = o.condition_tolerance;
  l.basis = fmt::format("pure error from {} conditions, {} of them repeated across runs ({})", C, repeated,
                        matched_words(o.condition_tolerance));
  l.df1 = df_lack;
  l.df2 = df_pure;
  l.statistic = ((ss_runs - ss_pure) / df_lack) / std::max(ss_pure / df_pure, 1e-300);
  l.p_value = fisher_f_upper_p(std::max(l.statistic, 0.0), l.df1, l.df2);
  l.pure_error_rms = std::sqrt(ss_pure / df_pure);
  l.lack_rms = std::sqrt(std::max((ss_runs - ss_pure) / df_lack - ss_pure / df_pure, 0.0));
  // Rejected when significant and material (a lack of a tenth of the noise over thousands of
  // conditions is significant without mattering).
  l.fits = l.p_value >= o.structure_p || l.lack_rms < o.min_structure_fraction * l.pure_error_rms;
  return l;
}

// ResidualDiagnostics::resolution_floor_N: M̂ times the acceleration noise of the runs' filters
// (root mean square over the kept samples); 0 without a fitted moving mass.
double resolution_floor_N(const FrictionLog& log, const FrictionFitResult& fit) {
  const auto mass = std::find_if(fit.fit.parameters.begin(), fit.fit.parameters.end(),
                                 [](const ParameterEstimate& p) { return p.name == MovingMass::info.name; });
  if (mass == fit.fit.parameters.end() || !std::isfinite(mass->value)) return 0;
  double ss = 0, kept = 0;
  for (const RunSegmentation& r : log.segmentation) {
    ss += static_cast<double>(r.kept) * r.acceleration_noise_m_s2 * r.acceleration_noise_m_s2;
    kept += static_cast<double>(r.kept);
  }
  return kept > 0 ? std::abs(mass->value) * std::sqrt(ss / kept) : 0.0;
}

// The size structure must reach to be called a discrepancy: a share of the residual RMSE, and
// the resolution floor.
double min_structure_N(const ResidualDiagnostics& d, const FrictionDiagnosisOptions& o) {
  return std::max(o.min_structure_fraction * d.rmse_N, d.resolution_floor_N);
}

}  // namespace

// The residuals of `fit` (random zero offsets per run): within-run structure on the condition
// means of the run-centred residuals; what changes only between runs on the run means,
// judged against their spread (the offsets' variance is the error term); interactions of
// every pair; lack of fit against pure error. Holm over all tests.
ResidualDiagnostics diagnose_residuals(const FrictionLog& log, const FrictionFitResult& fit, const FrictionDiagnosisOptions& o) {
  const double structure_p = o.structure_p;
  ResidualDiagnostics d;
  d.sigma = std::sqrt(fit.fit.residual_variance);
  const std::size_t n = log.size();
  const LawResiduals law = law_residuals(log, fit);
  double ss = 0, dw_num = 0, dw_den = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double e = log.friction_N[i] - fit.predicted_N[i];
    ss += e * e;
    dw_den += law.centred[i] * law.centred[i];
    if (i > 0 && log.run[i] == log.run[i - 1]) dw_num += std::pow(law.centred[i] - law.centred[i - 1], 2);
  }
  d.rmse_N = std::sqrt(ss / static_cast<double>(n));
  d.durbin_watson = dw_den > 0 ? dw_num / dw_den : kNaN;
  for (std::size_t r = 0; r < fit.run_offset_N.size(); ++r) d.run_bias_N.emplace_back(log.run_names[r], fit.run_offset_N[r]);

  const std::vector<Covariate> covariates = covariates_of(log, o.condition_tolerance);
  const std::size_t k = covariates.size();
  // Condition means of the centred residuals (within runs), conditions matched to their resolution.
  const std::vector<detail::ConditionKey> condition = detail::tolerant_condition_keys(log, o.condition_tolerance);
  const auto [within_x, within_e] = group_means(condition, covariates, law.centred);
  // Run means of the raw residuals (between runs); the covariates' run means to their
  // resolution: one block length whose run means differ in the last bit is one value, not tested.
  std::vector<std::uint32_t> run_key(log.run.begin(), log.run.end());
  auto [run_x, run_e] = group_means(run_key, covariates, law.raw);
  for (auto& x : run_x) x = detail::snap_to_resolution(x, o.condition_tolerance);
  const std::size_t runs = run_e.size();
  auto between = [&](const std::string& name, const std::vector<double>& x) {
    std::set<double> distinct(x.begin(), x.end());
    if (distinct.size() < 2) return CovariateTest{.covariate = name, .n = 0};
    // Replicated values: one-way ANOVA of the run means; otherwise a linear trend.
    return distinct.size() < runs ? detail::anova(name, x, run_e) : detail::regression_test(name, {}, {x}, run_e);
  };
  for (std::size_t c = 0; c < k; ++c) {
    if (!covariates[c].run_level) d.covariates.push_back(detail::anova(covariates[c].name, within_x[c], within_e));
    else d.covariates.push_back(between(std::string(covariates[c].name) + " (between runs)", run_x[c]));
  }
  // Run order: a trend of the runs' levels (random levels are not a trend).
  if (runs >= 4) {
    std::vector<double> order(runs);
    std::iota(order.begin(), order.end(), 0.0);
    d.covariates.push_back(detail::regression_test("run order", {}, {order}, run_e));
  }
  for (CovariateTest& t : along_the_travel(log, law.centred)) d.covariates.push_back(std::move(t));
  // Pairs: within runs when either varies within runs, else between runs (product term).
  for (std::size_t a = 0; a < k; ++a)
    for (std::size_t b = a + 1; b < k; ++b) {
      if (std::string(covariates[a].name) == "time_s" || std::string(covariates[b].name) == "time_s") continue;
      const std::string name = fmt::format("{} x {}", covariates[a].name, covariates[b].name);
      if (!covariates[a].run_level || !covariates[b].run_level) {
        d.covariates.push_back(detail::interaction_anova(name, within_x[a], within_x[b], within_e));
      } else if (runs >= 6) {
        std::vector<double> product(runs);
        for (std::size_t r = 0; r < runs; ++r) product[r] = run_x[a][r] * run_x[b][r];
        d.covariates.push_back(detail::regression_test(name + " (between runs)", {run_x[a], run_x[b]}, {product}, run_e));
      }
    }
  std::erase_if(d.covariates, [](const CovariateTest& t) { return t.n == 0; });
  detail::holm_adjust(d.covariates);
  // Strongest first: the ones that count by size, then the rest by p.
  d.resolution_floor_N = resolution_floor_N(log, fit);
  for (auto& c : d.covariates) c.structured = c.p_adjusted < structure_p && c.size >= min_structure_N(d, o);
  std::sort(d.covariates.begin(), d.covariates.end(), [](auto& a, auto& b) {
    if (a.structured != b.structured) return a.structured;
    return a.structured ? a.size > b.size : a.p_value < b.p_value;
  });
  d.structured = !d.covariates.empty() && d.covariates.front().structured;
  d.lack_of_fit = lack_of_fit(log, condition, law.centred, fit.fit.free_parameters, o);
  return d;
}

}  // namespace detail

ResidualDiagnostics diagnose_friction_residuals(const FrictionLog& log, const FrictionFitResult& fit,
                                                const FrictionDiagnosisOptions& options) {
  return detail::diagnose_residuals(log, fit, options);
}

std::string friction_structure_remains(const ResidualDiagnostics& r) {
  std::vector<std::string> found;
  if (r.structured) {
    const CovariateTest& t = r.covariates.front();
    found.push_back(fmt::format("the residuals follow {} ({}, size {:.3g} N of an RMSE of {:.3g} N)", t.covariate,
                                p_is(t.p_value), t.size, r.rmse_N));
  }
  if (r.lack_of_fit.tested && !r.lack_of_fit.fits)
    found.push_back(fmt::format("{} exceed the {} (lack of fit F = {:.3g}, {})", found.empty() ? "the residuals" : "they",
                                r.lack_of_fit.against, r.lack_of_fit.statistic, p_is(r.lack_of_fit.p_value)));
  return found.empty() ? std::string() : fmt::format("{}", fmt::join(found, "; "));
}

void warn_of_missed_structure(const FrictionLog& log, const FrictionFitOptions& options, FrictionFitResult& fit) {
  if (!fit.fit.solver.usable || log.run_names.size() < 2 || options.fit.loss != RobustLoss::none) return;
  const std::string missed = friction_structure_remains(detail::diagnose_residuals(log, fit, {}));
  if (!missed.empty())
    fit.fit.warnings.push_back(fmt::format(
        "the law misses structure: {}; `lmcal diagnose friction` on these files names a cause where the library has one, "
        "and `lmcal calibrate` fits the model with it (these constants absorb what the law misses)",
        missed));
}

}  // namespace lmcal
