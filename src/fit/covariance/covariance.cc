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
  std::vector<Eigen::MatrixXd> series(rows.clusters);
  for (std::size_t c = 0; c < rows.clusters; ++c) series[c] = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(steps[c]), m);
  for (std::size_t i = 0; i < rows.cluster.size(); ++i) {
    if (rows.is_prior(i) && !with_priors) continue;
    const auto row = static_cast<Eigen::Index>(i);
    const auto step = static_cast<Eigen::Index>(rows.is_prior(i) ? 0 : rows.time[i]);
    series[rows.cluster[i]].row(step) += in.residuals[row] * in.jacobian.row(row);
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
