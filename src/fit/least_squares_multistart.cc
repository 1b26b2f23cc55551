// Step 1, the multi-start: local searches on a subsample of the rows, from the given start and
// from a Halton sequence over the bounds, side by side where the model's cost allows: the
// polish's Levenberg-Marquardt where the cost accumulates normal equations, else bounded L-BFGS
// (NLopt).
#include <fmt/format.h>
#include <nlopt.hpp>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "least_squares_steps.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"
#include "parallel_slices.hpp"

namespace lmcal::detail::engine {

namespace {

// NLopt objective ½ Σ r² over a (sub)set of rows, in scaled free coordinates u = θ / scale.
struct LocalSearch {
  const ceres::CostFunction* cost;
  std::vector<double> full;
  std::vector<int> free;
  std::vector<double> scale;
  Eigen::VectorXd r;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J;

  static double objective(unsigned n, const double* u, double* grad, void* data) {
    auto& s = *static_cast<LocalSearch*>(data);
    for (unsigned k = 0; k < n; ++k) s.full[s.free[k]] = u[k] * s.scale[k];
    const double* parameters[] = {s.full.data()};
    double* jacobians[] = {s.J.data()};
    if (!s.cost->Evaluate(parameters, s.r.data(), grad ? jacobians : nullptr) || !s.r.allFinite())
      return std::numeric_limits<double>::max();
    if (grad) {
      const Eigen::VectorXd g = s.J.transpose() * s.r;
      for (unsigned k = 0; k < n; ++k) grad[k] = g[s.free[k]] * s.scale[k];
    }
    return 0.5 * s.r.squaredNorm();
  }
};

double radical_inverse(std::uint64_t index, unsigned base) {
  double result = 0, f = 1.0 / base;
  while (index > 0) {
    result += f * static_cast<double>(index % base);
    index /= base;
    f /= base;
  }
  return result;
}

// The k-th start: Halton point over the bounds (log-uniform where the bounds span > 100x).
std::vector<double> halton_start(const std::vector<ParameterSpec>& specs, const std::vector<bool>& held,
                                 const std::vector<double>& base, std::uint64_t index) {
  static constexpr unsigned kPrimes[] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53};
  std::vector<double> theta = base;
  std::size_t dim = 0;
  for (std::size_t j = 0; j < specs.size(); ++j) {
    if (held[j]) continue;
    const double h = radical_inverse(index, kPrimes[dim++ % std::size(kPrimes)]);
    const double lo = specs[j].lower, hi = specs[j].upper;
    theta[j] = lo > 0 && hi / lo > 100 ? lo * std::pow(hi / lo, h) : lo + h * (hi - lo);
  }
  return theta;
}

// A start's search ends here at the latest (L-BFGS: evaluations; Levenberg-Marquardt: iterations).
constexpr int kStartEvaluations = 250, kStartIterations = 100;

}  // namespace

MultiStart multi_start(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs,
                       const std::vector<bool>& held, const std::vector<double>& start, const FitOptions& options) {
  if (options.starts > io::kMaxStarts)
    throw InvalidParameter("starts", options.starts, fmt::format("at most {} (docs/formats.md#limits)", io::kMaxStarts));
  MultiStart out{start, 0, 0, {}, {}, 0};
  std::vector<int> free;
  for (std::size_t j = 0; j < specs.size(); ++j)
    if (!held[j]) free.push_back(static_cast<int>(j));
  if (free.empty() || options.starts < 1) return out;

  const std::size_t n = model.num_residuals();
  std::vector<std::size_t> rows;
  const std::size_t m = std::min(n, std::max<std::size_t>(options.subsample, 1));
  for (std::size_t k = 0; k < m; ++k) rows.push_back(k * n / m);  // evenly spread
  const auto cost = model.cost_function(rows, RowLoss{options.loss, options.loss_scale});

  std::vector<double> scale, lower, upper;
  for (int j : free) {
    scale.push_back(relative_scale(specs[j], start[j]));
    lower.push_back(specs[j].lower / scale.back());
    upper.push_back(specs[j].upper / scale.back());
  }

  // Each start's search on its own (its own buffers, its own NLopt object): side by side where
  // the model allows, and the same ends in the same order either way.
  std::vector<std::pair<double, std::vector<double>>> ends(static_cast<std::size_t>(options.starts));
  // A cost that accumulates its normal equations is searched by the polish's own
  // Levenberg-Marquardt, inside the bounds: a Gauss-Newton step per pass over the subsample, ~10
  // passes to a minimum where L-BFGS took ~150 (the starts of a 100 k-sample friction fit: 28 ms, then 5.5).
  const auto* normal = dynamic_cast<const NormalEquationsCost*>(cost.get());
  auto search_from = [&](std::size_t k) {
    std::vector<double> theta = k == 0 ? start : halton_start(specs, held, start, options.seed * 7919 + k);
    if (normal) {
      for (int j : free) theta[j] = std::clamp(theta[j], specs[j].lower, specs[j].upper);
      Polish end = solve_normal_equations(*normal, *cost, specs, held, std::move(theta), true, kStartIterations);
      ends[k] = {end.summary.final_cost, std::move(end.theta)};
      return;
    }
    LocalSearch search{cost.get(), theta, free, scale, Eigen::VectorXd(rows.size()), {}};
    search.J.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(specs.size()));
    std::vector<double> u;
    for (std::size_t i = 0; i < free.size(); ++i) u.push_back(std::clamp(theta[free[i]] / scale[i], lower[i], upper[i]));
    nlopt::opt opt(nlopt::LD_LBFGS, static_cast<unsigned>(free.size()));
    opt.set_lower_bounds(lower);
    opt.set_upper_bounds(upper);
    opt.set_min_objective(&LocalSearch::objective, &search);
    opt.set_ftol_rel(1e-10);
    opt.set_xtol_rel(1e-8);
    opt.set_maxeval(kStartEvaluations);
    double f = std::numeric_limits<double>::max();
    try {
      opt.optimize(u, f);
    } catch (const std::exception&) {
      // NLopt gives up on roundoff-limited or failed searches; keep the point it reached.
      f = LocalSearch::objective(static_cast<unsigned>(u.size()), u.data(), nullptr, &search);
    }
    for (std::size_t i = 0; i < free.size(); ++i) theta[free[i]] = u[i] * scale[i];
    ends[k] = {f, std::move(theta)};
  };
  if (model.costs_evaluate_concurrently()) {
    for_each_index(ends.size(), search_from);
  } else {
    for (std::size_t k = 0; k < ends.size(); ++k) search_from(k);
  }
  const auto best = std::min_element(ends.begin(), ends.end(), [](auto& a, auto& b) { return a.first < b.first; });
  out.best = best->second;
  out.starts = options.starts;
  out.rows = rows.size();
  for (const auto& [f, theta] : ends) {
    out.costs.push_back(f);
    out.ends.push_back(theta);
    if (f - best->first <= 1e-3 * std::abs(best->first) + 1e-12) ++out.agreed;
  }
  return out;
}

}  // namespace lmcal::detail::engine
