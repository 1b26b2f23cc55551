#include "empirical_thermal.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "fit/thermal_terms.hpp"
#include "lmcal/fit/statistics.hpp"
#include "sparse_regression.hpp"

namespace lmcal::detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kCurveBins = 20;
constexpr std::size_t kPeriods = 2;  // the ambient's strongest periods in the dictionary

// A dictionary entry: the term (its scale at the grid value) and its family.
struct Candidate {
  ThermalSensorTerm term;
  std::size_t family = 0;
};

bool periodic(ThermalTermKind kind) {
  return kind == ThermalTermKind::ambient_in_phase || kind == ThermalTermKind::ambient_quadrature;
}

std::vector<Candidate> dictionary(const std::vector<double>& periods_s, double longest_s, bool speeds_differ) {
  std::vector<Candidate> out;
  std::size_t family = 0;
  auto add = [&](ThermalTermKind kind, double scale = 0, double lower = 0, double upper = 0) {
    out.push_back({{.kind = kind, .scale_s = scale, .scale_lower_s = lower, .scale_upper_s = upper}, family});
  };
  add(ThermalTermKind::time), ++family;
  add(ThermalTermKind::time_squared), ++family;
  // Each period moves within a factor of 1.5 of the grid's choice (the next peak is farther)
  // and stays within the runs: beyond them a sine is a trend.
  for (double period_s : periods_s) {
    const double lower = std::max(period_s / 1.5, 1800.0), upper = std::max(std::min(1.5 * period_s, 1.5 * longest_s), 1.1 * lower);
    add(ThermalTermKind::ambient_in_phase, period_s, lower, upper), ++family;
    add(ThermalTermKind::ambient_quadrature, period_s, lower, upper), ++family;
  }
  add(ThermalTermKind::ambient_change), ++family;
  for (double tau_h : {0.25, 0.5, 1.0, 2.0, 4.0, 8.0}) add(ThermalTermKind::ambient_lag, tau_h * 3600, 60.0, 7 * 86400.0);
  ++family;
  add(ThermalTermKind::rise_time), ++family;
  if (speeds_differ) add(ThermalTermKind::velocity_time), ++family;
  return out;
}

// `period`: which of the dictionary's periods a periodic term has ("P", "P2", …).
std::string symbol(const ThermalSensorTerm& t, std::size_t j, const std::string& period = "P") {
  switch (t.kind) {
    case ThermalTermKind::time: return fmt::format("c{}·t", j);
    case ThermalTermKind::time_squared: return fmt::format("c{}·t²", j);
    case ThermalTermKind::ambient_in_phase: return fmt::format("c{}·a_{}(t)", j, period);
    case ThermalTermKind::ambient_quadrature: return fmt::format("c{}·b_{}(t)", j, period);
    case ThermalTermKind::ambient_lag: return fmt::format("c{}·(lag_τ{}(T∞) − T∞)", j, j);
    case ThermalTermKind::ambient_change: return fmt::format("c{}·(T∞ − T∞(0))", j);
    case ThermalTermKind::rise_time: return fmt::format("c{}·ΔT_model·t", j);
    case ThermalTermKind::velocity_time: return fmt::format("c{}·V·t", j);
  }
  return "?";
}

std::string words(const ThermalSensorTerm& t) {
  switch (t.kind) {
    case ThermalTermKind::time: return "a reading that grows in proportion to the time since the run's start t (h)";
    case ThermalTermKind::time_squared: return "a reading that grows with the square of the time since the run's start (h²)";
    case ThermalTermKind::ambient_in_phase:
      return "a share of the ambient's own swing at its dominant period P, in phase with it";
    case ThermalTermKind::ambient_quadrature:
      return "a share of the ambient's swing at its dominant period P, a quarter period ahead of it";
    case ThermalTermKind::ambient_lag:
      return "the ambient lagged through a first-order lag of time constant τ, less the ambient";
    case ThermalTermKind::ambient_change: return "a share of the ambient's change since the run's start";
    case ThermalTermKind::rise_time: return "the model's temperature rise times the time since the start (h)";
    case ThermalTermKind::velocity_time: return "the speed times the time since the start (h)";
  }
  return "";
}

std::vector<std::string> covariates(const ThermalSensorTerm& t) {
  switch (t.kind) {
    case ThermalTermKind::time:
    case ThermalTermKind::time_squared: return {"time_since_start_h"};
    case ThermalTermKind::ambient_in_phase:
    case ThermalTermKind::ambient_quadrature: return {"time_since_start_h", "ambient_C"};
    case ThermalTermKind::ambient_lag:
    case ThermalTermKind::ambient_change: return {"ambient_C"};
    case ThermalTermKind::rise_time: return {"time_since_start_h", "temperature rise"};
    case ThermalTermKind::velocity_time: return {"time_since_start_h", "velocity_m_s"};
  }
  return {};
}

// The mechanisms a term resembles, in words.
std::string resemblance(const ThermalSensorTerm& t, double coefficient, double scale_s) {
  switch (t.kind) {
    case ThermalTermKind::time:
      return fmt::format("a slow drift of the thermocouples or of the logger's cold junction ({:+.3g} K/h)", coefficient);
    case ThermalTermKind::time_squared: return "a drift of the thermocouples that speeds up or slows down over the run";
    case ThermalTermKind::ambient_in_phase:
    case ThermalTermKind::ambient_quadrature:
      return fmt::format(
          "the rail seeing a larger or later swing of the air at the ambient's period ({:.3g} h) than the ambient sensors "
          "log — sensor placement, sun, the bed's heat",
          scale_s / kSecondsPerHour);
    case ThermalTermKind::ambient_lag:
      return fmt::format("the rail's surroundings (the bed, the machine) following the air with a lag of {:.3g} h",
                         scale_s / kSecondsPerHour);
    case ThermalTermKind::ambient_change:
      return "the rail following the air more (or less) than the ambient sensors log — sensors in a sheltered spot";
    case ThermalTermKind::rise_time:
      return "a heat input or loss that changes over the run beyond the model (the grease's warm-up, wear)";
    case ThermalTermKind::velocity_time: return "a drift whose rate grows with the speed (the heat rate drifting during a run)";
  }
  return "";
}

// Means of `v` over the bins `label` (NaN for an empty bin).
std::vector<double> bin_means(const std::vector<double>& v, const std::vector<std::size_t>& label, std::size_t bins) {
  std::vector<double> sum(bins, 0.0), count(bins, 0.0);
  for (std::size_t i = 0; i < v.size(); ++i) sum[label[i]] += v[i], count[label[i]] += 1;
  for (std::size_t b = 0; b < bins; ++b) sum[b] = count[b] > 0 ? sum[b] / count[b] : kNaN;
  return sum;
}

// The term over the time since the run's start: its mean contribution per bin with a 95 %
// delta-method band (the joint covariance of its parameters, central differences), and the
// residual means without the term (partial residuals) and with it.
EmpiricalCurve time_curve(const ThermalDataSet& data, const ThermalFitOptions& joint_options, const ThermalFitResult& after) {
  EmpiricalCurve c;
  c.covariate = "time_since_start_h";
  c.unit = "h";
  double longest = 0;
  for (const auto& s : after.samples) longest = std::max(longest, s.time_s);
  const double width = std::max(longest, 1.0) / kCurveBins;
  std::vector<std::size_t> label;
  for (const auto& s : after.samples) label.push_back(std::min(static_cast<std::size_t>(s.time_s / width), kCurveBins - 1));
  const std::vector<double> theta = after.joint.values();
  const std::vector<double> term_K = thermal_sensor_term_sum(data, joint_options, after, theta);
  const std::vector<double> value = bin_means(term_K, label, kCurveBins);
  std::set<std::size_t> indices;
  for (const auto& term : after.sensor_term_parameters) indices.insert(term.begin(), term.end());
  std::vector<std::size_t> params(indices.begin(), indices.end());
  std::vector<std::vector<double>> gradient;
  for (std::size_t p : params) {
    const double h = 1e-4 * std::max(std::abs(theta[p]), after.joint.parameters[p].se > 0 ? after.joint.parameters[p].se : 1e-6);
    std::vector<double> up = theta, down = theta;
    up[p] += h;
    down[p] -= h;
    const auto mu = bin_means(thermal_sensor_term_sum(data, joint_options, after, up), label, kCurveBins);
    const auto md = bin_means(thermal_sensor_term_sum(data, joint_options, after, down), label, kCurveBins);
    std::vector<double> g(kCurveBins);
    for (std::size_t b = 0; b < kCurveBins; ++b) g[b] = (mu[b] - md[b]) / (2 * h);
    gradient.push_back(std::move(g));
  }
  // Before: the partial residuals — the joint fit's residuals with the term added back, what
  // the term has to explain (the model without it bends α, offsets and heat scales to absorb
  // part of it in sample).
  std::vector<double> e_before, e_after;
  for (std::size_t i = 0; i < after.samples.size(); ++i) {
    const auto& s = after.samples[i];
    e_after.push_back(s.measured_C - s.simulated_C);
    e_before.push_back(e_after.back() + term_K[i]);
  }
  c.residual_before = bin_means(e_before, label, kCurveBins);
  c.residual_after = bin_means(e_after, label, kCurveBins);
  const double t95 = student_t_quantile(0.975, std::max(after.joint.dof, 1.0));
  const Eigen::MatrixXd& V = after.joint.covariance;
  for (std::size_t b = 0; b < kCurveBins; ++b) {
    double variance = 0;
    for (std::size_t p = 0; p < params.size(); ++p)
      for (std::size_t q = 0; q < params.size(); ++q)
        variance += gradient[p][b] * V(static_cast<Eigen::Index>(params[p]), static_cast<Eigen::Index>(params[q])) * gradient[q][b];
    const double half = t95 * std::sqrt(std::max(variance, 0.0));
    c.x.push_back((static_cast<double>(b) + 0.5) * width / kSecondsPerHour);
    c.value.push_back(value[b]);
    c.low.push_back(value[b] - half);
    c.high.push_back(value[b] + half);
  }
  return c;
}

// What the fit re-estimates of a held-out run from its own records — its thermocouples'
// offsets and its heat scale — taken out of a column on each run's rows (the projection on the
// complement of those columns). The heat scales must go: the baseline bends them (and α) to
// absorb what it misses, and a term that lets them return to 1 would look worse, linearised,
// than it is.
class RunNuisance {
 public:
  explicit RunNuisance(const ThermalFitResult& fit) {
    const std::size_t runs = fit.runs.size();
    rows_.resize(runs);
    for (std::size_t k = 0; k < fit.samples.size(); ++k) rows_[fit.samples[k].run].push_back(k);
    for (std::size_t r = 0; r < runs; ++r) {
      const std::vector<double>* scale = nullptr;
      for (const auto& [name, column] : fit.sensitivities)
        if (name == "heat_scale " + fit.runs[r].id) scale = &column;
      const auto n = static_cast<Eigen::Index>(rows_[r].size());
      const auto sensors = static_cast<Eigen::Index>(fit.sensor_names[r].size());
      Eigen::MatrixXd N = Eigen::MatrixXd::Zero(n, sensors + (scale ? 1 : 0));
      for (Eigen::Index i = 0; i < n; ++i) {
        const auto& sample = fit.samples[rows_[r][static_cast<std::size_t>(i)]];
        N(i, static_cast<Eigen::Index>(sample.sensor)) = 1;
        if (scale) N(i, sensors) = (*scale)[rows_[r][static_cast<std::size_t>(i)]];
      }
      const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(N);
      basis_.push_back(qr.householderQ() * Eigen::MatrixXd::Identity(n, qr.rank()));
    }
  }

  void remove(std::vector<double>& column) const {
    for (std::size_t r = 0; r < rows_.size(); ++r) {
      Eigen::VectorXd x(static_cast<Eigen::Index>(rows_[r].size()));
      for (std::size_t i = 0; i < rows_[r].size(); ++i) x[static_cast<Eigen::Index>(i)] = column[rows_[r][i]];
      x -= basis_[r] * (basis_[r].transpose() * x);
      for (std::size_t i = 0; i < rows_[r].size(); ++i) column[rows_[r][i]] = x[static_cast<Eigen::Index>(i)];
    }
  }

 private:
  std::vector<std::vector<std::size_t>> rows_;  // per run: its samples
  std::vector<Eigen::MatrixXd> basis_;          // per run: orthonormal basis of its nuisance columns
};

}  // namespace

std::vector<double> dominant_ambient_periods_s(const std::vector<AmbientTrace>& ambients, std::size_t count,
                                               double shortest_s) {
  double longest = 0;
  for (const auto& a : ambients)
    if (!a.time_s.empty()) longest = std::max(longest, a.time_s.back() - a.time_s.front());
  if (!(longest > shortest_s)) return {shortest_s};
  constexpr int kGrid = 80;
  std::vector<double> period(kGrid), explained(kGrid, 0.0);
  for (int k = 0; k < kGrid; ++k) {
    period[k] = shortest_s * std::pow(longest / shortest_s, static_cast<double>(k) / (kGrid - 1));
    for (const auto& a : ambients) explained[k] += periodic_component<double>(a, period[k]).explained;
  }
  // The peaks (local maxima, the ends included), strongest first, each at least a factor of
  // 1.5 from a stronger one.
  std::vector<int> peaks;
  for (int k = 0; k < kGrid; ++k)
    if ((k == 0 || explained[k] >= explained[k - 1]) && (k == kGrid - 1 || explained[k] >= explained[k + 1])) peaks.push_back(k);
  std::sort(peaks.begin(), peaks.end(), [&](int a, int b) { return explained[a] > explained[b]; });
  std::vector<double> out;
  for (int k : peaks) {
    if (out.size() == count) break;
    if (std::all_of(out.begin(), out.end(), [&](double p) { return std::max(p, period[k]) / std::min(p, period[k]) >= 1.5; }))
      out.push_back(period[k]);
  }
  return out;
}

double dominant_ambient_period_s(const std::vector<AmbientTrace>& ambients, double shortest_s) {
  return dominant_ambient_periods_s(ambients, 1, shortest_s).front();
}

namespace {

// The residuals and the model's global parameters linearised, each run's nuisance (offsets,
// heat scale) taken out of every column on its own rows; the candidates' columns beside them.
SparseProblem linearised_problem(const ThermalDataSet& data, const ThermalFitOptions& options,
                                 const ThermalFitResult& current, const std::vector<Candidate>& candidates) {
  SparseProblem problem;
  for (const auto& s : current.samples) {
    problem.y.push_back(s.measured_C - s.simulated_C);
    problem.group.push_back(s.run);
  }
  for (const auto& [name, column] : current.sensitivities) {
    const ParameterEstimate& p = current.joint.parameter(name);
    if (name.rfind("heat_scale ", 0) != 0 && p.free && !p.held_unidentifiable && !p.at_bound) problem.fixed.push_back(column);
  }
  std::vector<ThermalSensorTerm> terms;
  for (const auto& c : candidates) terms.push_back(c.term);
  problem.candidates = thermal_sensor_term_values(data, options, current, terms);
  for (const auto& c : candidates) problem.family.push_back(c.family);
  const RunNuisance nuisance(current);
  nuisance.remove(problem.y);
  for (auto& column : problem.fixed) nuisance.remove(column);
  for (auto& column : problem.candidates) nuisance.remove(column);
  return problem;
}

// The sparsity tolerance: a tenth of what a perfect term could gain over the noise floor,
// within [the selection's minimum gain, 2 %] (the held-out RMSE is mostly noise when the
// excess is small).
double sparsity_tolerance_percent(const ThermalFitResult& current, const SelectionRules& rules) {
  const double achievable = rules.noise_floor > 0 && current.cv_rmse_K > rules.noise_floor
                                ? 100 * (1 - rules.noise_floor / current.cv_rmse_K)
                                : 100.0;
  return std::clamp(0.1 * achievable, rules.min_cv_gain_percent, 2.0);
}

// The finding's components, formula, look-alikes and the covariate ranges the chosen terms
// were learned on, from their joint fit.
void describe_terms(const std::vector<ThermalSensorTerm>& chosen_terms, const ThermalFitResult& joint,
                    const std::vector<double>& periods_s, const std::vector<AmbientTrace>& ambients, double longest_s,
                    EmpiricalFinding& f) {
  std::string formula;
  std::vector<std::string> resembles;
  std::set<std::string> used;
  for (std::size_t j = 0; j < chosen_terms.size(); ++j) {
    const ThermalSensorTerm& term = chosen_terms[j];
    const auto& indices = joint.sensor_term_parameters[j];
    EmpiricalComponent c;
    const auto which = std::find(periods_s.begin(), periods_s.end(), term.scale_s) - periods_s.begin();
    c.symbol = symbol(term, j + 1, which == 0 ? "P" : fmt::format("P{}", which + 1));
    c.words = words(term);
    c.covariates = covariates(term);
    c.coefficient = within_bounds(joint.joint.parameters[indices.front()]);
    double scale_s = term.scale_s;
    if (indices.size() > 1) {
      c.has_scale = true;
      c.scale = within_bounds(joint.joint.parameters[indices[1]]);
      scale_s = c.scale.value;
    }
    if (periodic(term.kind)) c.words += fmt::format(" (P = {:.3g} h)", scale_s / kSecondsPerHour);
    formula += (formula.empty() ? "" : " + ") + c.symbol;
    const std::string r = resemblance(term, c.coefficient.value, scale_s);
    if (std::find(resembles.begin(), resembles.end(), r) == resembles.end()) resembles.push_back(r);
    used.insert(c.covariates.begin(), c.covariates.end());
    f.components.push_back(std::move(c));
  }
  f.formula = formula;
  for (const auto& r : resembles) f.resembles += (f.resembles.empty() ? "" : "; or ") + r;
  if (used.count("time_since_start_h")) f.ranges.push_back({"time_since_start_h", 0.0, longest_s / kSecondsPerHour});
  if (used.count("ambient_C")) {
    CovariateRange r{"ambient_C", std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    for (const auto& a : ambients)
      for (double T : a.temperature_C) r.min = std::min(r.min, T), r.max = std::max(r.max, T);
    f.ranges.push_back(r);
  }
}

// The chosen terms with their parts at the joint fit's values: a coefficient, then the scale
// where the term has one.
std::vector<ThermalSensorTerm> at_fitted_values(std::vector<ThermalSensorTerm> terms, const ThermalFitResult& joint) {
  for (std::size_t j = 0; j < terms.size() && j < joint.sensor_term_parameters.size(); ++j) {
    const auto& at = joint.sensor_term_parameters[j];
    if (!at.empty()) terms[j].coefficient = joint.joint.parameters[at[0]].value;
    if (at.size() > 1) terms[j].scale_s = joint.joint.parameters[at[1]].value;
  }
  return terms;
}

}  // namespace

ThermalTermSearch learn_thermal_term(const ThermalDataSet& data, const ThermalFitOptions& options,
                                     const ThermalFitResult& current,
                                     const std::function<ThermalFitResult(const std::vector<ThermalSensorTerm>&)>& refit,
                                     const std::function<ModelFit(const ThermalFitResult&)>& summarise,
                                     const SelectionRules& rules) {
  ThermalTermSearch out;
  EmpiricalFinding& f = out.finding;
  f.searched = true;
  f.where = "every thermocouple reading";

  // The dictionary, at the ambient's dominant period.
  const std::vector<AmbientTrace> ambients = thermal_fit_ambients(data, options);
  const std::vector<double> periods_s = dominant_ambient_periods_s(ambients, kPeriods);
  double longest = 0;
  std::set<double> speeds;
  for (const auto& a : ambients) longest = std::max(longest, a.time_s.back() - a.time_s.front());
  for (const auto& run : data.runs) speeds.insert(run.velocity_m_s);
  const std::vector<Candidate> candidates = dictionary(periods_s, longest, speeds.size() >= 2);
  f.dictionary_size = candidates.size();

  const SparseProblem problem = linearised_problem(data, options, current, candidates);
  SparseOptions sparse;
  sparse.min_gain_percent = sparsity_tolerance_percent(current, rules);
  const SparseSelection chosen = select_sparse(problem, sparse);
  if (chosen.selected.empty()) {
    f.reason = fmt::format(
        "no set of them predicts held-out runs at least {:.3g} % better than the model alone (linearised "
        "leave-one-run-out RMSE {:.4g} K)",
        sparse.min_gain_percent, chosen.cv_rmse_fixed);
    return out;
  }

  // The joint fit: the model, its causes and the chosen terms, each scale free.
  std::vector<ThermalSensorTerm> chosen_terms;
  for (std::size_t a = 0; a < chosen.selected.size(); ++a) {
    ThermalSensorTerm t = candidates[chosen.selected[a]].term;
    t.coefficient = chosen.coefficient[a];
    chosen_terms.push_back(t);
  }
  ThermalFitResult joint = refit(chosen_terms);
  if (joint.samples.empty()) {
    f.reason = "the joint fit of the model with the chosen terms failed: " +
               (joint.joint.warnings.empty() ? std::string("no result") : joint.joint.warnings.front());
    return out;
  }
  const ModelFit before = summarise(current), after = summarise(joint);
  CandidateScore score;
  score.effect = "empirical term";
  const bool passes = score_candidate(before, after, rules, score);
  set_held_out(f, before, after);
  f.lrt_p = score.lrt_p;
  f.delta_bic = score.bic - information_criteria(before.ss, before.n, std::min(before.n_eff, after.n_eff), before.k).second;

  describe_terms(chosen_terms, joint, periods_s, ambients, longest, f);
  if (!passes) {
    f.reason = "the term the sparse regression chose (" + f.formula + "), fitted jointly with the model, was not kept: " +
               score.reason;
    return out;
  }
  f.found = true;
  f.reason = score.reason;
  ThermalFitOptions joint_options = options;
  joint_options.sensor_terms = chosen_terms;
  f.curve = time_curve(data, joint_options, joint);
  out.terms = at_fitted_values(chosen_terms, joint);
  out.fit = std::move(joint);
  return out;
}

}  // namespace lmcal::detail
