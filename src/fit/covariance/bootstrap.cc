// Cluster bootstrap by run (Davison & Hinkley 1997, §3.8): whole runs resampled with
// replacement, each replicate one Newton step from θ̂ on the resampled runs,
//   θ* = θ̂ − (Σ_c w_c H_c)⁻¹ Σ_c w_c (g_c + K_c u*),   H_c = J_cᵀJ_c, g_c = J_cᵀr_c, K_c = J_cᵀE_c,
// w_c how often run c was drawn, u* the replicate's deviation of an external input. A run
// drawn twice counts twice (its own parameters, fitted to the same records, are shared: the
// same estimate as two copies). Parameters no drawn run determines (the offsets of a run not
// drawn) are left out of that replicate.
#include <cmath>
#include <exception>
#include <fmt/format.h>
#include <limits>
#include <vector>

#include <Eigen/Dense>

#include "covariance.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"
#include "parallel_slices.hpp"

namespace lmcal::detail {

namespace {

// splitmix64: the replicate's own stream, so that replicates do not depend on the order
// threads run them in.
std::uint64_t splitmix64(std::uint64_t& x) {
  std::uint64_t z = (x += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// How many different multisets of G runs a resample can be: C(2G − 1, G).
double distinct_resamples(std::size_t G) {
  double c = 1;
  for (std::size_t k = 1; k <= G; ++k) c = c * static_cast<double>(G - 1 + k) / static_cast<double>(k);
  return c;
}

// Each run's H_c = J_cᵀJ_c and g_c = J_cᵀr_c (and K_c = J_cᵀE_c with an external input),
// adding the rows' outer products in row order, each row's nonzero entries only: a row of a
// thermal fit touches a third of the parameters (its run's), and a product with an exact 0
// adds nothing to a sum that starts at +0, so the sums are the same bits as the dense outer
// products'.
void run_sums_sparse(const ScoreInputs& in, const Eigen::MatrixXd* external_jacobian, std::vector<Eigen::MatrixXd>& H,
                     std::vector<Eigen::VectorXd>& g, std::vector<Eigen::MatrixXd>& K) {
  const bool external = external_jacobian != nullptr;  // null: no external input
  const auto m = in.jacobian.cols();
  std::vector<Eigen::Index> nonzero;
  for (Eigen::Index i = 0; i < in.jacobian.rows(); ++i) {
    const std::size_t c = in.rows.cluster[static_cast<std::size_t>(i)];
    const auto row = in.jacobian.row(i);
    if (!row.allFinite()) {  // 0 · inf is not 0: the dense sums
      H[c].noalias() += row.transpose() * row;
      g[c] += in.residuals[i] * row.transpose();
      if (external) K[c].noalias() += row.transpose() * external_jacobian->row(i);
      continue;
    }
    nonzero.clear();
    for (Eigen::Index j = 0; j < m; ++j)
      if (row[j] != 0) nonzero.push_back(j);
    for (const Eigen::Index b : nonzero) {
      const double x = row[b];
      for (const Eigen::Index a : nonzero) H[c](a, b) += x * row[a];
      g[c][b] += in.residuals[i] * x;
      if (external) K[c].row(b) += x * external_jacobian->row(i);
    }
  }
}

// The same sums where every entry of J is finite and there is no external input, the same
// bits (see run_sums_sparse: a product with an exact 0 changes no sum), without a branch per
// entry: every entry of the lower triangle and of g_c summed over the run's rows in row order,
// in flat arrays the compiler can keep in registers and vectorise across entries (each entry's
// own sum stays in row order); the upper triangle mirrored (x_a·x_b is x_b·x_a exactly). A
// 10⁶-row trajectory fit spent a tenth of its time in the branchy loop.
void run_sums(const ScoreInputs& in, std::vector<Eigen::MatrixXd>& H, std::vector<Eigen::VectorXd>& g) {
  const auto m = static_cast<std::size_t>(in.jacobian.cols());
  const auto n = static_cast<std::size_t>(in.jacobian.rows());
  const double* J = in.jacobian.data();  // column-major: entry (i, a) at J[a·n + i]
  // Each run's rows, in order; each run's sums on a free thread (they touch no other run's).
  std::vector<std::vector<std::size_t>> rows_of(H.size());
  for (std::size_t i = 0; i < n; ++i) rows_of[in.rows.cluster[i]].push_back(i);
  for_each_index(H.size(), [&](std::size_t c) {
    std::vector<double> row(m), lower(m * m, 0.0), score(m, 0.0);
    for (const std::size_t i : rows_of[c]) {
      for (std::size_t a = 0; a < m; ++a) row[a] = J[a * n + i];
      const double r = in.residuals[static_cast<Eigen::Index>(i)];
      for (std::size_t a = 0; a < m; ++a) {
        const double x = row[a];
        double* h_row = lower.data() + a * m;  // H(a, b) for b <= a
        for (std::size_t b = 0; b <= a; ++b) h_row[b] += row[b] * x;
        score[a] += r * x;
      }
    }
    for (std::size_t a = 0; a < m; ++a) {
      g[c][static_cast<Eigen::Index>(a)] = score[a];
      for (std::size_t b = 0; b <= a; ++b)
        H[c](static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) =
            H[c](static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(a)) = lower[a * m + b];
    }
  });
}

}  // namespace

std::vector<Eigen::VectorXd> standard_normal_draws(std::size_t count, Eigen::Index size, std::uint64_t seed) {
  std::vector<Eigen::VectorXd> out(count, Eigen::VectorXd(size));
  std::uint64_t state = seed;
  auto uniform = [&] { return (static_cast<double>(splitmix64(state) >> 11) + 0.5) * 0x1.0p-53; };
  for (auto& v : out)
    for (Eigen::Index k = 0; k < size; ++k) v[k] = std::sqrt(-2 * std::log(uniform())) * std::cos(2 * M_PI * uniform());
  return out;
}

BootstrapResult cluster_bootstrap(const ScoreInputs& in, std::size_t replicates, std::uint64_t seed,
                                  const Eigen::MatrixXd* external_jacobian, const std::vector<Eigen::VectorXd>* external_draws) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const auto m = in.jacobian.cols();
  const std::size_t G = in.rows.clusters;
  BootstrapResult out;
  CovarianceEstimate& e = out.estimate;
  e.method = "bootstrap";
  e.dof = G > 1 ? static_cast<double>(G - 1) : kNaN;
  e.description = fmt::format("cluster bootstrap: {} replicates of the {} runs drawn with replacement, one Newton step "
                              "from the estimate each{}",
                              replicates, G, external_draws ? ", the external input resampled with them" : "");
  if (replicates > io::kMaxBootstrapReplicates)
    throw InvalidParameter("bootstrap", static_cast<double>(replicates),
                           fmt::format("at most {} replicates (docs/formats.md#limits)", io::kMaxBootstrapReplicates));
  out.draws = Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(replicates), m, kNaN);
  if (G < 2 || replicates < 2) {
    e.note = "needs at least two runs";
    e.covariance = Eigen::MatrixXd::Constant(m, m, kNaN);
    return out;
  }
  const bool external = external_jacobian && external_draws && !external_draws->empty();
  std::vector<Eigen::MatrixXd> H(G, Eigen::MatrixXd::Zero(m, m)), K(G);
  std::vector<Eigen::VectorXd> g(G, Eigen::VectorXd::Zero(m));
  if (external)
    for (auto& k : K) k = Eigen::MatrixXd::Zero(m, external_jacobian->cols());
  if (!external && in.jacobian.allFinite()) run_sums(in, H, g);
  else run_sums_sparse(in, external ? external_jacobian : nullptr, H, g, K);

  // Each replicate on a free thread (parallel_slices.hpp), into its own row of the draws.
  for_each_index(replicates, [&](std::size_t replicate) {
    const auto b = static_cast<long>(replicate);
    std::uint64_t state = seed * 0x2545F4914F6CDD1DULL + static_cast<std::uint64_t>(b);
    Eigen::MatrixXd Hb = Eigen::MatrixXd::Zero(m, m);
    Eigen::VectorXd gb = Eigen::VectorXd::Zero(m);
    for (std::size_t k = 0; k < G; ++k) {
      const auto c = static_cast<std::size_t>(static_cast<double>(splitmix64(state) >> 11) * 0x1.0p-53 * static_cast<double>(G));
      Hb += H[c];
      gb += g[c];
      if (external) gb += K[c] * (*external_draws)[static_cast<std::size_t>(b) % external_draws->size()];
    }
    std::vector<Eigen::Index> determined;
    for (Eigen::Index j = 0; j < m; ++j)
      if (Hb(j, j) > 1e-12 * Hb.diagonal().maxCoeff()) determined.push_back(j);
    const auto d = static_cast<Eigen::Index>(determined.size());
    Eigen::MatrixXd Hd(d, d);
    Eigen::VectorXd gd(d);
    for (Eigen::Index a = 0; a < d; ++a) {
      gd[a] = gb[determined[a]];
      for (Eigen::Index c = 0; c < d; ++c) Hd(a, c) = Hb(determined[a], determined[c]);
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(Hd);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return;
    const Eigen::VectorXd step = ldlt.solve(-gd);
    if (!step.allFinite()) return;
    for (Eigen::Index a = 0; a < d; ++a) out.draws(b, determined[a]) = step[a];
  });

  // Covariance over the replicates that determined both parameters.
  e.covariance = Eigen::MatrixXd::Constant(m, m, kNaN);
  for (Eigen::Index a = 0; a < m; ++a)
    for (Eigen::Index c = 0; c <= a; ++c) {
      double sa = 0, sc = 0, sac = 0, n = 0;
      for (Eigen::Index b = 0; b < out.draws.rows(); ++b) {
        const double x = out.draws(b, a), y = out.draws(b, c);
        if (std::isnan(x) || std::isnan(y)) continue;
        sa += x, sc += y, sac += x * y, n += 1;
      }
      if (n >= 2) e.covariance(a, c) = e.covariance(c, a) = (sac - sa * sc / n) / (n - 1);
    }
  e.ok = true;
  if (G < 5)
    e.note = fmt::format("with {} runs the bootstrap sees at most {:.0f} distinct resamples: its spread is itself uncertain", G,
                         distinct_resamples(G));
  return out;
}

}  // namespace lmcal::detail
