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

#include <array>
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
  BatchedAutoDiffCostFunction(RowFunctor functor, int num_parameters, std::size_t rows, RowLoss loss = {})
      : functor_(std::move(functor)), rows_(rows), loss_(loss) {
    LMCAL_ASSERT(num_parameters >= 1 && num_parameters <= 16, "1 to 16 parameters");
    mutable_parameter_block_sizes()->push_back(num_parameters);
    set_num_residuals(static_cast<int>(rows));
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const double* theta = parameters[0];
    if (jacobians == nullptr || jacobians[0] == nullptr) {
      auto prepared = functor_.prepare(theta);
      for (std::size_t i = 0; i < rows_; ++i) {
        residuals[i] = robust_residual(functor_(prepared, i), loss_);
        if (!std::isfinite(residuals[i])) return false;
      }
      return true;
    }
    return parameter_block_sizes()[0] <= 8 ? evaluate_jets<8>(theta, residuals, jacobians[0])
                                           : evaluate_jets<16>(theta, residuals, jacobians[0]);
  }

 private:
  template <int N>
  bool evaluate_jets(const double* theta, double* residuals, double* jacobian) const {
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

  RowFunctor functor_;
  std::size_t rows_;
  RowLoss loss_;
};

}  // namespace lmcal::detail
