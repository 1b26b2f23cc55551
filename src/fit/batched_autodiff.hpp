// A Ceres cost function over many independent rows, r_i = f(θ, i), differentiated
// automatically with ceres::Jet. Unlike ceres::AutoDiffCostFunction over all rows, it
// evaluates the functor row by row and writes each row's derivatives straight into the
// Jacobian: no array of output Jets, so a 10⁵-row fit stays within cache and time.
//
// The functor has two templated members — the same model code serves double (residuals
// only) and Jet (Jacobian):
//   template <typename T> Prepared<T> prepare(const T* theta) const;   // once per evaluation
//   template <typename T> T operator()(Prepared<T>& prepared, std::size_t row) const;
// `prepare` turns θ into the model's parameter structs once, so the row loop does not
// rebuild them (for Jets that copying is a large part of the cost).
// Up to 8 parameters use Jet<double, 8>, up to 16 Jet<double, 16>.
#pragma once

#include <ceres/cost_function.h>
#include <ceres/jet.h>

#include <algorithm>
#include <array>
#include <vector>
#include <cmath>
#include <cstddef>
#include <utility>

#include "lmcal/error.hpp"
#include "lmcal/fit/fit_result.hpp"

namespace lmcal::detail {

// A robust loss applied row by row: r̃ = r · sqrt(ρ(r²) / r²), so that Σ r̃² = Σ ρ(r²) and a
// plain least-squares solver (Ceres, NLopt) minimises the robust cost of every row on its
// own. (A ceres::LossFunction on a batched block would act on the block's total instead.)
//   Huber:  ρ(s) = s for s <= δ², 2δ√s - δ² beyond;   Cauchy: ρ(s) = δ² ln(1 + s/δ²).
struct RowLoss {
  RobustLoss kind = RobustLoss::none;
  double scale = 1.0;  // δ, in units of the (whitened) residual
};

template <typename T>
T robust_residual(const T& r, const RowLoss& loss) {
  using std::abs;
  using std::log1p;
  using std::sqrt;
  const double d = loss.scale;
  switch (loss.kind) {
    case RobustLoss::none: return r;
    case RobustLoss::huber:
      if (abs(r) <= d) return r;
      return r * sqrt(2.0 * d / abs(r) - d * d / (r * r));
    case RobustLoss::cauchy: {
      const T s = r * r;
      if (s == 0.0) return r;
      return r * sqrt(d * d * log1p(s / (d * d)) / s);
    }
  }
  return r;
}

template <typename RowFunctor>
class BatchedAutoDiffCostFunction final : public ceres::CostFunction {
 public:
  // `groups` (one id per row, optional): residuals and their derivatives are centred within
  // each group, r_i - c_g · mean_g(r), which profiles out one free offset per group (c_g = 1,
  // e.g. a load cell's zero per run) or whitens a random one (c_g = 1 - 1/sqrt(1 + n_g λ) for
  // an offset of variance λ σ²: generalised least squares). `shrink` holds c_g per group
  // (empty: 1 for all). Not combined with a robust loss.
  BatchedAutoDiffCostFunction(RowFunctor functor, int num_parameters, std::size_t rows, RowLoss loss = {},
                              std::vector<std::size_t> groups = {}, std::vector<double> shrink = {})
      : functor_(std::move(functor)), rows_(rows), loss_(loss), groups_(std::move(groups)), shrink_(std::move(shrink)) {
    LMCAL_ASSERT(groups_.empty() || (groups_.size() == rows && loss.kind == RobustLoss::none),
                 "group centring needs one group per row and no robust loss");
    LMCAL_ASSERT(num_parameters >= 1 && num_parameters <= 16, "1 to 16 parameters");
    mutable_parameter_block_sizes()->push_back(num_parameters);
    set_num_residuals(static_cast<int>(rows));
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const double* theta = parameters[0];
    bool ok = true;
    if (jacobians == nullptr || jacobians[0] == nullptr) {
      auto prepared = functor_.prepare(theta);
      for (std::size_t i = 0; i < rows_ && ok; ++i) {
        residuals[i] = robust_residual(functor_(prepared, i), loss_);
        ok = std::isfinite(residuals[i]);
      }
    } else {
      ok = parameter_block_sizes()[0] <= 8 ? evaluate_jets<8>(theta, residuals, jacobians[0])
                                           : evaluate_jets<16>(theta, residuals, jacobians[0]);
    }
    if (ok && !groups_.empty()) centre(residuals, jacobians ? jacobians[0] : nullptr);
    return ok;
  }

 private:
  // Flattened: GCC otherwise leaves Eigen's Jet assignments out of line in the row loop (a
  // call per Jet operation); inlined, the 100 k-sample diagnosis's Jet<16> fits run 1.5x faster.
  template <int N>
  [[gnu::flatten]] bool evaluate_jets(const double* theta, double* residuals, double* jacobian) const {
    using Jet = ceres::Jet<double, N>;
    const int p = parameter_block_sizes()[0];
    std::array<Jet, N> t;
    for (int j = 0; j < p; ++j) t[j] = Jet(theta[j], j);
    auto prepared = functor_.prepare(t.data());
    for (std::size_t i = 0; i < rows_; ++i) {
      const Jet r = robust_residual(functor_(prepared, i), loss_);
      residuals[i] = r.a;
      double* row = jacobian + i * static_cast<std::size_t>(p);
      for (int j = 0; j < p; ++j) row[j] = r.v[j];
      if (!std::isfinite(r.a)) return false;
    }
    return true;
  }

  void centre(double* residuals, double* jacobian) const {
    const std::size_t p = static_cast<std::size_t>(parameter_block_sizes()[0]);
    const std::size_t groups = *std::max_element(groups_.begin(), groups_.end()) + 1;
    std::vector<double> sum(groups * (p + 1), 0.0), count(groups, 0.0);
    for (std::size_t i = 0; i < rows_; ++i) {
      double* s = &sum[groups_[i] * (p + 1)];
      s[0] += residuals[i];
      for (std::size_t j = 0; jacobian && j < p; ++j) s[j + 1] += jacobian[i * p + j];
      count[groups_[i]] += 1;
    }
    for (std::size_t i = 0; i < rows_; ++i) {
      const double* s = &sum[groups_[i] * (p + 1)];
      const double c = (shrink_.empty() ? 1.0 : shrink_[groups_[i]]) / count[groups_[i]];
      residuals[i] -= c * s[0];
      for (std::size_t j = 0; jacobian && j < p; ++j) jacobian[i * p + j] -= c * s[j + 1];
    }
  }

  RowFunctor functor_;
  std::size_t rows_;
  RowLoss loss_;
  std::vector<std::size_t> groups_;
  std::vector<double> shrink_;
};

}  // namespace lmcal::detail
