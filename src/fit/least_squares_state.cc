// What the Jacobian at a fit's estimate gives without refitting: (JᵀJ)⁻¹ over the free
// parameters, and each group's normal equations and leave-one-group-out step.
#include "least_squares_state.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace lmcal::detail {

// (JᵀJ)⁻¹ over the free parameters (held rows and columns zero): from the eigenvalues of the
// column-scaled JᵀJ when it is well conditioned, else from a rank-revealing QR of J at the
// solution: J P = Q R, (JᵀJ)⁻¹ = P (RᵀR)⁻¹ Pᵀ. This is the
// quantity ceres::Covariance computes (a test checks they agree); Ceres' dense SVD of a
// 10⁵-row J cost most of the friction fit's time budget. Returns false, with a message, when
// J is rank deficient.
bool covariance_from_jacobian(const Eigen::MatrixXd& J, const std::vector<bool>& held, Eigen::MatrixXd& covariance,
                              std::string& message) {
  const auto p = J.cols();
  covariance = Eigen::MatrixXd::Zero(p, p);
  std::vector<Eigen::Index> free;
  for (Eigen::Index j = 0; j < p; ++j)
    if (!held[static_cast<std::size_t>(j)]) free.push_back(j);
  if (free.empty()) return true;
  const auto m = static_cast<Eigen::Index>(free.size());
  // Column scaling keeps the rank decision about directions, not about units.
  Eigen::MatrixXd all = Eigen::MatrixXd::Zero(p, p);
  all.selfadjointView<Eigen::Lower>().rankUpdate(J.transpose());
  Eigen::VectorXd norms(m);
  Eigen::MatrixXd information(m, m);
  for (Eigen::Index a = 0; a < m; ++a) {
    norms[a] = std::sqrt(all(free[a], free[a]));
    if (!(norms[a] > 0)) {
      message = "the Jacobian is rank deficient at the solution: a parameter has no effect on any residual";
      return false;
    }
  }
  for (Eigen::Index a = 0; a < m; ++a)
    for (Eigen::Index b = 0; b < m; ++b) {
      const Eigen::Index i = std::max(free[a], free[b]), j = std::min(free[a], free[b]);
      information(a, b) = all(i, j) / (norms[a] * norms[b]);
    }
  // Well conditioned (the scaled JᵀJ's condition number below 1e8, J's below 1e4): the
  // inverse of the small information matrix, accurate to about 1e-8 and far cheaper than a QR
  // of a 10⁵-row J. Otherwise the QR, whose rank decision sees directions JᵀJ would lose.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> spectrum(information);
  const Eigen::VectorXd eigenvalues = spectrum.eigenvalues();
  if (spectrum.info() == Eigen::Success && eigenvalues[0] > 1e-8 * eigenvalues[m - 1]) {
    const Eigen::MatrixXd scaled = spectrum.eigenvectors() * eigenvalues.cwiseInverse().asDiagonal() *
                                   spectrum.eigenvectors().transpose();
    for (Eigen::Index a = 0; a < m; ++a)
      for (Eigen::Index b = 0; b < m; ++b) covariance(free[a], free[b]) = scaled(a, b) / (norms[a] * norms[b]);
    return true;
  }
  Eigen::MatrixXd Jf(J.rows(), m);
  for (Eigen::Index k = 0; k < m; ++k) Jf.col(k) = J.col(free[k]) / norms[k];
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Jf);
  qr.setThreshold(1e-10);
  if (qr.rank() < m) {
    message = fmt::format("the Jacobian is rank deficient at the solution (rank {} of {})", qr.rank(), m);
    return false;
  }
  const Eigen::MatrixXd R = qr.matrixR().topLeftCorner(m, m).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd Rinv = R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(m, m));
  const Eigen::MatrixXd permuted = Rinv * Rinv.transpose();
  const Eigen::MatrixXd scaled = qr.colsPermutation() * permuted * qr.colsPermutation().transpose();
  for (Eigen::Index a = 0; a < m; ++a)
    for (Eigen::Index b = 0; b < m; ++b) covariance(free[a], free[b]) = scaled(a, b) / (norms[a] * norms[b]);
  return true;
}

GroupNormalEquations group_normal_equations(const FinalState& state, const std::vector<std::size_t>& group_of_row) {
  const Eigen::MatrixXd& J = state.jacobian;
  const Eigen::VectorXd& r = state.residuals;
  const auto p = J.cols();
  const std::size_t groups = group_of_row.empty() ? 0 : *std::max_element(group_of_row.begin(), group_of_row.end()) + 1;
  GroupNormalEquations sums{std::vector<Eigen::MatrixXd>(groups, Eigen::MatrixXd::Zero(p, p)),
                            std::vector<Eigen::VectorXd>(groups, Eigen::VectorXd::Zero(p)), Eigen::MatrixXd::Zero(p, p)};
  // By stretches of consecutive rows of one group: a rank-k update each (BLAS-3 speed).
  for (std::size_t first = 0; first < group_of_row.size();) {
    std::size_t last = first + 1;
    while (last < group_of_row.size() && group_of_row[last] == group_of_row[first]) ++last;
    const auto start = static_cast<Eigen::Index>(first), length = static_cast<Eigen::Index>(last - first);
    const std::size_t g = group_of_row[first];
    sums.H[g].selfadjointView<Eigen::Lower>().rankUpdate(J.middleRows(start, length).transpose());
    sums.b[g].noalias() += J.middleRows(start, length).transpose() * r.segment(start, length);
    first = last;
  }
  for (auto& h : sums.H) {
    h = h.selfadjointView<Eigen::Lower>();
    sums.total += h;
  }
  return sums;
}

Eigen::VectorXd leave_group_out_step(const GroupNormalEquations& sums, std::size_t g, const std::vector<bool>& held,
                                     bool* undetermined) {
  std::vector<Eigen::Index> free;
  for (std::size_t j = 0; j < held.size(); ++j)
    if (!held[j]) free.push_back(static_cast<Eigen::Index>(j));
  const auto m = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd A(m, m);
  Eigen::VectorXd b(m);
  for (Eigen::Index a = 0; a < m; ++a) {
    b[a] = sums.b[g][free[static_cast<std::size_t>(a)]];
    for (Eigen::Index c = 0; c < m; ++c)
      A(a, c) = sums.total(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(c)]) -
                sums.H[g](free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(c)]);
  }
  // The other groups may leave a direction undetermined (a load only the held-out run has):
  // the matrix without g is then singular, and its solve an arbitrary step (10^5 N held-out
  // errors on 2 N data). With the columns scaled to unit diagonal of the whole, an eigenvalue
  // below kUndetermined of the largest is such a direction (legitimate designs measured here
  // stay above 1e-5; singular ones fall to rounding, 1e-15). The step is then taken in the
  // determined directions only: the undetermined ones stay at the full fit's estimate.
  constexpr double kUndetermined = 1e-9;
  Eigen::VectorXd scale(m);
  for (Eigen::Index a = 0; a < m; ++a) {
    const double d = sums.total(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(a)]);
    scale[a] = d > 0 ? 1 / std::sqrt(d) : 1.0;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scale.asDiagonal() * A * scale.asDiagonal());
  const Eigen::VectorXd& lambda = eigen.eigenvalues();  // ascending
  const bool singular = m > 0 && !(lambda[0] > kUndetermined * lambda[m - 1]);
  if (undetermined) *undetermined = singular;
  Eigen::VectorXd step;
  if (!singular) {
    step = A.ldlt().solve(b);
  } else {
    Eigen::VectorXd inverse = Eigen::VectorXd::Zero(m);
    for (Eigen::Index k = 0; k < m; ++k)
      if (lambda[k] > kUndetermined * lambda[m - 1]) inverse[k] = 1 / lambda[k];
    const Eigen::MatrixXd& V = eigen.eigenvectors();
    step = scale.asDiagonal() * (V * inverse.asDiagonal() * V.transpose() * (scale.asDiagonal() * b));
  }
  Eigen::VectorXd out = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(held.size()));
  for (Eigen::Index a = 0; a < m; ++a) out[free[static_cast<std::size_t>(a)]] = step[a];
  return out;
}

Eigen::VectorXd leave_group_out_residuals(const FinalState& state, const std::vector<std::size_t>& group_of_row,
                                          const std::vector<bool>& held, std::vector<std::size_t>* undetermined) {
  const GroupNormalEquations sums = group_normal_equations(state, group_of_row);
  Eigen::VectorXd out = state.residuals;
  std::vector<Eigen::VectorXd> step(sums.H.size());
  for (std::size_t g = 0; g < step.size(); ++g) {
    bool alone = false;
    step[g] = leave_group_out_step(sums, g, held, &alone);
    if (alone && undetermined) undetermined->push_back(g);
  }
  for (Eigen::Index i = 0; i < out.size(); ++i) out[i] += state.jacobian.row(i).dot(step[group_of_row[static_cast<std::size_t>(i)]]);
  return out;
}

}  // namespace lmcal::detail
