// The fit engine on models that cannot always be evaluated (issue 23 #2, #3, #8): a residual
// that is not finite, nothing free, nothing left to estimate the noise with. Each is a result
// that says why (usable = false with the reason) or a correct fit, never an abort.
#include <ceres/cost_function.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "fit/least_squares.hpp"

namespace lmcal {
namespace {

// y = a·x + b at x = 0..n-1; the residual is NaN where a > nan_above. Unless `a_seen`, the
// model leaves a out (a column of zeros). Linear where it is never NaN, or where it says so
// (`claims_linear`: the engine's linear path, which takes the start's residuals with its
// Jacobian).
class Line : public detail::LeastSquaresModel {
 public:
  Line(std::size_t n, double nan_above, bool a_seen = true, bool claims_linear = false)
      : n_(n), nan_above_(nan_above), a_seen_(a_seen), claims_linear_(claims_linear) {}
  std::size_t num_residuals() const override { return n_; }
  bool linear(const std::vector<bool>&) const override { return claims_linear_ || !std::isfinite(nan_above_); }
  std::unique_ptr<ceres::CostFunction> cost_function(const std::vector<std::size_t>& rows,
                                                     const detail::RowLoss&) const override {
    return std::make_unique<Cost>(rows.empty() ? all() : rows, nan_above_, a_seen_ ? 1.0 : 0.0);
  }

 private:
  class Cost : public ceres::CostFunction {
   public:
    Cost(std::vector<std::size_t> rows, double nan_above, double seen)
        : rows_(std::move(rows)), nan_above_(nan_above), seen_(seen) {
      set_num_residuals(static_cast<int>(rows_.size()));
      mutable_parameter_block_sizes()->push_back(2);
    }
    bool Evaluate(double const* const* p, double* r, double** J) const override {
      const double a = p[0][0], b = p[0][1];
      for (std::size_t k = 0; k < rows_.size(); ++k) {
        const auto x = static_cast<double>(rows_[k]);
        const double y = 2 * x + 1 + (k % 2 == 0 ? 0.1 : -0.1);
        r[k] = a > nan_above_ ? std::numeric_limits<double>::quiet_NaN() : seen_ * a * x + b - y;
        if (J && J[0]) {
          J[0][2 * k] = seen_ * x;
          J[0][2 * k + 1] = 1;
        }
      }
      return true;
    }

   private:
    std::vector<std::size_t> rows_;
    double nan_above_, seen_;
  };
  std::vector<std::size_t> all() const {
    std::vector<std::size_t> rows(n_);
    for (std::size_t i = 0; i < n_; ++i) rows[i] = i;
    return rows;
  }
  std::size_t n_;
  double nan_above_;
  bool a_seen_, claims_linear_;
};

std::vector<detail::ParameterSpec> specs(double a_start, bool free = true) {
  return {{"a", "", a_start, 0.1, 10, free, 1}, {"b", "", 0.5, -10, 10, free, 1}};
}

constexpr double kNever = std::numeric_limits<double>::infinity();

TEST(FitFailure, ALinearModelNotFiniteAtTheStartSaysSoToo) {
  // A linear model's start residuals come with its Jacobian (no residual pass of their own).
  const FitResult fit = detail::solve_least_squares(Line(20, 5, true, true), specs(6), {});
  EXPECT_FALSE(fit.solver.usable);
  EXPECT_NE(fit.solver.unusable_reason.find("the residuals are not finite: residual 1 of 20 is nan at the start values"),
            std::string::npos)
      << fit.solver.unusable_reason;
  EXPECT_EQ(fit.parameter("a").value, 6);
}

TEST(FitFailure, ResidualsNotFiniteAtTheStartAreAnUnusableResultThatSaysWhy) {
  // Was an abort: "internal error at least_squares.cc: residual evaluation failed".
  detail::FinalState state;
  const FitResult fit = detail::solve_least_squares(Line(20, 5), specs(6), {}, &state);
  EXPECT_FALSE(fit.solver.usable);
  EXPECT_FALSE(fit.solver.converged);
  EXPECT_EQ(fit.solver.termination, "FAILURE");
  EXPECT_NE(fit.solver.unusable_reason.find("the residuals are not finite: residual 1 of 20 is nan at the start values"),
            std::string::npos)
      << fit.solver.unusable_reason;
  ASSERT_EQ(fit.parameters.size(), 2u);
  EXPECT_EQ(fit.parameter("a").value, 6);  // the start, not an estimate
  EXPECT_TRUE(std::isnan(fit.parameter("a").se));
  EXPECT_EQ(fit.parameter("a").interval, "none");
  EXPECT_EQ(state.residuals.size(), 20);
  EXPECT_EQ(state.jacobian.rows(), 20);
  EXPECT_FALSE(fit.warnings.empty());
}

TEST(FitFailure, ResidualsNotFiniteInPartOfTheBoundsDoNotStopTheFitFindingTheMinimum) {
  // The multi-start's Halton points land beyond a = 5; those searches end there, the rest find a = 2.
  FitOptions options;
  options.starts = 8;
  const FitResult fit = detail::solve_least_squares(Line(20, 5), specs(1), options);
  EXPECT_TRUE(fit.solver.usable) << fit.solver.unusable_reason;
  EXPECT_NEAR(fit.parameter("a").value, 2, 0.01);
  EXPECT_NEAR(fit.parameter("b").value, 1, 0.1);
  EXPECT_LT(fit.parameter("a").ci_low, 2);
  EXPECT_GT(fit.parameter("a").ci_high, 2);
}

TEST(FitFailure, NothingFreeIsNoSolveAndAUsableEvaluation) {
  // A linear model with every parameter held reached a QR of a matrix without columns (SIGSEGV).
  detail::FinalState state;
  const FitResult fit = detail::solve_least_squares(Line(20, kNever), specs(2, false), {}, &state);
  EXPECT_TRUE(fit.solver.usable) << fit.solver.unusable_reason;
  EXPECT_EQ(fit.free_parameters, 0u);
  EXPECT_EQ(fit.dof, 20);
  EXPECT_EQ(fit.parameter("a").value, 2);
  EXPECT_NEAR(state.residuals.squaredNorm(), 10 * (0.6 * 0.6 + 0.4 * 0.4), 1e-9);  // b held at 0.5: -0.5 ∓ 0.1
}

// A linear model whose Jacobian has a column of zeros (a parameter the data do not see: α
// without heat) took the polish fallback, which left the residuals out, and the covariance
// read past them (SIGSEGV, issue 22).
TEST(FitFailure, AParameterTheDataDoNotSeeIsHeldAndTheRestFitted) {
  detail::FinalState state;
  const FitResult fit = detail::solve_least_squares(Line(20, kNever, /*a_seen=*/false), specs(1), {}, &state);
  EXPECT_TRUE(fit.solver.usable) << fit.solver.unusable_reason;
  EXPECT_TRUE(fit.parameter("a").held_unidentifiable);
  EXPECT_EQ(state.residuals.size(), 20);
  EXPECT_TRUE(std::isfinite(fit.parameter("b").se));
  EXPECT_GT(fit.parameter("b").se, 0);
}

TEST(FitFailure, NoDegreeOfFreedomLeftIsUnusable) {
  // Two points, two free constants: a fit through both, with nothing to estimate the noise by.
  const FitResult fit = detail::solve_least_squares(Line(2, kNever), specs(1), {});
  EXPECT_FALSE(fit.solver.usable);
  EXPECT_EQ(fit.solver.unusable_reason, "no degree of freedom left: 2 residuals for 2 free parameters");
  const FitResult three = detail::solve_least_squares(Line(3, kNever), specs(1), {});
  EXPECT_TRUE(three.solver.usable) << three.solver.unusable_reason;
}

}  // namespace
}  // namespace lmcal
