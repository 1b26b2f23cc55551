#include "run_scale.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "lmcal/fit/statistics.hpp"

namespace lmcal::detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct RunFactor {
  double u = kNaN, se = kNaN;
  double zero = kNaN;  // a: the run's residual at a model force of 0 (its zero, the factor apart)
};

// r = a + u·F + e within one run, by least squares; u's SE widened for the residuals' lag-1
// autocorrelation (rows in log order, which is time order within a run).
RunFactor run_factor(const std::vector<std::size_t>& rows, const std::vector<double>& residual_N,
                     const std::vector<double>& model_N) {
  RunFactor out;
  const double n = static_cast<double>(rows.size());
  if (rows.size() < 4) return out;
  double mean_F = 0, mean_r = 0;
  for (std::size_t i : rows) mean_F += model_N[i], mean_r += residual_N[i];
  mean_F /= n, mean_r /= n;
  double sxx = 0, sxy = 0;
  for (std::size_t i : rows) {
    sxx += (model_N[i] - mean_F) * (model_N[i] - mean_F);
    sxy += (model_N[i] - mean_F) * (residual_N[i] - mean_r);
  }
  if (!(sxx > 1e-12 * n * (mean_F * mean_F + 1))) return out;  // the force does not vary within the run
  out.u = sxy / sxx;
  out.zero = mean_r - out.u * mean_F;
  std::vector<double> e;
  for (std::size_t i : rows) e.push_back(residual_N[i] - mean_r - out.u * (model_N[i] - mean_F));
  double ss = 0, lag = 0;
  for (std::size_t k = 0; k < e.size(); ++k) {
    ss += e[k] * e[k];
    if (k > 0) lag += e[k] * e[k - 1];
  }
  // The lag-1 autocorrelation of a short demeaned series is biased low by about (1 + 3ρ)/n
  // (Marriott & Pope 1954): corrected, or a 20-row run would look far less correlated than it is.
  const double raw = ss > 0 ? lag / ss : 0.0;
  const double rho = std::clamp(raw + (1 + 3 * raw) / n, 0.0, 0.95);
  out.se = std::sqrt(ss / (n - 2) / sxx * (1 + rho) / (1 - rho));
  return out;
}

}  // namespace

RunScaleTest test_run_scale(const FrictionLog& log, const std::vector<double>& residual_N, const std::vector<double>& model_N,
                            double lrt_p) {
  RunScaleTest t;
  std::vector<std::vector<std::size_t>> rows(log.run_names.size());
  for (std::size_t i = 0; i < log.size(); ++i) rows[log.run[i]].push_back(i);
  std::vector<RunFactor> factors;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const RunFactor f = run_factor(rows[r], residual_N, model_N);
    if (std::isfinite(f.u) && f.se > 0) {
      factors.push_back(f);
      t.run.push_back(log.run_names[r]);
      t.factor_percent.push_back(100 * f.u);
      t.se_percent.push_back(100 * f.se);
    }
  }
  t.runs = factors.size();
  if (factors.size() < 3) {
    t.reason = "fewer than 3 runs whose model force varies within the run";
    return t;
  }
  double sw = 0, sw2 = 0, swu = 0;
  for (const RunFactor& f : factors) {
    const double w = 1 / (f.se * f.se);
    sw += w, sw2 += w * w, swu += w * f.u;
  }
  const double mean = swu / sw;
  double q = 0;
  for (const RunFactor& f : factors) q += (f.u - mean) * (f.u - mean) / (f.se * f.se);
  t.tested = true;
  t.q = q;
  t.dof = static_cast<double>(factors.size() - 1);
  t.p = chi_squared_upper_p(q, t.dof);
  t.tau_percent = 100 * std::sqrt(std::max(0.0, (q - t.dof) / (sw - sw2 / sw)));
  // A factor changes a run's level by τ·F̄: where that is within the spread of the runs' zeros
  // (their residual at a force of 0, the factor apart), the runs are not told apart by it.
  double mean_F = 0, zero_mean = 0, zero_ss = 0;
  for (double F : model_N) mean_F += std::abs(F) / static_cast<double>(model_N.size());
  for (const RunFactor& f : factors) zero_mean += f.zero / static_cast<double>(factors.size());
  for (const RunFactor& f : factors) zero_ss += (f.zero - zero_mean) * (f.zero - zero_mean);
  const double zero_sd_N = std::sqrt(zero_ss / static_cast<double>(factors.size() - 1));
  t.floor_percent = mean_F > 0 ? 100 * zero_sd_N / mean_F : 0.0;
  t.differ = t.p < lrt_p && t.tau_percent > t.floor_percent;
  t.reason = fmt::format("Cochran's Q = {:.3g} on {:.0f} dof, {}; spread of the runs' factors beyond their SEs "
                         "tau = {:.3g} % of the friction (DerSimonian-Laird), against {:.3g} % that the runs' zeros "
                         "spread (their SD {:.3g} N at a force of 0, over a mean force of {:.3g} N)",
                         q, t.dof, p_is(t.p), t.tau_percent, t.floor_percent, zero_sd_N, mean_F);
  return t;
}

}  // namespace lmcal::detail
