// The empirical friction term's dictionary: the current law's columns (its force, parts and
// temperature slope) and the candidate terms built from what the log varies, each with its
// column (the list in empirical_friction.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "empirical_friction_parts.hpp"
#include "parallel_slices.hpp"

namespace lmcal::detail {

std::vector<double> TermColumns::factor(const TermFactor& f, double scale) const {
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
std::vector<double> TermColumns::column(const FrictionTerm& t) const {
  std::vector<double> v(log.size(), 1.0);
  for (const auto& f : t.factors) {
    const std::vector<double> x = factor(f, t.scale);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] *= x[i];
  }
  return v;
}

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

bool varies_across_rows(const std::vector<double>& part) {
  return std::any_of(part.begin(), part.end(), [&](double v) { return v != part.front(); });
}

namespace {

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

// The dictionary's entries as they are listed, each with its family's number: a term alone is
// a family; one transform at several scales (decay_family) or thresholds is one.
struct Entries {
  std::vector<DictionaryEntry> list;
  std::size_t family = 0;
  void add(FrictionTerm term) { list.push_back({std::move(term), {}, family++}); }
};

TermFactor linear_factor(TermCovariate c, double reference_C) {
  return TermFactor{c, TermTransform::linear, c == TermCovariate::temperature_C ? reference_C : 0.0};
}

const TermFactor kLawFactor{TermCovariate::law_force_N};

// Linear, square and product terms in the covariates the log varies, and the law's force times
// speed or temperature.
void add_polynomials(Entries& out, const FrictionLog& log, const TermSeries& series, double reference_C) {
  auto linear = [&](TermCovariate c) { return linear_factor(c, reference_C); };
  std::vector<TermCovariate> base;
  for (TermCovariate c : {TermCovariate::velocity_m_s, TermCovariate::load_N, TermCovariate::preload_um,
                          TermCovariate::block_length_mm, TermCovariate::temperature_C, TermCovariate::direction})
    if (varies(log, series, c)) base.push_back(c);
  for (TermCovariate c : base) out.add({.factors = {linear(c)}});
  for (TermCovariate c : base)
    if (c == TermCovariate::velocity_m_s || c == TermCovariate::load_N || c == TermCovariate::temperature_C)
      out.add({.factors = {TermFactor{c, TermTransform::square, linear(c).centre}}});
  for (std::size_t a = 0; a < base.size(); ++a)
    for (std::size_t b = a + 1; b < base.size(); ++b) out.add({.factors = {linear(base[a]), linear(base[b])}});
  for (TermCovariate c : base)
    if (c == TermCovariate::velocity_m_s || c == TermCovariate::temperature_C) out.add({.factors = {kLawFactor, linear(c)}});
}

// A family with a scale: exp(−x/ℓ) in covariate c (times `with`), one column per ℓ on a grid of
// shares of c's span.
void add_decay_family(Entries& out, const FrictionLog& log, const TermSeries& series, TermCovariate c,
                      std::vector<TermFactor> with) {
  const std::vector<double> shares{0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0};
  double span = 0;
  for (std::size_t i = 0; i < log.size(); ++i) span = std::max(span, term_covariate_value(log, series, i, c));
  if (!(span > 0)) return;
  for (double share : shares) {
    FrictionTerm t{.factors = {TermFactor{c, TermTransform::decay}}, .scale = share * span,
                   .scale_lower = 1e-3 * span, .scale_upper = 10 * span};
    // An input shift leads its term (term_form_problem); any other factor follows the decay.
    const bool shift = !with.empty() && with.front().transform == TermTransform::input_shift;
    t.factors.insert(shift ? t.factors.begin() : t.factors.end(), with.begin(), with.end());
    out.list.push_back({std::move(t), {}, out.family});
  }
  ++out.family;
}

// A timed log's families: running-in over the sliding distance, settling within each run, and
// the law at a temperature lagging the logged one (its column computed here, by the law itself).
void add_timed_families(Entries& out, const FrictionLog& log, const TermSeries& series, const std::vector<double>& law,
                        const std::function<double(std::size_t, double)>& law_warmer, double reference_C) {
  add_decay_family(out, log, series, TermCovariate::sliding_distance_m, {});
  add_decay_family(out, log, series, TermCovariate::sliding_distance_m, {kLawFactor});
  if (varies(log, series, TermCovariate::load_N))
    add_decay_family(out, log, series, TermCovariate::sliding_distance_m, {linear_factor(TermCovariate::load_N, reference_C)});
  add_decay_family(out, log, series, TermCovariate::time_in_run_s, {});
  add_decay_family(out, log, series, TermCovariate::time_in_run_s, {kLawFactor});
  if (temperature_changes_within_runs(log, series)) {
    // Each lag's column (the law evaluated at every row) on a free thread.
    constexpr double kLags_s[] = {15.0, 30.0, 60.0, 120.0, 240.0, 480.0, 960.0, 1920.0};
    std::vector<std::vector<double>> columns(std::size(kLags_s));
    for_each_index(columns.size(), [&](std::size_t k) {
      const std::vector<double> change = lagged_temperature_change(log, series, kLags_s[k]);
      columns[k].resize(log.size());
      for (std::size_t i = 0; i < log.size(); ++i) columns[k][i] = law_warmer(i, change[i]) - law[i];
    });
    for (std::size_t k = 0; k < columns.size(); ++k) {
      FrictionTerm t{.factors = {TermFactor{TermCovariate::temperature_C, TermTransform::lagged_temperature}},
                     .scale = kLags_s[k], .scale_lower = 1.0, .scale_upper = 1e5};
      out.list.push_back({std::move(t), std::move(columns[k]), out.family});
    }
    ++out.family;
  }
}

// The law at a corrected temperature, F_law(T + c·g(x)), linearised: ∂F_law/∂T · g(x) — a step
// above a temperature, a drift over the campaign, a warm-up within each run the logged
// temperature does not show.
void add_input_shifts(Entries& out, const FrictionLog& log, const TermSeries& series, bool campaign) {
  const TermFactor shift_T{TermCovariate::temperature_C, TermTransform::input_shift};
  if (!(varies(log, series, TermCovariate::temperature_C) || series.timed || campaign)) return;
  const std::vector<double> thresholds = temperature_thresholds(log);
  for (double threshold : thresholds) {
    out.list.push_back({{.factors = {shift_T, TermFactor{TermCovariate::temperature_C, TermTransform::step, threshold}}}, {}, out.family});
  }
  out.family += thresholds.empty() ? 0 : 1;
  const TermCovariate clock = series.timed ? TermCovariate::campaign_time_s : TermCovariate::run_index;
  if (series.timed || campaign)
    out.add({.factors = {shift_T, TermFactor{clock, TermTransform::linear, mean_and_middle(log, series, clock).second}}});
  if (series.timed) add_decay_family(out, log, series, TermCovariate::time_in_run_s, {shift_T});
}

// The law's own parts reweighted by a covariate: c · F_part · (x − x̄), c · F_part · (x − x_mid)².
void add_reweighted_parts(Entries& out, const FrictionLog& log, const TermSeries& series, const LawColumns& law_columns,
                          bool campaign) {
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
      out.add({.factors = {part, TermFactor{c, TermTransform::linear, mean}}});
      if (c == TermCovariate::velocity_m_s || c == TermCovariate::load_N || c == TermCovariate::temperature_C)
        out.add({.factors = {part, TermFactor{c, TermTransform::square, middle}}});
    }
  }
}

}  // namespace

std::vector<DictionaryEntry> dictionary(const FrictionLog& log, const TermSeries& series, const LawColumns& law_columns,
                                  const std::function<double(std::size_t, double)>& law_warmer, double reference_C) {
  // The terms first, their columns (independent of each other) at the end on the free threads.
  Entries out;
  add_polynomials(out, log, series, reference_C);
  if (series.timed) add_timed_families(out, log, series, law_columns.law, law_warmer, reference_C);
  const bool campaign = series.run_rows.size() >= 3;  // runs enough to follow a trend over them
  add_input_shifts(out, log, series, campaign);
  add_reweighted_parts(out, log, series, law_columns, campaign);
  // Campaign covariates: the friction changing from run to run in the order they were made.
  if (campaign) {
    out.add({.factors = {kLawFactor, TermFactor{TermCovariate::run_index, TermTransform::linear,
                                                mean_and_middle(log, series, TermCovariate::run_index).second}}});
    add_decay_family(out, log, series, TermCovariate::run_index, {kLawFactor});
  }
  const TermColumns columns{log, series, law_columns};
  for_each_index(out.list.size(), [&](std::size_t k) {
    if (out.list[k].column.empty()) out.list[k].column = columns.column(out.list[k].term);
  });
  return std::move(out.list);
}

}  // namespace lmcal::detail
