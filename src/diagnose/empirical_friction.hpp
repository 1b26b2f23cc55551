// The friction diagnosis's search beyond the library (private): when the law with its named
// causes still leaves structure, learn an empirical term (friction_terms.hpp) from a
// dictionary of transforms of the log's covariates by sparse regression (sparse_regression.hpp),
// refit it jointly with the law, and keep it only if that fit passes the rules a named cause
// must pass (significant, and better on held-out runs).
//
// The dictionary, from what the log varies (each covariate only when it takes ≥ 2 values):
//   linear      V, P, pc, Lb, T − T_i, direction
//   square      V², P², (T − T_i)²
//   products    every pair of the above linear ones; F_law·V, F_law·(T − T_i)
//   decay       exp(−s/ℓ), exp(−s/ℓ)·F_law, exp(−s/ℓ)·P in the sliding distance s;
//               exp(−t/ℓ), exp(−t/ℓ)·F_law in the time since the run's start (needs time_s);
//               ℓ on a grid from 1 % to 100 % of the distance (duration) in the data
//   lag         the law at a temperature lagging the logged one, for the search
//               F_law(lag_τ(T)) − F_law(T), τ from 15 s to 32 min (needs time_s, and a temperature
//               that changes within runs)
// A family (one transform at different scales) enters with one scale at most; the joint fit
// then frees that scale.
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "lmcal/diagnose/friction_diagnosis.hpp"
#include "selection.hpp"

namespace lmcal::detail {

struct FrictionTermSearch {
  EmpiricalFinding finding;
  std::optional<FrictionFitResult> fit;  // the law, its causes and the term, when found
};

// `current`: the law with the accepted causes, fitted with random run offsets; `refit(terms)`
// fits that model plus the terms (warm-started); `summarise` gives a fit's ModelFit as the
// forward selection scores it; `rules` are the selection's.
FrictionTermSearch learn_friction_term(const FrictionLog& log, const FrictionFitResult& current,
                                       const std::function<FrictionFitResult(const std::vector<FrictionTerm>&)>& refit,
                                       const std::function<ModelFit(const FrictionFitResult&)>& summarise,
                                       const SelectionRules& rules, double reference_temperature_C);

}  // namespace lmcal::detail
