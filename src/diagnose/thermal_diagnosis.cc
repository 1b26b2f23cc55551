#include "lmcal/diagnose/thermal_diagnosis.hpp"

#include "lmcal/version.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "lmcal/error.hpp"
#include "lmcal/fit/statistics.hpp"
#include "lmcal/models/thermal_mechanisms.hpp"
#include "empirical_thermal.hpp"
#include "fit/fit_json.hpp"
#include "selection.hpp"

namespace lmcal {

namespace {

constexpr int kCandidateIterations = 30;

// Every model of the diagnosis is fitted like this: offsets per thermocouple, one start
// (warm-started from the model before), no profiles or bootstrap, leave-one-run-out scores.
ThermalFitOptions model_options(const ThermalDiagnosisOptions& o) {
  ThermalFitOptions f = o.fit;
  f.offsets = ThermalOffsets::fitted;
  f.fit_heat_scales = true;
  f.per_run_fits = false;
  f.compare_sources = false;
  f.curve_points = 0;
  f.cross_validate = true;
  f.fit.starts = 0;
  f.fit.profile = ProfileMode::none;
  f.fit.bootstrap = 0;  // the diagnosis quotes no bootstrap intervals (the calibrated model does)
  f.sensitivities = true;  // the empirical term's search linearises the model in its global parameters
  return f;
}

// Residual series: the samples of the fit are stored run by run, sensor by sensor, in time order.
struct Series {
  std::size_t run, sensor, first, count;
};

std::vector<Series> series_of(const ThermalFitResult& fit) {
  std::vector<Series> out;
  const auto& s = fit.samples;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (i == 0 || s[i].run != s[i - 1].run || s[i].sensor != s[i - 1].sensor) out.push_back({s[i].run, s[i].sensor, i, 0});
    else ++out.back().count;
  for (auto& se : out) ++se.count;
  return out;
}

// Lag-1 autocorrelation of the residuals within the series, pooled.
double lag1_autocorrelation(const ThermalFitResult& fit) {
  double num = 0, den = 0;
  for (const auto& se : series_of(fit))
    for (std::size_t i = se.first; i < se.first + se.count; ++i) {
      const double e = fit.samples[i].measured_C - fit.samples[i].simulated_C;
      den += e * e;
      if (i > se.first) num += e * (fit.samples[i - 1].measured_C - fit.samples[i - 1].simulated_C);
    }
  return den > 0 ? num / den : 0.0;
}

double effective_sample_size(double n, double rho) {
  rho = std::clamp(rho, 0.0, 0.999);
  return std::max(n * (1 - rho) / (1 + rho), 2.0);
}

// The thermocouples' noise over all runs (RMS of each run's second-difference estimate, over
// noise_spacing_s) and the degrees of freedom of that estimate (NoiseFloor, selection.hpp).
detail::NoiseFloor noise_floor(const ThermalDataSet& data, const ThermalDiagnosisOptions& o) {
  double ss = 0, differences = 0;
  for (const auto& run : data.runs) {
    std::size_t m = 0;
    ss += std::pow(thermocouple_noise_K(run.trace, o.noise_spacing_s, &m), 2);
    differences += static_cast<double>(m);
  }
  return {std::sqrt(ss / static_cast<double>(data.runs.size())), differences * detail::kSecondDifferenceDofShare};
}

ThermalResidualDiagnostics diagnose_residuals(const ThermalFitResult& fit, const ThermalDiagnosisOptions& o,
                                              const detail::NoiseFloor& noise) {
  ThermalResidualDiagnostics d;
  const auto& samples = fit.samples;
  double ss = 0;
  for (const auto& s : samples) ss += std::pow(s.measured_C - s.simulated_C, 2);
  const auto n = static_cast<double>(samples.size());
  d.rmse_K = std::sqrt(ss / std::max(n, 1.0));
  d.lag1_autocorrelation = lag1_autocorrelation(fit);
  d.n_eff = effective_sample_size(n, d.lag1_autocorrelation);
  // Called a lack of fit only when the excess sqrt(s² − σ²) is at least min_structure_fraction
  // of σ, i.e. s above sqrt(1 + fraction²) σ: on thousands of records millikelvin are
  // significant without mattering.
  d.lack_of_fit = detail::lack_of_fit_against_noise(
      ss, n, d.n_eff, fit.joint.free_parameters, noise, o.structure_p,
      std::sqrt(1 + o.min_structure_fraction * o.min_structure_fraction),
      fmt::format("the thermocouples' noise (second differences of the traces over {:g} s)", o.noise_spacing_s));

  // Per sensor series, and cell means (time bins of the run's duration).
  const int bins = std::max(o.time_bins, 2);
  std::vector<double> cell_e, cell_rise, cell_velocity, cell_load, cell_position, cell_run;
  std::vector<std::size_t> cell_bin;
  for (const auto& se : series_of(fit)) {
    SensorResiduals r{fit.runs[se.run].id, fit.sensor_names[se.run][se.sensor], 0, 0, 0, 2};
    for (const auto& g : fit.goodness)
      if (g.run == r.run && g.sensor == r.sensor) r.position_m = g.position_m;
    double sum = 0, sq = 0, dw = 0;
    const double duration = samples[se.first + se.count - 1].time_s;
    std::vector<double> e_sum(static_cast<std::size_t>(bins), 0), rise_sum(static_cast<std::size_t>(bins), 0),
        count(static_cast<std::size_t>(bins), 0);
    for (std::size_t i = se.first; i < se.first + se.count; ++i) {
      const double e = samples[i].measured_C - samples[i].simulated_C;
      sum += e;
      sq += e * e;
      if (i > se.first) dw += std::pow(e - (samples[i - 1].measured_C - samples[i - 1].simulated_C), 2);
      const auto b = static_cast<std::size_t>(
          std::clamp(static_cast<int>(samples[i].time_s / std::max(duration, 1e-9) * bins), 0, bins - 1));
      e_sum[b] += e;
      rise_sum[b] += samples[i].simulated_C - fit.runs[se.run].initial_temperature_C;
      count[b] += 1;
    }
    const double n = static_cast<double>(se.count);
    r.bias_K = sum / n;
    r.rmse_K = std::sqrt(sq / n);
    r.durbin_watson = sq > 0 ? dw / sq : 2.0;
    d.sensors.push_back(r);
    for (std::size_t b = 0; b < static_cast<std::size_t>(bins); ++b) {
      if (count[b] == 0) continue;
      cell_e.push_back(e_sum[b] / count[b]);
      cell_rise.push_back(rise_sum[b] / count[b]);
      cell_bin.push_back(b);
      cell_velocity.push_back(fit.runs[se.run].velocity_m_s);
      cell_load.push_back(fit.runs[se.run].load_N);
      cell_position.push_back(r.position_m);
      cell_run.push_back(static_cast<double>(se.run));
    }
  }
  const std::size_t cells = cell_e.size();
  const std::vector<std::size_t> all(cells, 0);
  std::vector<std::size_t> phase(cells);
  for (std::size_t c = 0; c < cells; ++c) phase[c] = cell_bin[c] < static_cast<std::size_t>(bins) / 2 ? 0 : 1;
  // The course over time, refined by a covariate: label = bin + bins · covariate group.
  auto by_time_and = [&](const std::vector<double>& covariate) {
    const std::vector<std::size_t> groups = detail::value_bins(covariate);
    std::vector<std::size_t> labels(cells);
    for (std::size_t c = 0; c < cells; ++c) labels[c] = cell_bin[c] + static_cast<std::size_t>(bins) * groups[c];
    return labels;
  };
  d.covariates.push_back(detail::nested_anova("time_s", all, cell_bin, cell_e));
  d.covariates.push_back(detail::nested_anova("heating vs steady phase", all, phase, cell_e));
  d.covariates.push_back(detail::nested_anova("temperature rise", all, detail::value_bins(cell_rise), cell_e));
  d.covariates.push_back(detail::nested_anova("velocity_m_s", cell_bin, by_time_and(cell_velocity), cell_e));
  d.covariates.push_back(detail::nested_anova("load_N", cell_bin, by_time_and(cell_load), cell_e));
  d.covariates.push_back(detail::nested_anova("position_m", cell_bin, by_time_and(cell_position), cell_e));
  // Runs at the same conditions that still differ in their course: run order (or the rig).
  std::vector<double> condition(cells);
  for (std::size_t c = 0; c < cells; ++c) condition[c] = cell_velocity[c] * 1e6 + cell_load[c];
  const std::vector<std::size_t> coarse = by_time_and(condition), fine = by_time_and(cell_run);
  d.covariates.push_back(detail::nested_anova("run order", coarse, fine, cell_e));
  std::erase_if(d.covariates, [](const CovariateTest& t) { return t.n == 0; });
  detail::holm_adjust(d.covariates);  // seven tests of the same residuals: the family's error stays at structure_p
  std::sort(d.covariates.begin(), d.covariates.end(), [](auto& a, auto& b) { return a.p_value < b.p_value; });
  // Strongest first: the significant ones by size, then the rest by p.
  auto counts = [&](const CovariateTest& t) {
    return t.p_adjusted < o.structure_p && t.size >= o.min_structure_fraction * d.rmse_K;
  };
  std::stable_sort(d.covariates.begin(), d.covariates.end(), [&](auto& a, auto& b) {
    if (counts(a) != counts(b)) return counts(a);
    return counts(a) ? a.size > b.size : a.p_value < b.p_value;
  });
  for (auto& c : d.covariates) c.structured = counts(c);
  d.structured = !d.covariates.empty() && d.covariates.front().structured;
  return d;
}

ThermalFitResult fit_model(const ThermalDataSet& data, const ThermalDiagnosisOptions& o, const std::vector<std::string>& extensions,
                           const ThermalFitResult* from, const std::vector<ThermalSensorTerm>& terms = {}) {
  ThermalFitOptions f = model_options(o);
  f.extensions = extensions;
  f.sensor_terms = terms;
  // Warm-started, a mechanism converges in a few iterations; one that crawls (a lag or an h(V)
  // the data push to a bound) gains nothing by crawling on. Terms start from a linearised
  // estimate, further away: they get the iterations a fit needs.
  if (terms.empty()) f.fit.max_iterations = std::min(f.fit.max_iterations, kCandidateIterations);
  if (from) {
    f.alpha_start = std::clamp(from->joint.parameter("alpha").value, f.alpha_lower, f.alpha_upper);
    for (const auto& p : from->joint.parameters) f.parameter_start.emplace_back(p.name, p.value);
  }
  try {
    return fit_thermal(data, f);
  } catch (const InvalidParameter& e) {
    ThermalFitResult failed;
    failed.joint.warnings.push_back(e.what());
    return failed;
  }
}

}  // namespace

namespace {

// The preconditions this diagnosis knows how to check (thermal_mechanism.hpp): a mechanism
// registered with another fails to compile here, not silently tried.
constexpr bool preconditions_known() {
  for (const auto& m : ThermalMechanismLibrary::infos) {
    const std::string_view varies = m.precondition.varies, fitted = m.precondition.not_with_fitted;
    if (!(varies.empty() || varies == "velocity_m_s") || !(fitted.empty() || fitted == "h_W_m2K")) return false;
  }
  return true;
}
static_assert(preconditions_known(), "a thermal mechanism's precondition this diagnosis does not check");

// Why these data cannot tell the named mechanism (its precondition), or "" when they can.
std::string untellable_because(const ThermalDataSet& data, const ThermalFitOptions& fit, const std::string& name) {
  const ThermalMechanismPrecondition& needs = ThermalMechanismLibrary::infos[*find_thermal_mechanism(name)].precondition;
  if (std::string_view(needs.varies) == "velocity_m_s") {
    std::set<double> speeds;
    for (const auto& run : data.runs) speeds.insert(run.velocity_m_s);
    if (speeds.size() < 2) return "all runs at one speed";
  }
  if (std::string_view(needs.not_with_fitted) == "h_W_m2K" && fit.fit_h) return "h is fitted in every model";
  return "";
}

// The library's mechanisms a diagnosis tries on these data; those whose precondition the data
// lack go to `skipped`, with why.
std::vector<std::string> candidates(const ThermalDataSet& data, const ThermalFitOptions& fit,
                                    std::vector<std::string>& skipped) {
  std::vector<std::string> library;
  for (const auto& e : thermal_extension_library()) {
    if (e.source && (*e.source == fit.source || *e.source == SourceModel::paper)) continue;  // no step back to the paper's
    if (const std::string why = untellable_because(data, fit, e.name); !why.empty()) {
      skipped.push_back(e.name + ": " + why);
      continue;
    }
    library.push_back(e.name);
  }
  return library;
}

// The named mechanism's entry of the library.
ThermalExtensionInfo mechanism_info(const std::string& name) {
  for (auto& e : thermal_extension_library())
    if (e.name == name) return e;
  throw InvalidParameter("extension", "unknown thermal mechanism '" + name + "'");
}

// A fitted model as the selection compares it, with the estimate of `effect` (none: "").
std::pair<detail::ModelFit, CandidateScore> summarise(const ThermalFitResult& fit, const std::string& effect) {
  detail::ModelFit m;
  CandidateScore c;
  c.value = c.se = c.ci_low = c.ci_high = std::numeric_limits<double>::quiet_NaN();
  if (fit.samples.empty()) {
    m.problem = "the fit failed: " + (fit.joint.warnings.empty() ? std::string("no result") : fit.joint.warnings.front());
    m.ss = m.n = m.n_eff = m.cv_rmse = std::numeric_limits<double>::infinity();
    return std::make_pair(m, c);
  }
  m.ss = fit.sum_of_squares_K2;
  m.n = static_cast<double>(fit.samples.size());
  m.n_eff = effective_sample_size(m.n, lag1_autocorrelation(fit));
  m.k = fit.joint.free_parameters;
  m.cv_rmse = fit.cv_rmse_K;
  for (const auto& s : fit.samples) m.fitted.push_back(s.simulated_C);
  if (const ParameterEstimate a = detail::within_bounds(fit.joint.parameter("alpha")); fit.joint.solver.usable)
    c.alpha = a.value, c.alpha_low = a.interval == "profile" ? a.profile_low : a.ci_low,
    c.alpha_high = a.interval == "profile" ? a.profile_high : a.ci_high;
  if (!fit.joint.solver.usable) m.problem = "the fit did not converge: " + fit.joint.solver.termination;
  for (const auto& issue : fit.joint.identifiability.issues) m.problem = "not identifiable: " + issue.why;
  if (!effect.empty()) {
    const ThermalExtensionInfo e = mechanism_info(effect);
    c.measure = e.measure;
    if (!e.parameters.empty()) detail::set_estimate(c, fit.joint.parameter(e.parameters.front()));
  }
  return std::make_pair(m, c);
}

detail::ModelFit model_fit(const ThermalFitResult& fit) { return summarise(fit, std::string()).first; }

// The diagnosis's final model: `fit`, with the causes `accepted`; what it leaves and how α
// (and h) moved from the baseline.
void settle(ThermalDiagnosis& d, const std::vector<std::string>& accepted, ThermalFitResult fit,
            const ThermalDiagnosisOptions& o, const detail::NoiseFloor& noise) {
  d.final_fit = std::move(fit);
  d.final = diagnose_residuals(d.final_fit, o, noise);
  d.cv_rmse_before_K = d.baseline_fit.cv_rmse_K;
  d.cv_rmse_after_K = d.final_fit.cv_rmse_K;
  d.accepted = detail::accepted_scores(d.rounds, accepted, [&](const std::string& name) {
    const ThermalExtensionInfo e = mechanism_info(name);
    return e.parameters.empty() ? nullptr : &d.final_fit.joint.parameter(e.parameters.front());
  });
  d.shifts.clear();
  for (const auto& p : d.baseline_fit.joint.parameters)
    if (p.name == "alpha" || p.name == "h_W_m2K") d.shifts.push_back(parameter_shift(p, d.final_fit.joint.parameter(p.name)));
}

// Beyond the library: an empirical sensor term, fitted jointly with the accepted causes. A
// cause accepted before the term may only have stood in for what the term models: each must
// still pass, as a candidate, on top of the others and the term (learned anew without it), or
// it is dropped.
void search_beyond_the_library(const ThermalDataSet& data, const ThermalDiagnosisOptions& o,
                               const detail::NoiseFloor& noise, const detail::SelectionRules& rules,
                               const detail::Selection<ThermalFitResult>& selection,
                               std::vector<std::string>& accepted, ThermalDiagnosis& d) {
  auto search_with = [&](const std::vector<std::string>& causes, const ThermalFitResult& named) {
    ThermalFitOptions current = model_options(o);
    current.extensions = causes;
    auto refit = [&](const std::vector<ThermalSensorTerm>& terms) { return fit_model(data, o, causes, &named, terms); };
    return detail::learn_thermal_term(data, current, named, refit, model_fit, rules);
  };
  detail::ThermalTermSearch search = search_with(accepted, d.final_fit);
  for (std::size_t i = accepted.size(); search.fit && i-- > 0;) {
    std::vector<std::string> others = accepted;
    others.erase(others.begin() + static_cast<std::ptrdiff_t>(i));
    // The model without it: the forward selection's own where it passed through it (the same
    // model, the same held-out RMSE), else refitted.
    const bool on_path = others.size() < selection.path.size() &&
                         std::equal(others.begin(), others.end(), selection.accepted.begin());
    ThermalFitResult named = on_path ? selection.path[others.size()] : fit_model(data, o, others, &d.final_fit);
    if (named.samples.empty()) continue;
    detail::ThermalTermSearch without = search_with(others, named);
    if (!without.fit) continue;
    CandidateScore c;
    if (detail::score_candidate(model_fit(*without.fit), model_fit(*search.fit), rules, c)) continue;
    d.dropped.push_back(fmt::format("{} (accepted in round {}, it adds nothing once the empirical term is in: {})",
                                    accepted[i], i + 1, c.reason));
    // Its own step: from the model with it to the model refitted without it.
    d.steps.push_back(detail::make_step("drop cause", accepted[i], model_fit(d.final_fit), model_fit(named)));
    accepted = others;
    settle(d, accepted, std::move(named), o, noise);
    search = std::move(without);
  }
  d.empirical = std::move(search.finding);
  d.empirical_terms = std::move(search.terms);
  if (search.fit) d.empirical_fit = std::move(*search.fit);
  if (d.empirical.found)
    d.steps.push_back(detail::make_step("add empirical term", d.empirical.formula, model_fit(d.final_fit), model_fit(d.empirical_fit)));
}

}  // namespace

ThermalFitOptions diagnosis_fit_options(const ThermalDataSet& data, const ThermalDiagnosisOptions& options) {
  ThermalFitOptions f = model_options(options);
  const std::vector<double> none;
  const auto& times = data.runs.empty() ? none : data.runs.front().trace.time_s;
  if (options.min_record_spacing_s > 0 && f.every == 1 && times.size() >= 2) {
    const double spacing = (times.back() - times.front()) / static_cast<double>(times.size() - 1);
    f.every = static_cast<std::size_t>(std::max(1.0, std::ceil(options.min_record_spacing_s / spacing - 1e-9)));
  }
  return f;
}

ThermalDiagnosis diagnose_thermal(const ThermalDataSet& data, const ThermalDiagnosisOptions& options) {
  if (data.runs.size() < kMinDiagnosisRuns)
    throw InvalidParameter("runs", fmt::format("a diagnosis needs at least {} runs (it holds one out at a time)",
                                               kMinDiagnosisRuns));
  ThermalDiagnosisOptions o = options;
  o.fit.every = diagnosis_fit_options(data, options).every;
  ThermalDiagnosis d;
  // The noise floor of the residuals and of the held-out RMSE: the thermocouples' own noise.
  const detail::NoiseFloor noise = noise_floor(data, o);
  d.noise_K = noise.sigma;

  // 1. The baseline.
  d.baseline_fit = fit_thermal(data, model_options(o));
  d.baseline = diagnose_residuals(d.baseline_fit, o, noise);

  // 2-3. The library, less what these data cannot show, added one cause at a time.
  const std::vector<std::string> library = candidates(data, o.fit, d.skipped);
  auto fit_candidate = [&](const std::vector<std::string>& extensions, const ThermalFitResult& current) {
    return fit_model(data, o, extensions, &current);
  };
  const detail::SelectionRules rules{.lrt_p = o.lrt_p,
                                     .min_cv_gain_percent = o.min_cv_gain_percent,
                                     .noise_floor = std::isfinite(d.noise_K) ? d.noise_K : 0.0,
                                     .min_excess_removed = o.min_excess_removed,
                                     .max_effects = o.max_effects,
                                     .parallel = true,
                                     .progress = o.progress};
  auto selection = detail::forward_select(library, d.baseline_fit, fit_candidate, summarise, rules);
  d.rounds = std::move(selection.rounds);

  // 4. What the accepted causes leave, and how α (and h) move.
  std::vector<std::string> accepted = selection.accepted;
  d.steps = selection.steps;
  settle(d, accepted, selection.current, o, noise);

  // 5. Beyond the library: when structure remains, an empirical sensor term, fitted jointly.
  if (d.final.structured || !d.final.lack_of_fit.fits) search_beyond_the_library(data, o, noise, rules, selection, accepted, d);
  d.cv_rmse_after_K = detail::final_cv_rmse(d.steps, d.cv_rmse_before_K);

  detail::conclude(d, "The published rail model", "K", d.cv_rmse_before_K, d.final_fit.cv_rmse_K, d.baseline.rmse_K);
  for (const auto& why : d.dropped) d.summary += " Dropped: " + why + ".";
  return d;
}

std::string thermal_diagnosis_json(const ThermalDiagnosis& d) {
  using detail::number;
  auto diagnostics = [&](const ThermalResidualDiagnostics& r) {
    nlohmann::json sensors = nlohmann::json::array();
    for (const auto& s : r.sensors)
      sensors.push_back({{"run", s.run}, {"sensor", s.sensor}, {"position_m", s.position_m}, {"bias_K", number(s.bias_K)},
                         {"rmse_K", number(s.rmse_K)}, {"durbin_watson", number(s.durbin_watson)}});
    return nlohmann::json{{"rmse_K", number(r.rmse_K)},
                          {"lag1_autocorrelation", number(r.lag1_autocorrelation)},
                          {"n_eff", number(r.n_eff)},
                          {"sensors", sensors},
                          {"covariates", detail::covariates_json(r.covariates)},
                          {"structured", r.structured},
                          {"lack_of_fit", detail::lack_of_fit_json(r.lack_of_fit)}};
  };
  nlohmann::json j = detail::verdict_json(d, d.cv_rmse_before_K, d.cv_rmse_after_K, "K");
  j["kind"] = "thermal diagnosis";
  j["lmcal_version"] = LMCAL_VERSION;
  j["schema_version"] = kOutputSchemaVersion;
  j["thermocouple_noise_K"] = number(d.noise_K);
  j["not_tried"] = d.skipped;
  j["dropped_for_the_empirical_term"] = d.dropped;
  j["baseline_residuals"] = diagnostics(d.baseline);
  j["final_residuals"] = diagnostics(d.final);
  return j.dump(2) +
         "\n";
}

}  // namespace lmcal
