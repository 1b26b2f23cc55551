// Cluster-robust covariance by run (Cameron & Miller 2015), and the test of whether runs
// disagree beyond their own errors.
#include <algorithm>
#include <cmath>
#include <fmt/format.h>

#include "covariance.hpp"
#include "lmcal/fit/statistics.hpp"

namespace lmcal::detail {

namespace {

// B (Σ_c S_c S_cᵀ) B with S_c run c's whole score (priors included); no small-sample factor.
Eigen::MatrixXd raw_cluster_covariance(const ScoreInputs& in) {
  const auto m = in.jacobian.cols();
  Eigen::MatrixXd totals = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(in.rows.clusters), m);
  // By stretches of rows of one run, each a dot product of a column of J with the residuals.
  const std::vector<std::size_t>& cluster = in.rows.cluster;
  for (std::size_t first = 0; first < cluster.size();) {
    std::size_t last = first + 1;
    while (last < cluster.size() && cluster[last] == cluster[first]) ++last;
    const auto start = static_cast<Eigen::Index>(first), length = static_cast<Eigen::Index>(last - first);
    const auto c = static_cast<Eigen::Index>(cluster[first]);
    totals.row(c) += in.residuals.segment(start, length).transpose() * in.jacobian.middleRows(start, length);
    first = last;
  }
  const Eigen::MatrixXd meat = totals.transpose() * totals;
  return in.bread * meat * in.bread;
}

}  // namespace

CovarianceEstimate cluster_covariance(const ScoreInputs& in) {
  CovarianceEstimate e;
  e.method = "cluster";
  const double G = static_cast<double>(in.rows.clusters);
  const double n = static_cast<double>(in.residuals.size()), m = static_cast<double>(in.jacobian.cols());
  e.dof = G - 1;
  e.description = fmt::format(
      "cluster-robust sandwich by run ({} runs, t with {} dof): any dependence within a run, and runs that "
      "differ beyond their noise; runs independent",
      in.rows.clusters, in.rows.clusters > 0 ? in.rows.clusters - 1 : 0);
  if (in.rows.clusters < 2 || n <= m) {
    e.note = "needs at least two runs";
    e.covariance = in.bread * std::numeric_limits<double>::quiet_NaN();
    return e;
  }
  e.covariance = raw_cluster_covariance(in) * (G / (G - 1) * (n - 1) / (n - m));
  e.ok = e.covariance.allFinite();
  if (in.rows.clusters < 5) e.note = fmt::format("with {} runs a cluster covariance is itself uncertain: compare the bootstrap", in.rows.clusters);
  return e;
}

std::vector<HeterogeneityTest> between_run_heterogeneity(const ScoreInputs& in, const CovarianceEstimate& hac) {
  std::vector<HeterogeneityTest> tests;
  if (in.rows.clusters < 2 || !hac.ok) return tests;
  const Eigen::MatrixXd raw = raw_cluster_covariance(in);
  for (Eigen::Index j = 0; j < in.jacobian.cols(); ++j) {
    std::vector<char> touches(in.rows.clusters, 0);
    for (Eigen::Index i = 0; i < in.jacobian.rows(); ++i)
      if (in.jacobian(i, j) != 0) touches[in.rows.cluster[static_cast<std::size_t>(i)]] = 1;
    HeterogeneityTest t;
    t.parameter = static_cast<std::size_t>(j);
    t.runs = static_cast<std::size_t>(std::count(touches.begin(), touches.end(), 1));
    if (t.runs < 2 || !(hac.covariance(j, j) > 0)) continue;
    t.q = static_cast<double>(t.runs) * raw(j, j) / hac.covariance(j, j);
    const double dof = static_cast<double>(t.runs - 1);
    t.p_value = chi_squared_upper_p(t.q, dof);
    t.i_squared = t.q > 0 ? std::max(0.0, (t.q - dof) / t.q) : 0.0;
    tests.push_back(t);
  }
  return tests;
}

}  // namespace lmcal::detail
