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

RunScoreSeries::RunScoreSeries(const ScoreInputs& in, bool with_priors) : in_(in) {
  const RowStructure& rows = in.rows;
  LMCAL_ASSERT(static_cast<Eigen::Index>(rows.cluster.size()) == in.jacobian.rows() && rows.time.size() == rows.cluster.size(),
               "a run and a time step for every residual row");
  steps_.assign(rows.clusters, 0);
  const std::size_t n = rows.cluster.size();
  for (std::size_t i = 0; i < n; ++i)
    steps_[rows.cluster[i]] = std::max(steps_[rows.cluster[i]], rows.is_prior(i) ? std::size_t{1} : rows.time[i] + 1);
  // Series order: no priors, each run's time steps 0, 1, 2, … on consecutive rows, and each run
  // starting once (one block per run).
  bool blocks = true;
  std::vector<std::size_t> first(rows.clusters, n);
  for (std::size_t i = 0; i < n && blocks; ++i) {
    blocks = !rows.is_prior(i) &&
             (rows.time[i] == 0 ? i == 0 || rows.cluster[i] != rows.cluster[i - 1]
                                : i > 0 && rows.cluster[i] == rows.cluster[i - 1] && rows.time[i] == rows.time[i - 1] + 1);
    if (blocks && rows.time[i] == 0) {
      blocks = first[rows.cluster[i]] == n;
      first[rows.cluster[i]] = i;
    }
  }
  if (blocks) {
    first_ = std::move(first);
    return;
  }
  rows_of_.resize(rows.clusters);
  for (std::size_t i = 0; i < n; ++i)
    if (with_priors || !rows.is_prior(i)) rows_of_[rows.cluster[i]].push_back(i);
}

Eigen::MatrixXd RunScoreSeries::operator()(std::size_t run) const {
  const auto m = in_.jacobian.cols();
  const auto steps = length(run);
  if (!first_.empty()) {
    if (first_[run] == static_cast<std::size_t>(in_.rows.cluster.size())) return Eigen::MatrixXd::Zero(steps, m);  // no rows
    const auto first = static_cast<Eigen::Index>(first_[run]);
    return in_.jacobian.middleRows(first, steps).array().colwise() * in_.residuals.segment(first, steps).array();
  }
  Eigen::MatrixXd series = Eigen::MatrixXd::Zero(steps, m);
  // Column by column: J is stored by columns, and so is the series.
  const double* r = in_.residuals.data();
  for (Eigen::Index a = 0; a < m; ++a) {
    const double* J = in_.jacobian.col(a).data();
    double* s = series.col(a).data();
    for (std::size_t i : rows_of_[run]) s[in_.rows.is_prior(i) ? 0 : in_.rows.time[i]] += r[i] * J[i];
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
