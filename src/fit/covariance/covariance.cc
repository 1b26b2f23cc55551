// What the covariance methods share: each run's score series, the i.i.d. covariance, and the
// residuals' autocorrelation within their series.
#include <algorithm>
#include <cmath>
#include <limits>

#include "covariance.hpp"
#include "lmcal/error.hpp"

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

namespace lmcal::detail {

std::vector<Eigen::MatrixXd> run_score_series(const ScoreInputs& in, bool with_priors) {
  const RowStructure& rows = in.rows;
  const auto m = in.jacobian.cols();
  LMCAL_ASSERT(static_cast<Eigen::Index>(rows.cluster.size()) == in.jacobian.rows() && rows.time.size() == rows.cluster.size(),
               "a run and a time step for every residual row");
  std::vector<std::size_t> steps(rows.clusters, 0);
  for (std::size_t i = 0; i < rows.cluster.size(); ++i)
    steps[rows.cluster[i]] = std::max(steps[rows.cluster[i]], rows.is_prior(i) ? std::size_t{1} : rows.time[i] + 1);
  const std::size_t n = rows.cluster.size();
  // Rows already in series order (each run's rows together, time 0, 1, 2, …; no priors): each
  // run's series is a block of J scaled by its residuals, taken without zeroing it first.
  bool blocks = true;
  for (std::size_t i = 0; i < n && blocks; ++i)
    blocks = !rows.is_prior(i) &&
             (rows.time[i] == 0 ? i == 0 || rows.cluster[i] != rows.cluster[i - 1]
                                : i > 0 && rows.cluster[i] == rows.cluster[i - 1] && rows.time[i] == rows.time[i - 1] + 1);
  std::vector<Eigen::MatrixXd> series(rows.clusters);
  if (blocks) {
    std::vector<char> seen(rows.clusters, 0);
    for (std::size_t first = 0; first < n && blocks;) {
      const std::size_t c = rows.cluster[first];
      const auto count = static_cast<Eigen::Index>(steps[c]);
      blocks = !seen[c];  // a run in two blocks: not this layout after all
      seen[c] = 1;
      series[c] = in.jacobian.middleRows(static_cast<Eigen::Index>(first), count).array().colwise() *
                  in.residuals.segment(static_cast<Eigen::Index>(first), count).array();
      first += static_cast<std::size_t>(count);
    }
    // (A run without rows has an empty series.)
    for (std::size_t c = 0; c < rows.clusters && blocks; ++c)
      if (!seen[c]) series[c] = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(steps[c]), m);
    if (blocks) return series;
  }
  for (std::size_t c = 0; c < rows.clusters; ++c) series[c] = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(steps[c]), m);
  // Column by column: J is stored by columns, and so are the series.
  std::vector<Eigen::Index> step(n);
  for (std::size_t i = 0; i < n; ++i)
    step[i] = rows.is_prior(i) ? (with_priors ? 0 : -1) : static_cast<Eigen::Index>(rows.time[i]);
  const double* r = in.residuals.data();
  for (Eigen::Index a = 0; a < m; ++a) {
    const double* J = in.jacobian.col(a).data();
    for (std::size_t i = 0; i < n; ++i)
      if (step[i] >= 0) series[rows.cluster[i]](step[i], a) += r[i] * J[i];
  }
  return series;
}

CovarianceEstimate iid_covariance(const ScoreInputs& in) {
  CovarianceEstimate e;
  e.method = "iid";
  e.description = "s²(JᵀJ)⁻¹: independent residuals of equal variance";
  const double n = static_cast<double>(in.residuals.size()), m = static_cast<double>(in.jacobian.cols());
  e.dof = n - m;
  e.ok = e.dof > 0;
  e.covariance = e.ok ? Eigen::MatrixXd(in.bread * (in.residuals.squaredNorm() / e.dof)) : in.bread * kNaN;
  if (!e.ok) e.note = "no residual degrees of freedom";
  return e;
}

double residual_lag1_autocorrelation(const Eigen::VectorXd& residuals, const RowStructure& rows) {
  if (rows.empty()) return kNaN;
  const std::vector<std::size_t>& id = rows.series.empty() ? rows.cluster : rows.series;
  const std::size_t count = id.empty() ? 0 : *std::max_element(id.begin(), id.end()) + 1;
  std::vector<double> last(count, kNaN);
  double num = 0, den = 0;
  for (Eigen::Index i = 0; i < residuals.size(); ++i) {
    const double e = residuals[i];
    double& previous = last[id[static_cast<std::size_t>(i)]];
    den += e * e;
    if (!std::isnan(previous)) num += e * previous;
    previous = e;
  }
  return den > 0 ? num / den : kNaN;
}

double effective_sample_size(double n, double rho) {
  if (std::isnan(rho)) return n;
  rho = std::clamp(rho, 0.0, 0.999);
  return std::max(n * (1 - rho) / (1 + rho), 2.0);
}

}  // namespace lmcal::detail
