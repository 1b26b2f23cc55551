// Step 4 of every fit: the covariance of the estimates by every method the rows' structure
// allows, the one that fits the data, and the intervals from it (see fit_result.hpp for the
// methods and covariance/covariance.hpp for their formulas).
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "least_squares.hpp"
#include "lmcal/fit/statistics.hpp"

namespace lmcal {

const CovarianceSummary* Uncertainty::find(const std::string& name) const {
  for (const auto& m : methods)
    if (m.method == name) return &m;
  return nullptr;
}

namespace detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The free parameters' part of the final state (the Jacobian copied only when a parameter
// is held: a 10⁵-row copy is a good share of a fit's time).
struct FreeView {
  std::vector<Eigen::Index> free;
  Eigen::MatrixXd own_jacobian, bread;
  const Eigen::MatrixXd* jacobian = nullptr;
};

FreeView free_view(const FinalState& state) {
  FreeView v;
  for (std::size_t j = 0; j < state.held.size(); ++j)
    if (!state.held[j]) v.free.push_back(static_cast<Eigen::Index>(j));
  const auto m = static_cast<Eigen::Index>(v.free.size());
  v.bread.resize(m, m);
  const bool all_free = m == state.jacobian.cols();
  if (!all_free) v.own_jacobian.resize(state.jacobian.rows(), m);
  for (Eigen::Index a = 0; a < m; ++a) {
    if (!all_free) v.own_jacobian.col(a) = state.jacobian.col(v.free[a]);
    for (Eigen::Index b = 0; b < m; ++b) v.bread(a, b) = state.bread(v.free[a], v.free[b]);
  }
  v.jacobian = all_free ? &state.jacobian : &v.own_jacobian;
  return v;
}

Eigen::MatrixXd expand(const Eigen::MatrixXd& free_covariance, const FreeView& v, std::size_t p) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(p));
  for (std::size_t a = 0; a < v.free.size(); ++a)
    for (std::size_t b = 0; b < v.free.size(); ++b)
      out(v.free[a], v.free[b]) = free_covariance(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
  return out;
}

Eigen::MatrixXd restrict_to_free(const Eigen::MatrixXd& full, const FreeView& v) {
  const auto m = static_cast<Eigen::Index>(v.free.size());
  Eigen::MatrixXd out(m, m);
  for (Eigen::Index a = 0; a < m; ++a)
    for (Eigen::Index b = 0; b < m; ++b) out(a, b) = full(v.free[a], v.free[b]);
  return out;
}

CovarianceSummary summary_of(const CovarianceEstimate& e, const FreeView& v, std::size_t p) {
  CovarianceSummary s{e.method, e.description, e.note, e.ok, e.dof, std::vector<double>(p, kNaN)};
  for (std::size_t a = 0; a < v.free.size(); ++a) {
    const double variance = e.covariance(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(a));
    s.se[static_cast<std::size_t>(v.free[a])] = variance >= 0 ? std::sqrt(variance) : kNaN;
  }
  return s;
}

// Holm's step-down adjustment over the parameters tested.
std::vector<RunHeterogeneity> holm(const std::vector<HeterogeneityTest>& tests, const FreeView& v,
                                   const std::vector<ParameterEstimate>& parameters, double level) {
  std::vector<RunHeterogeneity> out;
  std::vector<double> p;
  for (const auto& t : tests) {
    out.push_back({parameters[static_cast<std::size_t>(v.free[t.parameter])].name, t.runs, t.q, t.p_value, 1, t.i_squared, false});
    p.push_back(t.p_value);
  }
  const std::vector<double> adjusted = holm_adjust(p);
  for (std::size_t k = 0; k < out.size(); ++k) {
    out[k].p_holm = adjusted[k];
    out[k].significant = adjusted[k] < level;
  }
  return out;
}

// The cluster covariance with each SE raised to at least the within-run (HAC) one: D V D,
// D = diag(max(1, se_hac/se_cluster)), which keeps the correlations. With few runs the
// cluster estimate is noisy and can fall below what the noise within the runs alone implies.
CovarianceEstimate floored(CovarianceEstimate cluster, const CovarianceEstimate& hac) {
  const auto m = cluster.covariance.rows();
  Eigen::VectorXd d(m);
  for (Eigen::Index j = 0; j < m; ++j) {
    const double c = cluster.covariance(j, j), h = hac.covariance(j, j);
    d[j] = c > 0 && h > c ? std::sqrt(h / c) : 1.0;
  }
  cluster.covariance = d.asDiagonal() * cluster.covariance * d.asDiagonal();
  return cluster;
}

std::string strongest_disagreement(const std::vector<RunHeterogeneity>& tests) {
  std::string out;
  for (const auto& h : tests)
    if (h.significant)
      out += fmt::format("{}{} (Q = {:.3g} on {} runs, Holm {}, I² = {:.0f} %)", out.empty() ? "" : ", ", h.parameter,
                         h.q, h.runs, p_is(h.p_holm), 100 * h.i_squared);
  return out;
}

struct Choice {
  CovarianceEstimate estimate;
  std::string reason;
};

Choice choose(const FitOptions& o, const Uncertainty& u, const CovarianceEstimate& iid, const CovarianceEstimate* hac,
              const CovarianceEstimate* cluster, const CovarianceEstimate* bootstrap) {
  const std::string disagree = strongest_disagreement(u.heterogeneity);
  switch (o.covariance) {
    case CovarianceMethod::iid: return {iid, "asked for"};
    case CovarianceMethod::hac:
      if (hac) return {*hac, "asked for"};
      break;
    case CovarianceMethod::cluster:
      if (cluster && cluster->ok) return {*cluster, "asked for"};
      break;
    case CovarianceMethod::bootstrap:
      if (bootstrap && bootstrap->ok) return {*bootstrap, "asked for"};
      break;
    case CovarianceMethod::automatic: break;
  }
  if (!hac) return {iid, "the model knows no run or time structure of its rows: independent residuals assumed"};
  if (!disagree.empty() && cluster && cluster->ok && u.runs >= 3)
    return {floored(*cluster, *hac),
            fmt::format("the runs disagree beyond their own noise about {}: cluster-robust by run (t with {} dof), "
                        "each SE at least the within-run (HAC) one",
                        disagree, u.runs - 1)};
  if (o.runs_replicate && cluster && cluster->ok && u.runs >= 3)
    return {floored(*cluster, *hac),
            fmt::format("the runs are the replicates (what differs between runs unseen, such as the heat reaching the rail, "
                        "is in no run's own residuals; the test between runs finds no significant difference, but with {} "
                        "runs it has little power): cluster-robust by run (t with {} dof), each SE at least the within-run "
                        "(HAC) one",
                        u.runs, u.runs - 1)};
  std::string reason = fmt::format("residuals within runs have lag-1 autocorrelation {:.2f} ({:.0f} effective independent rows): "
                       "Newey-West within runs",
                       u.lag1_autocorrelation, u.effective_sample_size);
  if (!disagree.empty())
    reason += fmt::format("; the runs disagree about {}, but {} runs are too few for a cluster method: that spread is NOT "
                          "in the intervals",
                          disagree, u.runs);
  else if (u.runs >= 2)
    reason += "; no run disagrees with the others beyond that within-run noise";
  if (o.runs_replicate && u.runs < 3)
    reason += fmt::format("; what differs between runs unseen (such as the heat reaching the rail) needs at least 3 runs to "
                          "be measured: with {} it is NOT in the intervals",
                          u.runs);
  return {*hac, reason};
}

void set_intervals(FitResult& result, const Eigen::MatrixXd& covariance, const std::vector<double>& dof, double confidence) {
  const auto p = static_cast<Eigen::Index>(result.parameters.size());
  result.covariance = covariance;
  result.correlation = Eigen::MatrixXd::Constant(p, p, kNaN);
  for (Eigen::Index i = 0; i < p; ++i)
    for (Eigen::Index j = 0; j < p; ++j) {
      const double d = covariance(i, i) * covariance(j, j);
      if (d > 0) result.correlation(i, j) = covariance(i, j) / std::sqrt(d);
    }
  for (Eigen::Index j = 0; j < p; ++j) {
    ParameterEstimate& e = result.parameters[static_cast<std::size_t>(j)];
    if (e.interval == "none") continue;
    e.se = covariance(j, j) >= 0 ? std::sqrt(covariance(j, j)) : kNaN;
    e.dof = dof[static_cast<std::size_t>(j)];
    const double t = e.dof > 0 ? student_t_quantile(1 - (1 - confidence) / 2, std::min(e.dof, 1e7)) : kNaN;
    e.ci_low = e.value - t * e.se;
    e.ci_high = e.value + t * e.se;
  }
}

// Percentile intervals of θ̂ + (θ* − θ̂) over the replicates that determined the parameter.
void set_bootstrap(FitResult& result, const Eigen::MatrixXd& draws, const FreeView& v, double confidence) {
  const auto p = static_cast<Eigen::Index>(result.parameters.size());
  Eigen::MatrixXd full = Eigen::MatrixXd::Constant(draws.rows(), p, kNaN);
  for (std::size_t a = 0; a < v.free.size(); ++a) {
    full.col(v.free[a]) = draws.col(static_cast<Eigen::Index>(a));
    std::vector<double> d;
    for (Eigen::Index b = 0; b < draws.rows(); ++b)
      if (!std::isnan(draws(b, static_cast<Eigen::Index>(a)))) d.push_back(draws(b, static_cast<Eigen::Index>(a)));
    if (d.size() < 10) continue;
    std::sort(d.begin(), d.end());
    auto quantile = [&](double q) {
      const double x = q * static_cast<double>(d.size() - 1);
      const auto k = static_cast<std::size_t>(std::floor(x));
      return k + 1 < d.size() ? d[k] + (x - static_cast<double>(k)) * (d[k + 1] - d[k]) : d[k];
    };
    ParameterEstimate& e = result.parameters[static_cast<std::size_t>(v.free[a])];
    e.boot_low = e.value + quantile((1 - confidence) / 2);
    e.boot_high = e.value + quantile(1 - (1 - confidence) / 2);
  }
  result.uncertainty.bootstrap_draws = std::move(full);
}

void replace_method(Uncertainty& u, CovarianceSummary s) {
  for (auto& m : u.methods)
    if (m.method == s.method) {
      m = std::move(s);
      return;
    }
  u.methods.push_back(std::move(s));
}

}  // namespace

void assess_uncertainty(const RowStructure& rows, const FitOptions& o, const FinalState& state, FitResult& result) {
  const std::size_t p = result.parameters.size();
  Uncertainty& u = result.uncertainty;
  u = {};
  u.runs = rows.clusters;
  u.lag1_autocorrelation = residual_lag1_autocorrelation(state.residuals, rows);
  u.effective_sample_size = effective_sample_size(static_cast<double>(state.residuals.size()), u.lag1_autocorrelation);
  u.hac_lags = kNaN;
  u.dof = result.dof;
  const FreeView v = free_view(state);
  if (v.free.empty() || !state.covariance_ok) {
    u.method = "none";
    u.reason = v.free.empty() ? "no free parameters" : "the covariance failed: " + state.covariance_message;
    set_intervals(result, Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(p), kNaN),
                  std::vector<double>(p, kNaN), o.confidence);
    return;
  }
  const ScoreInputs in{*v.jacobian, state.residuals, v.bread, rows};
  const CovarianceEstimate iid = iid_covariance(in);
  u.methods.push_back(summary_of(iid, v, p));
  std::optional<CovarianceEstimate> hac, cluster;
  std::optional<BootstrapResult> bootstrap;
  if (!rows.empty()) {
    hac = hac_covariance(in);
    u.hac_lags = hac->bandwidth;
    u.methods.push_back(summary_of(*hac, v, p));
    if (rows.clusters >= 2) {
      cluster = cluster_covariance(in);
      u.methods.push_back(summary_of(*cluster, v, p));
      u.heterogeneity = holm(between_run_heterogeneity(in, *hac), v, result.parameters, o.heterogeneity_p);
      if (o.bootstrap > 0) {
        bootstrap = cluster_bootstrap(in, o.bootstrap, o.seed);
        u.methods.push_back(summary_of(bootstrap->estimate, v, p));
      }
    }
    if (rows.clusters < 3)
      u.notes.push_back(fmt::format("{} run{}: too few for a cluster method (at least 3); the within-run sandwich is quoted",
                                    rows.clusters, rows.clusters == 1 ? "" : "s"));
  }
  const Choice chosen = choose(o, u, iid, hac ? &*hac : nullptr, cluster ? &*cluster : nullptr,
                               bootstrap ? &bootstrap->estimate : nullptr);
  u.method = chosen.estimate.method;
  u.reason = chosen.reason;
  u.dof = chosen.estimate.dof;
  if (!chosen.estimate.note.empty() && chosen.estimate.method != "iid") u.notes.push_back(chosen.estimate.note);
  if (bootstrap) set_bootstrap(result, bootstrap->draws, v, o.confidence);
  set_intervals(result, expand(chosen.estimate.covariance, v, p), std::vector<double>(p, chosen.estimate.dof), o.confidence);
}

void add_input_uncertainty(const RowStructure& rows, const FitOptions& o, const FinalState& state,
                           const Eigen::MatrixXd& input_jacobian, const Eigen::MatrixXd& input_covariance,
                           const std::vector<Eigen::VectorXd>* draws, const std::string& label, FitResult& result) {
  const std::size_t p = result.parameters.size();
  const FreeView v = free_view(state);
  if (v.free.empty() || !state.covariance_ok || !result.covariance.allFinite()) return;
  const Eigen::MatrixXd D = -v.bread * (v.jacobian->transpose() * input_jacobian);  // m × q
  const Eigen::MatrixXd added = D * input_covariance * D.transpose();
  const Eigen::MatrixXd before = restrict_to_free(result.covariance, v);
  const Eigen::MatrixXd total = before + added;
  Uncertainty& u = result.uncertainty;
  u.input = label;
  u.covariance_given_input = expand(before, v, p);
  u.input_variance_share.assign(p, kNaN);
  std::vector<double> dof(p, kNaN);
  CovarianceSummary alone{label, fmt::format("the {}'s own uncertainty carried into the estimates (delta method)", label),
                          "", true, std::numeric_limits<double>::infinity(), std::vector<double>(p, kNaN)};
  for (std::size_t a = 0; a < v.free.size(); ++a) {
    const auto j = static_cast<std::size_t>(v.free[a]);
    const auto k = static_cast<Eigen::Index>(a);
    const double v1 = before(k, k), v2 = added(k, k), nu1 = result.parameters[j].dof;
    u.input_variance_share[j] = v1 + v2 > 0 ? v2 / (v1 + v2) : kNaN;
    dof[j] = v1 > 0 ? std::min(1e7, (v1 + v2) * (v1 + v2) / (v1 * v1 / nu1)) : 1e7;  // Welch-Satterthwaite, ν₂ = ∞
    alone.se[j] = std::sqrt(std::max(v2, 0.0));
  }
  replace_method(u, alone);
  CovarianceEstimate combined{u.method + " + " + label, "", total, u.dof, true, "", kNaN};
  combined.description = fmt::format("the quoted covariance ({}) plus the {}'s (delta method), t dof by Welch-Satterthwaite",
                                     u.method, label);
  replace_method(u, summary_of(combined, v, p));

  // The bootstrap over both stages: each replicate also draws the input (its own replicates
  // when given, else normal draws from its covariance).
  if (o.bootstrap > 0 && rows.clusters >= 2) {
    std::vector<Eigen::VectorXd> own;
    if (!draws || draws->empty()) {
      // A square root of Σ_u that also serves a singular one (one error common to all runs):
      // V diag(√λ₊).
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(input_covariance);
      const Eigen::MatrixXd L = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
      own = standard_normal_draws(o.bootstrap, input_covariance.rows(), o.seed ^ 0x5eedULL);
      for (auto& z : own) z = L * z;
      draws = &own;
    }
    const ScoreInputs in{*v.jacobian, state.residuals, v.bread, rows};
    BootstrapResult both = cluster_bootstrap(in, o.bootstrap, o.seed, &input_jacobian, draws);
    both.estimate.description += fmt::format(" (both stages: the {} redrawn in every replicate)", label);
    replace_method(u, summary_of(both.estimate, v, p));
    set_bootstrap(result, both.draws, v, o.confidence);
  }
  u.method = combined.method;
  u.reason += fmt::format("; the {}'s uncertainty added (delta method)", label);
  set_intervals(result, expand(total, v, p), dof, o.confidence);
}

}  // namespace detail
}  // namespace lmcal
