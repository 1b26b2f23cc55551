// The empirical friction term's smooth alternative: blocks of cubic B-splines in one
// covariate (alone, times a part of the law, or as the law's temperature input), each scored by
// leave-one-run-out error, the best with the fewest basis functions kept.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <optional>

#include "empirical_friction_parts.hpp"
#include "parallel_slices.hpp"

namespace lmcal::detail {

namespace {

// A covariate the smooth terms are tried in: its distinct values and each sample's among them
// (a basis function is evaluated once per value: a speed or a load takes a handful), and the
// factor a block is multiplied by (a part of the law; none: 1).
struct SplineCovariate {
  TermCovariate c;
  std::optional<TermFactor> times;
  std::vector<double> values;
  std::vector<std::uint32_t> value_of;
  std::vector<double> multiplier;
};

// A block of splines to try: its covariate and knots.
struct Block {
  std::size_t covariate;  // in Blocks::covariates
  std::vector<double> knots;
};

// The spline blocks tried (F and the block alone: blocks never enter together). Each block is
// built and scored on a free thread, with its own columns, then taken in the order found.
struct Blocks {
  std::vector<SplineCovariate> covariates;
  std::vector<Block> blocks;
};

// The blocks of splines in covariate c (times the factor `times`, when given): 1 to 4
// interior knots at quantiles of its values (fewer for a covariate of few values), or one
// cubic over the whole range (`cubic_only`).
void add_blocks(Blocks& blocks, const FrictionLog& log, const TermSeries& series, const TermColumns& columns, TermCovariate c,
                std::optional<TermFactor> times, bool cubic_only) {
  std::vector<double> x(log.size());
  for (std::size_t i = 0; i < log.size(); ++i) x[i] = term_covariate_value(log, series, i, c);
  std::vector<double> sorted = x;
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> distinct;
  for (double v : sorted)
    if (distinct.empty() || v > distinct.back() + 1e-9 * std::max(1.0, std::abs(v))) distinct.push_back(v);
  if (distinct.size() < 4) return;
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
    blocks.blocks.push_back({blocks.covariates.size(), std::move(knots)});
  }
  if (blocks.blocks.empty() || blocks.blocks.back().covariate != blocks.covariates.size()) return;  // no block in c
  std::vector<double> values = sorted;
  values.erase(std::unique(values.begin(), values.end()), values.end());
  std::vector<std::uint32_t> value_of(x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    value_of[i] = static_cast<std::uint32_t>(std::lower_bound(values.begin(), values.end(), x[i]) - values.begin());
  std::vector<double> multiplier = times ? columns.factor(*times, 0) : std::vector<double>{};
  blocks.covariates.push_back({c, times, std::move(values), std::move(value_of), std::move(multiplier)});
}

// A block's terms (basis functions 1 … bases − 1: the first is the level, the runs' own) and
// its score with F.
struct ScoredBlock {
  std::vector<FrictionTerm> terms;
  SupportScore score;
};
ScoredBlock score_block(const SparseProblem& p, const SplineCovariate& v, const Block& block) {
  const int bases = static_cast<int>(block.knots.size()) - 4;
  ScoredBlock out;
  std::vector<std::vector<double>> columns;
  for (int b = 1; b < bases; ++b) {
    FrictionTerm t{.factors = {TermFactor{.covariate = v.c, .transform = TermTransform::spline, .basis = b, .knots = block.knots}}};
    if (v.times) t.factors.insert(t.factors.begin(), *v.times);
    std::vector<double> at(v.values.size()), column(v.value_of.size());
    for (std::size_t k = 0; k < at.size(); ++k) at[k] = bspline(block.knots, b, v.values[k]);
    for (std::size_t i = 0; i < column.size(); ++i) column[i] = v.times ? v.multiplier[i] * at[v.value_of[i]] : at[v.value_of[i]];
    columns.push_back(std::move(column));
    out.terms.push_back(std::move(t));
  }
  out.score = score_columns(p, columns);
  return out;
}

// Only a covariate that varies within runs: what changes only between runs is the random
// run offsets' to explain, and a spline over a handful of run levels would fit them.
bool varies_within_runs(const FrictionLog& log, const TermSeries& series, TermCovariate c) {
  bool within = false;
  for (const auto& rows : series.run_rows)
    for (std::size_t k = 1; k < rows.size() && !within; ++k)
      within = std::abs(term_covariate_value(log, series, rows[k], c) - term_covariate_value(log, series, rows[0], c)) >
               (c == TermCovariate::temperature_C ? 1.0 : 0.0);  // a logged temperature's noise is no change
  return within;
}

}  // namespace

SmoothChoice smooth_term(const FrictionLog& log, const TermSeries& series, const TermColumns& columns, const SparseProblem& linear,
                         double min_gain_percent) {
  SmoothChoice out;
  Blocks blocks;
  for (TermCovariate c : {TermCovariate::velocity_m_s, TermCovariate::load_N, TermCovariate::temperature_C}) {
    // A logged temperature scatters around its setting: knots inside that scatter would fit
    // the thermocouple's noise through the law's temperature slope (errors in variables), so
    // in temperature the smooth term is one cubic over the whole range.
    if (varies_within_runs(log, series, c)) add_blocks(blocks, log, series, columns, c, std::nullopt, c == TermCovariate::temperature_C);
  }
  // A part of the law times a smooth function of speed, load or the run index, and the law at a
  // temperature corrected by a smooth function of the campaign's time (or the run index): these
  // vary within runs through the part or the law's slope, whatever the covariate does.
  const bool campaign = series.run_rows.size() >= 3;
  for (TermCovariate part : kLawParts) {
    if (!varies_across_rows(columns.factor(TermFactor{part}, 0))) continue;
    for (TermCovariate c : {TermCovariate::velocity_m_s, TermCovariate::load_N}) add_blocks(blocks, log, series, columns, c, TermFactor{part}, false);
    if (campaign) add_blocks(blocks, log, series, columns, TermCovariate::run_index, TermFactor{part}, false);
  }
  const TermFactor shift_T{TermCovariate::temperature_C, TermTransform::input_shift};
  if (series.timed) add_blocks(blocks, log, series, columns, TermCovariate::campaign_time_s, shift_T, false);
  else if (campaign) add_blocks(blocks, log, series, columns, TermCovariate::run_index, shift_T, false);
  std::vector<ScoredBlock> scored(blocks.blocks.size());
  for_each_index(scored.size(), [&](std::size_t b) {
    const Block& block = blocks.blocks[b];
    scored[b] = score_block(linear, blocks.covariates[block.covariate], block);
  });
  std::vector<std::vector<FrictionTerm>> block_terms;
  std::vector<SupportScore> scores;
  for (ScoredBlock& b : scored) {
    out.tried += b.terms.size();
    block_terms.push_back(std::move(b.terms));
    scores.push_back(std::move(b.score));
  }
  if (block_terms.empty()) {
    out.why_not = "no covariate varies enough for a smooth term";
    return out;
  }
  const double fixed = score_columns(linear, {}).cv_rmse;  // the model alone
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

}  // namespace lmcal::detail
