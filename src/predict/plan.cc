// `lmcal plan friction`: sequential optimal design from the friction law's Jacobian (plan.hpp).

#include "lmcal/version.hpp"
#include "lmcal/predict/plan.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "lmcal/error.hpp"
#include "lmcal/io/csv_writer.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/models/friction_effects.hpp"
#include "predict/design.hpp"

namespace lmcal {

namespace {

// 3 significant digits: plateau speeds of a raw log differ in the last digits.
double rounded(double v) {
  if (v == 0 || !std::isfinite(v)) return v;
  const double scale = std::pow(10.0, 2 - std::floor(std::log10(std::abs(v))));
  return std::round(v * scale) / scale;
}

std::vector<double> distinct(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

// The law's parameters a plan is for: the constants and effects the fit was asked to fit.
struct Parameters {
  std::vector<std::size_t> index;  // into fit.parameters
  Eigen::VectorXd value, scale;    // at the estimates; the unit each is measured in
};

Parameters parameters_of(const FrictionFitResult& fit) {
  Parameters p;
  std::vector<double> values, scales;
  for (std::size_t j = 0; j < fit.fit.parameters.size(); ++j) {
    const ParameterEstimate& e = fit.fit.parameters[j];
    const bool law = find_friction_constant(e.name).has_value() || find_friction_effect(e.name).has_value();
    if (!e.free || e.per_run || !law) continue;
    p.index.push_back(j);
    values.push_back(e.value);
    // Its own size, or (near 0) a thousandth of its range: the step and the unit of the design.
    scales.push_back(std::max({std::abs(e.value), 1e-3 * (e.upper - e.lower), 1e-12}));
  }
  p.value = Eigen::Map<Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
  p.scale = Eigen::Map<Eigen::VectorXd>(scales.data(), static_cast<Eigen::Index>(scales.size()));
  return p;
}

// ∂F/∂(θ_j / scale_j) at one condition: central differences of the law with the fit's effects.
class Gradient {
 public:
  Gradient(const FrictionFitResult& fit, const Parameters& p) : fit_(fit), p_(p), base_(fit.constants()), effects_(fit.effects()) {}

  Eigen::VectorXd at(const FrictionConditions<double>& c, double viscosity40) const {
    Eigen::VectorXd g(p_.value.size());
    for (Eigen::Index j = 0; j < g.size(); ++j) {
      const double h = 1e-6 * p_.scale(j);
      g(j) = (force(c, viscosity40, j, h) - force(c, viscosity40, j, -h)) / (2 * h) * p_.scale(j);
    }
    return g;
  }

 private:
  double force(const FrictionConditions<double>& c, double viscosity40, Eigen::Index j, double step) const {
    FrictionConstants<double> k = base_;
    FrictionEffects<double> e = effects_;
    k.nu_ref_mm2_s = viscosity40;
    *find_law_parameter(k, e, fit_.fit.parameters[p_.index[static_cast<std::size_t>(j)]].name) = p_.value(j) + step;
    return friction_force_with_effects_N(k, e, c);
  }

  const FrictionFitResult& fit_;
  const Parameters& p_;
  FrictionConstants<double> base_;
  FrictionEffects<double> effects_;
};

// "k2 held at 0.03 1/um, beta_per_K at 0.067 1/K".
std::string held_values(const FrictionFitResult& fit, const std::vector<std::string>& names) {
  std::string out;
  for (const auto& name : names) {
    const ParameterEstimate& e = fit.fit.parameter(name);
    out += fmt::format("{}{} {}at {:.4g}{}", out.empty() ? "" : ", ", name, out.empty() ? "held " : "", e.value,
                       e.unit.empty() || e.unit == "1" ? "" : " " + e.unit);
  }
  return out;
}

// Notes naming the picks at a level the log lacks, proposed for a held constant
// (FrictionCandidate::proposed_for), and what for.
void proposed_picks(FrictionPlan& plan) {
  std::map<std::string, std::vector<std::size_t>> by_reason;
  for (std::size_t k = 0; k < plan.picks.size(); ++k)
    if (!plan.picks[k].candidate.proposed_for.empty()) by_reason[plan.picks[k].candidate.proposed_for].push_back(k + 1);
  for (const auto& [why, picks] : by_reason)
    plan.notes.push_back(fmt::format("{} {} {}; proposed because the logs lack it", picks.size() == 1 ? "pick" : "picks",
                                     fmt::join(picks, ", "), why));
}

// The position of `j` in `v`, or -1.
Eigen::Index position(const std::vector<Eigen::Index>& v, Eigen::Index j) {
  const auto at = std::find(v.begin(), v.end(), j);
  return at == v.end() ? -1 : at - v.begin();
}

// Below this share of its information not explained by the others (1 − R²), a constant is a
// direction the data do not determine at all (collinear), not merely a weak one.
constexpr double kCollinear = 1e-8;
// A constant held now moves the quoted estimate of another by B = ∂θ̂_d/∂θ_h (both relative to
// their sizes); above this, the parameter means another thing once the constant is estimated.
constexpr double kCoupled = 1e-3;

// The samples per planned condition that shrink an SE `ratio` times its goal to the goal, where
// the planned conditions alone determine it (its variance falls as 1/samples), rounded up to 10.
std::size_t samples_needed(std::size_t samples, double ratio) {
  return static_cast<std::size_t>(10 * std::ceil(static_cast<double>(samples) * ratio * ratio / 10));
}

// Each parameter's SE now -> after, like with like (plan.hpp): `info` and `info_after` the
// logs' information and with the planned conditions, relatively scaled; `determined` the
// parameters the fit quoted an SE of. Notes what stays undetermined and why.
std::vector<PlannedParameter> expected_standard_errors(const FrictionFitResult& fit, const Parameters& p,
                                                       const Eigen::MatrixXd& info, const Eigen::MatrixXd& info_after,
                                                       const std::vector<Eigen::Index>& determined, std::size_t samples,
                                                       std::vector<std::string>& notes) {
  const auto m = p.value.size();
  const auto estimate = [&](Eigen::Index j) -> const ParameterEstimate& { return fit.fit.parameters[p.index[static_cast<std::size_t>(j)]]; };
  // The constants held now that the planned conditions determine (an SE below the fit's
  // identifiability threshold of their size, estimated with all determined after).
  const double threshold = FitOptions{}.identifiability_threshold;
  std::vector<Eigen::Index> after = determined, freed;
  std::vector<double> relative_se(static_cast<std::size_t>(m), INFINITY);  // of a held one, after
  for (Eigen::Index h = 0; h < m; ++h) {
    if (position(determined, h) >= 0) continue;
    std::vector<Eigen::Index> with = after;
    with.push_back(h);
    const detail::SubsetCovariance c = detail::subset_covariance(info_after, with);
    const auto last = static_cast<Eigen::Index>(with.size()) - 1;
    if (c.unexplained(last) > kCollinear) relative_se[static_cast<std::size_t>(h)] = std::sqrt(std::max(c.covariance(last, last), 0.0));
    if (relative_se[static_cast<std::size_t>(h)] < threshold) {
      after.push_back(h);
      freed.push_back(h);
    }
  }
  // What the fit quoted now (the determined with the others held) and the same after.
  const Eigen::MatrixXd now = detail::subset_covariance(info, determined).covariance;
  const Eigen::MatrixXd later = detail::subset_covariance(info_after, after).covariance;
  // The quoted estimate of d is θ_d + Σ_h B(d,h)(θ_h − held value): B = I_DD⁻¹ I_DH of the logs.
  Eigen::MatrixXd coupling = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(determined.size()), static_cast<Eigen::Index>(freed.size()));
  for (std::size_t k = 0; k < freed.size(); ++k)
    for (std::size_t d = 0; d < determined.size(); ++d)
      for (std::size_t e = 0; e < determined.size(); ++e)
        coupling(static_cast<Eigen::Index>(d), static_cast<Eigen::Index>(k)) +=
            now(static_cast<Eigen::Index>(d), static_cast<Eigen::Index>(e)) * info(determined[e], freed[k]);

  std::vector<PlannedParameter> out;
  for (Eigen::Index j = 0; j < m; ++j) {
    const ParameterEstimate& e = estimate(j);
    PlannedParameter r{e.name, e.unit, e.value};
    const Eigen::Index d = position(determined, j), ja = position(after, j);
    if (d >= 0) {
      // The quoted SE changes as the information's variance of the same quantity does (keeping
      // what the quoted covariance adds for correlated residuals or runs).
      const auto quoted_se = [&](double variance) { return e.se * std::sqrt(std::max(variance, 0.0) / now(d, d)); };
      Eigen::VectorXd held = Eigen::VectorXd::Unit(static_cast<Eigen::Index>(after.size()), ja);
      for (std::size_t k = 0; k < freed.size(); ++k)
        if (std::abs(coupling(d, static_cast<Eigen::Index>(k))) > kCoupled) {
          r.held_now.push_back(estimate(freed[k]).name);
          held(position(after, freed[k])) = coupling(d, static_cast<Eigen::Index>(k));
        }
      r.se_after = quoted_se(later(ja, ja));
      r.se_before = r.held_now.empty() ? e.se : INFINITY;
      if (!r.held_now.empty()) {
        r.se_held_now = e.se;
        r.se_held_after = quoted_se(held.dot(later * held));
      }
    } else if (ja >= 0) {
      r.se_before = INFINITY;
      r.se_after = p.scale(j) * std::sqrt(std::max(later(ja, ja), 0.0));
      notes.push_back(fmt::format("{} is not determined by the data yet (held); the planned conditions determine it", e.name));
    } else {
      r.se_before = r.se_after = INFINITY;
      const double se = relative_se[static_cast<std::size_t>(j)] * p.scale(j);
      notes.push_back(!(relative_se[static_cast<std::size_t>(j)] < 1e3)
                          ? fmt::format("{} is not determined by the data, nor by these candidates: widen the grid", e.name)
                          : fmt::format("{} is not determined by the data; the planned conditions would give it an SE of {:.3g} "
                                        "{}, more than {:g} times its size {:.4g}, where a fit holds it: about {} samples per "
                                        "condition would determine it (--samples), or more conditions (-n)",
                                        e.name, se, e.unit, threshold, e.value,
                                        samples_needed(samples, relative_se[static_cast<std::size_t>(j)] / threshold)));
    }
    r.determined_before = std::isfinite(r.se_before);
    out.push_back(r);
  }
  for (const auto& r : out)
    if (!r.held_now.empty())
      notes.push_back(fmt::format("{0}'s SE now, {1:.4g}, is that of {0} with {2} (what the logs determine); a refit with the "
                                  "planned conditions estimates {3} too and quotes {0} itself, another quantity: SE {4:.4g}. "
                                  "{0} with {2}, as quoted now: {1:.4g} -> {5:.4g}",
                                  r.name, r.se_held_now, held_values(fit, r.held_now), fmt::join(r.held_now, ", "), r.se_after,
                                  r.se_held_after));
  return out;
}

}  // namespace

std::vector<FrictionCandidate> friction_candidates(const FrictionLog& log, const FrictionCandidateGrid& grid) {
  if (log.size() == 0) throw InvalidParameter("log", "no samples to plan from");
  std::vector<double> v, P, pc, T, d;
  std::map<std::string, std::pair<double, double>> guides;  // guide -> block length, ν40 (first seen)
  for (std::size_t i = 0; i < log.size(); ++i) {
    v.push_back(rounded(log.velocity_m_s[i]));
    P.push_back(rounded(log.load_N[i]));
    pc.push_back(rounded(log.preload_um[i]));
    T.push_back(std::round(log.temperature_C[i]));
    d.push_back(log.direction[i]);
    guides.try_emplace(log.guide_names.empty() ? std::string() : log.guide_names[log.guide[i]], log.block_length_mm[i],
                       log.viscosity40_mm2_s[i]);
  }
  if (!grid.guides.empty()) {  // the catalog's block lengths, the log's oil
    const double oil = log.viscosity40_mm2_s.front();
    guides.clear();
    for (const auto& model : grid.guides)
      guides.try_emplace(model, require(find_guide(model, grid.catalog), &GuideSpec::block_length_mm, "block_length_mm"), oil);
  }
  const auto given_or = [](const std::vector<double>& given, std::vector<double> own) { return given.empty() ? distinct(std::move(own)) : distinct(given); };
  const std::vector<double> vs = given_or(grid.velocity_m_s, v), Ps = given_or(grid.load_N, P), pcs = given_or(grid.preload_um, pc),
                            Ts = given_or(grid.temperature_C, T), ds = given_or(grid.directions, d);
  std::vector<FrictionCandidate> out;
  for (const auto& [guide, block] : guides)
    for (double pci : pcs)
      for (double Pi : Ps)
        for (double Ti : Ts)
          for (double vi : vs)
            for (double di : ds) {
              FrictionCandidate c{guide, {.load_N = Pi, .preload_um = pci, .block_length_mm = block.first, .velocity_m_s = vi,
                                          .temperature_C = Ti, .direction = di},
                                  block.second};
              validate(c.conditions);
              out.push_back(c);
            }
  if (out.size() > 1000000) throw InvalidParameter("candidates", static_cast<double>(out.size()), "at most 1e6 combinations");
  return out;
}

std::vector<FrictionCandidate> friction_candidates(const FrictionLog& log, const FrictionCandidateGrid& given,
                                                   const FrictionFitResult& fit) {
  const auto held = [&](const char* name) {
    return std::any_of(fit.fit.parameters.begin(), fit.fit.parameters.end(),
                       [&](const ParameterEstimate& e) { return e.name == name && e.free && e.held_unidentifiable; });
  };
  std::set<double> preloads, speeds;
  std::set<std::string> guides;
  double coldest = INFINITY, warmest = -INFINITY;
  for (std::size_t i = 0; i < log.size(); ++i) {
    preloads.insert(rounded(log.preload_um[i]));
    speeds.insert(rounded(log.velocity_m_s[i]));
    coldest = std::min(coldest, log.temperature_C[i]);
    warmest = std::max(warmest, log.temperature_C[i]);
    guides.insert(log.guide_names.empty() ? std::string() : log.guide_names[log.guide[i]]);
  }
  if (!given.guides.empty()) guides = {given.guides.begin(), given.guides.end()};
  FrictionCandidateGrid grid = given;
  // A level the log lacks, by variable, and what it is for.
  std::map<double, std::string> new_preload, new_temperature, new_speed;
  if (grid.preload_um.empty() && preloads.size() == 1 && held("k2")) {
    grid.preload_um = {preloads.begin(), preloads.end()};
    for (const auto& guide : guides)
      for (const char* preload_class : {"normal", "C1", "C0"}) {
        const double pc = preload_class_um(preload_class, guide);
        if (preloads.count(pc)) continue;
        grid.preload_um.push_back(pc);
        new_preload[pc] = fmt::format("at pc = {:g} um (preload class {}): a second preload class, which determines k2 (one "
                                      "class leaves k1 and k2 tied)",
                                      pc, preload_class);
      }
  }
  if (grid.temperature_C.empty() && warmest - coldest < 3 && held("beta_per_K")) {
    const double T = std::round(0.5 * (coldest + warmest));
    grid.temperature_C = {T, T + 15};
    new_temperature[T + 15] = fmt::format("at T = {:g} C: a second temperature, 15 K above the logs', which determines beta_per_K", T + 15);
  }
  if (grid.velocity_m_s.empty() && !speeds.empty() && *speeds.begin() >= 0.03 && held("v_st_m_s")) {
    grid.velocity_m_s = {speeds.begin(), speeds.end()};
    for (double v : {0.002, 0.005, 0.01, 0.02}) {
      grid.velocity_m_s.push_back(v);
      new_speed[v] = fmt::format("at V = {:g} m/s: below 0.03 m/s, where the Stribeck term shows, which determines v_st_m_s", v);
    }
  }
  std::vector<FrictionCandidate> out = friction_candidates(log, grid);
  for (auto& c : out) {
    std::vector<std::string> why;
    const std::pair<const std::map<double, std::string>*, double> levels[] = {
        {&new_preload, c.conditions.preload_um}, {&new_temperature, c.conditions.temperature_C}, {&new_speed, c.conditions.velocity_m_s}};
    for (const auto& [level, value] : levels)
      if (const auto at = level->find(value); at != level->end()) why.push_back(at->second);
    c.proposed_for = fmt::format("{}", fmt::join(why, "; "));
  }
  return out;
}

namespace {

// The positions in `p` of the parameters called `names` (option `option`); InvalidParameter
// for a name that is not `what` of the fit.
std::vector<Eigen::Index> indices_of(const FrictionFitResult& fit, const Parameters& p, const std::vector<std::string>& names,
                                     const char* option, const char* what) {
  std::vector<Eigen::Index> out;
  for (const auto& name : names) {
    const auto at = std::find_if(p.index.begin(), p.index.end(), [&](std::size_t j) { return fit.fit.parameters[j].name == name; });
    if (at == p.index.end()) throw InvalidParameter(option, fmt::format("'{}' is not {} of the fit", name, what));
    out.push_back(at - p.index.begin());
  }
  return out;
}

// The greedy design: `count` times, the candidate (gradient `grads[c]`, each logged with weight
// `a` = samples / σ²) whose condition gains most — the pair's separation (Ds), the `named`
// parameters' variances relative to `before` (A) or the log determinant (D) — taken into the
// plan, `cov` and `info_after`.
void pick_conditions(const std::vector<FrictionCandidate>& candidates, const std::vector<Eigen::VectorXd>& grads, double a,
                     const std::vector<Eigen::Index>& named, const std::vector<Eigen::Index>& pair,
                     const Eigen::VectorXd& before, std::size_t count, Eigen::MatrixXd& cov, Eigen::MatrixXd& info_after,
                     FrictionPlan& plan) {
  std::vector<bool> taken(candidates.size(), false);
  for (std::size_t k = 0; k < count; ++k) {
    double best = -1;
    std::size_t best_c = 0;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      if (taken[c]) continue;  // N distinct conditions
      const Eigen::VectorXd v = cov * grads[c];
      const double q = grads[c].dot(v);
      double gain = 0;
      if (!pair.empty()) {  // log det of the pair's covariance: −log(1 − c v_Pᵀ Σ_PP⁻¹ v_P)
        Eigen::Matrix2d spp;
        spp << cov(pair[0], pair[0]), cov(pair[0], pair[1]), cov(pair[1], pair[0]), cov(pair[1], pair[1]);
        const Eigen::Vector2d vp(v(pair[0]), v(pair[1]));
        gain = -std::log1p(-(a / (1 + a * q)) * vp.dot(spp.ldlt().solve(vp)));
      } else if (named.empty()) {
        gain = std::log1p(a * q);
      } else {
        for (Eigen::Index j : named) gain += a * v(j) * v(j) / (1 + a * q) / before(j);
      }
      if (gain > best) {
        best = gain;
        best_c = c;
      }
    }
    const Eigen::VectorXd v = cov * grads[best_c];
    cov -= (a / (1 + a * grads[best_c].dot(v))) * v * v.transpose();
    info_after += a * grads[best_c] * grads[best_c].transpose();
    taken[best_c] = true;
    plan.picks.push_back({candidates[best_c], best});
  }
}

}  // namespace

FrictionPlan plan_friction(const FrictionLog& log, const FrictionFitResult& fit, const std::vector<FrictionCandidate>& candidates,
                           const PlanOptions& o) {
  if (candidates.empty()) throw InvalidParameter("candidates", "no candidate conditions to choose from");
  if (o.conditions < 1) throw InvalidParameter("conditions", 0.0, "at least 1");
  const Parameters p = parameters_of(fit);
  const auto m = p.value.size();
  if (m == 0) throw InvalidParameter("parameters", "the fit has no free parameter of the law to plan for");
  const std::vector<Eigen::Index> named = indices_of(fit, p, o.parameters, "parameters", "a free parameter");
  const std::vector<Eigen::Index> pair = indices_of(fit, p, o.separate, "separate", "an effect");
  if (!pair.empty() && pair.size() != 2) throw InvalidParameter("separate", "two effects to tell apart, e.g. seal_drag,seal_drag_block");
  FrictionPlan plan;
  plan.criterion = !pair.empty()   ? fmt::format("Ds-optimal: separate {} from {}", o.separate[0], o.separate[1])
                   : named.empty() ? "D-optimal (all parameters)"
                                   : fmt::format("A-optimal for {}", fmt::join(o.parameters, ", "));
  plan.sigma_N = fit.rmse_N;
  if (!(plan.sigma_N > 0)) throw InvalidParameter("fit", "a residual RMSE of 0: no noise to plan against");
  std::vector<double> per_condition;
  for (const auto& c : fit.conditions) per_condition.push_back(static_cast<double>(c.n));
  std::sort(per_condition.begin(), per_condition.end());
  plan.samples_per_condition = o.samples_per_condition > 0 ? o.samples_per_condition
                               : per_condition.empty()     ? 20
                                                           : static_cast<std::size_t>(per_condition[per_condition.size() / 2]);

  // The information of the logged samples, in units of the parameters' own sizes.
  const Gradient gradient(fit, p);
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(m, m);
  for (std::size_t i = 0; i < log.size(); ++i) {
    const Eigen::VectorXd g = gradient.at(log.conditions(i), log.viscosity40_mm2_s[i]);
    info.selfadjointView<Eigen::Lower>().rankUpdate(g);
  }
  info = info.selfadjointView<Eigen::Lower>();
  info /= plan.sigma_N * plan.sigma_N;
  const double ridge = 1e-10 * info.trace() / static_cast<double>(m);
  Eigen::MatrixXd cov = detail::ridge_inverse(info, ridge);
  const Eigen::VectorXd before = cov.diagonal();
  std::vector<Eigen::Index> determined;  // the parameters the fit quoted an SE of
  for (Eigen::Index j = 0; j < m; ++j) {
    const ParameterEstimate& e = fit.fit.parameters[p.index[static_cast<std::size_t>(j)]];
    if (!e.held_unidentifiable && std::isfinite(e.se) && e.se > 0) determined.push_back(j);
  }

  std::vector<Eigen::VectorXd> grads(candidates.size());
  for (std::size_t c = 0; c < candidates.size(); ++c) grads[c] = gradient.at(candidates[c].conditions, candidates[c].viscosity40_mm2_s);
  const double a = static_cast<double>(plan.samples_per_condition) / (plan.sigma_N * plan.sigma_N);
  const auto pair_correlation = [&] {
    return pair.empty() ? NAN : cov(pair[0], pair[1]) / std::sqrt(cov(pair[0], pair[0]) * cov(pair[1], pair[1]));
  };
  plan.correlation_before = pair_correlation();
  Eigen::MatrixXd info_after = info;
  pick_conditions(candidates, grads, a, named, pair, before, std::min(o.conditions, candidates.size()), cov, info_after, plan);

  plan.parameters = expected_standard_errors(fit, p, info, info_after, determined, plan.samples_per_condition, plan.notes);
  proposed_picks(plan);
  plan.correlation_after = pair_correlation();
  if (!pair.empty())
    plan.notes.push_back(fmt::format("{} and {}: correlation of their estimates {:.3f} with the logs, {:.3f} with the planned "
                                     "conditions too",
                                     o.separate[0], o.separate[1], plan.correlation_before, plan.correlation_after));
  for (const auto& issue : fit.fit.identifiability.issues)
    if (!issue.measure.empty()) plan.notes.push_back("the fit's identifiability issue: " + issue.why + "; it says: " + issue.measure);
  plan.notes.push_back(fmt::format("each planned condition logged as {} samples with the fit's noise ({:.3g} N); the expected SEs keep "
                                   "the quoted covariance's inflation over independent residuals",
                                   plan.samples_per_condition, plan.sigma_N));
  return plan;
}

namespace {

// Run names by setup (guide, preload, load, temperature): "plan1", "plan2", … in the order of the picks.
std::vector<std::string> run_names(const FrictionPlan& plan) {
  std::map<std::tuple<std::string, double, double, double>, std::string> runs;
  std::vector<std::string> out;
  for (const auto& pick : plan.picks) {
    const auto& c = pick.candidate.conditions;
    const auto key = std::make_tuple(pick.candidate.guide, c.preload_um, c.load_N, c.temperature_C);
    auto [it, added] = runs.try_emplace(key, fmt::format("plan{}", runs.size() + 1));
    out.push_back(it->second);
  }
  return out;
}

// What the SEs compare, in the summary and plan.json.
constexpr const char* kSameQuantity =
    "the same quantity on both sides: each parameter as a refit with the planned conditions would quote it";

}  // namespace

std::string friction_plan_json(const FrictionPlan& plan, const std::vector<std::string>& command) {
  nlohmann::json picks = nlohmann::json::array();
  const auto runs = run_names(plan);
  for (std::size_t k = 0; k < plan.picks.size(); ++k) {
    const auto& c = plan.picks[k].candidate.conditions;
    picks.push_back({{"run", runs[k]}, {"guide", plan.picks[k].candidate.guide}, {"velocity_m_s", c.velocity_m_s},
                     {"load_N", c.load_N}, {"preload_um", c.preload_um}, {"block_length_mm", c.block_length_mm},
                     {"temperature_C", c.temperature_C}, {"direction", c.direction},
                     {"viscosity40_mm2_s", plan.picks[k].candidate.viscosity40_mm2_s}, {"gain", plan.picks[k].gain}});
    if (!plan.picks[k].candidate.proposed_for.empty()) picks.back()["proposed_for"] = plan.picks[k].candidate.proposed_for;
  }
  nlohmann::json parameters = nlohmann::json::array();
  for (const auto& p : plan.parameters) {
    const auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
    nlohmann::json row = {{"name", p.name}, {"unit", p.unit}, {"value", p.value}, {"se_before", number(p.se_before)},
                          {"se_after", number(p.se_after)}, {"determined_before", p.determined_before}};
    if (!p.held_now.empty())
      row["as_quoted_now"] = {{"held", p.held_now}, {"se_before", number(p.se_held_now)}, {"se_after", number(p.se_held_after)}};
    parameters.push_back(row);
  }
  const nlohmann::json j = {{"kind", "friction plan"},
                            {"lmcal_version", LMCAL_VERSION}, {"schema_version", kOutputSchemaVersion},
                            {"command", command},
                            {"criterion", plan.criterion},
                            {"samples_per_condition", plan.samples_per_condition},
                            {"noise_N", plan.sigma_N},
                            {"conditions", picks},
                            {"parameters", parameters},
                            {"standard_errors", kSameQuantity},
                            {"correlation_before", std::isfinite(plan.correlation_before) ? nlohmann::json(plan.correlation_before) : nlohmann::json(nullptr)},
                            {"correlation_after", std::isfinite(plan.correlation_after) ? nlohmann::json(plan.correlation_after) : nlohmann::json(nullptr)},
                            {"notes", plan.notes}};
  return j.dump(1) + "\n";
}

std::string friction_plan_template_csv(const FrictionPlan& plan) {
  CsvText csv({"run", "guide", "velocity_m_s", "load_N", "preload_um", "block_length_mm", "temperature_C", "direction",
               "viscosity40_mm2_s", "friction_N"},
              {"lmcal plan: the next conditions to log, " + plan.criterion,
               fmt::format("log about {} samples at each row's conditions (a row per sample), friction_N as measured; "
                           "then fit the old and the new logs together",
                           plan.samples_per_condition)});
  const auto runs = run_names(plan);
  for (std::size_t k = 0; k < plan.picks.size(); ++k) {
    const auto& pick = plan.picks[k].candidate;
    const auto& c = pick.conditions;
    csv.cell(runs[k]).cell(pick.guide).cell(c.velocity_m_s).cell(c.load_N).cell(c.preload_um).cell(c.block_length_mm);
    csv.cell(c.temperature_C).cell(c.direction).cell(pick.viscosity40_mm2_s).cell("").end_row();
  }
  return csv.str();
}

std::string friction_plan_summary(const FrictionPlan& plan) {
  std::string out = fmt::format("plan: the next {} conditions, {}, {} samples each:\n", plan.picks.size(), plan.criterion,
                                plan.samples_per_condition);
  const auto runs = run_names(plan);
  for (std::size_t k = 0; k < plan.picks.size(); ++k) {
    const auto& p = plan.picks[k].candidate;
    const auto& c = p.conditions;
    out += fmt::format("  {:>2}. {} {}  V = {:g} m/s  P = {:g} N  pc = {:g} um  T = {:g} C  dir {:+g}{}\n", k + 1, runs[k], p.guide,
                       c.velocity_m_s, c.load_N, c.preload_um, c.temperature_C, c.direction,
                       p.proposed_for.empty() ? "" : "  (new: see the notes)");
  }
  out += fmt::format("expected standard errors, now -> after ({}):\n", kSameQuantity);
  for (const auto& p : plan.parameters) out += detail::expected_se_line(p);
  bool held = false;
  for (const auto& p : plan.parameters)
    if (!p.held_now.empty()) {
      if (!held) out += "as quoted now, with the constants the fit holds at their values (what the logs determine), now -> after:\n";
      held = true;
      PlannedParameter quoted = p;
      quoted.name = fmt::format("{} ({} held)", p.name, fmt::join(p.held_now, ", "));
      quoted.held_now.clear();
      quoted.se_before = p.se_held_now;
      quoted.se_after = p.se_held_after;
      out += detail::expected_se_line(quoted);
    }
  for (const auto& n : plan.notes) out += "  note: " + n + "\n";
  return out;
}

}  // namespace lmcal
