#include "empirical_friction.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>

#include "lmcal/fit/statistics.hpp"
#include "parallel_slices.hpp"
#include "sparse_regression.hpp"

namespace lmcal::detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kMaxFitParameters = 16;  // the batched cost's largest Jet

// The law with the fit's named effects for the parameter values `values` (the seven constants,
// then the effects, as in `params`), at row i of the log with the temperature `warmer_K`
// higher. The constants and effects are set once: by name per row, a 10⁵-row log's finite
// differences looked the effects up millions of times.
class LawAt {
 public:
  LawAt(const FrictionLog& log, const std::vector<ParameterEstimate>& params, const std::vector<double>& values,
        double reference_C)
      : log_(log) {
    for (std::size_t j = 0; j < FrictionConstants<double>::kFittable; ++j) fittable_constant(k_, j) = values[j];
    k_.T_ref_C = reference_C;
    for (std::size_t j = FrictionConstants<double>::kFittable; j < params.size(); ++j)
      if (const auto slot = find_friction_effect(params[j].name)) e_[*slot] = values[j];
  }
  double operator()(std::size_t i, double warmer_K = 0) const {
    FrictionConstants<double> k = k_;
    k.nu_ref_mm2_s = log_.viscosity40_mm2_s[i];
    FrictionConditions<double> c = log_.conditions(i);
    c.temperature_C += warmer_K;
    return friction_force_with_effects_N(k, e_, c);
  }

 private:
  const FrictionLog& log_;
  FrictionConstants<double> k_;
  FrictionEffects<double> e_;
};

// A dictionary entry: the term it stands for (coefficient to be fitted) and its column.
struct Candidate {
  FrictionTerm term;
  std::vector<double> column;
  std::size_t family = 0;
};

// What the current law gives every row beyond the log's columns: its force, its parts (for
// terms that reweight one) and its slope in the temperature (for terms that shift that input:
// the column of c·g(x) in F_law(T + c·g(x)) is ∂F_law/∂T · g(x), the law's own derivative).
struct LawColumns {
  std::vector<double> law;                     // F_law per row (the current fit's)
  std::vector<std::vector<double>> part;       // per part (coulomb, stribeck, viscous, seal), per row
  std::vector<double> dF_dT;                   // ∂F_law/∂T per row, N/K
};

constexpr TermCovariate kLawParts[] = {TermCovariate::coulomb_N, TermCovariate::stribeck_N, TermCovariate::viscous_N,
                                       TermCovariate::seal_N};

struct Columns {
  const FrictionLog& log;
  const TermSeries& series;
  const LawColumns& law;
  std::vector<double> factor(const TermFactor& f, double scale) const {
    std::vector<double> v(log.size());
    if (f.transform == TermTransform::input_shift) return law.dF_dT;
    for (std::size_t k = 0; k < std::size(kLawParts); ++k)
      if (f.covariate == kLawParts[k]) return law.part[k];
    for (std::size_t i = 0; i < log.size(); ++i) {
      if (f.covariate == TermCovariate::law_force_N) {
        v[i] = law.law[i];
        continue;
      }
      const double x = term_covariate_value(log, series, i, f.covariate);
      v[i] = f.transform == TermTransform::decay    ? std::exp(-x / scale)
             : f.transform == TermTransform::square ? (x - f.centre) * (x - f.centre)
             : f.transform == TermTransform::step   ? (x > f.centre ? 1.0 : 0.0)
             : f.transform == TermTransform::spline ? bspline(f.knots, f.basis, x)
                                                    : x - f.centre;
    }
    return v;
  }
  std::vector<double> column(const FrictionTerm& t) const {
    std::vector<double> v(log.size(), 1.0);
    for (const auto& f : t.factors) {
      const std::vector<double> x = factor(f, t.scale);
      for (std::size_t i = 0; i < v.size(); ++i) v[i] *= x[i];
    }
    return v;
  }
};

// The law's columns at the current fit's parameter values: its force `law` (given), its parts
// and its temperature slope (central difference over ±0.5 K).
LawColumns law_columns_at(const FrictionLog& log, const std::vector<double>& values, std::vector<double> law, const std::function<double(std::size_t, double)>& law_warmer,
                          double reference_C) {
  LawColumns out;
  out.law = std::move(law);
  FrictionConstants<double> k;
  for (std::size_t j = 0; j < FrictionConstants<double>::kFittable; ++j) fittable_constant(k, j) = values[j];
  k.T_ref_C = reference_C;
  out.part.assign(std::size(kLawParts), std::vector<double>(log.size()));
  out.dF_dT.resize(log.size());
  // Row by row, each independent: on the free threads.
  for_each_index(log.size(), [&](std::size_t i) {
    FrictionConstants<double> ki = k;
    ki.nu_ref_mm2_s = log.viscosity40_mm2_s[i];
    const FrictionConditions<double> c = log.conditions(i);
    const auto b = friction_breakdown(ki, c);
    for (std::size_t p = 0; p < std::size(kLawParts); ++p) out.part[p][i] = law_part_N(ki, b, c.block_length_mm, kLawParts[p]);
    out.dF_dT[i] = law_warmer(i, 0.5) - law_warmer(i, -0.5);
  });
  return out;
}

// A part that is the same in every row (the seal offset of one guide) reweighted by a covariate
// is that covariate's own column: only a part that varies is worth its terms.
bool varies_across_rows(const std::vector<double>& part) {
  return std::any_of(part.begin(), part.end(), [&](double v) { return v != part.front(); });
}

bool varies(const FrictionLog& log, const TermSeries& series, TermCovariate c) {
  std::set<double> values;
  for (std::size_t i = 0; i < log.size() && values.size() < 2; ++i) values.insert(term_covariate_value(log, series, i, c));
  return values.size() >= 2;
}

// Does the logged temperature change within a run (by more than its noise)?
bool temperature_changes_within_runs(const FrictionLog& log, const TermSeries& series) {
  for (const auto& rows : series.run_rows) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t i : rows) lo = std::min(lo, log.temperature_C[i]), hi = std::max(hi, log.temperature_C[i]);
    if (hi - lo > 1.0) return true;
  }
  return false;
}

// The mean and the middle of the range of a covariate over the rows.
std::pair<double, double> mean_and_middle(const FrictionLog& log, const TermSeries& series, TermCovariate c) {
  double sum = 0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < log.size(); ++i) {
    const double x = term_covariate_value(log, series, i, c);
    sum += x, lo = std::min(lo, x), hi = std::max(hi, x);
  }
  return {sum / static_cast<double>(log.size()), 0.5 * (lo + hi)};
}

// Where a step in the temperature may sit: in each gap of more than 1 K (a logged temperature's
// noise is no level) between the temperatures the log holds, with a twentieth of the rows or
// more on either side; a log whose temperatures spread without gaps gets its quartiles.
std::vector<double> temperature_thresholds(const FrictionLog& log) {
  std::vector<double> t = log.temperature_C;
  std::sort(t.begin(), t.end());
  const std::size_t n = t.size(), least = std::max<std::size_t>(1, n / 20);
  std::vector<double> out;
  for (std::size_t k = least; k + least <= n; ++k)
    if (t[k] - t[k - 1] > 1.0) out.push_back(0.5 * (t[k] + t[k - 1]));
  if (out.empty() && n >= 8 && t.back() - t.front() > 1.0)
    for (std::size_t q : {n / 4, n / 2, 3 * n / 4}) out.push_back(t[q]);
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// The dictionary. `law_warmer(i, ΔT)`: the current law at row i with the temperature ΔT higher.
std::vector<Candidate> dictionary(const FrictionLog& log, const TermSeries& series, const LawColumns& law_columns,
                                  const std::function<double(std::size_t, double)>& law_warmer, double reference_C) {
  const std::vector<double>& law = law_columns.law;
  const Columns columns{log, series, law_columns};
  std::vector<Candidate> out;
  std::size_t family = 0;
  // The terms first, their columns (independent of each other) at the end on the free threads.
  auto add = [&](FrictionTerm term) { out.push_back({std::move(term), {}, family++}); };
  const auto with_columns = [&] {
    for_each_index(out.size(), [&](std::size_t k) {
      if (out[k].column.empty()) out[k].column = columns.column(out[k].term);
    });
    return std::move(out);
  };
  auto linear = [&](TermCovariate c) {
    return TermFactor{c, TermTransform::linear, c == TermCovariate::temperature_C ? reference_C : 0.0};
  };
  std::vector<TermCovariate> base;
  for (TermCovariate c : {TermCovariate::velocity_m_s, TermCovariate::load_N, TermCovariate::preload_um,
                          TermCovariate::block_length_mm, TermCovariate::temperature_C, TermCovariate::direction})
    if (varies(log, series, c)) base.push_back(c);
  for (TermCovariate c : base) add({.factors = {linear(c)}});
  for (TermCovariate c : base)
    if (c == TermCovariate::velocity_m_s || c == TermCovariate::load_N || c == TermCovariate::temperature_C)
      add({.factors = {TermFactor{c, TermTransform::square, linear(c).centre}}});
  for (std::size_t a = 0; a < base.size(); ++a)
    for (std::size_t b = a + 1; b < base.size(); ++b) add({.factors = {linear(base[a]), linear(base[b])}});
  const TermFactor law_factor{TermCovariate::law_force_N};
  for (TermCovariate c : base)
    if (c == TermCovariate::velocity_m_s || c == TermCovariate::temperature_C) add({.factors = {law_factor, linear(c)}});

  // Families with a scale: one column per grid value.
  const std::vector<double> shares{0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0};
  auto decay_family = [&](TermCovariate c, std::vector<TermFactor> with) {
    double span = 0;
    for (std::size_t i = 0; i < log.size(); ++i) span = std::max(span, term_covariate_value(log, series, i, c));
    if (!(span > 0)) return;
    for (double share : shares) {
      FrictionTerm t{.factors = {TermFactor{c, TermTransform::decay}}, .scale = share * span,
                     .scale_lower = 1e-3 * span, .scale_upper = 10 * span};
      // An input shift leads its term (term_form_problem); any other factor follows the decay.
      const bool shift = !with.empty() && with.front().transform == TermTransform::input_shift;
      t.factors.insert(shift ? t.factors.begin() : t.factors.end(), with.begin(), with.end());
      out.push_back({std::move(t), {}, family});
    }
    ++family;
  };
  if (series.timed) {
    decay_family(TermCovariate::sliding_distance_m, {});
    decay_family(TermCovariate::sliding_distance_m, {law_factor});
    if (varies(log, series, TermCovariate::load_N)) decay_family(TermCovariate::sliding_distance_m, {linear(TermCovariate::load_N)});
    decay_family(TermCovariate::time_in_run_s, {});
    decay_family(TermCovariate::time_in_run_s, {law_factor});
    if (temperature_changes_within_runs(log, series)) {
      for (double tau : {15.0, 30.0, 60.0, 120.0, 240.0, 480.0, 960.0, 1920.0}) {
        FrictionTerm t{.factors = {TermFactor{TermCovariate::temperature_C, TermTransform::lagged_temperature}},
                       .scale = tau, .scale_lower = 1.0, .scale_upper = 1e5};
        const std::vector<double> change = lagged_temperature_change(log, series, tau);
        std::vector<double> column(log.size());
        for (std::size_t i = 0; i < log.size(); ++i) column[i] = law_warmer(i, change[i]) - law[i];
        out.push_back({std::move(t), std::move(column), family});
      }
      ++family;
    }
  }

  // The law at a corrected temperature, F_law(T + c·g(x)), linearised: ∂F_law/∂T · g(x) — a step
  // above a temperature, a drift over the campaign, a warm-up within each run the logged
  // temperature does not show.
  const bool campaign = series.run_rows.size() >= 3;  // runs enough to follow a trend over them
  const TermFactor shift_T{TermCovariate::temperature_C, TermTransform::input_shift};
  if (varies(log, series, TermCovariate::temperature_C) || series.timed || campaign) {
    const std::vector<double> thresholds = temperature_thresholds(log);
    for (double threshold : thresholds) {
      out.push_back({{.factors = {shift_T, TermFactor{TermCovariate::temperature_C, TermTransform::step, threshold}}}, {}, family});
    }
    family += thresholds.empty() ? 0 : 1;
    const TermCovariate clock = series.timed ? TermCovariate::campaign_time_s : TermCovariate::run_index;
    if (series.timed || campaign)
      add({.factors = {shift_T, TermFactor{clock, TermTransform::linear, mean_and_middle(log, series, clock).second}}});
    if (series.timed) decay_family(TermCovariate::time_in_run_s, {shift_T});
  }
  // The law's own parts reweighted by a covariate: c · F_part · (x − x̄), c · F_part · (x − x_mid)².
  std::vector<TermCovariate> reweighting;
  for (TermCovariate c : {TermCovariate::velocity_m_s, TermCovariate::load_N, TermCovariate::temperature_C})
    if (varies(log, series, c)) reweighting.push_back(c);
  if (campaign) reweighting.push_back(TermCovariate::run_index);
  if (series.timed) reweighting.push_back(TermCovariate::sliding_distance_m);
  for (std::size_t k = 0; k < std::size(kLawParts); ++k) {
    if (!varies_across_rows(law_columns.part[k])) continue;
    const TermFactor part{kLawParts[k]};
    for (TermCovariate c : reweighting) {
      const auto [mean, middle] = mean_and_middle(log, series, c);
      add({.factors = {part, TermFactor{c, TermTransform::linear, mean}}});
      if (c == TermCovariate::velocity_m_s || c == TermCovariate::load_N || c == TermCovariate::temperature_C)
        add({.factors = {part, TermFactor{c, TermTransform::square, middle}}});
    }
  }
  // Campaign covariates: the friction changing from run to run in the order they were made.
  if (campaign) {
    add({.factors = {law_factor, TermFactor{TermCovariate::run_index, TermTransform::linear,
                                            mean_and_middle(log, series, TermCovariate::run_index).second}}});
    decay_family(TermCovariate::run_index, {law_factor});
  }
  return with_columns();
}

// A law part's name in words ("" for the law's force and for covariates).
const char* part_words(TermCovariate c) {
  switch (c) {
    case TermCovariate::coulomb_N: return "Coulomb term";
    case TermCovariate::stribeck_N: return "Stribeck term";
    case TermCovariate::viscous_N: return "viscous term";
    case TermCovariate::seal_N: return "seal offset Lb·f0";
    default: return "";
  }
}

// What a term does, in words.
std::string term_words(const FrictionTerm& t) {
  if (t.lagged_temperature())
    return "the law evaluated at a temperature that trails the logged one through a first-order lag of time constant tau";
  std::string words, share;
  for (const auto& f : t.factors) {
    if (f.covariate == TermCovariate::law_force_N) {
      share = "a share of the law's force, ";
      continue;
    }
    if (is_law_covariate(f.covariate)) {
      share = fmt::format("a share of the law's {}, ", part_words(f.covariate));
      continue;
    }
    if (f.transform == TermTransform::input_shift) continue;
    const std::string x = term_covariate_name(f.covariate);
    words += words.empty() ? "" : " and ";
    switch (f.transform) {
      case TermTransform::linear: words += f.centre == 0 ? "in proportion to " + x : fmt::format("in proportion to {} - {:g}", x, f.centre); break;
      case TermTransform::square: words += f.centre == 0 ? "with the square of " + x : fmt::format("with the square of {} - {:g}", x, f.centre); break;
      case TermTransform::decay: words += "decaying exponentially with " + x; break;
      case TermTransform::spline: words += "a smooth function (cubic B-spline) of " + x; break;
      case TermTransform::step: words += fmt::format("where {} > {:g}", x, f.centre); break;
      case TermTransform::lagged_temperature:
      case TermTransform::input_shift: break;
    }
  }
  if (const auto input = t.shifted_input())
    return fmt::format("the law evaluated at the logged {} plus a correction ({}) {}",
                       *input == TermCovariate::velocity_m_s ? "speed" : "temperature", term_covariate_unit(*input),
                       words.empty() ? "that is constant" : words);
  return (share.empty() ? "a force " : share) + words;
}

bool has(const FrictionTerm& t, TermCovariate c, TermTransform how) {
  return std::any_of(t.factors.begin(), t.factors.end(), [&](const TermFactor& f) { return f.covariate == c && f.transform == how; });
}

bool has_spline(const FrictionTerm& t) {
  return std::any_of(t.factors.begin(), t.factors.end(), [](const TermFactor& f) { return f.transform == TermTransform::spline; });
}

// The law part a term reweights, if it does.
std::optional<TermCovariate> reweighted_part(const FrictionTerm& t) {
  for (const auto& f : t.factors)
    if (is_law_covariate(f.covariate) && f.covariate != TermCovariate::law_force_N) return f.covariate;
  return std::nullopt;
}

// What an input correction resembles: the law sees a temperature off the logged one.
std::string input_resemblance(const FrictionTerm& t, const std::string& chronology) {
  using C = TermCovariate;
  using X = TermTransform;
  if (t.shifted_input() == C::velocity_m_s) return "the law seeing a speed off the logged one (an encoder's or a drive's scale)";
  if (has_spline(t))
    return fmt::format("the law seeing a temperature off the logged one by an amount that changes smoothly with {} "
                       "(the contacts' temperature is not the logged one)",
                       term_covariate_name(t.factors.back().covariate));
  for (const auto& f : t.factors)
    if (f.transform == X::step)
      return fmt::format("the law seeing a temperature {:+.3g} K off the logged one where T > {:g} C (a thermocouple that "
                         "reads off when hot, or oil whose viscosity falls otherwise than nu(T) above it)",
                         t.coefficient, f.centre);
  if (has(t, C::campaign_time_s, X::linear))
    return fmt::format("the law seeing a temperature drifting by {:+.3g} K per hour over the campaign that the logged one "
                       "does not show (a thermocouple drifting, the room or the oil changing over the day; the runs in "
                       "order of {})",
                       t.coefficient * 3600, chronology == "time_s" ? "their clocks" : "the file");
  if (has(t, C::run_index, X::linear))
    return fmt::format("the law seeing a temperature drifting by {:+.3g} K per run over the campaign that the logged one "
                       "does not show (runs in order of {})",
                       t.coefficient, chronology == "time_s" ? "their clocks" : "the file");
  if (has(t, C::time_in_run_s, X::decay))
    return fmt::format("the law seeing a temperature {:+.3g} K off the logged one at each run's start, settling over about "
                       "{:.3g} s (a warm-up the logged temperature does not show)",
                       t.coefficient, t.scale);
  return fmt::format("the law seeing a temperature {:+.3g} K off the logged one", t.coefficient);
}

// The mechanisms a term resembles, in words ("" when none comes to mind); `chronology` says
// how the runs were put in order (TermSeries::chronology).
std::string resemblance(const FrictionTerm& t, const std::string& chronology) {
  using C = TermCovariate;
  using X = TermTransform;
  if (t.shifted_input()) return input_resemblance(t, chronology);
  if (const auto part = reweighted_part(t)) {
    const TermFactor& by = t.factors.back();
    return fmt::format("the law's {} following {} otherwise than the law has it{}", part_words(*part),
                       term_covariate_name(by.covariate),
                       *part == C::viscous_N && by.covariate == C::load_N ? " (its viscous term mu_v pc V nu Lb has no load in it)"
                       : *part == C::coulomb_N && by.covariate == C::velocity_m_s ? " (a Coulomb level that changes with speed)"
                       : by.covariate == C::run_index ? " (changing from run to run over the campaign)"
                                                     : "");
  }
  if (has_spline(t))
    return fmt::format("a dependence on {} of a shape none of the law's terms or the dictionary's simple forms has",
                       term_covariate_name(t.factors.front().covariate));
  if (t.lagged_temperature())
    return fmt::format("the lubricant's temperature trailing the logged one by tau = {:.3g} s (a thermocouple away "
                       "from the contacts, or oil that warms slower than what is logged)",
                       t.scale);
  if (has(t, C::run_index, X::decay) || has(t, C::run_index, X::linear))
    return fmt::format("friction changing from run to run over the campaign{} (running-in, seals bedding in, the lubricant "
                       "ageing; the runs in order of {})",
                       has(t, C::run_index, X::decay) ? fmt::format(", over about {:.3g} runs", t.scale) : "",
                       chronology == "time_s" ? "their clocks" : "the file");
  if (has(t, C::sliding_distance_m, X::decay))
    return fmt::format("running-in: friction falling as the contacts and seals wear in, over about {:.3g} m of sliding",
                       t.scale);
  if (has(t, C::time_in_run_s, X::decay))
    return fmt::format("a settling within each run over about {:.3g} s (lubricant redistributing after a stop, a "
                       "warm-up the logged temperature does not show)",
                       t.scale);
  if (has(t, C::velocity_m_s, X::linear) && has(t, C::temperature_C, X::linear))
    return "a speed-proportional (viscous) force whose temperature dependence differs from the law's "
           "nu(T) = nu_i exp(-beta (T - T_i))";
  if (has(t, C::velocity_m_s, X::square)) return "a speed dependence beyond the linear viscous term (churning of the lubricant)";
  if (has(t, C::load_N, X::square)) return "a Coulomb force not proportional to the load";
  if (t.factors.size() == 1 && has(t, C::temperature_C, X::linear))
    return "a Coulomb or seal force that changes with temperature";
  if (has(t, C::direction, X::linear)) return "a force that depends on the direction of travel";
  return "";
}

// The covariate a term is drawn over in the report.
TermCovariate main_covariate(const FrictionTerm& t) {
  if (t.lagged_temperature()) return TermCovariate::time_in_run_s;
  for (const auto& f : t.factors)
    if (f.transform == TermTransform::decay) return f.covariate;
  for (const auto& f : t.factors)
    if (!is_law_covariate(f.covariate) && f.transform != TermTransform::input_shift) return f.covariate;
  for (const auto& f : t.factors)
    if (f.transform == TermTransform::input_shift) return f.covariate;
  return TermCovariate::law_force_N;
}

// Up to `bins` groups of the values (one per distinct value when there are few), as labels
// and the centre of each group.
std::pair<std::vector<std::size_t>, std::vector<double>> binned(const std::vector<double>& x, std::size_t bins) {
  std::vector<double> sorted = x;
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> edges;
  std::set<double> distinct(sorted.begin(), sorted.end());
  if (distinct.size() <= bins) {
    edges.assign(distinct.begin(), distinct.end());
  } else {
    for (std::size_t b = 0; b < bins; ++b) edges.push_back(sorted[b * sorted.size() / bins]);
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  }
  std::vector<std::size_t> label(x.size());
  std::vector<double> sum(edges.size(), 0.0), count(edges.size(), 0.0);
  for (std::size_t i = 0; i < x.size(); ++i) {
    label[i] = static_cast<std::size_t>(std::upper_bound(edges.begin(), edges.end(), x[i]) - edges.begin()) - 1;
    sum[label[i]] += x[i];
    count[label[i]] += 1;
  }
  std::vector<double> centre(edges.size());
  for (std::size_t b = 0; b < edges.size(); ++b) centre[b] = count[b] > 0 ? sum[b] / count[b] : kNaN;
  return {label, centre};
}

// The term's contribution per row (the model with the terms minus without), at the fit's
// law and effects and the term parameters `theta`.
std::vector<double> contribution(const FrictionLog& log, const TermSeries& series, const FrictionFitResult& fit,
                                 const std::vector<double>& theta, double reference_C) {
  const FrictionConstants<double> k0 = fit.constants();
  const FrictionEffects<double> e = fit.effects();
  std::vector<double> lag;
  for (std::size_t t = 0, at = 0; t < fit.terms.size(); at += fit.terms[t].has_scale() ? 2 : 1, ++t)
    if (fit.terms[t].lagged_temperature()) lag = lagged_temperature_change(log, series, theta[at + 1]);
  std::vector<double> out(log.size());
  for (std::size_t i = 0; i < log.size(); ++i) {
    FrictionConstants<double> k = k0;
    k.nu_ref_mm2_s = log.viscosity40_mm2_s[i];
    k.T_ref_C = reference_C;
    out[i] = friction_with_terms_N(k, e, log, series, i, fit.terms, theta.data(), lag.empty() ? nullptr : &lag) -
             friction_force_with_effects_N(k, e, log.conditions(i));
  }
  return out;
}

EmpiricalCurve curve_of(const FrictionLog& log, const TermSeries& series, const FrictionFitResult& before,
                        const FrictionFitResult& after, double reference_C) {
  EmpiricalCurve c;
  const TermCovariate main = main_covariate(after.terms.front());
  c.covariate = term_covariate_name(main);
  c.unit = term_covariate_unit(main);
  std::vector<double> x(log.size());
  for (std::size_t i = 0; i < log.size(); ++i)
    x[i] = main == TermCovariate::law_force_N ? before.predicted_N[i] : term_covariate_value(log, series, i, main);
  const auto [label, centre] = binned(x, 20);
  const std::size_t bins = centre.size();
  // The term's parameters: after the constants and the effects.
  const std::size_t first = after.fit.parameters.size() - term_parameter_count(after.terms);
  std::vector<double> theta;
  for (std::size_t j = first; j < after.fit.parameters.size(); ++j) theta.push_back(after.fit.parameters[j].value);
  auto bin_means = [&](const std::vector<double>& v) {
    std::vector<double> sum(bins, 0.0), count(bins, 0.0);
    for (std::size_t i = 0; i < v.size(); ++i) sum[label[i]] += v[i], count[label[i]] += 1;
    for (std::size_t b = 0; b < bins; ++b) sum[b] = count[b] > 0 ? sum[b] / count[b] : kNaN;
    return sum;
  };
  const std::vector<double> contribution_N = contribution(log, series, after, theta, reference_C);
  const std::vector<double> value = bin_means(contribution_N);
  // Delta method over the term's parameters (central differences of the bin means).
  std::vector<std::vector<double>> gradient;
  for (std::size_t a = 0; a < theta.size(); ++a) {
    const double h = 1e-4 * std::max(std::abs(theta[a]), 1e-9);
    std::vector<double> up = theta, down = theta;
    up[a] += h;
    down[a] -= h;
    const std::vector<double> mu = bin_means(contribution(log, series, after, up, reference_C));
    const std::vector<double> md = bin_means(contribution(log, series, after, down, reference_C));
    std::vector<double> g(bins);
    for (std::size_t b = 0; b < bins; ++b) g[b] = (mu[b] - md[b]) / (2 * h);
    gradient.push_back(g);
  }
  const double t95 = student_t_quantile(0.975, std::max(after.fit.dof, 1.0));
  std::vector<double> before_residual(log.size()), after_residual(log.size());
  // Before: the partial residuals — the joint fit's residuals with the term added back, what
  // the term has to explain (the model without it absorbs part of it in its run offsets and
  // constants, in sample; the held-out gain is what it cannot absorb).
  for (std::size_t i = 0; i < log.size(); ++i) {
    after_residual[i] = log.friction_N[i] - after.predicted_N[i];
    before_residual[i] = after_residual[i] + contribution_N[i];
  }
  c.residual_before = bin_means(before_residual);
  c.residual_after = bin_means(after_residual);
  for (std::size_t b = 0; b < bins; ++b) {
    double variance = 0;
    for (std::size_t p = 0; p < theta.size(); ++p)
      for (std::size_t q = 0; q < theta.size(); ++q)
        variance += gradient[p][b] * after.fit.covariance(static_cast<Eigen::Index>(first + p), static_cast<Eigen::Index>(first + q)) *
                    gradient[q][b];
    const double half = t95 * std::sqrt(std::max(variance, 0.0));
    c.x.push_back(centre[b]);
    c.value.push_back(value[b]);
    c.low.push_back(value[b] - half);
    c.high.push_back(value[b] + half);
  }
  return c;
}

// The smooth alternative: cubic B-splines in one covariate that varies within runs (speed,
// load, temperature), 1 to 4 interior knots at quantiles of its values (fewer for a covariate
// of few values; none in temperature), the first basis function left out (the run levels carry
// a constant); the covariate and the knots chosen by leave-one-run-out error, fewer basis
// functions preferred within the tolerance.
struct SmoothChoice {
  std::vector<FrictionTerm> terms;
  double cv_rmse = 0;     // linearised leave-one-run-out RMSE of the runs' shape with it
  std::size_t tried = 0;  // basis functions tried, over all covariates
  std::string why_not;
};

SmoothChoice smooth_term(const FrictionLog& log, const TermSeries& series, const Columns& columns, const SparseProblem& linear,
                         double min_gain_percent) {
  SmoothChoice out;
  SparseProblem p;
  p.y = linear.y;
  p.group = linear.group;
  p.level = linear.level;
  p.fixed = linear.fixed;
  // Each block is scored as it is built (F and the block alone: blocks never enter together),
  // so that only one block's columns exist at a time.
  std::vector<std::vector<FrictionTerm>> block_terms;
  std::vector<SupportScore> scores;
  // The blocks of splines in covariate c (times the factor `times`, when given): 1 to 4
  // interior knots at quantiles of its values (fewer for a covariate of few values), or one
  // cubic over the whole range (`cubic_only`).
  auto add_blocks = [&](TermCovariate c, std::optional<TermFactor> times, bool cubic_only) {
    std::vector<double> x(log.size());
    for (std::size_t i = 0; i < log.size(); ++i) x[i] = term_covariate_value(log, series, i, c);
    std::vector<double> sorted = x;
    std::sort(sorted.begin(), sorted.end());
    std::vector<double> distinct;
    for (double v : sorted)
      if (distinct.empty() || v > distinct.back() + 1e-9 * std::max(1.0, std::abs(v))) distinct.push_back(v);
    if (distinct.size() < 4) return;
    const std::vector<double> multiplier = times ? columns.factor(*times, 0) : std::vector<double>(log.size(), 1.0);
    // A campaign covariate is almost one value per run: a spline with a knot every few runs
    // would follow each run's own level and shape (a factor of its own, which no new run shares),
    // so it gets a knot per six runs at most, and none under twelve runs.
    const std::size_t runs = series.run_rows.size();
    if (is_campaign_covariate(c) && runs < 12) return;
    const std::size_t knots_allowed = is_campaign_covariate(c) ? runs / 6 : 4;
    const std::size_t most = cubic_only ? 0 : std::min<std::size_t>({4, knots_allowed, distinct.size() - 4});
    for (std::size_t interior = cubic_only ? 0 : 1; interior <= most; ++interior) {
      std::vector<double> knots(4, sorted.front());
      for (std::size_t k = 1; k <= interior; ++k) {
        const double q = sorted[k * sorted.size() / (interior + 1)];
        if (q > knots.back() && q < sorted.back()) knots.push_back(q);
      }
      knots.insert(knots.end(), 4, sorted.back());
      const int bases = static_cast<int>(knots.size()) - 4;
      std::vector<FrictionTerm> terms;
      p.candidates.clear();
      for (int b = 1; b < bases; ++b) {
        FrictionTerm t{.factors = {TermFactor{.covariate = c, .transform = TermTransform::spline, .basis = b, .knots = knots}}};
        if (times) t.factors.insert(t.factors.begin(), *times);
        std::vector<double> column(log.size());
        for (std::size_t i = 0; i < log.size(); ++i) column[i] = times ? multiplier[i] * bspline(knots, b, x[i]) : bspline(knots, b, x[i]);
        p.candidates.push_back(std::move(column));
        terms.push_back(std::move(t));
      }
      std::vector<std::size_t> block(p.candidates.size());
      std::iota(block.begin(), block.end(), std::size_t{0});
      scores.push_back(score_supports(p, {block}).front());
      out.tried += terms.size();
      block_terms.push_back(std::move(terms));
    }
  };
  for (TermCovariate c : {TermCovariate::velocity_m_s, TermCovariate::load_N, TermCovariate::temperature_C}) {
    // Only a covariate that varies within runs: what changes only between runs is the random
    // run offsets' to explain, and a spline over a handful of run levels would fit them.
    bool within = false;
    for (const auto& rows : series.run_rows)
      for (std::size_t k = 1; k < rows.size() && !within; ++k)
        within = std::abs(term_covariate_value(log, series, rows[k], c) - term_covariate_value(log, series, rows[0], c)) >
                 (c == TermCovariate::temperature_C ? 1.0 : 0.0);  // a logged temperature's noise is no change
    // A logged temperature scatters around its setting: knots inside that scatter would fit
    // the thermocouple's noise through the law's temperature slope (errors in variables), so
    // in temperature the smooth term is one cubic over the whole range.
    if (within) add_blocks(c, std::nullopt, c == TermCovariate::temperature_C);
  }
  // A part of the law times a smooth function of speed, load or the run index, and the law at a
  // temperature corrected by a smooth function of the campaign's time (or the run index): these
  // vary within runs through the part or the law's slope, whatever the covariate does.
  const bool campaign = series.run_rows.size() >= 3;
  for (TermCovariate part : kLawParts) {
    if (!varies_across_rows(columns.factor(TermFactor{part}, 0))) continue;
    for (TermCovariate c : {TermCovariate::velocity_m_s, TermCovariate::load_N}) add_blocks(c, TermFactor{part}, false);
    if (campaign) add_blocks(TermCovariate::run_index, TermFactor{part}, false);
  }
  const TermFactor shift_T{TermCovariate::temperature_C, TermTransform::input_shift};
  if (series.timed) add_blocks(TermCovariate::campaign_time_s, shift_T, false);
  else if (campaign) add_blocks(TermCovariate::run_index, shift_T, false);
  if (block_terms.empty()) {
    out.why_not = "no covariate varies enough for a smooth term";
    return out;
  }
  p.candidates.clear();
  const double fixed = score_supports(p, {{}}).front().cv_rmse;  // the model alone
  // The best, and among those within the tolerance of it the one with the fewest basis functions.
  std::size_t best = 0;
  for (std::size_t b = 1; b < scores.size(); ++b)
    if (scores[b].cv_rmse < scores[best].cv_rmse) best = b;
  for (std::size_t b = 0; b < scores.size(); ++b)
    if (scores[b].cv_rmse <= scores[best].cv_rmse * (1 + min_gain_percent / 100) &&
        block_terms[b].size() < block_terms[best].size())
      best = b;
  if (100 * (1 - scores[best].cv_rmse / fixed) < min_gain_percent) {
    out.why_not = fmt::format("nor does a smooth term (cubic B-splines in speed, load or temperature, alone, times a part "
                              "of the law, or as the law's temperature input; best {:.2f} %)",
                              100 * (1 - scores[best].cv_rmse / fixed));
    return out;
  }
  out.cv_rmse = scores[best].cv_rmse;
  out.terms = std::move(block_terms[best]);
  for (std::size_t k = 0; k < out.terms.size(); ++k) out.terms[k].coefficient = scores[best].coefficient[k];
  return out;
}

// The empirical term is judged as a cause is (score_candidate): its interval must exclude its
// neutral value, 0, and the whole model must not lose on held-out runs. Which coefficient
// speaks for the term: for a sparse form every term must be there, so the one nearest 0 in its
// standard errors decides; for a smooth term the curve must differ from 0 somewhere, so the basis
// coefficient farthest from 0 does (one B-spline's coefficient may sit at 0 where the curve
// does not). Returns that term's index, terms.size() when no coefficient has a finite SE (the
// interval unknown: not a rejection, the fit's own problem is reported instead).
bool is_smooth(const std::vector<FrictionTerm>& terms) {
  return !terms.empty() && has_spline(terms.front());
}

const ParameterEstimate& term_coefficient(const FrictionFitResult& fit, const std::vector<FrictionTerm>& terms, std::size_t k) {
  std::size_t at = fit.fit.parameters.size() - term_parameter_count(terms);
  for (std::size_t j = 0; j < k; ++j) at += terms[j].has_scale() ? 2 : 1;
  return fit.fit.parameters[at];
}

std::size_t decisive_term(const FrictionFitResult& fit, const std::vector<FrictionTerm>& terms) {
  const bool smooth = is_smooth(terms);
  std::size_t decisive = terms.size();
  double decisive_t = smooth ? -1.0 : std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < terms.size(); ++k) {
    const ParameterEstimate& c = term_coefficient(fit, terms, k);
    const double t = std::abs(c.value) / c.se;
    if (std::isfinite(t) && (smooth ? t > decisive_t : t < decisive_t)) decisive = k, decisive_t = t;
  }
  return decisive;
}

// The score's value and interval from the decisive coefficient, its neutral value 0.
void score_the_term(const FrictionFitResult& fit, const std::vector<FrictionTerm>& terms, CandidateScore& score) {
  score.neutral = 0;
  if (const std::size_t k = decisive_term(fit, terms); k < terms.size()) set_estimate(score, term_coefficient(fit, terms, k));
}

}  // namespace

FrictionTermSearch learn_friction_term(const FrictionLog& log, const FrictionFitResult& current,
                                       const std::function<FrictionFitResult(const std::vector<FrictionTerm>&)>& refit,
                                       const std::function<ModelFit(const FrictionFitResult&)>& summarise,
                                       const SelectionRules& rules, double reference_C) {
  FrictionTermSearch out;
  EmpiricalFinding& f = out.finding;
  f.searched = true;
  f.where = "the friction force";
  const std::size_t n = log.size();
  const TermSeries series = term_series(log);

  // The residuals of the law (the run levels are the sparse regression's levels), the law, its
  // temperature slope, and its Jacobian in the parameters the fit moves.
  const auto& params = current.fit.parameters;
  std::vector<double> values;
  for (const auto& p : params) values.push_back(p.value);
  std::vector<double> law(n), y(n);
  for (std::size_t i = 0; i < n; ++i) {
    law[i] = current.predicted_N[i] - current.run_offset_N[log.run[i]];
    y[i] = log.friction_N[i] - law[i];
  }
  const LawAt current_law(log, params, values, reference_C);
  const auto law_warmer = [&](std::size_t i, double dT) { return current_law(i, dT); };
  const LawColumns law_columns = law_columns_at(log, values, law, law_warmer, reference_C);
  const Columns columns{log, series, law_columns};
  SparseProblem problem;
  problem.y = y;
  problem.group.assign(log.run.begin(), log.run.end());
  problem.level = problem.group;
  std::vector<std::size_t> moved;  // the parameters the fit moves
  for (std::size_t j = 0; j < params.size(); ++j)
    if (params[j].free && !params[j].held_unidentifiable && !params[j].at_bound) moved.push_back(j);
  problem.fixed.resize(moved.size());
  // Central differences, one column per parameter: independent, each on a free thread.
  for_each_index(moved.size(), [&](std::size_t m) {
    const std::size_t j = moved[m];
    const double h = 1e-6 * std::max(std::abs(params[j].value), 1e-3);
    std::vector<double> up = values, down = values, column(n);
    up[j] += h;
    down[j] -= h;
    const LawAt law_up(log, params, up, reference_C), law_down(log, params, down, reference_C);
    for (std::size_t i = 0; i < n; ++i) column[i] = (law_up(i) - law_down(i)) / (2 * h);
    problem.fixed[m] = std::move(column);
  });
  std::vector<Candidate> candidates = dictionary(log, series, law_columns, law_warmer, reference_C);
  f.dictionary_size = candidates.size();
  for (auto& c : candidates) {
    problem.candidates.push_back(std::move(c.column));
    problem.family.push_back(c.family);
  }
  SparseOptions sparse;
  sparse.min_gain_percent = rules.min_cv_gain_percent;
  const SparseSelection chosen = select_sparse(problem, sparse);

  // A candidate set of terms, fitted jointly with the law, its causes and the run offsets,
  // and judged as a cause is.
  struct Trial {
    std::vector<FrictionTerm> terms;
    FrictionFitResult fit;
    CandidateScore score;
    bool passes = false;
  };
  const ModelFit before = summarise(current);
  auto trial = [&](std::vector<FrictionTerm> terms) {
    Trial t;
    std::size_t count = params.size();
    for (auto& term : terms) {
      const std::size_t adds = term.has_scale() ? 2 : 1;
      if (count + adds > kMaxFitParameters) continue;  // within the fit's parameter limit
      count += adds;
      t.terms.push_back(std::move(term));
    }
    // A term the data cannot determine beside the law and the others (a spline's basis
    // function that the Stribeck term already draws) is dropped, and the rest refitted once.
    auto undetermined = [&](const FrictionFitResult& fit) {
      std::vector<std::size_t> out;
      const std::size_t first = fit.fit.parameters.size() - term_parameter_count(t.terms);
      for (std::size_t k = 0, at = first; k < t.terms.size(); at += t.terms[k].has_scale() ? 2 : 1, ++k)
        for (std::size_t j = at; j < at + (t.terms[k].has_scale() ? 2 : 1); ++j)
          if (fit.fit.parameters[j].held_unidentifiable || !std::isfinite(fit.fit.parameters[j].se)) {
            out.push_back(k);
            break;
          }
      return out;
    };
    if (t.terms.empty()) {
      t.score.reason = "no room for the term within the fit's 16 parameters";
      return t;
    }
    t.fit = refit(t.terms);
    if (const auto drop = undetermined(t.fit); !drop.empty() && drop.size() < t.terms.size()) {
      for (auto k = drop.rbegin(); k != drop.rend(); ++k) t.terms.erase(t.terms.begin() + static_cast<std::ptrdiff_t>(*k));
      t.fit = refit(t.terms);
    }
    // A sparse form keeps only the terms its fit can tell from 0, as a cause must be: the
    // weakest of the others is dropped and the rest refitted, one at a time.
    while (!is_smooth(t.terms) && t.terms.size() > 1) {
      CandidateScore weakest;
      score_the_term(t.fit, t.terms, weakest);
      if (interval_excludes_neutral(weakest)) break;
      t.terms.erase(t.terms.begin() + static_cast<std::ptrdiff_t>(decisive_term(t.fit, t.terms)));
      t.fit = refit(t.terms);
    }
    ModelFit after = summarise(t.fit);
    if (!undetermined(t.fit).empty()) after.problem = "a term the data cannot determine beside the law";
    t.score.effect = "empirical term";
    score_the_term(t.fit, t.terms, t.score);
    t.passes = score_candidate(before, after, rules, t.score);
    return t;
  };
  std::optional<Trial> kept;
  std::string why_not;
  if (chosen.selected.empty()) {
    why_not = fmt::format("no sparse set predicts held-out runs at least {:.3g} % better than the model alone (linearised "
                          "leave-one-run-out RMSE of the runs' shape {:.4g} N)",
                          rules.min_cv_gain_percent, chosen.cv_rmse_fixed);
  } else {
    std::vector<FrictionTerm> terms;
    for (std::size_t a = 0; a < chosen.selected.size(); ++a) {
      terms.push_back(candidates[chosen.selected[a]].term);
      terms.back().coefficient = chosen.coefficient[a];  // a lag's is its start: the joint fit is exact
    }
    Trial t = trial(std::move(terms));
    if (t.passes) kept = std::move(t);
    else why_not = "the sparse form fitted jointly with the law was not kept: " + t.score.reason;
  }
  // Where no sparse form wins: a smooth term in the one covariate whose spline predicts
  // held-out runs best — tried when the sparse form failed, or when its linearised held-out
  // RMSE beats the sparse form's by the gain a term must bring; kept if it does so fitted.
  const SmoothChoice smooth = smooth_term(log, series, columns, problem, rules.min_cv_gain_percent);
  f.dictionary_size += smooth.tried;
  const bool smooth_better = !smooth.terms.empty() && kept &&
                             smooth.cv_rmse < chosen.cv_rmse * (1 - rules.min_cv_gain_percent / 100);
  if (smooth.terms.empty()) {
    if (!kept) why_not += "; " + smooth.why_not;
  } else if (!kept || smooth_better) {
    Trial t = trial(smooth.terms);
    const bool wins = t.passes && (!kept || counted_gain(t.score) >= counted_gain(kept->score) + rules.min_cv_gain_percent);
    if (wins) {
      if (kept) why_not = "a smooth term predicts held-out runs better than the sparse form (" +
                          kept->terms.front().symbol(1) + (kept->terms.size() > 1 ? " + …" : "") + ")";
      kept = std::move(t);
    } else if (!kept) {
      why_not += "; the smooth term fitted jointly was not kept: " + t.score.reason;
    }
  }
  if (!kept) {
    f.reason = why_not;
    return out;
  }
  FrictionFitResult& joint = kept->fit;
  const CandidateScore& score = kept->score;
  set_held_out(f, before, summarise(joint));
  f.lrt_p = score.lrt_p;
  f.delta_bic = score.bic - information_criteria(before.ss, before.n, std::min(before.n_eff, summarise(joint).n_eff), before.k).second;
  // Every covariate's range in these data: the terms are extrapolations beyond.
  auto range_of = [&](TermCovariate c) {
    TermRange r{c, std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    const std::vector<double> part = is_law_covariate(c) ? columns.factor(TermFactor{c}, 0) : std::vector<double>{};
    for (std::size_t i = 0; i < n; ++i) {
      const double x = is_law_covariate(c) ? part[i] : term_covariate_value(log, series, i, c);
      r.min = std::min(r.min, x);
      r.max = std::max(r.max, x);
    }
    return r;
  };
  std::string formula, resembles;
  std::map<std::string, TermRange> used;
  const std::size_t first = joint.fit.parameters.size() - term_parameter_count(joint.terms);
  for (std::size_t t = 0, at = first; t < joint.terms.size(); ++t) {
    FrictionTerm& term = joint.terms[t];
    for (const auto& factor : term.factors)
      if (std::none_of(term.seen.begin(), term.seen.end(), [&](const TermRange& r) { return r.covariate == factor.covariate; }))
        term.seen.push_back(range_of(factor.covariate));
    if (term.lagged_temperature()) term.seen.push_back(range_of(TermCovariate::time_in_run_s));
    for (const auto& r : term.seen) used.emplace(term_covariate_name(r.covariate), r);
    EmpiricalComponent c;
    c.symbol = term.symbol(t + 1);
    c.words = term_words(term);
    c.covariates = term.covariates();
    c.coefficient = within_bounds(joint.fit.parameters[at++]);
    if (term.has_scale()) {
      c.has_scale = true;
      c.scale = within_bounds(joint.fit.parameters[at++]);
    }
    formula += (formula.empty() ? "" : " + ") + c.symbol;
    const std::string r = resemblance(term, series.chronology);
    if (!r.empty() && resembles.find(r) == std::string::npos) resembles += (resembles.empty() ? "" : "; or ") + r;
    f.components.push_back(std::move(c));
  }
  f.form = is_smooth(joint.terms) ? "smooth" : "sparse";
  f.formula = formula;
  f.resembles = resembles;
  for (const auto& [name, r] : used) f.ranges.push_back({name, r.min, r.max});
  f.found = true;
  f.reason = score.reason + (f.form == "smooth" ? " (no sparse form did as well: " + why_not + ")" : "");
  f.curve = curve_of(log, series, current, joint, reference_C);
  out.fit = std::move(joint);
  return out;
}

}  // namespace lmcal::detail
