#include "lmcal/fleet/fleet_record.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>

#include "lmcal/error.hpp"

namespace lmcal {

namespace {

using nlohmann::json;

// NaN is null in JSON and back.
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
double number(const json& j) { return j.is_number() ? j.get<double>() : NAN; }

// The parameters of a fit worth comparing across units: the model's own, not a run's
// nuisance or an empirical term (its meaning differs from set to set).
void add_parameters(FleetRecord& r, const char* model, const FitResult& fit) {
  for (const ParameterEstimate& p : fit.parameters) {
    if (p.per_run || p.name.starts_with("term")) continue;
    const bool profile = p.interval == "profile";
    const bool quoted = p.interval != "none" && std::isfinite(p.se);
    r.parameters.push_back({.model = model,
                            .name = p.name,
                            .unit = p.unit,
                            .value = p.value,
                            .se = quoted ? p.se : NAN,
                            .low = !quoted ? NAN : profile ? p.profile_low : p.ci_low,
                            .high = !quoted ? NAN : profile ? p.profile_high : p.ci_high,
                            .interval = quoted ? p.interval : "none"});
  }
}

}  // namespace

const FleetParameter* FleetRecord::find(std::string_view model, std::string_view name) const {
  const auto it = std::find_if(parameters.begin(), parameters.end(),
                               [&](const FleetParameter& p) { return p.model == model && p.name == name; });
  return it == parameters.end() ? nullptr : &*it;
}

std::string fleet_series(std::string_view unit, std::string_view axis) {
  return axis.empty() ? std::string(unit) : fmt::format("{} axis {}", unit, axis);
}

void fill_fleet_record(FleetRecord& r, const Calibration& c) {
  const CalibratedModel& m = c.calibrated;
  if (const FrictionFitResult* f = m.friction ? &*m.friction : c.friction ? &*c.friction : nullptr) {
    add_parameters(r, "friction", f->fit);
    r.friction_rmse_N = f->rmse_N;
  }
  if (const ThermalFitResult* t = m.thermal ? &*m.thermal : c.thermal ? &*c.thermal : nullptr) {
    add_parameters(r, "thermal", t->joint);
    r.thermal_cv_rmse_K = t->cv_rmse_K;
  }
  if (auto why = unusable_headline(c); why && r.status == "ok") {
    r.status = "failed";
    r.error = *why;
  }
  r.friction_causes = m.friction_causes;
  r.thermal_causes = m.thermal_causes;
  if (c.friction_diagnosis) r.friction_verdict = c.friction_diagnosis->verdict;
  if (c.thermal_diagnosis) r.thermal_verdict = c.thermal_diagnosis->verdict;
  r.warnings = c.warnings;
}

std::string fleet_record_json(const FleetRecord& r) {
  json parameters = json::array();
  for (const FleetParameter& p : r.parameters)
    parameters.push_back({{"model", p.model}, {"name", p.name}, {"unit", p.unit}, {"value", number(p.value)},
                          {"se", number(p.se)}, {"low", number(p.low)}, {"high", number(p.high)}, {"interval", p.interval}});
  json inputs = json::array();
  for (const auto& [file, hash] : r.inputs) inputs.push_back({{"file", file}, {"sha256", hash}});
  const json j{{"kind", "fleet_set"},
               {"lmcal_version", r.lmcal_version},
               {"id", r.id},
               {"unit", r.unit},
               {"axis", r.axis},
               {"machine", r.machine},
               {"date", r.date},
               {"status", r.status},
               {"error", r.error},
               {"parameters", parameters},
               {"friction_causes", r.friction_causes},
               {"thermal_causes", r.thermal_causes},
               {"friction_verdict", r.friction_verdict},
               {"thermal_verdict", r.thermal_verdict},
               {"friction_rmse_N", number(r.friction_rmse_N)},
               {"thermal_cv_rmse_K", number(r.thermal_cv_rmse_K)},
               {"warnings", r.warnings},
               {"inputs", inputs},
               {"outputs", r.outputs.value_or(std::vector<std::string>{})},
               {"options_sha256", r.options_sha256}};
  return j.dump(2) + "\n";
}

FleetRecord parse_fleet_record(std::string_view text, const std::string& file) {
  try {
    const json j = json::parse(text);
    if (j.value("kind", "") != "fleet_set") throw InputError(file, 0, 0, "expected a fleet record (kind \"fleet_set\")");
    FleetRecord r;
    r.lmcal_version = j.at("lmcal_version").get<std::string>();
    r.id = j.at("id").get<std::string>();
    r.unit = j.at("unit").get<std::string>();
    r.axis = j.at("axis").get<std::string>();
    r.machine = j.at("machine").get<std::string>();
    r.date = j.at("date").get<std::string>();
    r.status = j.at("status").get<std::string>();
    r.error = j.at("error").get<std::string>();
    for (const json& p : j.at("parameters"))
      r.parameters.push_back({.model = p.at("model").get<std::string>(),
                              .name = p.at("name").get<std::string>(),
                              .unit = p.at("unit").get<std::string>(),
                              .value = number(p.at("value")),
                              .se = number(p.at("se")),
                              .low = number(p.at("low")),
                              .high = number(p.at("high")),
                              .interval = p.at("interval").get<std::string>()});
    r.friction_causes = j.at("friction_causes").get<std::vector<std::string>>();
    r.thermal_causes = j.at("thermal_causes").get<std::vector<std::string>>();
    r.friction_verdict = j.at("friction_verdict").get<std::string>();
    r.thermal_verdict = j.at("thermal_verdict").get<std::string>();
    r.friction_rmse_N = number(j.at("friction_rmse_N"));
    r.thermal_cv_rmse_K = number(j.at("thermal_cv_rmse_K"));
    r.warnings = j.at("warnings").get<std::vector<std::string>>();
    for (const json& i : j.at("inputs")) r.inputs.emplace_back(i.at("file").get<std::string>(), i.at("sha256").get<std::string>());
    if (j.contains("outputs")) r.outputs = j.at("outputs").get<std::vector<std::string>>();
    r.options_sha256 = j.at("options_sha256").get<std::string>();
    return r;
  } catch (const json::exception& e) {
    throw InputError(file, 0, 0, fmt::format("not a fleet record of this lmcal version: {}", e.what()));
  }
}

}  // namespace lmcal
