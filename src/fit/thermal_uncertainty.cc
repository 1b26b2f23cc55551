// The thermal fit's uncertainty beyond its own records: the heat's (two-stage: the friction
// fit's covariance through the law, or the manifest's stated uncertainty) and the runs taken
// as replicates of the global parameters.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "bounded_interval.hpp"
#include "thermal_prepared.hpp"

namespace lmcal {

using detail::PreparedRun;

namespace {

// ∂ ln Q_f(run) / ∂θ over the friction fit's parameters (central differences of the one law).
Eigen::RowVectorXd log_heat_gradient(const PreparedRun& run, const FitResult& friction) {
  const auto p = static_cast<Eigen::Index>(friction.parameters.size());
  Eigen::RowVectorXd g = Eigen::RowVectorXd::Zero(p);
  auto log_q = [&](std::size_t j, double value) {
    FrictionConstants<double> k = run.friction;
    FrictionEffects<double> e = run.friction_effects;
    if (double* law = find_law_parameter(k, e, friction.parameters[j].name)) *law = value;
    return std::log(heat_rate_with_effects_W(k, e, run.conditions));
  };
  for (std::size_t j = 0; j < friction.parameters.size(); ++j) {
    const ParameterEstimate& q = friction.parameters[j];
    if (!std::isfinite(q.se) || !(q.se > 0)) continue;
    const double h = 1e-3 * q.se;
    g[static_cast<Eigen::Index>(j)] = (log_q(j, q.value + h) - log_q(j, q.value - h)) / (2 * h);
  }
  return g;
}

}  // namespace

namespace detail {

HeatUncertainty heat_uncertainty(const std::vector<PreparedRun>& runs, const std::vector<RunInfo>& infos,
                                 const ThermalDataSet& data, const ThermalFitOptions& o) {
  const auto G = static_cast<Eigen::Index>(runs.size());
  HeatUncertainty h;
  h.covariance = Eigen::MatrixXd::Zero(G, G);
  std::vector<std::string> counted, missing;
  // Friction law: V₁ through ∇ ln Q_f, the replicates likewise.
  Eigen::MatrixXd gradient = Eigen::MatrixXd::Zero(G, o.friction_fit ? static_cast<Eigen::Index>(o.friction_fit->parameters.size()) : 0);
  // Measured mean friction: its stated uncertainty, one systematic error common to all runs.
  Eigen::VectorXd measured = Eigen::VectorXd::Zero(G);
  for (Eigen::Index r = 0; r < G; ++r) {
    const auto i = static_cast<std::size_t>(r);
    if (infos[i].heat_source == kMeasuredMeanFriction || infos[i].heat_source == kMeasuredStartFriction) {
      // Relative: a load cell's error is mostly its gain, the same for the start and the mean.
      const auto& run = data.runs[i];
      if (run.mean_friction_uncertainty_N) measured[r] = *run.mean_friction_uncertainty_N / *run.mean_friction_N;
      else missing.push_back(run.id + ": no mean_friction_uncertainty_N in the manifest");
    } else if (infos[i].heat_source == kGivenHeat) {
      // Relative at the largest given heat: a power meter's (or heater's) error is mostly its gain.
      const auto& run = data.runs[i];
      if (run.heat_rate_uncertainty_W) measured[r] = *run.heat_rate_uncertainty_W / given_heat_reference_W(run);
      else missing.push_back(run.id + ": no heat_rate_uncertainty_W in the manifest");
    } else if (o.friction_fit && o.friction_fit->covariance.allFinite()) {
      gradient.row(r) = log_heat_gradient(runs[i], *o.friction_fit);
    } else {
      missing.push_back(runs[i].id + (o.friction ? ": the friction fit's covariance is not known" : ": the paper's constants"));
    }
  }
  if (gradient.cols() > 0 && !gradient.isZero()) {
    h.covariance += gradient * o.friction_fit->covariance * gradient.transpose();
    counted.push_back("the friction fit's covariance through the law (delta method)");
    const Eigen::MatrixXd& d = o.friction_fit->uncertainty.bootstrap_draws;
    for (Eigen::Index b = 0; b < d.rows() && d.cols() == gradient.cols(); ++b)
      h.draws.push_back(gradient * d.row(b).transpose().unaryExpr([](double x) { return std::isnan(x) ? 0.0 : x; }));
  }
  if (!measured.isZero()) {
    h.covariance += measured * measured.transpose();
    counted.push_back("the measured friction's or given heat's stated uncertainty, as one systematic error of all runs");
    h.draws.clear();  // a mixture: the bootstrap draws from the covariance instead
  }
  h.description = fmt::format("{}", fmt::join(counted, "; "));
  if (!missing.empty()) h.missing = fmt::format("the heat's uncertainty is not counted for {}", fmt::join(missing, ", "));
  return h;
}

// A global parameter's variance as the runs make it (α above all: the heat reaching each rail
// has its own error, which no record of the run sees). The joint fit weighs each run by its
// information (1/SE² of the run's own i.i.d. fit): θ̂ ≈ Σ c_r θ_r, and θ_r = θ + u_r + e_r, where
// e_r is the run's own error (its quoted SE, without an error common to all runs) and u_r what
// differs between runs unseen by any record (τ, REML, of the per-run θ). So
// Var(θ̂) = Σ c_r² (SE_r² + τ²), plus what is common to all runs (the heat's stated
// uncertainty), with t(runs − 1). A cluster-robust covariance estimates the same, but with a
// few runs carrying most of the information it falls well short (α: SD/SE 1.8 at 8 runs).
// Replaces a parameter's SE (the correlations kept) only where it is larger than the quoted
// one; a parameter that some run's own fit did not estimate keeps the quoted one.
void widen_to_the_runs(ThermalFitResult& result, double confidence) {
  FitResult& joint = result.joint;
  const std::size_t runs = result.per_run.size();
  if (runs < 3 || joint.covariance.rows() == 0) return;
  Uncertainty& u = joint.uncertainty;
  std::vector<std::string> widened;
  for (std::size_t a = 0; a < joint.parameters.size(); ++a) {
    ParameterEstimate& p = joint.parameters[a];
    if (p.per_run || !p.free || p.held_unidentifiable || p.interval == "none") continue;
    std::vector<Estimate> estimates;
    std::vector<double> info, own;
    for (const FitResult& run : result.per_run) {
      std::size_t j = 0;
      while (j < run.parameters.size() && run.parameters[j].name != p.name) ++j;
      const CovarianceSummary* iid = run.uncertainty.find("iid");
      if (j == run.parameters.size() || run.parameters[j].held_unidentifiable || !iid || !(iid->se[j] > 0)) break;
      const ParameterEstimate& q = run.parameters[j];
      if (!std::isfinite(q.value) || !(q.se > 0)) break;
      const Eigen::MatrixXd& given = run.uncertainty.covariance_given_input;
      const auto k = static_cast<Eigen::Index>(j);
      own.push_back(given.rows() > k ? given(k, k) : q.se * q.se);
      info.push_back(1 / (iid->se[j] * iid->se[j]));
      estimates.push_back({q.value, q.se});
    }
    if (estimates.size() != runs) continue;
    const RandomEffects re = random_effects(estimates, confidence);
    if (!std::isfinite(re.tau)) continue;
    const double total_info = std::accumulate(info.begin(), info.end(), 0.0);
    double runs_variance = 0;
    for (std::size_t r = 0; r < runs; ++r) runs_variance += std::pow(info[r] / total_info, 2) * (own[r] + re.tau * re.tau);
    const auto ja = static_cast<Eigen::Index>(a);
    const double quoted = joint.covariance(ja, ja);
    const double given = u.covariance_given_input.rows() > ja ? u.covariance_given_input(ja, ja) : quoted;
    const double common = std::max(quoted - given, 0.0);  // the heat's stated, common uncertainty
    if (!(runs_variance > given) || !(quoted > 0)) continue;
    const double variance = runs_variance + common, dof = static_cast<double>(runs - 1);
    const double d = std::sqrt(variance / quoted);
    joint.covariance.row(ja) *= d;
    joint.covariance.col(ja) *= d;
    p.se = std::sqrt(variance);
    // Welch-Satterthwaite with the common part known (ν = ∞).
    p.dof = std::min(1e7, variance * variance / (runs_variance * runs_variance / dof));
    const double t = student_t_quantile(1 - (1 - confidence) / 2, p.dof);
    // Within the bounds (α below 0 is no heat partition): where the wider t interval would cross
    // one, on the log scale of the distance to it (logit between two), bounded_interval.hpp.
    const detail::BoundedInterval bounded = detail::bounded_interval(p.value, p.se, t, p.lower, p.upper);
    p.ci_low = bounded.low;
    p.ci_high = bounded.high;
    if (p.interval == "linear" && bounded.method != "linear") {
      p.interval = bounded.method;
      u.notes.push_back(fmt::format("{}'s interval on the {} scale of its distance to its bounds [{:.4g}, {:.4g}]: the t "
                                    "interval, [{:.4g}, {:.4g}], would cross one",
                                    p.name, bounded.method == "clipped" ? "linear" : bounded.method, p.lower, p.upper,
                                    p.value - t * p.se, p.value + t * p.se));
    }
    // A profile interval (a bound inside it) widens about the estimate by the same factor, and
    // stays within the bounds.
    if (p.interval == "profile") {
      if (std::isfinite(p.profile_low)) p.profile_low = std::max(p.lower, p.value - d * (p.value - p.profile_low));
      if (std::isfinite(p.profile_high)) p.profile_high = std::min(p.upper, p.value + d * (p.profile_high - p.value));
    }
    widened.push_back(fmt::format("{} {:.3g} (tau {:.3g}, t with {:.1f} dof)", p.name, p.se, re.tau, p.dof));
    u.from_replicates.push_back(p.name);
  }
  if (widened.empty()) return;  // (scaling a row and column keeps the correlations)
  u.reason += fmt::format("; the SE of {} from the runs as replicates (notes)", widened.size() == 1 ? "one parameter" : "some parameters");
  u.notes.push_back(fmt::format(
      "SEs from the runs as replicates, sqrt(sum c_r^2 (SE_r^2 + tau^2)) plus any uncertainty common to all runs (c_r: each "
      "run's share of the joint fit's information; tau: the spread of the {} runs' own estimates beyond their SEs, REML): {}; "
      "the others quote {}",
      runs, fmt::join(widened, "; "), u.method));
}

}  // namespace detail

}  // namespace lmcal
