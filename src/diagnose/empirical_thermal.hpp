// The thermal diagnosis's search beyond the library (private): when the rail model with its
// named causes still leaves structure, learn an empirical sensor-side term (a sum of
// c_j φ_j(run, t) added to every thermocouple reading; src/fit/thermal_terms.hpp) from a
// dictionary by sparse regression (sparse_regression.hpp), refit it jointly with the model,
// and keep it only if that fit passes the rules a named cause must pass.
//
// The dictionary (family = one transform at different scales; one member enters at most):
//   t, t²                     time since the run's first record (h)
//   a_P, b_P                  the run's ambient's own swing at its dominant period P, in phase and
//                             a quarter period earlier; P the period (≥ 1 h, ≤ the longest run)
//                             whose least-squares sine explains most of the runs' detrended ambient;
//                             a_P2, b_P2 the same at the next strongest period (a factor ≥ 1.5 away)
//   T∞ − T∞(0)                the ambient's change since the start
//   lag_τ(T∞) − T∞            τ from 15 min to 8 h (a family)
//   rise·t                    the simulated rise times t
//   V·t                       the speed times t (when the runs differ in speed)
// The regression's fixed columns are the model's global parameters linearised (∂reading/∂θ
// of α, h and the extensions'), and it holds one run out at a time. What the fit re-estimates
// of a held-out run from its own records — its thermocouples' offsets and its heat scale — is
// projected out of every column on that run's rows first: the baseline bends the heat scales
// (and α) to absorb what it misses, and a term judged without letting them return would look
// worse, linearised, than its joint fit is.
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "lmcal/diagnose/thermal_diagnosis.hpp"
#include "selection.hpp"

namespace lmcal::detail {

struct ThermalTermSearch {
  EmpiricalFinding finding;
  std::optional<ThermalFitResult> fit;  // the model, its causes and the term, when found
  std::vector<ThermalSensorTerm> terms;  // the term's parts at the joint fit's values, when found
};

// The period (s) whose sine, on top of a line, explains most of the ambients' variation
// (summed over runs), on a log grid from `shortest_s` to the longest ambient record; and the
// `count` strongest such peaks, strongest first, each a factor of 1.5 or more from the others.
double dominant_ambient_period_s(const std::vector<AmbientTrace>& ambients, double shortest_s = 3600);
std::vector<double> dominant_ambient_periods_s(const std::vector<AmbientTrace>& ambients, std::size_t count,
                                               double shortest_s = 3600);

// `options`: what `current` was fitted with (its extensions, sensitivities on); `refit(terms)`
// fits that model plus the sensor terms (warm-started); `summarise` gives a fit's ModelFit as
// the forward selection scores it; `rules` are the selection's.
ThermalTermSearch learn_thermal_term(const ThermalDataSet& data, const ThermalFitOptions& options,
                                     const ThermalFitResult& current,
                                     const std::function<ThermalFitResult(const std::vector<ThermalSensorTerm>&)>& refit,
                                     const std::function<ModelFit(const ThermalFitResult&)>& summarise,
                                     const SelectionRules& rules);

}  // namespace lmcal::detail
