// `lmcal plan friction`: sequential optimal design from the friction law's Jacobian (plan.hpp).

#include "lmcal/version.hpp"
#include "lmcal/predict/plan.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "lmcal/error.hpp"
#include "lmcal/io/csv_writer.hpp"
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

FrictionPlan plan_friction(const FrictionLog& log, const FrictionFitResult& fit, const std::vector<FrictionCandidate>& candidates,
                           const PlanOptions& o) {
  if (candidates.empty()) throw InvalidParameter("candidates", "no candidate conditions to choose from");
  if (o.conditions < 1) throw InvalidParameter("conditions", 0.0, "at least 1");
  const Parameters p = parameters_of(fit);
  const auto m = p.value.size();
  if (m == 0) throw InvalidParameter("parameters", "the fit has no free parameter of the law to plan for");
  std::vector<Eigen::Index> named;
  for (const auto& name : o.parameters) {
    const auto at = std::find_if(p.index.begin(), p.index.end(), [&](std::size_t j) { return fit.fit.parameters[j].name == name; });
    if (at == p.index.end()) throw InvalidParameter("parameters", fmt::format("'{}' is not a free parameter of the fit", name));
    named.push_back(at - p.index.begin());
  }
  std::vector<Eigen::Index> pair;
  for (const auto& name : o.separate) {
    const auto at = std::find_if(p.index.begin(), p.index.end(), [&](std::size_t j) { return fit.fit.parameters[j].name == name; });
    if (at == p.index.end()) throw InvalidParameter("separate", fmt::format("'{}' is not an effect of the fit", name));
    pair.push_back(at - p.index.begin());
  }
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
  // The quoted SEs of the determined parameters are conditional on the undetermined ones held
  // at their start: their variance before, the same (the information of the determined alone).
  std::vector<Eigen::Index> determined;
  for (Eigen::Index j = 0; j < m; ++j) {
    const ParameterEstimate& e = fit.fit.parameters[p.index[static_cast<std::size_t>(j)]];
    if (!e.held_unidentifiable && std::isfinite(e.se) && e.se > 0) determined.push_back(j);
  }
  const Eigen::VectorXd before_held = detail::variances_holding_others(info, determined, ridge);

  std::vector<Eigen::VectorXd> grads(candidates.size());
  for (std::size_t c = 0; c < candidates.size(); ++c) grads[c] = gradient.at(candidates[c].conditions, candidates[c].viscosity40_mm2_s);
  const double a = static_cast<double>(plan.samples_per_condition) / (plan.sigma_N * plan.sigma_N);
  const auto pair_correlation = [&] {
    return pair.empty() ? NAN : cov(pair[0], pair[1]) / std::sqrt(cov(pair[0], pair[0]) * cov(pair[1], pair[1]));
  };
  plan.correlation_before = pair_correlation();
  std::vector<bool> taken(candidates.size(), false);
  for (std::size_t k = 0; k < std::min(o.conditions, candidates.size()); ++k) {
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
    taken[best_c] = true;
    plan.picks.push_back({candidates[best_c], best});
  }

  for (Eigen::Index j = 0; j < m; ++j) {
    const ParameterEstimate& e = fit.fit.parameters[p.index[static_cast<std::size_t>(j)]];
    PlannedParameter r{e.name, e.unit, e.value};
    r.determined_before = !e.held_unidentifiable && std::isfinite(e.se) && e.se > 0;
    // The quoted SE changes as the information's variance does (keeping what the quoted
    // covariance adds for correlated residuals or runs): it grows where a parameter determined
    // only with another held becomes a joint estimate. An undetermined one from the information.
    const double shrink = std::sqrt(std::max(cov(j, j), 0.0) / before_held(j));
    r.se_before = r.determined_before ? e.se : INFINITY;
    r.se_after = r.determined_before ? e.se * shrink : p.scale(j) * std::sqrt(std::max(cov(j, j), 0.0));
    if (!r.determined_before && cov(j, j) > 1e-2 / ridge) r.se_after = INFINITY;  // still undetermined
    if (!r.determined_before)
      plan.notes.push_back(std::isfinite(r.se_after)
                               ? fmt::format("{} is not determined by the data yet (held); the planned conditions determine it", e.name)
                               : fmt::format("{} is not determined by the data, nor by these candidates: widen the grid", e.name));
    plan.parameters.push_back(r);
  }
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
  }
  nlohmann::json parameters = nlohmann::json::array();
  for (const auto& p : plan.parameters) {
    const auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
    parameters.push_back({{"name", p.name}, {"unit", p.unit}, {"value", p.value}, {"se_before", number(p.se_before)},
                          {"se_after", number(p.se_after)}, {"determined_before", p.determined_before}});
  }
  const nlohmann::json j = {{"kind", "friction plan"},
                            {"lmcal_version", LMCAL_VERSION}, {"schema_version", kOutputSchemaVersion},
                            {"command", command},
                            {"criterion", plan.criterion},
                            {"samples_per_condition", plan.samples_per_condition},
                            {"noise_N", plan.sigma_N},
                            {"conditions", picks},
                            {"parameters", parameters},
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
    out += fmt::format("  {:>2}. {} {}  V = {:g} m/s  P = {:g} N  pc = {:g} um  T = {:g} C  dir {:+g}\n", k + 1, runs[k], p.guide,
                       c.velocity_m_s, c.load_N, c.preload_um, c.temperature_C, c.direction);
  }
  out += "expected standard errors, now -> after:\n";
  for (const auto& p : plan.parameters) out += detail::expected_se_line(p);
  for (const auto& n : plan.notes) out += "  note: " + n + "\n";
  return out;
}

}  // namespace lmcal
