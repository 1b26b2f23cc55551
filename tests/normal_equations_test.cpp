// The friction fit's fast path (issue 16): the published law's closed-form gradient, the
// normal equations accumulated row by row (centred within runs), and the Levenberg-Marquardt
// that solves them — each against what it replaces (Jets, the stored Jacobian, Ceres).
#include <ceres/cost_function.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <optional>
#include <cstdlib>
#include <string>
#include <memory>
#include <vector>

#include "fit/batched_autodiff.hpp"
#include "fit/friction_model.hpp"
#include "fit/friction_residual.hpp"
#include "lmcal/rig/virtual_rig.hpp"
#include "support/finite_differences.hpp"

namespace lmcal {
namespace {

FrictionLog small_log(int runs, double run_offset_N) {
  FrictionRigConfig c;
  c.guides = {"SRG 25C", "SRN 35C"};
  c.velocity_m_s = {0.002, 0.005, 0.01, 0.02, 0.04, 0.066, 0.11};
  c.temperature_C = {22, 30, 40};
  c.runs = runs;
  c.run_offset_N = run_offset_N;
  c.seed = 21;
  return generate_friction_log(c, {}).log;
}

detail::FrictionData all_samples(const FrictionLog& log, std::size_t every = 1) {
  detail::FrictionData data{&log, {}, {}, 40.0};
  for (std::size_t i = 0; i < log.size(); i += every) {
    data.samples.push_back(i);
    data.inv_sigma.push_back(1 / 0.15);
  }
  return data;
}

const std::vector<double> kTheta = {0.31, 0.031, 1.5, 0.0152, 0.00301, 0.0668, 0.0291};

// The published law through Jets: the same functor with its closed form hidden.
struct JetsOnly {
  detail::FrictionResidual<false> f;
  template <typename T>
  auto prepare(const T* theta) const {
    return f.prepare(theta);
  }
  template <typename T>
  T operator()(typename detail::FrictionResidual<false>::template Prepared<T>& p, std::size_t row) const {
    return f(p, row);
  }
};

// J and r of a cost function at θ (row-major J).
void evaluate(const ceres::CostFunction& cost, const std::vector<double>& theta, Eigen::VectorXd& r,
              Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& J) {
  r.resize(cost.num_residuals());
  J.resize(cost.num_residuals(), static_cast<Eigen::Index>(theta.size()));
  const double* parameters[] = {theta.data()};
  double* jacobians[] = {J.data()};
  ASSERT_TRUE(cost.Evaluate(parameters, r.data(), jacobians));
}

TEST(NormalEquations, ClosedFormGradientEqualsJetsAndFiniteDifferences) {
  const FrictionLog log = small_log(1, 0);
  const detail::FrictionData data = all_samples(log, 5);
  for (const auto& loss : {detail::RowLoss{}, detail::RowLoss{RobustLoss::huber, 1.345}, detail::RowLoss{RobustLoss::cauchy, 2.0}}) {
    const detail::FrictionModel model(data, {});
    const auto closed = model.cost_function({}, loss);
    test::expect_jacobian_matches_central_differences(*closed, kTheta, 1e-6, 1e-6);
    const detail::BatchedAutoDiffCostFunction<JetsOnly> jets(JetsOnly{{&data, {}, {}}}, 7, data.samples.size(), loss);
    Eigen::VectorXd r1, r2, r0(closed->num_residuals());
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J1, J2;
    evaluate(*closed, kTheta, r1, J1);
    evaluate(jets, kTheta, r2, J2);
    const double* parameters[] = {kTheta.data()};
    ASSERT_TRUE(closed->Evaluate(parameters, r0.data(), nullptr));
    if (loss.kind == RobustLoss::none) {
      EXPECT_EQ(r1, r0) << "the residuals agree to the last bit with the residual-only evaluation";
    }
    EXPECT_LE((r1 - r0).norm(), 1e-15 * r0.norm());
    EXPECT_LE((r1 - r2).norm(), 1e-14 * r2.norm());
    for (Eigen::Index j = 0; j < 7; ++j)
      EXPECT_LE((J1.col(j) - J2.col(j)).norm(), 1e-12 * J2.col(j).norm()) << "column " << j;
  }
}

// JᵀJ, Jᵀr and ½‖r‖² accumulated row by row equal those of the stored (centred) Jacobian:
// no offsets, a profiled offset per run, a random one (shrunk), and runs whose rows
// interleave. Each run's load is constant (one setup per run), so k1's column is constant
// within a run and its centred sums must come out 0, not rounding noise.
TEST(NormalEquations, AccumulatedRowByRowEqualTheStoredJacobians) {
  FrictionLog log = small_log(4, 0.5);
  for (std::size_t i = 0; i < log.size(); ++i) log.load_N[i] = 500.0 + 250.0 * log.run[i];
  const std::size_t runs = log.run_names.size();
  for (int variant = 0; variant < 4; ++variant) {
    detail::FrictionData data = all_samples(log);
    if (variant == 1) data.run_shrink.assign(runs, 1.0);
    if (variant >= 2)
      for (std::size_t r = 0; r < runs; ++r) data.run_shrink.push_back(0.3 + 0.15 * static_cast<double>(r));
    if (variant == 3)  // the runs' rows interleaved: every run in several chunks
      std::sort(data.samples.begin(), data.samples.end(), [&](std::size_t a, std::size_t b) {
        return std::make_pair(a % 97, a) < std::make_pair(b % 97, b);
      });
    const detail::FrictionModel model(data, {});
    const auto cost = model.cost_function({}, {});
    const auto* normal = dynamic_cast<const detail::NormalEquationsCost*>(cost.get());
    ASSERT_NE(normal, nullptr);
    Eigen::VectorXd r;
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J;
    evaluate(*cost, kTheta, r, J);
    double f = 0;
    Eigen::MatrixXd JtJ;
    Eigen::VectorXd Jtr;
    ASSERT_TRUE(normal->normal_equations(kTheta.data(), {}, f, JtJ, Jtr));
    const Eigen::MatrixXd expected = J.transpose() * J;
    const Eigen::VectorXd expected_g = J.transpose() * r;
    EXPECT_NEAR(f, 0.5 * r.squaredNorm(), 1e-11 * f) << "variant " << variant;
    for (Eigen::Index a = 0; a < 7; ++a) {
      EXPECT_NEAR(Jtr[a], expected_g[a], 1e-9 * std::sqrt(expected.diagonal().maxCoeff() * 2 * f)) << variant << ": " << a;
      for (Eigen::Index b = 0; b < 7; ++b)
        EXPECT_NEAR(JtJ(a, b), expected(a, b),
                    1e-10 * std::sqrt(expected(a, a) * expected(b, b)) + 1e-14 * expected.diagonal().maxCoeff())
            << variant << ": " << a << "," << b;
    }
    if (variant == 1) {
      EXPECT_EQ(JtJ(0, 0), 0.0) << "k1 is constant within every run: centred away exactly";
    }
  }
}

// The covariance from the information matrix (a well-conditioned J) equals the one from a QR
// of J to 1e-8 (CovarianceEqualsCeresCovariance checks the rank-deficient QR path).
TEST(NormalEquations, CovarianceFromTheInformationMatrixEqualsTheQr) {
  auto from_qr = [](const Eigen::MatrixXd& J) {
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(J);
    const auto m = J.cols();
    const Eigen::MatrixXd R = qr.matrixR().topLeftCorner(m, m).triangularView<Eigen::Upper>();
    const Eigen::MatrixXd Rinv = R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(m, m));
    return Eigen::MatrixXd(qr.colsPermutation() * (Rinv * Rinv.transpose()) * qr.colsPermutation().transpose());
  };
  const FrictionLog log = small_log(2, 0);
  const detail::FrictionData data = all_samples(log);
  const detail::FrictionModel model(data, {});
  Eigen::MatrixXd friction;
  detail::evaluate_residuals(model, kTheta, {}, &friction);
  std::srand(3);
  for (const Eigen::MatrixXd& J : {friction, Eigen::MatrixXd(Eigen::MatrixXd::Random(5000, 6))}) {
    Eigen::MatrixXd ours;
    std::string message;
    ASSERT_TRUE(detail::covariance_from_jacobian(J, std::vector<bool>(static_cast<std::size_t>(J.cols()), false), ours, message))
        << message;
    const Eigen::MatrixXd reference = from_qr(J);
    for (Eigen::Index a = 0; a < J.cols(); ++a)
      for (Eigen::Index b = 0; b < J.cols(); ++b)
        EXPECT_NEAR(ours(a, b), reference(a, b), 1e-8 * std::sqrt(reference(a, a) * reference(b, b))) << a << "," << b;
  }
}

// A model that hides the normal equations: the engine polishes it with Ceres.
class CeresOnly final : public detail::LeastSquaresModel {
 public:
  explicit CeresOnly(const detail::FrictionModel& model) : model_(model) {}
  std::size_t num_residuals() const override { return model_.num_residuals(); }
  std::unique_ptr<ceres::CostFunction> cost_function(const std::vector<std::size_t>& rows,
                                                     const detail::RowLoss& loss) const override {
    struct Wrapped final : ceres::CostFunction {
      std::unique_ptr<ceres::CostFunction> inner;
      explicit Wrapped(std::unique_ptr<ceres::CostFunction> c) : inner(std::move(c)) {
        *mutable_parameter_block_sizes() = inner->parameter_block_sizes();
        set_num_residuals(inner->num_residuals());
      }
      bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
        return inner->Evaluate(parameters, residuals, jacobians);
      }
    };
    return std::make_unique<Wrapped>(model_.cost_function(rows, loss));
  }
  std::vector<IdentifiabilityIssue> design_issues(const std::vector<std::string>& free) const override {
    return model_.design_issues(free);
  }
  detail::RowStructure row_structure() const override { return model_.row_structure(); }

 private:
  const detail::FrictionModel& model_;
};

// The same minimum as Ceres' Levenberg-Marquardt, to far below the standard errors, with
// and without a profiled offset per run, from the paper's constants and from a start on a
// bound.
TEST(NormalEquations, LevenbergMarquardtReachesCeresMinimum) {
  const FrictionLog log = small_log(3, 0.4);
  for (const bool offsets : {false, true}) {
    detail::FrictionData data = all_samples(log);
    if (offsets) data.run_shrink.assign(log.run_names.size(), 1.0);
    const detail::FrictionModel model(data, {});
    const CeresOnly ceres_only(model);
    std::vector<detail::ParameterSpec> specs;
    const char* names[] = {"k1", "k2", "mu_st", "v_st_m_s", "mu_v", "beta_per_K", "f0"};
    const double lower[] = {0, 0, 0, 0.001, 0, 0, 0}, upper[] = {2, 0.2, 10, 0.2, 0.05, 0.3, 1};
    for (std::size_t j = 0; j < 7; ++j) specs.push_back({names[j], "", kTheta[j] * 0.8, lower[j], upper[j], true});
    specs[1].start = 0;  // on its bound
    FitOptions options;
    options.starts = 0;
    options.bootstrap = 0;
    options.profile = ProfileMode::none;
    const FitResult ours = detail::solve_least_squares(model, specs, options);
    const FitResult theirs = detail::solve_least_squares(ceres_only, specs, options);
    ASSERT_TRUE(ours.solver.converged) << ours.solver.brief;
    ASSERT_TRUE(theirs.solver.converged) << theirs.solver.brief;
    EXPECT_NE(ours.solver.brief.find("normal equations"), std::string::npos);
    EXPECT_NEAR(ours.solver.final_cost, theirs.solver.final_cost, 1e-9 * theirs.solver.final_cost);
    for (std::size_t j = 0; j < 7; ++j) {
      EXPECT_NEAR(ours.parameters[j].value, theirs.parameters[j].value, 1e-3 * theirs.parameters[j].se) << names[j];
      EXPECT_NEAR(ours.parameters[j].se, theirs.parameters[j].se, 1e-5 * theirs.parameters[j].se) << names[j];
    }
  }
}

}  // namespace
}  // namespace lmcal

namespace lmcal {
namespace {

// A pass sums its rows in parts of fixed size, each on its own, merged in row order
// (CentredSums::append): the parts' merge equals the sums of all rows at once, wherever the
// seams fall (inside a group's stretch or at its edge), and a column constant within a group
// stays exactly 0 once centred.
TEST(NormalEquations, SumsMergedFromPartsEqualTheSumsOfAllRows) {
  const std::size_t n = 3000, size = 4;
  std::vector<std::size_t> group(n);
  std::vector<std::array<double, 4>> rows(n);
  std::srand(7);
  for (std::size_t i = 0; i < n; ++i) {
    group[i] = (i / 350) % 5;  // stretches of 350 rows, groups recurring
    const double noise = static_cast<double>(std::rand()) / RAND_MAX - 0.5;
    rows[i] = {250.0 + 125.0 * static_cast<double>(group[i]), 1e3 + 0.1 * static_cast<double>(i) + noise, noise,
               3.0 * noise + 1e-3 * static_cast<double>(i)};
  }
  const std::vector<double> shrink{1.0, 0.4, 1.0, 0.7, 0.2};
  detail::CentredSums whole(static_cast<Eigen::Index>(size));
  for (std::size_t i = 0; i < n; ++i) whole.add(group[i], rows[i].data());
  const Eigen::MatrixXd expected = whole.finish(shrink);
  for (const auto& seams : {std::vector<std::size_t>{1000, 2000}, {350, 700, 1050}, {1, 2999}, {173, 1777, 2501}}) {
    std::optional<detail::CentredSums> merged;
    std::size_t begin = 0;
    for (std::size_t k = 0; k <= seams.size(); ++k) {
      const std::size_t end = k < seams.size() ? seams[k] : n;
      detail::CentredSums part(static_cast<Eigen::Index>(size));
      for (std::size_t i = begin; i < end; ++i) part.add(group[i], rows[i].data());
      if (merged) merged->append(std::move(part));
      else merged.emplace(std::move(part));
      begin = end;
    }
    const Eigen::MatrixXd got = merged->finish(shrink);
    for (Eigen::Index a = 0; a < 4; ++a)
      for (Eigen::Index b = 0; b < 4; ++b)
        EXPECT_NEAR(got(a, b), expected(a, b), 1e-11 * std::sqrt(expected(a, a) * expected(b, b)) + 1e-12)
            << "seams at " << seams.front() << "…: " << a << "," << b;
    EXPECT_EQ(merged->finish(std::vector<double>(5, 1.0))(0, 0), 0.0) << "constant within each group: exactly 0 centred";
  }
}

}  // namespace
}  // namespace lmcal
