// The friction residuals' tests (friction_residual_tests.cc): the covariates a fit's residuals
// are tested against and the tests themselves, shared with the diagnosis that runs them on the
// models it tries.
#pragma once

#include <string_view>
#include <vector>

#include "lmcal/diagnose/friction_diagnosis.hpp"

namespace lmcal::detail {

// An RMS acceleration under which a mass error's force is under a tenth of a newton per 10 kg of
// error: no precondition for moving_mass_error.
constexpr double kMinCauseAcceleration_m_s2 = 0.01;

// Whether the log's accelerations are large enough to matter beside friction (RMS).
bool accelerates(const FrictionLog& log);

// Whether a log column varies enough for a cause that needs it (FrictionEffectInfo::varies):
// both directions, or a spread beyond the column's resolution (a condition a combination law
// did not log is constant at its neutral value).
bool varies_in(const FrictionLog& log, std::string_view column);

// The covariates the residuals are tested against, one value per sample. Temperature at
// its nominal (condition) value: grouping by the logged temperature itself would find the
// thermocouple's noise (errors in variables), not a missing term.
struct Covariate {
  const char* name;
  std::vector<double> value;
  bool run_level = true;  // one value within every run: seen only between runs
};

// `tolerance`: values within it of a run's first are that value (condition_tolerance).
std::vector<Covariate> covariates_of(const FrictionLog& log, double tolerance);

// The residuals of `fit` (random zero offsets per run): within-run structure on the condition
// means of the run-centred residuals; what changes only between runs on the run means,
// judged against their spread (the offsets' variance is the error term); interactions of
// every pair; lack of fit against pure error. Holm over all tests.
ResidualDiagnostics diagnose_residuals(const FrictionLog& log, const FrictionFitResult& fit, const FrictionDiagnosisOptions& o);

}  // namespace lmcal::detail
