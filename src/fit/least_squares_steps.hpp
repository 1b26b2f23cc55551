// The steps of solve_least_squares (least_squares.cc), shared by the engine's files only:
// the polish (least_squares_polish.cc, on row-by-row normal equations in
// least_squares_normal_equations.cc), the multi-start (least_squares_multistart.cc), steps 1-3
// with the identifiability rounds (least_squares_estimate.cc) and the profile intervals
// (least_squares_profile.cc).
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "least_squares.hpp"

namespace lmcal::detail::engine {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// One Ceres solve over a fixed cost function, held parameters constant.
struct Polish {
  std::vector<double> theta;
  ceres::Solver::Summary summary;
  std::string brief;          // one line: solver, iterations, costs, termination
  Eigen::VectorXd residuals;  // at theta, when known (linear solve)
};

// The tolerances of every polish (Ceres' and the normal equations' alike).
constexpr double kFunctionTolerance = 1e-10, kGradientTolerance = 1e-10, kParameterTolerance = 1e-9;

// Levenberg-Marquardt on the normal equations `normal` accumulates row by row, `cost` being
// the same cost function (for the cost at a trial step).
Polish solve_normal_equations(const NormalEquationsCost& normal, const ceres::CostFunction& cost,
                              const std::vector<ParameterSpec>& specs, const std::vector<bool>& held,
                              std::vector<double> theta, bool bounded, int max_iterations);

// The polish from `theta` (Ceres, or the normal equations where the cost accumulates them),
// inside the bounds.
Polish polish(const ceres::CostFunction& cost, const std::vector<ParameterSpec>& specs, const std::vector<bool>& held,
              const std::vector<double>& theta, int max_iterations = 200);

// For a model linear in its free parameters: the exact solution in one Gauss-Newton step
// (the polish where it leaves the bounds). Fills J.
Polish linear_solve(const LeastSquaresModel& model, const ceres::CostFunction& cost,
                    const std::vector<ParameterSpec>& specs, const std::vector<bool>& held, std::vector<double> theta,
                    const RowLoss& loss, Eigen::MatrixXd& J);

// Where the starts of step 1 ended.
struct MultiStart {
  std::vector<double> best;
  int starts = 0, agreed = 0;
  std::vector<double> costs;               // where each start ended, in start order
  std::vector<std::vector<double>> ends;   // and at which parameters
  std::size_t rows = 0;                    // residuals the searches used
};

// Step 1: `options.starts` local searches on a subsample of the rows, from `start` and from a
// Halton sequence over the bounds.
MultiStart multi_start(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs,
                       const std::vector<bool>& held, const std::vector<double>& start, const FitOptions& options);

// Steps 1-3 and how they ended.
struct Estimate {
  FinalState state;
  Polish fit;
  MultiStart starts;
  double remaining_step = 0;   // at the end, in SEs: see remaining_step()
  bool stopped_short = false;  // and a step along it lowers the cost: no minimum
  bool restarted = false;      // the polish stopped short of a minimum and was run again from the best start
};

// A step still to go above this many standard errors is no minimum, if taking it (or half, or a
// quarter of it) lowers the cost by more than a hundredth of what one SE is worth (½ s²): where
// the model is strongly nonlinear the quadratic model's step may not, and the polish did stop
// at a minimum.
constexpr double kStationary = 0.1;

// Steps 1-3: multi-start, polish, and the covariance at the solution; a direction the data
// cannot determine is held and the rest refitted, until every direction is determined.
Estimate estimate(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs, const FitOptions& options,
                  std::vector<bool> held, Identifiability& identifiability);

// Step 5: profile-likelihood intervals where the linear interval is unreliable (or everywhere,
// if asked).
void profile_intervals(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs, const FitOptions& options,
                       const FinalState& state, double final_cost, FitResult& result);

inline double relative_scale(const ParameterSpec& spec, double value) {
  // A typical size (effects neutral at 0): relative to it, or to the value where that is
  // larger — an effect estimated at 8 typical sizes with an SE of 2 is determined.
  if (spec.scale > 0) return std::max(spec.scale, std::abs(value));
  const double s = std::max(std::abs(value), std::abs(spec.start));
  return s > 0 ? s : 0.1 * (spec.upper - spec.lower);
}

inline std::vector<std::size_t> free_indices(const std::vector<bool>& held) {
  std::vector<std::size_t> free;
  for (std::size_t j = 0; j < held.size(); ++j)
    if (!held[j]) free.push_back(j);
  return free;
}

}  // namespace lmcal::detail::engine
