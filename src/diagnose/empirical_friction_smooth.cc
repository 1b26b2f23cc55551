// The empirical friction term's smooth alternative: blocks of cubic B-splines in one
// covariate (alone, times a part of the law, or as the law's temperature input), each scored by
// leave-one-run-out error, the best with the fewest basis functions kept.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

#include "empirical_friction_parts.hpp"

namespace lmcal::detail {

namespace {

// The spline blocks tried, each scored as it is built (F and the block alone: blocks never enter
// together), so that only one block's columns exist at a time in `p.candidates`.
struct Blocks {
  SparseProblem p;
  std::vector<std::vector<FrictionTerm>> terms;
  std::vector<SupportScore> scores;
  std::size_t tried = 0;  // basis functions, over all blocks
};

// The blocks of splines in covariate c (times the factor `times`, when given): 1 to 4
// interior knots at quantiles of its values (fewer for a covariate of few values), or one
// cubic over the whole range (`cubic_only`).
void add_blocks(Blocks& blocks, const FrictionLog& log, const TermSeries& series, const TermColumns& columns, TermCovariate c,
                std::optional<TermFactor> times, bool cubic_only) {
  SparseProblem& p = blocks.p;
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
    blocks.scores.push_back(score_supports(p, {block}).front());
    blocks.tried += terms.size();
    blocks.terms.push_back(std::move(terms));
  }
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
  SparseProblem& p = blocks.p;
  p.y = linear.y;
  p.group = linear.group;
  p.level = linear.level;
  p.fixed = linear.fixed;
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
  out.tried = blocks.tried;
  std::vector<std::vector<FrictionTerm>>& block_terms = blocks.terms;
  const std::vector<SupportScore>& scores = blocks.scores;
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

}  // namespace lmcal::detail
