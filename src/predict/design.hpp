// Private arithmetic of the sequential designs (plan.cc, plan_thermal.cc): the covariance of an
// information matrix, regularised where the data determine a direction not at all; and the
// summaries' line of a planned parameter.
#pragma once

#include <Eigen/Dense>
#include <fmt/format.h>

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

// "  k1      0.01439 -> 0.01439     -": a parameter's expected standard error now and after the
// plan, in its unit ("-" for a dimensionless one), `note` after. An SE the data do not give is
// "n/a" with the reason: not determined yet (now), still not determined (after).
inline std::string expected_se_line(const PlannedParameter& p, std::string_view note = "") {
  const auto se = [](double v, const char* why) {
    return std::isfinite(v) ? fmt::format("{:.4g}", v) : fmt::format("n/a ({})", why);
  };
  return fmt::format("  {:<22} {:>11} -> {:<11} {}{}\n", p.name, se(p.se_before, "not determined yet"),
                     se(p.se_after, "still not determined"), p.unit.empty() || p.unit == "1" ? "-" : p.unit, note);
}

}  // namespace lmcal::detail
