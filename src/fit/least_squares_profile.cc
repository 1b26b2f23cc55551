// Step 5 of a fit: profile-likelihood intervals, each side found by doubling steps and
// bisection over refits with the parameter held.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "least_squares_steps.hpp"
#include "lmcal/fit/statistics.hpp"

namespace lmcal::detail::engine {

namespace {

// Refits a profile search may spend on one side of one parameter.
constexpr int kMaxProfileFits = 24;

}  // namespace

// Step 5: profile-likelihood intervals where the linear interval is unreliable (or everywhere,
// if asked): {θ_j : S(θ_j) − S_min <= k_j · ½ s² F(conf; 1, dof)}, k_j = max(1, chosen / iid
// variance of θ_j), so that the profile widens as the chosen covariance does.
void profile_intervals(const LeastSquaresModel& model, const std::vector<ParameterSpec>& specs, const FitOptions& options,
                       const FinalState& state, double final_cost, FitResult& result) {
  if (options.profile == ProfileMode::none || !(result.dof > 0) || result.free_parameters <= 1) return;
  const auto cost = model.cost_function({}, RowLoss{options.loss, options.loss_scale});
  const double s2 = result.residual_variance;
  const double base_threshold = 0.5 * s2 * fisher_f_quantile(options.confidence, 1, result.dof);
  const double t = student_t_quantile(1 - (1 - options.confidence) / 2, std::min(result.dof, 1e7));
  const CovarianceSummary* iid = result.uncertainty.find("iid");
  // A model linear in its parameters has a profile that is the linear interval: only a bound
  // inside the interval makes it differ.
  const bool linear = model.linear(state.held) && options.loss == RobustLoss::none;
  for (std::size_t j = 0; j < specs.size(); ++j) {
    ParameterEstimate& e = result.parameters[j];
    if (state.held[j]) continue;
    const bool truncated = e.at_bound || e.ci_low < e.lower || e.ci_high > e.upper;
    const bool unreliable = truncated || (!linear && (!std::isfinite(e.se) || e.se > 0.3 * relative_scale(specs[j], e.value)));
    // A run's nuisance parameter (an offset, a start temperature) is not quoted: `auto` spends no
    // refits on its profile.
    if (options.profile == ProfileMode::automatic && (!unreliable || specs[j].per_run)) continue;
    const double iid_se = iid ? iid->se[j] : kNaN;
    const double inflation = std::isfinite(e.se) && iid_se > 0 ? std::max(1.0, std::pow(e.se / iid_se, 2)) : 1.0;
    const double threshold = base_threshold * inflation;
    std::vector<bool> held_j = state.held;
    held_j[j] = true;
    auto excess = [&](double value) {
      std::vector<double> th = state.theta;
      th[j] = value;
      const double x = polish(*cost, specs, held_j, th).summary.final_cost - final_cost;
      e.profile_curve.push_back({value, x / threshold});
      return x;
    };
    // Each side in at most kMaxProfileFits refits (each a whole fit: minutes for a large thermal
    // model otherwise): doubling steps out from the estimate until the cost rises past the
    // threshold, then bisection to 1e-3 of the bracket. NaN: the side did not close.
    auto bound_side = [&](double direction) {
      const double limit = direction > 0 ? specs[j].upper : specs[j].lower;
      double step = std::isfinite(e.se) && e.se > 0 ? t * e.se : 0.1 * (specs[j].upper - specs[j].lower);
      double inside = e.value;
      int fits = 0;
      while (fits < kMaxProfileFits) {
        const double trial = std::clamp(e.value + direction * step, specs[j].lower, specs[j].upper);
        ++fits;
        if (excess(trial) > threshold) {
          double a = inside, b = trial;  // a inside, b outside: bisect
          while (fits < kMaxProfileFits && std::abs(b - a) > 1e-3 * std::abs(trial - e.value)) {
            const double mid = 0.5 * (a + b);
            ++fits;
            (excess(mid) > threshold ? b : a) = mid;
          }
          return 0.5 * (a + b);
        }
        if (trial == limit) return limit;
        inside = trial;
        step *= 2;
      }
      return kNaN;
    };
    e.profile_curve = {{e.value, 0.0}};
    e.profile_low = bound_side(-1);
    e.profile_high = bound_side(+1);
    if (!std::isfinite(e.profile_low) || !std::isfinite(e.profile_high)) {
      result.warnings.push_back(fmt::format("the profile of {} did not close within {} refits a side: its {} interval is quoted",
                                            e.name, kMaxProfileFits, e.interval));
      e.profile_low = e.profile_high = kNaN;
      e.profile_curve.clear();
      continue;
    }
    // The search crowds its points at the edges; half-way in and a half beyond draw the shape.
    for (const double edge : {e.profile_low, e.profile_high}) {
      excess(e.value + 0.5 * (edge - e.value));
      const double beyond = std::clamp(e.value + 1.5 * (edge - e.value), specs[j].lower, specs[j].upper);
      if (beyond != edge) excess(beyond);
    }
    std::sort(e.profile_curve.begin(), e.profile_curve.end(), [](const ProfilePoint& a, const ProfilePoint& b) { return a.value < b.value; });
    e.interval = "profile";
  }
}

}  // namespace lmcal::detail::engine
