// JSON of a FitResult, shared by every fit's output (private to the fit layer).
#pragma once

#include <nlohmann/json.hpp>

#include "lmcal/fit/fit_result.hpp"

namespace lmcal::detail {

// A number, or null when it is not finite (NaN SE of a held parameter, say).
nlohmann::json number(double v);
// The covariance methods side by side, the one quoted and why, the between-run tests.
nlohmann::json uncertainty_json(const FitResult& fit);
// The quoted covariance in a few lines for a terminal: method and why, the SE of each free
// (non-nuisance) parameter by every method, notes.
std::string uncertainty_summary(const FitResult& fit);
// Parameters, uncertainty, correlation, identifiability, solver and warnings.
// One estimate as every output writes it (schema_version 2): "ci95" is the interval the text
// quotes ("interval" says which: linear, profile, or none with nulls); the linear, profile and
// bootstrap intervals beside it; "held" when not fitted (asked to be held, or not identifiable).
nlohmann::json parameter_json(const ParameterEstimate& p);
nlohmann::json fit_json(const FitResult& fit);

}  // namespace lmcal::detail
