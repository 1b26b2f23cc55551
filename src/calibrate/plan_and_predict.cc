// What the calibrated models are for, inside the calibration: the next measurements to make
// (friction conditions, thermal runs) and the runs' own cycle predicted with bands.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

#include "calibrate/steps.hpp"

namespace lmcal::detail {

// The next friction conditions to log for the calibrated law: D-optimal over every combination
// of the logs' own speeds, loads, preloads, temperatures and directions.
void plan_next_friction(Calibration& c) {
  if (!c.calibrated.friction || !c.friction_log) return;
  // A combination law's log holds neutral stand-ins for what it did not give: a plan over them
  // would print a load and a preload nobody logged.
  if (const FrictionLawConditions& law = c.friction_log->law; law.combination()) {
    c.notes.push_back(fmt::format("plan of the next friction conditions skipped: the law is fitted in combinations (not given: {}); "
                                  "log them to plan for the paper's constants",
                                  fmt::join(law.not_logged(), ", ")));
    return;
  }
  try {
    // A tie the diagnosis reported among the accepted causes: the conditions that separate it,
    // from a fit with both.
    if (c.friction_diagnosis)
      for (const auto& cause : c.friction_diagnosis->accepted)
        for (const auto& tie : cause.tied_with) {
          if (!find_friction_effect(cause.effect) || !find_friction_effect(tie) || c.plan) continue;
          FrictionFitOptions both = c.calibrated.friction_options;
          if (std::find(both.effects.begin(), both.effects.end(), tie) == both.effects.end()) both.effects.push_back(tie);
          both.per_run_fits = false;
          both.fit.bootstrap = 0;
          const FrictionFitResult fit = fit_friction(*c.friction_log, both);
          c.plan = plan_friction(*c.friction_log, fit, friction_candidates(*c.friction_log, {}, fit), {.separate = {cause.effect, tie}});
        }
    if (!c.plan)
      c.plan = plan_friction(*c.friction_log, *c.calibrated.friction, friction_candidates(*c.friction_log, {}, *c.calibrated.friction), {});
  } catch (const std::exception& e) {  // too many combinations, no noise, …
    c.notes.push_back(std::string("plan of the next friction conditions skipped: ") + e.what());
  }
}

// The next thermal runs for the calibrated rail model: to separate the first tie of the thermal
// diagnosis's accepted causes, else D-optimal; speeds from half the slowest run's to 1.5 times
// the fastest's.
void plan_next_thermal(Calibration& c) {
  if (!c.calibrated.thermal || !c.calibrated.friction) return;
  std::vector<std::string> separate;
  const auto library = thermal_extension_library();
  const auto with_parameter = [&](const std::string& name) {
    return std::any_of(library.begin(), library.end(), [&](auto& e) { return e.name == name && !e.parameters.empty(); });
  };
  if (c.thermal_diagnosis)
    for (const auto& cause : c.thermal_diagnosis->accepted)
      for (const auto& tie : cause.tied_with)
        if (separate.empty() && with_parameter(cause.effect) && with_parameter(tie)) separate = {cause.effect, tie};
  try {
    ThermalCandidateGrid grid;
    for (const auto& run : c.thermal_data->runs) grid.velocity_m_s.push_back(run.velocity_m_s);
    const auto [lo, hi] = std::minmax_element(grid.velocity_m_s.begin(), grid.velocity_m_s.end());
    const double slow = 0.5 * *lo, fast = 1.5 * *hi;
    grid.velocity_m_s.push_back(slow);
    grid.velocity_m_s.push_back(fast);
    c.thermal_plan = plan_thermal(calibrated_model_file(c), *c.thermal_data, thermal_candidates(*c.thermal_data, grid),
                                  {.separate = separate});
  } catch (const std::exception& e) {
    c.notes.push_back(std::string("plan of the next thermal runs skipped: ") + e.what());
  }
}

// The calibrated model over the runs' own cycle, with bands; a note says why not when it cannot.
void predict_runs_cycle(Calibration& c) {
  if (!c.calibrated.friction || !c.calibrated.thermal || !c.thermal) {
    c.notes.push_back("prediction of the runs' cycle skipped: it needs both calibrated models");
    return;
  }
  try {
    const double ambient_C = c.thermal->runs.front().initial_temperature_C;
    DutyCycle duty = duty_of_runs(*c.thermal_data, ambient_C);
    c.prediction = predict(calibrated_model_file(c), duty, {});
    c.duty = std::move(duty);
  } catch (const std::exception& e) {  // a catalog without the rail's section, a model without covariance, …
    c.notes.push_back(std::string("prediction of the runs' cycle skipped: ") + e.what());
  }
}

}  // namespace lmcal::detail
