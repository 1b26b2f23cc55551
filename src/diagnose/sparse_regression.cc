#include "sparse_regression.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

#include "lmcal/error.hpp"
#include "parallel_slices.hpp"

namespace lmcal::detail {

namespace {

// Sufficient statistics of [F, D] and y per held-out group, after the level intercepts are
// projected out (levels are nested in groups, so a group's centring is its own).
struct GroupGrams {
  std::vector<Eigen::MatrixXd> xx;  // per group: X_g' X_g
  std::vector<Eigen::VectorXd> xy;  // X_g' y_g
  std::vector<double> yy;           // y_g' y_g
  Eigen::MatrixXd XX;               // totals
  Eigen::VectorXd Xy;
  double YY = 0;
  double n = 0;
};

// The Gram sums of `columns` (pointers to n-row columns) and y, per group and in total.
GroupGrams group_grams(const SparseProblem& p, const std::vector<const std::vector<double>*>& columns) {
  const std::size_t n = p.y.size(), k = columns.size();
  const std::size_t groups = n == 0 ? 0 : *std::max_element(p.group.begin(), p.group.end()) + 1;
  auto column = [&](std::size_t j) -> const std::vector<double>& { return *columns[j]; };
  // Each row's level as an index 0..L-1 (in order of first appearance), and the level means of
  // every column and of y.
  const bool centre = !p.level.empty();
  std::vector<std::size_t> level(n, 0);
  std::size_t levels = 1;
  if (centre) {
    std::map<std::size_t, std::size_t> level_index;
    // Looked up only where the level changes (a run's rows are a stretch): a tree look-up per
    // row was most of a Gram's serial part.
    for (std::size_t i = 0; i < n; ++i)
      level[i] = i > 0 && p.level[i] == p.level[i - 1] ? level[i - 1]
                                                       : level_index.try_emplace(p.level[i], level_index.size()).first->second;
    levels = level_index.size();
  }
  Eigen::MatrixXd mean = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(levels), static_cast<Eigen::Index>(k + 1));
  Eigen::VectorXd count = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(levels));
  if (centre && n > 0) {
    for (std::size_t i = 0; i < n; ++i) count(static_cast<Eigen::Index>(level[i])) += 1;
    // Column by column (each on a free thread), its rows in order: the same sums as row by row.
    for_each_index(k + 1, [&](std::size_t j) {
      const std::vector<double>& x = j < k ? column(j) : p.y;
      double* sum = mean.col(static_cast<Eigen::Index>(j)).data();
      // The running sum in a register through each stretch of one level: the same additions
      // in the same order as sum[level[i]] += x[i], without a store and load per row.
      std::size_t at = level[0];
      double running = sum[at];
      for (std::size_t i = 0; i < n; ++i) {
        if (level[i] != at) sum[at] = running, at = level[i], running = sum[at];
        running += x[i];
      }
      sum[at] = running;
      for (std::size_t l = 0; l < levels; ++l) sum[l] /= count(static_cast<Eigen::Index>(l));
    });
  }
  GroupGrams g;
  const auto K = static_cast<Eigen::Index>(k);
  g.xx.assign(groups, Eigen::MatrixXd::Zero(K, K));
  g.xy.assign(groups, Eigen::VectorXd::Zero(K));
  g.yy.assign(groups, 0.0);
  // Rows in blocks per group: rank updates of a block are much faster than row by row. The
  // groups' sums are independent: each group on a free thread (its own sums in its own order).
  constexpr std::size_t kBlock = 256;
  std::vector<std::vector<std::size_t>> rows(groups);
  for (std::size_t i = 0; i < n; ++i) rows[p.group[i]].push_back(i);
  for_each_index(groups, [&](std::size_t gr) {
    Eigen::MatrixXd X(static_cast<Eigen::Index>(kBlock), K);
    Eigen::VectorXd y(static_cast<Eigen::Index>(kBlock));
    for (std::size_t start = 0; start < rows[gr].size(); start += kBlock) {
      const std::size_t m = std::min(kBlock, rows[gr].size() - start);
      const std::size_t* block = rows[gr].data() + start;
      std::array<std::size_t, kBlock> block_level;
      for (std::size_t r = 0; r < m; ++r) block_level[r] = level[block[r]];
      // A group's rows are mostly a stretch (a run): then read straight, not through the indices.
      const bool stretch = block[m - 1] - block[0] == m - 1;
      // Column by column: X is column-major.
      for (std::size_t j = 0; j <= k; ++j) {
        const std::vector<double>& x = j < k ? column(j) : p.y;
        double* out = j < k ? X.col(static_cast<Eigen::Index>(j)).data() : y.data();
        if (stretch) std::copy_n(x.data() + block[0], m, out);
        else
          for (std::size_t r = 0; r < m; ++r) out[r] = x[block[r]];
        if (!centre) continue;
        const double* level_mean = mean.col(static_cast<Eigen::Index>(j)).data();
        for (std::size_t r = 0; r < m; ++r) out[r] -= level_mean[block_level[r]];
      }
      const auto M = static_cast<Eigen::Index>(m);
      g.xx[gr].selfadjointView<Eigen::Lower>().rankUpdate(X.topRows(M).transpose());  // the lower half: half the work
      g.xy[gr].noalias() += X.topRows(M).transpose() * y.head(M);
      g.yy[gr] += y.head(M).squaredNorm();
    }
    g.xx[gr] = g.xx[gr].selfadjointView<Eigen::Lower>();
  });
  g.XX = Eigen::MatrixXd::Zero(K, K);
  g.Xy = Eigen::VectorXd::Zero(K);
  for (std::size_t gr = 0; gr < groups; ++gr) {
    g.XX += g.xx[gr];
    g.Xy += g.xy[gr];
    g.YY += g.yy[gr];
  }
  g.n = static_cast<double>(n);
  return g;
}

// The fixed columns and then the candidates `of` (all of them when not given).
std::vector<const std::vector<double>*> problem_columns(const SparseProblem& p, const std::vector<std::size_t>* of = nullptr) {
  std::vector<const std::vector<double>*> columns;
  for (const auto& c : p.fixed) columns.push_back(&c);
  if (!of)
    for (const auto& c : p.candidates) columns.push_back(&c);
  else
    for (std::size_t j : *of) columns.push_back(&p.candidates[j]);
  return columns;
}

GroupGrams group_grams(const SparseProblem& p) { return group_grams(p, problem_columns(p)); }

// Least squares on the columns `cols` from Gram blocks; a tiny ridge keeps a collinear (held,
// unidentifiable) fixed column from breaking the solve.
Eigen::VectorXd solve(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, const std::vector<Eigen::Index>& cols) {
  const auto m = static_cast<Eigen::Index>(cols.size());
  Eigen::MatrixXd As(m, m);
  Eigen::VectorXd bs(m);
  double scale = 0;
  for (Eigen::Index a = 0; a < m; ++a) {
    bs(a) = b(cols[static_cast<std::size_t>(a)]);
    for (Eigen::Index c = 0; c < m; ++c) As(a, c) = A(cols[static_cast<std::size_t>(a)], cols[static_cast<std::size_t>(c)]);
    scale = std::max(scale, As(a, a));
  }
  As.diagonal().array() += 1e-12 * std::max(scale, 1e-300);
  return As.ldlt().solve(bs);
}

class Scorer {
 public:
  Scorer(const GroupGrams& g, std::size_t fixed) : g_(g), fixed_(fixed) {}

  std::vector<Eigen::Index> columns(const std::vector<std::size_t>& support) const {
    std::vector<Eigen::Index> cols(fixed_);
    std::iota(cols.begin(), cols.end(), Eigen::Index{0});
    for (std::size_t j : support) cols.push_back(static_cast<Eigen::Index>(fixed_ + j));
    return cols;
  }

  // Leave-one-group-out RMSE of F plus the candidates of `support`.
  double cv_rmse(const std::vector<std::size_t>& support) const {
    const auto cols = columns(support);
    if (cols.empty()) return std::sqrt(g_.YY / g_.n);
    double sse = 0;
    for (std::size_t gr = 0; gr < g_.xx.size(); ++gr) {
      const Eigen::VectorXd b = solve(g_.XX - g_.xx[gr], g_.Xy - g_.xy[gr], cols);
      double e = g_.yy[gr];
      for (std::size_t a = 0; a < cols.size(); ++a) {
        e -= 2 * b(static_cast<Eigen::Index>(a)) * g_.xy[gr](cols[a]);
        for (std::size_t c = 0; c < cols.size(); ++c)
          e += b(static_cast<Eigen::Index>(a)) * g_.xx[gr](cols[a], cols[c]) * b(static_cast<Eigen::Index>(c));
      }
      sse += std::max(e, 0.0);
    }
    return std::sqrt(sse / g_.n);
  }

  // Coefficients of the support's candidates on all data.
  std::vector<double> coefficients(const std::vector<std::size_t>& support) const {
    const auto cols = columns(support);
    const Eigen::VectorXd b = solve(g_.XX, g_.Xy, cols);
    return {b.data() + fixed_, b.data() + b.size()};
  }

  // The RMS of each candidate once F is projected out (0: nothing beyond F).
  double rms_beyond_fixed(std::size_t j) const {
    const auto J = static_cast<Eigen::Index>(fixed_ + j);
    double ss = g_.XX(J, J);
    if (fixed_ > 0) {
      std::vector<Eigen::Index> cols(fixed_);
      std::iota(cols.begin(), cols.end(), Eigen::Index{0});
      const Eigen::VectorXd b = solve(g_.XX, g_.XX.col(J), cols);
      for (std::size_t a = 0; a < fixed_; ++a) ss -= b(static_cast<Eigen::Index>(a)) * g_.XX(cols[a], J);
    }
    return std::sqrt(std::max(ss, 0.0) / g_.n);
  }

  // RMS of the residuals after F alone, on all data.
  double residual_rms_fixed() const {
    double ss = g_.YY;
    if (fixed_ > 0) {
      const auto cols = columns({});
      const Eigen::VectorXd b = solve(g_.XX, g_.Xy, cols);
      for (std::size_t a = 0; a < fixed_; ++a) ss -= b(static_cast<Eigen::Index>(a)) * g_.Xy(cols[a]);
    }
    return std::sqrt(std::max(ss, 0.0) / g_.n);
  }

 private:
  const GroupGrams& g_;
  std::size_t fixed_;
};

// One member per family: the one that alone predicts held-out groups best (each candidate's
// score on a free thread, then taken in candidate order), in candidate order.
std::vector<std::size_t> family_representatives(const SparseProblem& p, const Scorer& scorer, const std::vector<double>& rms,
                                                double y_rms) {
  const std::size_t m = p.candidates.size();
  const auto beyond = [&](std::size_t j) { return rms[j] > 1e-9 * std::max(y_rms, 1e-300); };  // else nothing beyond F and the levels
  std::vector<double> alone(m);
  for_each_index(m, [&](std::size_t j) {
    if (beyond(j)) alone[j] = scorer.cv_rmse({j});
  });
  std::map<std::size_t, std::pair<double, std::size_t>> best_of_family;  // family -> (cv, member)
  for (std::size_t j = 0; j < m; ++j) {
    if (!beyond(j)) continue;
    const std::size_t family = p.family.empty() ? j : p.family[j];
    auto [it, inserted] = best_of_family.try_emplace(family, alone[j], j);
    if (!inserted && alone[j] < it->second.first) it->second = {alone[j], j};
  }
  std::vector<std::size_t> pool;
  for (const auto& [family, best] : best_of_family) pool.push_back(best.second);
  std::sort(pool.begin(), pool.end());
  return pool;
}

}  // namespace

SparseSelection select_sparse(const SparseProblem& p, const SparseOptions& o) {
  const std::size_t n = p.y.size(), m = p.candidates.size();
  LMCAL_ASSERT(p.group.size() == n && (p.level.empty() || p.level.size() == n), "one group (and level) per row");
  for (const auto& c : p.fixed) LMCAL_ASSERT(c.size() == n, "fixed columns of n rows");
  for (const auto& c : p.candidates) LMCAL_ASSERT(c.size() == n, "candidate columns of n rows");
  LMCAL_ASSERT(p.family.empty() || p.family.size() == m, "one family per candidate");
  SparseSelection s;
  if (n == 0) return s;
  const GroupGrams grams = group_grams(p);
  const Scorer scorer(grams, p.fixed.size());
  s.cv_rmse_fixed = s.cv_rmse = scorer.cv_rmse({});

  // Each candidate's RMS beyond F: the unit of its standardised coefficient.
  std::vector<double> rms(m);
  for (std::size_t j = 0; j < m; ++j) rms[j] = scorer.rms_beyond_fixed(j);
  const double y_rms = scorer.residual_rms_fixed();

  std::vector<std::size_t> pool = family_representatives(p, scorer, rms, y_rms);
  s.family_representative = pool;

  // The STLSQ path.
  double best_cv = s.cv_rmse_fixed;
  for (double share : o.thresholds) {
    const double lambda = share * y_rms;
    std::vector<std::size_t> support = pool;
    for (int iteration = 0; iteration < 50 && !support.empty(); ++iteration) {
      const std::vector<double> c = scorer.coefficients(support);
      std::vector<std::size_t> kept;
      std::vector<std::pair<double, std::size_t>> size;  // standardised |γ|, candidate
      for (std::size_t a = 0; a < support.size(); ++a) {
        const double standardised = std::abs(c[a]) * rms[support[a]];
        if (standardised >= lambda) size.emplace_back(standardised, support[a]);
      }
      // At most max_terms: the largest.
      std::sort(size.begin(), size.end(), std::greater<>());
      if (size.size() > o.max_terms) size.resize(o.max_terms);
      for (const auto& [value, j] : size) kept.push_back(j);
      std::sort(kept.begin(), kept.end());
      if (kept == support) break;
      support = std::move(kept);
    }
    SparseStep step{lambda, support, support.empty() ? s.cv_rmse_fixed : scorer.cv_rmse(support)};
    s.path.push_back(step);
    if (step.cv_rmse < best_cv) best_cv = step.cv_rmse;
  }
  // Forward steps beside the thresholds: on a dictionary of correlated transforms, the full
  // least-squares fit STLSQ starts from can spread a term over its look-alikes and drop it;
  // adding, one at a time, the term that best predicts held-out groups cannot.
  std::vector<std::size_t> forward;
  while (forward.size() < o.max_terms) {
    std::size_t best = m;
    double best_step_cv = std::numeric_limits<double>::infinity();
    // Each trial on a free thread, taken in pool order (NaN: already in).
    std::vector<double> with(pool.size(), std::numeric_limits<double>::quiet_NaN());
    for_each_index(pool.size(), [&](std::size_t a) {
      if (std::find(forward.begin(), forward.end(), pool[a]) != forward.end()) return;
      std::vector<std::size_t> trial = forward;
      trial.push_back(pool[a]);
      std::sort(trial.begin(), trial.end());
      with[a] = scorer.cv_rmse(trial);
    });
    for (std::size_t a = 0; a < pool.size(); ++a)
      if (with[a] < best_step_cv) best_step_cv = with[a], best = pool[a];
    if (best == m) break;
    forward.push_back(best);
    std::sort(forward.begin(), forward.end());
    s.path.push_back({std::numeric_limits<double>::quiet_NaN(), forward, best_step_cv});
    best_cv = std::min(best_cv, best_step_cv);
  }
  // The sparsest support within the tolerance of the best; kept only if it gains enough.
  const double tolerance = 1 + o.min_gain_percent / 100;
  const SparseStep* chosen = nullptr;
  for (const auto& step : s.path) {
    if (step.support.empty() || step.cv_rmse > best_cv * tolerance) continue;
    if (!chosen || step.support.size() < chosen->support.size() ||
        (step.support.size() == chosen->support.size() && step.cv_rmse < chosen->cv_rmse))
      chosen = &step;
  }
  if (!chosen || 100 * (1 - chosen->cv_rmse / s.cv_rmse_fixed) < o.min_gain_percent) return s;
  s.selected = chosen->support;
  s.cv_rmse = chosen->cv_rmse;
  s.coefficient = scorer.coefficients(s.selected);
  return s;
}

SupportScore score_columns(const SparseProblem& p, const std::vector<std::vector<double>>& columns) {
  std::vector<const std::vector<double>*> all;
  for (const auto& c : p.fixed) all.push_back(&c);
  for (const auto& c : columns) {
    LMCAL_ASSERT(c.size() == p.y.size(), "columns of n rows");
    all.push_back(&c);
  }
  const GroupGrams grams = group_grams(p, all);
  const Scorer scorer(grams, p.fixed.size());
  std::vector<std::size_t> own(columns.size());
  std::iota(own.begin(), own.end(), std::size_t{0});
  return {scorer.cv_rmse(own), scorer.coefficients(own)};
}

std::vector<SupportScore> score_supports(const SparseProblem& p, const std::vector<std::vector<std::size_t>>& supports) {
  // Each support with F alone: its own Gram sums, never the cross products between supports
  // (a smooth search's blocks: hundreds of columns, of which each score needs a handful).
  std::vector<SupportScore> out;
  for (auto support : supports) {
    std::sort(support.begin(), support.end());
    const GroupGrams grams = group_grams(p, problem_columns(p, &support));
    const Scorer scorer(grams, p.fixed.size());
    std::vector<std::size_t> own(support.size());
    std::iota(own.begin(), own.end(), std::size_t{0});
    out.push_back({scorer.cv_rmse(own), scorer.coefficients(own)});
  }
  return out;
}

}  // namespace lmcal::detail
