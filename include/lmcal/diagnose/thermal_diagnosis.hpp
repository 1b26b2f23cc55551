// What the published rail model gets wrong on thermocouple traces, the named physical
// cause, and what modelling it gains on runs it was not fitted to.
//
//   Every thermocouple of every run gets an offset (its bias against the ambient sensors),
//   and every run a heat scale tied to 1 by the heat rate's uncertainty (a prior; the
//   friction law is evaluated at a temperature known to a few tenths of a kelvin, and Q_f
//   changes by about 5 %/K), fitted with α in every model. So the diagnosis looks at the
//   course of the traces over time and at levels beyond what the heat rate's uncertainty
//   allows, not at thermocouple biases. Those two are the nuisance parameters that are always
//   fitted; a global heat scale is α itself (the rail sees only αQ), and a bias of the ambient
//   sensors shifts the ambient and the start temperature alike, hence the whole simulated
//   field, by one constant (the model is linear in temperature): every thermocouple's offset
//   takes it, and the heat scale the 5 %/K it makes in Q_f. Neither is a candidate.
//
//   1. baseline: α (and what the fit options free) with the published model; the residuals
//      per run and sensor (bias, RMSE, Durbin-Watson), their lag-1 autocorrelation and the
//      effective sample size n_eff = n (1 - ρ)/(1 + ρ) it leaves, and ANOVA F tests on cell
//      means (run × sensor × time bin; one value per cell, so serially correlated samples do
//      not count as independent evidence): time, heating vs steady phase, temperature rise,
//      and how the course over time differs with speed, load, sensor position and run, their
//      p Holm-adjusted over the seven; and a lack-of-fit F test of the residual variance
//      against the thermocouples' noise variance (second differences of the traces);
//   2. candidates: each mechanism of the thermal extension library added on its own and
//      fitted, the nuisance "h differs" (convection_scale) among them; scored by leave-one-run-out prediction RMSE (the run's global parameters from
//      the others, one Gauss-Newton step), AICc, BIC and a likelihood-ratio test, both on
//      n_eff; a switch without parameters (the source model) needs a BIC 10 lower;
//   3. forward selection: a candidate passes when significant, when it lowers the held-out
//      RMSE by 0.1 % and removes a tenth of its excess over the thermocouple noise; the
//      passing candidate with the largest held-out gain is
//      accepted, the rest are tried on top of it, until nothing more passes; candidates
//      that change the fitted temperatures as the accepted one does (correlation > 0.99) are
//      a tie, named with it (base_loss and convection_scale: b = Δh·p, only the rail's two
//      end faces tell them apart);
//   4. verdict: causes with magnitude and interval, held-out RMSE before and after, how α
//      moves, what remains; "explained" only when the final residuals follow no covariate and
//      pass the lack-of-fit test, else "partly explained"; "unexplained" with the covariate
//      the residuals follow (or their lack of fit) when no candidate passes, or "no
//      significant discrepancy";
//   5. beyond the library, when the final residuals stay structured or fail the lack-of-fit
//      test: an empirical sensor-side term c_1 φ_1 + … added to every thermocouple reading,
//      chosen by sparse regression over a dictionary (time since the start t and t², the
//      ambient's swing at its dominant period in phase and in quadrature, the ambient's change
//      and its lags, rise·t, V·t) against leave-one-run-out error, then fitted jointly with
//      the model (its period or lag free) and kept only if it passes the candidates' rules:
//      "unexplained — empirical term found" (or "partly explained — …"), never a named cause.
//      Each cause accepted before it must then pass again on top of the others and the term
//      (learned anew without it), or it is dropped (`dropped`): it stood in for the term.
//
//   Trap: with the heat from a measured run-mean friction (mean_friction_N), the coupling
//   candidate keeps the run mean of its heat at that value; give start_friction_N when the
//   friction of the cold rail is known instead.
#pragma once

#include "lmcal/export.hpp"

#include <string>
#include <vector>

#include "lmcal/diagnose/diagnosis.hpp"
#include "lmcal/fit/thermal_fit.hpp"

namespace LMCAL_API lmcal {

struct SensorResiduals {
  std::string run, sensor;
  double position_m = 0;
  double bias_K = 0, rmse_K = 0;
  double durbin_watson = 2;
};

struct ThermalResidualDiagnostics {
  double rmse_K = 0;
  double lag1_autocorrelation = 0;  // pooled over the sensor series
  double n_eff = 0;                 // effective independent residuals
  std::vector<SensorResiduals> sensors;
  std::vector<CovariateTest> covariates;  // strongest first
  bool structured = false;                // a covariate significant at structure_p, and large enough
  LackOfFit lack_of_fit;                  // the residual variance against the thermocouples' noise
};

struct ThermalDiagnosisOptions {
  // The baseline: source, heat input, numerics (offsets and heat scales are always fitted).
  // Dozens of fits: 60 s steps (Crank-Nicolson; the rail's time constant is over an hour).
  ThermalFitOptions fit{.time_step_s = 60};
  // Records closer than this are thinned (every n-th) unless fit.every asks for more.
  double min_record_spacing_s = 15;
  double lrt_p = 1e-3;
  double min_cv_gain_percent = 0.1;
  double min_excess_removed = 0.1;  // and this share of the held-out RMSE above the thermocouple noise  // the held-out RMSE is mostly noise: gains are small in %
  double structure_p = 1e-3;
  // Structure smaller than this share of the residual RMSE is reported but not called a
  // discrepancy: with thousands of records, millikelvin (the start temperature read from a
  // noisy ambient, a logger's rounding) is significant without mattering.
  double min_structure_fraction = 0.2;
  // The thermocouples' noise (the lack of fit's pure error, and the floor of the held-out
  // RMSE) from second differences over records this far apart: a logger's or sensor's noise
  // with memory of seconds counts in full (consecutive records would see only its fast part,
  // and call the rest a lack of fit), while the rail's warm-up stays smooth on this scale.
  double noise_spacing_s = 120;
  std::size_t max_effects = 3;
  int time_bins = 12;     // cells per sensor series for the covariate tests
  Progress progress;      // the candidate fits, round by round
};

struct ThermalDiagnosis {
  std::string verdict;  // "no significant discrepancy", "explained", "partly explained", "unexplained"
  std::string summary;
  ThermalResidualDiagnostics baseline, final;
  std::vector<std::vector<CandidateScore>> rounds;
  std::vector<CandidateScore> accepted;
  std::vector<std::string> skipped;  // mechanisms not tried, and why
  // Causes accepted before the empirical term that no longer pass on top of it (they stood in
  // for what it models), and why: left out of `accepted` and the final fit.
  std::vector<std::string> dropped;
  // From the baseline to the final model: the causes added, each cause dropped (its own step:
  // the model refitted without it) and the empirical term; each step's before is the previous
  // step's after, and cv_rmse_after_K is the last step's after.
  std::vector<DiagnosisStep> steps;
  double cv_rmse_before_K = 0, cv_rmse_after_K = 0, cv_gain_percent = 0;
  double noise_K = 0;  // the thermocouples' noise (second differences): the floor of the held-out RMSE
  std::vector<ParameterShift> shifts;
  std::string unexplained_covariate;
  ThermalFitResult baseline_fit, final_fit;  // for before/after plots
  // When the residuals stay structured after the causes: the empirical term learned (its
  // curve over the time since the run's start, h), and the fit with the causes and that term
  // (empty unless found; its samples' simulated_C include the term).
  EmpiricalFinding empirical;
  ThermalFitResult empirical_fit;
  std::vector<ThermalSensorTerm> empirical_terms;  // its parts at their fitted values (for the calibrated model)
};

ThermalDiagnosis diagnose_thermal(const ThermalDataSet& data, const ThermalDiagnosisOptions& options);
// How the diagnosis fits every model of these data: its numerics (records thinned to
// min_record_spacing_s), every thermocouple's offset and every run's heat scale fitted, one
// start, leave-one-run-out scores, no per-run fits or profiles.
ThermalFitOptions diagnosis_fit_options(const ThermalDataSet& data, const ThermalDiagnosisOptions& options);
std::string thermal_diagnosis_json(const ThermalDiagnosis& d);

}  // namespace lmcal
