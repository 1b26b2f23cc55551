// Private arithmetic of the sequential designs (plan.cc, plan_thermal.cc): the covariance of an
// information matrix, regularised where the data determine a direction not at all; and the
// summaries' line of a planned parameter.
#pragma once

#include <Eigen/Dense>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "lmcal/predict/plan.hpp"

namespace lmcal::detail {

// (info + ridge·I)⁻¹.
inline Eigen::MatrixXd ridge_inverse(const Eigen::MatrixXd& info, double ridge) {
  const auto k = info.rows();
  return (info + ridge * Eigen::MatrixXd::Identity(k, k)).ldlt().solve(Eigen::MatrixXd::Identity(k, k));
}

// The variances of the parameters `subset` with the others held at their values (the inverse
// of the information of the subset alone: what a fit that held the others quoted), and the
// joint ones of ridge_inverse(info) for the others.
inline Eigen::VectorXd variances_holding_others(const Eigen::MatrixXd& info, const std::vector<Eigen::Index>& subset,
                                                double ridge) {
  Eigen::VectorXd v = ridge_inverse(info, ridge).diagonal();
  if (subset.empty() || static_cast<Eigen::Index>(subset.size()) == info.rows()) return v;
  const auto d = static_cast<Eigen::Index>(subset.size());
  Eigen::MatrixXd sub(d, d);
  for (Eigen::Index a = 0; a < d; ++a)
    for (Eigen::Index b = 0; b < d; ++b) sub(a, b) = info(subset[a], subset[b]);
  const Eigen::MatrixXd sub_cov = ridge_inverse(sub, ridge);
  for (Eigen::Index a = 0; a < d; ++a) v(subset[a]) = sub_cov(a, a);
  return v;
}

// The rows and columns `subset` of `a`.
inline Eigen::MatrixXd submatrix(const Eigen::MatrixXd& a, const std::vector<Eigen::Index>& subset) {
  const auto d = static_cast<Eigen::Index>(subset.size());
  Eigen::MatrixXd s(d, d);
  for (Eigen::Index i = 0; i < d; ++i)
    for (Eigen::Index j = 0; j < d; ++j) s(i, j) = a(subset[static_cast<std::size_t>(i)], subset[static_cast<std::size_t>(j)]);
  return s;
}

// The covariance of the parameters `subset` with the others held (the inverse of their
// information), computed on the information's unit-diagonal (correlation) form, where a ridge
// of 1e-12 touches only what is collinear whatever the parameters' scales; and per parameter the
// share of its information that the others of the subset do not explain (1 − R²: ~0 where the
// data determine it only with another, a direction they do not determine at all).
struct SubsetCovariance {
  Eigen::MatrixXd covariance;
  Eigen::VectorXd unexplained;
};
inline SubsetCovariance subset_covariance(const Eigen::MatrixXd& info, const std::vector<Eigen::Index>& subset) {
  const Eigen::MatrixXd s = submatrix(info, subset);
  const Eigen::VectorXd d = s.diagonal().unaryExpr([](double v) { return v > 0 ? 1 / std::sqrt(v) : 0.0; });
  const Eigen::MatrixXd r_inverse = ridge_inverse(d.asDiagonal() * s * d.asDiagonal(), 1e-12);
  return {d.asDiagonal() * r_inverse * d.asDiagonal(), r_inverse.diagonal().cwiseInverse()};
}

// "  k1      0.01439 -> 0.01439     -": a parameter's expected standard error now and after the
// plan, in its unit ("-" for a dimensionless one), `note` after. An SE the data do not give is
// "n/a" with the reason: not determined yet, or only with another held (now), still not
// determined (after).
inline std::string expected_se_line(const PlannedParameter& p, std::string_view note = "") {
  const auto se = [](double v, const std::string& why) {
    return std::isfinite(v) ? fmt::format("{:.4g}", v) : fmt::format("n/a ({})", why);
  };
  const std::string now = p.held_now.empty() ? "not determined yet" : fmt::format("only with {} held", fmt::join(p.held_now, ", "));
  return fmt::format("  {:<22} {:>11} -> {:<11} {}{}\n", p.name, se(p.se_before, now), se(p.se_after, "still not determined"),
                     p.unit.empty() || p.unit == "1" ? "-" : p.unit, note);
}

}  // namespace lmcal::detail
