// The calibrated models: the published ones with the causes the diagnoses accepted, refitted in
// full, and model.toml made of them.
#include <algorithm>

#include "calibrate/steps.hpp"

namespace lmcal {

namespace detail {

// The calibrated friction model: the law with the causes the diagnosis accepted (and the
// empirical term it learned, if any), each run's load-cell zero a nuisance offset (as the
// diagnosis fits it), refitted in full.
void calibrate_friction_model(Calibration& c) {
  CalibratedModel& m = c.calibrated;
  if (c.friction_diagnosis)
    for (const auto& cause : c.friction_diagnosis->accepted) m.friction_causes.push_back(cause.effect);
  m.friction_options = c.friction_options;
  m.friction_options.effects = m.friction_causes;
  m.friction_options.effect_start.clear();
  for (const auto& name : m.friction_causes) m.friction_options.effect_start.push_back(c.friction_diagnosis->final_fit.fit.parameter(name).value);
  // An empirical term the diagnosis kept is part of the model, marked as such (its fitted
  // values are the start).
  m.friction_options.terms.clear();
  if (c.friction_diagnosis && c.friction_diagnosis->empirical.found) {
    const FrictionFitResult& learned = c.friction_diagnosis->empirical_fit;
    m.friction_options.terms = learned.terms;
    // A term's coefficient has no natural bounds for a multi-start to sample within: start
    // from the diagnosis's joint fit instead.
    const FrictionConstants<double> k = learned.constants();
    for (std::size_t j = 0; j < FrictionConstants<double>::kFittable; ++j)
      fittable_constant(m.friction_options.start, j) =
          std::clamp(fittable_constant(k, j), m.friction_options.bounds[j].first, m.friction_options.bounds[j].second);
    m.friction_options.fit.starts = 0;
  }
  m.friction_options.run_offsets = c.options.friction_diagnosis.fit.run_offsets;  // random unless asked otherwise
  m.friction_options.cross_validate = c.friction_log->run_names.size() >= 2;
  m.friction = fit_friction(*c.friction_log, m.friction_options);
}

// The calibrated rail model: the mechanisms the diagnosis accepted, fitted as the diagnosis
// fits its models (offsets where the data determine them, a heat scale per run), with the heat
// from the calibrated friction model and that model's uncertainty carried into α.
void calibrate_thermal_model(Calibration& c, const CalibrationOptions& options) {
  CalibratedModel& m = c.calibrated;
  ThermalFitOptions& t = m.thermal_options;
  t = diagnosis_fit_options(*c.thermal_data, options.thermal_diagnosis);
  t.offsets = options.thermal.offsets;
  t.per_run_fits = true;
  t.fit.profile = ProfileMode::automatic;
  t.fit.bootstrap = options.thermal.fit.bootstrap;
  t.fit.covariance = options.thermal.fit.covariance;
  if (c.thermal_diagnosis) {
    const ThermalFitResult& final_fit = c.thermal_diagnosis->final_fit;
    for (const auto& cause : c.thermal_diagnosis->accepted) m.thermal_causes.push_back(cause.effect);
    t.extensions = m.thermal_causes;
    t.alpha_start = std::clamp(final_fit.joint.parameter("alpha").value, t.alpha_lower, t.alpha_upper);
    for (const auto& p : final_fit.joint.parameters) t.parameter_start.emplace_back(p.name, p.value);
    // An empirical term on the readings (a drift, a swing the ambient sensors miss) is fitted
    // with the model, so that α is not bent to absorb it; it describes the readings, not the
    // rail, and the model file records it as such.
    if (c.thermal_diagnosis->empirical.found) t.sensor_terms = c.thermal_diagnosis->empirical_terms;
  }
  if (m.friction) {
    t.friction = m.friction->constants();
    t.friction_effects = m.friction->effects();
    t.friction_fit = m.friction->fit;
  }
  m.thermal = fit_thermal(*c.thermal_data, t);
}

}  // namespace detail

// model.toml: the calibrated model with the set's provenance.
ModelFile calibrated_model_file(const Calibration& c) {
  const CalibratedModel& m = c.calibrated;
  ModelFile file = model_file_of(m.friction ? &*m.friction : nullptr, m.friction_options, m.thermal ? &*m.thermal : nullptr,
                                 m.thermal_options);
  file.set = c.set.name;
  if (c.thermal_data) file.guide = calibrated_guide(*c.thermal_data);
  file.command = c.command;
  file.inputs = c.inputs;
  return file;
}

}  // namespace lmcal
