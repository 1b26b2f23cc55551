#include "lmcal/diagnose/friction_diagnosis.hpp"

#include "lmcal/version.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <future>
#include <mutex>
#include <numeric>
#include <set>
#include <tuple>

#include "lmcal/error.hpp"
#include "lmcal/fit/statistics.hpp"
#include "fit/fit_json.hpp"
#include "fit/friction_condition.hpp"
#include "cause_starts.hpp"
#include "empirical_friction.hpp"
#include "run_scale.hpp"
#include "selection.hpp"

namespace lmcal {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kCandidateIterations = 15;
// An RMS acceleration under which a mass error's force is under a tenth of a newton per 10 kg of
// error: no precondition for moving_mass_error.
constexpr double kMinCauseAcceleration_m_s2 = 0.01;

// Whether the log's accelerations are large enough to matter beside friction (RMS).
bool accelerates(const FrictionLog& log) {
  double sum2 = 0;
  for (double a : log.acceleration_m_s2) sum2 += a * a;
  return log.size() > 0 && std::sqrt(sum2 / static_cast<double>(log.size())) >= kMinCauseAcceleration_m_s2;
}

// A cause is named only where its precondition holds. A constant force signed with the motion
// (signed_zero_offset's signature) is a load cell's or torque sensor's zero only where one
// measured the force on an axis whose mounting is known; otherwise it may as well be the weight
// on an inclined axis or a drive's current offset, and it is reported as what the data show,
// under a neutral name, with those candidates.
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

// Why a cause's precondition is absent, in words.
std::string absent_because(const FrictionLog& log, std::string_view column) {
  if (column == "direction") return "has one sense only";
  if (column == "acceleration_m_s2")
    return log.trajectory ? "a trajectory: its moving mass is fitted with the law (moving_mass)"
                          : fmt::format("RMS under {} m/s2 or not logged", kMinCauseAcceleration_m_s2);
  if (column == "position_m" || column == "distance_since_reversal_m") return "spans under 1 mm or not logged (a raw log's)";
  return "constant or not logged";
}

// The library's causes a log can show; the others, with why, into `not_tried`.
std::vector<std::string> causes_that_can_show(const FrictionLog& log, std::vector<std::string>& not_tried) {
  std::vector<std::string> out;
  for (const std::string& name : friction_cause_names()) {
    const FrictionEffectInfo& info = FrictionEffectLibrary::infos[*find_friction_effect(name)];
    if (varies_in(log, info.varies)) out.push_back(name);
    else not_tried.push_back(fmt::format("{} ({} {})", name, info.varies, absent_because(log, info.varies)));
  }
  return out;
}

void read_precondition(CandidateScore& c, const FrictionLog& log) {
  if (c.effect != SignedZeroOffset::info.name) return;
  const ForceSensor sensor = log.force_sensor;
  const bool has_zero = sensor == ForceSensor::load_cell || sensor == ForceSensor::torque_sensor;
  if (has_zero && log.incline_stated) return;
  std::vector<std::string> candidates, unstated;
  if (sensor != ForceSensor::motor_current)
    candidates.push_back(sensor == ForceSensor::torque_sensor ? "a torque sensor's zero" : "a load cell's zero");
  if (!log.incline_stated) candidates.push_back("the weight on an inclined axis");
  if (!has_zero) candidates.push_back("a drive's current offset");
  if (sensor == ForceSensor::unknown) unstated.push_back("what measured the force (force_sensor)");
  if (!log.incline_stated) unstated.push_back("the axis's mounting (axis_incline_deg)");
  candidates.insert(candidates.end(), c.tied_with.begin(), c.tied_with.end());
  c.shown = "signed_constant_force";
  c.tied_with = std::move(candidates);
  c.precondition = unstated.empty()
                       ? std::string("a constant force signed with the motion, which a motor's current cannot tell from "
                                     "the friction's level")
                       : fmt::format("a constant force signed with the motion; not stated: {}", fmt::join(unstated, ", "));
  c.measure = "state force_sensor and axis_incline_deg in the friction manifest's [raw] table (--force-sensor, "
              "--axis-incline), and log the force at rest before each run";
}

// What a candidate cause's fit is expected to cost, for the order the fits start in: a cause
// with parts (a ripple's period and phase, a pre-sliding distance) is nonlinear in them and
// takes several times the iterations of the others (the 100k-sample axis: 0.5 s against 0.15 s);
// listed last in the library, they were started last and left one thread alone at the end.
double expected_fit_cost(const std::string& cause) {
  const std::size_t slot = friction_effect_slot(cause);
  double parts = 0;
  for (std::size_t s = slot + 1; s < kFrictionEffectCount && std::string_view(FrictionEffectLibrary::infos[s].part_of) == cause; ++s)
    parts += 1;
  return 1 + parts;
}

// A fit of the law plus `effects`, started at `start` (one start: the diagnosis refits many times).
FrictionFitResult fit_with(const FrictionLog& log, const FrictionDiagnosisOptions& o, const std::vector<std::string>& effects,
                           const FrictionConstants<double>& start, const std::vector<double>& effect_start,
                           double run_offset_ratio, const std::vector<FrictionTerm>& terms = {}, bool hold_ratio = false) {
  FrictionFitOptions f = o.fit;
  f.terms = terms;
  f.run_offset_ratio_start = run_offset_ratio;  // the current model's: its variance settles in fewer fits
  if (hold_ratio) f.max_variance_passes = 1;    // and stays there
  f.effects = effects;
  f.effect_start = effect_start;
  f.start = start;
  for (std::size_t j = 0; j < FrictionConstants<double>::kFittable; ++j)
    fittable_constant(f.start, j) = std::clamp(fittable_constant(f.start, j), f.bounds[j].first, f.bounds[j].second);
  f.per_run_fits = false;
  f.cross_validate = true;
  f.fit.starts = 0;  // warm-started from the previous model's estimate: no multi-start
  f.fit.profile = ProfileMode::none;
  f.fit.bootstrap = 0;  // the diagnosis quotes no bootstrap intervals
  // Warm-started, a candidate converges in a few iterations; one that crawls along a bound
  // (a drag pinned at 0 beside its twin) adds nothing and is reported as not converged.
  // A term starts from a linearised estimate, further away: it gets the iterations a fit needs.
  f.fit.max_iterations = terms.empty() ? kCandidateIterations : o.fit.fit.max_iterations;
  return fit_friction(log, f);
}

// The covariates the residuals are tested against, one value per sample. Temperature at
// its nominal (condition) value: grouping by the logged temperature itself would find the
// thermocouple's noise (errors in variables), not a missing term.
struct Covariate {
  const char* name;
  std::vector<double> value;
  bool run_level = true;  // one value within every run: seen only between runs
};

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
  std::map<detail::ConditionKey, std::size_t> condition_index;
  std::map<std::pair<std::size_t, std::size_t>, std::pair<double, double>> cells;  // (run, condition) -> sum, count
  for (std::size_t i = 0; i < log.size(); ++i) {
    const std::size_t ci = condition_index.try_emplace(keys[i], condition_index.size()).first->second;
    auto& cell = cells[{log.run[i], ci}];
    cell.first += centred[i];
    cell.second += 1;
  }
  const std::size_t R = log.run_names.size(), C = condition_index.size(), N = cells.size();
  std::vector<std::size_t> runs_of_condition(C, 0);
  for (const auto& [rc, cell] : cells) ++runs_of_condition[rc.second];
  const auto repeated = static_cast<std::size_t>(std::count_if(runs_of_condition.begin(), runs_of_condition.end(),
                                                               [](std::size_t runs) { return runs >= 2; }));
  // Connected components of the run-condition graph: the additive model's rank is R + C - components.
  std::vector<std::size_t> parent(R + C);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& [rc, cell] : cells) parent[find(rc.first)] = find(R + rc.second);
  std::set<std::size_t> roots;
  for (const auto& [rc, cell] : cells) roots.insert(find(rc.first));
  const double df_pure = static_cast<double>(N) - static_cast<double>(R + C) + static_cast<double>(roots.size());
  const double df_lack = static_cast<double>(C) - static_cast<double>(roots.size()) - static_cast<double>(parameters);
  if (df_pure < 3 || df_lack < 1 || 2 * repeated < C)
    return noise_lack_of_fit(log, keys, centred, parameters,
                             fmt::format("{} of {} conditions recur in another run, too few for a pure error", repeated, C), o);
  std::vector<double> run_effect(R, 0.0), condition_effect(C, 0.0);
  auto sweep = [&](bool runs) {
    std::vector<double> sum(runs ? R : C, 0.0), count(runs ? R : C, 0.0);
    for (const auto& [rc, cell] : cells) {
      const double m = cell.first / cell.second;
      if (runs) sum[rc.first] += m - condition_effect[rc.second], count[rc.first] += 1;
      else sum[rc.second] += m - run_effect[rc.first], count[rc.second] += 1;
    }
    auto& effect = runs ? run_effect : condition_effect;
    for (std::size_t g = 0; g < effect.size(); ++g) effect[g] = count[g] > 0 ? sum[g] / count[g] : 0.0;
  };
  auto ss = [&](bool with_conditions) {
    double total = 0;
    for (const auto& [rc, cell] : cells)
      total += std::pow(cell.first / cell.second - run_effect[rc.first] - (with_conditions ? condition_effect[rc.second] : 0.0), 2);
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

constexpr const char* kResolutionFloorWords =
    "the force the position's resolution makes through the moving mass (M σ_a; a repeating move repeats the encoder's "
    "quantization)";

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

// What the design hides or makes costly, in words; and what the final residuals' tests found
// significant but left unexplained because of its size.
std::vector<std::string> design_notes(const FrictionLog& log, const FrictionFitResult& baseline, const LackOfFit& lack,
                                      const ResidualDiagnostics& final, const FrictionDiagnosisOptions& o) {
  std::vector<std::string> notes;
  std::string between, single;
  const std::vector<std::string> not_given = log.law.not_logged();  // their columns hold neutral stand-ins
  for (const Covariate& c : covariates_of(log, o.condition_tolerance)) {
    const std::vector<double> snapped = detail::snap_to_resolution(c.value, o.condition_tolerance);
    const std::set<double> values(snapped.begin(), snapped.end());
    if (std::string(c.name) == "time_s") continue;
    if (std::string(c.name) == "direction") {
      // Each run moves one way: a force signed with the motion is seen only between runs,
      // against the spread of their zero offsets.
      if (values.size() > 1 && c.run_level)
        notes.push_back(fmt::format(
            "direction changes only between runs (each run moves one way): direction is confounded with the runs, so a "
            "force signed with the motion (a zero offset, a direction asymmetry) is judged on the {} run means against "
            "the spread of the runs' zero offsets (tau = {:.3g} N); log both senses in each run to see it within runs",
            log.run_names.size(), baseline.run_offset_sd_N));
      continue;
    }
    if (std::find(not_given.begin(), not_given.end(), c.name) != not_given.end()) continue;
    if (values.size() == 1) single += fmt::format("{}{} ({:g})", single.empty() ? "" : ", ", c.name, *values.begin());
    else if (c.run_level) between += (between.empty() ? "" : ", ") + std::string(c.name);
  }
  if (!between.empty())
    notes.push_back(fmt::format(
        "{} change only between runs (each run holds one value): their effects are judged on the {} run means against "
        "the spread of the runs' zero offsets (tau = {:.3g} N), not on the samples; to see them within runs, log two "
        "setups per run or repeat setups",
        between, log.run_names.size(), baseline.run_offset_sd_N));
  if (!single.empty())
    notes.push_back(fmt::format("one value only of {}: no effect of these can be seen in these data", single));
  if (!not_given.empty())
    notes.push_back(fmt::format("not given: {}: no effect of these can be seen in these data", fmt::join(not_given, ", ")));
  if (!lack.tested) notes.push_back("lack of fit not tested (" + lack.basis + "): repeat a setup in a second run to get it");
  else if (lack.against == "noise")
    notes.push_back("lack of fit judged against the noise of consecutive residuals, not against pure error (too few "
                    "conditions recur in another run): repeat setups in a second run for a test against pure error");
  // Significant, but under the size that counts: said, not dropped silently.
  std::vector<std::string> small;
  for (const CovariateTest& t : final.covariates)
    if (t.p_adjusted < o.structure_p && !t.structured)
      small.push_back(fmt::format("{} ({}, Holm {}; size {:.3g} N)", t.covariate, p_is(t.p_value), p_value_text(t.p_adjusted), t.size));
  if (!small.empty()) {
    const bool floor_binds = final.resolution_floor_N > o.min_structure_fraction * final.rmse_N;
    notes.push_back(fmt::format(
        "left unexplained, significant but each of a size {}: {}",
        floor_binds ? fmt::format("within {}, {:.3g} N", kResolutionFloorWords, final.resolution_floor_N)
                    : fmt::format("under {:g} % of the sample RMSE ({:.3g} N)", 100 * o.min_structure_fraction, final.rmse_N),
        fmt::join(small, "; ")));
  }
  return notes;
}

}  // namespace

FrictionDiagnosis diagnose_friction(const FrictionLog& log, const FrictionDiagnosisOptions& o) {
  if (log.run_names.size() < kMinDiagnosisRuns)
    throw InvalidParameter("runs", fmt::format("a diagnosis needs at least {} runs (it holds one out at a time)",
                                               kMinDiagnosisRuns));
  FrictionDiagnosis d;
  const std::size_t n = log.size();

  // 1. The baseline and its residuals.
  FrictionFitOptions base_options = o.fit;
  base_options.per_run_fits = false;
  base_options.cross_validate = true;
  base_options.fit.profile = ProfileMode::none;
  base_options.fit.bootstrap = 0;
  const FrictionFitResult baseline = fit_friction(log, base_options);
  d.baseline = diagnose_residuals(log, baseline, o);

  // 2-3. Candidates, forward.
  std::set<std::string> held_zeros;  // candidates fitted with the zeros' variance held (fitted in parallel)
  std::mutex held_zeros_mutex;
  auto fit_candidate = [&](const std::vector<std::string>& causes, const FrictionFitResult& current,
                           const std::vector<FrictionTerm>& terms = {}) {
    // The causes with their parts and the drive's terms, each from the current model's value
    // where it has one; a new cause from its neutral value, or where it says so from the
    // current residuals (cause_starts.hpp).
    std::vector<std::string> effects = causes;
    with_effect_parts(effects);
    for (const std::string& name : drive_effects(log))
      if (std::find(effects.begin(), effects.end(), name) == effects.end()) effects.push_back(name);
    std::vector<double> effect_start;
    for (const std::string& name : effects) {
      const auto at = std::find_if(current.fit.parameters.begin() + FrictionConstants<double>::kFittable, current.fit.parameters.end(),
                                   [&](const ParameterEstimate& p) { return p.name == name; });
      effect_start.push_back(at != current.fit.parameters.end() ? at->value
                                                                : FrictionEffectLibrary::infos[friction_effect_slot(name)].neutral);
    }
    const std::string& added = causes.empty() ? std::string() : causes.back();
    if (!added.empty() && std::none_of(current.fit.parameters.begin(), current.fit.parameters.end(),
                                       [&](const ParameterEstimate& p) { return p.name == added; })) {
      std::vector<double> residual_N(n);
      for (std::size_t i = 0; i < n; ++i) residual_N[i] = log.friction_N[i] - current.predicted_N[i];
      const std::vector<double> start = detail::cause_start(added, log, residual_N);
      const auto at = std::find(effects.begin(), effects.end(), added) - effects.begin();
      for (std::size_t p = 0; p < start.size(); ++p) effect_start[static_cast<std::size_t>(at) + p] = start[p];
    }
    // From the current estimate where it is inside its bounds (fewer iterations), else from
    // the given start (a misspecified fit may sit on a bound).
    FrictionConstants<double> start = o.fit.start;
    for (std::size_t j = 0; j < FrictionConstants<double>::kFittable; ++j) {
      const ParameterEstimate& p = current.fit.parameters[j];
      if (p.free && !p.held_unidentifiable && p.value > o.fit.bounds[j].first && p.value < o.fit.bounds[j].second &&
          !p.at_bound)
        fittable_constant(start, j) = p.value;
    }
    FrictionFitResult fit = fit_with(log, o, effects, start, effect_start, current.run_offset_ratio, terms);
    // The random zeros are a spread about 0 added outside the law and its effects. A candidate
    // whose fit needs them to spread far wider than the model before it trades the law's level
    // against a zero common to the runs: outside an effect on the total, (F + c)(1 + a·dir) - c
    // is a signed force c·a·dir, and the candidate's held-out runs (predicted at the zeros'
    // mean, 0) miss by c. Such a candidate is fitted with the zeros' variance held at the
    // current model's: it must explain the data with the law's level where the law puts it.
    if (fit.run_offsets == RunOffsets::random &&
        fit.run_offset_sd_N > 2 * current.run_offset_sd_N + 0.5 * current.rmse_N) {
      fit = fit_with(log, o, effects, start, effect_start, current.run_offset_ratio, terms, true);
      const std::lock_guard<std::mutex> lock(held_zeros_mutex);
      held_zeros.insert(terms.empty() ? added : "the empirical term");
    }
    return fit;
  };
  auto summarise = [&](const FrictionFitResult& fit, const std::string& effect) {
    // The likelihood of the random run offsets' fit (their variance included), and the
    // law's own predictions (without the offsets) to tell ties.
    detail::ModelFit m{.ss = fit.deviance_ss,
                       .n = static_cast<double>(n),
                       .n_eff = static_cast<double>(n),
                       .k = fit.fit.free_parameters + 1,
                       .cv_rmse = fit.cv_rmse_N,
                       .cv_shape_rmse = fit.cv_shape_rmse_N};
    m.fitted = fit.predicted_N;
    for (std::size_t i = 0; i < n; ++i) m.fitted[i] -= fit.run_offset_N[log.run[i]];
    CandidateScore c;
    if (!effect.empty()) {
      const auto& p = fit.fit.parameter(effect);
      detail::set_estimate(c, p);
      c.measure = FrictionEffectLibrary::infos[friction_effect_slot(effect)].measure;
      c.neutral = FrictionEffectLibrary::infos[friction_effect_slot(effect)].neutral;
      if (p.held_unidentifiable) m.problem = "not identifiable from these data";
    }
    if (!fit.fit.solver.converged)
      m.problem = fmt::format("the fit did not converge ({}, {} iterations)", fit.fit.solver.termination,
                              fit.fit.solver.iterations);
    return std::make_pair(m, c);
  };
  const detail::SelectionRules rules{.lrt_p = o.lrt_p,
                                     .min_cv_gain_percent = o.min_cv_gain_percent,
                                     .min_effect = d.baseline.resolution_floor_N,
                                     .effect_floor_basis = kResolutionFloorWords,
                                     .max_effects = o.max_effects,
                                     .parallel = true,
                                     .progress = o.progress,
                                     .expected_cost = expected_fit_cost};
  std::vector<std::string> not_tried;
  auto selection =
      detail::forward_select(causes_that_can_show(log, not_tried), baseline, fit_candidate, summarise, rules);
  std::vector<std::string> accepted = selection.accepted;
  FrictionFitResult current = selection.current;
  d.rounds = std::move(selection.rounds);
  d.steps = std::move(selection.steps);
  auto model_fit = [&](const FrictionFitResult& fit) { return summarise(fit, std::string()).first; };

  // 4. What remains; beyond the library, an empirical term when structure remains.
  // Searched unless named causes were found and nothing is left: structure the residual tests
  // miss (running-in, shared between the runs' levels and their pure error) shows only as a
  // term that predicts held-out runs, and the term must pass the rules a cause passes.
  auto search_with = [&](const std::vector<std::string>& causes, const FrictionFitResult& named) {
    return detail::learn_friction_term(
        log, named, [&](const std::vector<FrictionTerm>& terms) { return fit_candidate(causes, named, terms); }, model_fit,
        rules, o.fit.start.T_ref_C);
  };
  std::optional<detail::FrictionTermSearch> search;
  auto search_term = [&] {
    if (o.progress) o.progress("empirical term", 0, 1);
    search = search_with(accepted, current);
  };
  if (o.learn_term && accepted.empty()) {
    // Searched whatever the residuals' tests say: they run on a thread of their own meanwhile
    // (they only read the log and the fit).
    auto tests = std::async(std::launch::async, [&] { return diagnose_residuals(log, current, o); });
    search_term();
    d.final = tests.get();
  } else {
    d.final = diagnose_residuals(log, current, o);
    const bool left = d.final.structured || (d.final.lack_of_fit.tested && !d.final.lack_of_fit.fits);
    if (o.learn_term && left) search_term();
  }
  // A cause accepted before the term may only have stood in for what the term models (a
  // Coulomb level changing with temperature for the law seeing another temperature above
  // 35 C): each must still pass, as a candidate, on top of the others and the term (learned
  // anew without it), or it is dropped — its own step, the model refitted without it.
  for (std::size_t i = accepted.size(); search && search->fit && i-- > 0;) {
    std::vector<std::string> others = accepted;
    others.erase(others.begin() + static_cast<std::ptrdiff_t>(i));
    // The model without it: the forward selection's own where it passed through it.
    const bool on_path = others.size() < selection.path.size() &&
                         std::equal(others.begin(), others.end(), selection.accepted.begin());
    FrictionFitResult named = on_path ? selection.path[others.size()] : fit_candidate(others, current);
    detail::FrictionTermSearch without = search_with(others, named);
    if (!without.fit) continue;
    CandidateScore c;
    if (detail::score_candidate(model_fit(*without.fit), model_fit(*search->fit), rules, c)) continue;
    d.dropped.push_back(fmt::format("{} (accepted in round {}, it adds nothing once the empirical term is in: {})",
                                    accepted[i], i + 1, c.reason));
    d.steps.push_back(detail::make_step("drop cause", accepted[i], model_fit(current), model_fit(named)));
    accepted = std::move(others);
    current = std::move(named);
    d.final = diagnose_residuals(log, current, o);
    search = std::move(without);
  }
  if (search) {
    d.empirical = std::move(search->finding);
    if (search->fit) d.empirical_fit = std::move(*search->fit);
  }

  // 5. Verdict. The steps carry each model's held-out RMSE: the causes, then the term.
  if (d.empirical.found)
    d.steps.push_back(detail::make_step("add empirical term", d.empirical.formula, model_fit(current),
                                        model_fit(d.empirical_fit)));
  d.cv_rmse_before_N = baseline.cv_rmse_N;
  d.cv_rmse_after_N = detail::final_cv_rmse(d.steps, d.cv_rmse_before_N);
  d.accepted = detail::accepted_scores(d.rounds, accepted,
                                       [&](const std::string& name) { return &current.fit.parameter(name); });
  for (auto& round : d.rounds)
    for (CandidateScore& c : round) read_precondition(c, log);
  for (CandidateScore& c : d.accepted) read_precondition(c, log);
  for (std::size_t j = 0; j < FrictionConstants<double>::kFittable; ++j)
    d.shifts.push_back(parameter_shift(baseline.fit.parameters[j], current.fit.parameters[j]));

  detail::conclude(d, "The published law", "N", d.cv_rmse_before_N, current.cv_rmse_N, d.baseline.rmse_N);
  for (const auto& why : d.dropped) d.summary += " Dropped: " + why + ".";
  {
    const FrictionFitResult& last = d.empirical.found ? d.empirical_fit : current;
    std::vector<double> residual_N(n), model_N(n);
    for (std::size_t i = 0; i < n; ++i) {
      model_N[i] = last.predicted_N[i] - last.run_offset_N[log.run[i]];
      residual_N[i] = log.friction_N[i] - model_N[i];
    }
    d.run_scale = detail::test_run_scale(log, residual_N, model_N, o.lrt_p);
    if (d.run_scale.differ)
      d.summary += fmt::format(" The runs' friction also differs by a factor from run to run beyond their zeros: about "
                               "{:.2g} % ({}); nothing logged predicts it, so a new run's level is uncertain by that share.",
                               d.run_scale.tau_percent, d.run_scale.reason);
  }
  d.design_notes = design_notes(log, baseline, d.baseline.lack_of_fit, d.final, o);
  if (!not_tried.empty())
    d.design_notes.push_back(fmt::format("not tried, their precondition absent: {}", fmt::join(not_tried, "; ")));
  if (!held_zeros.empty())
    d.design_notes.push_back(fmt::format(
        "{} fitted with the spread of the runs' zeros held at the model's before it: fitted freely, the zeros spread "
        "far wider and the law's level moved against them (a zero common to the runs, outside an effect on the total "
        "force, acts as a signed force), which held-out runs cannot follow",
        fmt::join(held_zeros, ", ")));
  d.final_fit = current;
  d.baseline_fit = baseline;
  return d;
}

ResidualDiagnostics diagnose_friction_residuals(const FrictionLog& log, const FrictionFitResult& fit,
                                                const FrictionDiagnosisOptions& options) {
  return diagnose_residuals(log, fit, options);
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
  const std::string missed = friction_structure_remains(diagnose_residuals(log, fit, {}));
  if (!missed.empty())
    fit.fit.warnings.push_back(fmt::format(
        "the law misses structure: {}; `lmcal diagnose friction` on these files names a cause where the library has one, "
        "and `lmcal calibrate` fits the model with it (these constants absorb what the law misses)",
        missed));
}

std::string friction_diagnosis_json(const FrictionDiagnosis& d) {
  using detail::number;
  auto diagnostics = [&](const ResidualDiagnostics& r) {
    nlohmann::json runs = nlohmann::json::object();
    for (const auto& [run, bias] : r.run_bias_N) runs[run] = number(bias);
    return nlohmann::json{{"rmse_N", number(r.rmse_N)},         {"sigma", number(r.sigma)},
                          {"durbin_watson", number(r.durbin_watson)}, {"resolution_floor_N", number(r.resolution_floor_N)}, {"run_bias_N", runs},
                          {"covariates", detail::covariates_json(r.covariates)}, {"structured", r.structured},
                          {"lack_of_fit", detail::lack_of_fit_json(r.lack_of_fit)}};
  };
  nlohmann::json j = detail::verdict_json(d, d.cv_rmse_before_N, d.cv_rmse_after_N, "N");
  j["kind"] = "friction diagnosis";
  j["design_notes"] = d.design_notes;
  j["lmcal_version"] = LMCAL_VERSION;
  j["schema_version"] = kOutputSchemaVersion;
  j["baseline_residuals"] = diagnostics(d.baseline);
  j["final_residuals"] = diagnostics(d.final);
  j["dropped_for_the_empirical_term"] = d.dropped;
  {
    const RunScaleTest& t = d.run_scale;
    nlohmann::json runs = nlohmann::json::array();
    for (std::size_t r = 0; r < t.run.size(); ++r)
      runs.push_back({{"run", t.run[r]}, {"factor_percent", number(t.factor_percent[r])}, {"se_percent", number(t.se_percent[r])}});
    j["run_scale"] = {{"tested", t.tested}, {"differ", t.differ},     {"q", number(t.q)},
                      {"dof", number(t.dof)}, {"p", number(t.p)},     {"tau_percent", number(t.tau_percent)}, {"floor_percent", number(t.floor_percent)},
                      {"runs", runs},         {"reason", t.reason},
                      {"method", "within each run, the final model's residual (its zero left in) on its force with an "
                                 "intercept; Cochran's Q over the runs' factors, SEs widened for lag-1 autocorrelation; "
                                 "tau by DerSimonian-Laird; the runs differ when p < the LRT level and tau exceeds the "
                                 "runs' zeros' spread as a share of the mean force"}};
  }
  return j.dump(2) +
         "\n";
}

}  // namespace lmcal
