#include "lmcal/rig/fleet_rig.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>

#include "io/toml_text.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/date.hpp"
#include "rig/rig_common.hpp"

namespace lmcal {

namespace {

namespace fs = std::filesystem;

// The value of `parameter` (a friction constant or "alpha") in a unit's truth.
double& truth_value(FrictionConstants<double>& k, double& alpha, const std::string& parameter) {
  if (parameter == "alpha") return alpha;
  return fittable_constant(k, friction_constant_index("fleet rig parameter", parameter));
}

void check_change(const FleetRigConfig& c, const FleetRigChange& change, const char* what) {
  if (change.unit < 1 || change.unit > c.units)
    throw InvalidParameter(what, fmt::format("unit {}: expected 1 … {}", change.unit, c.units));
  if (change.parameter != "alpha") friction_constant_index(what, change.parameter);
  if (!std::isfinite(change.value)) throw InvalidParameter(what, change.value, "a finite number");
}

std::string date_after(const std::string& first, int days) {
  const auto day = io::parse_iso_date(first);
  if (!day) throw InvalidParameter("first_date", fmt::format("'{}': expected YYYY-MM-DD", first));
  const std::chrono::year_month_day d{std::chrono::sys_days(std::chrono::days(*day + days))};
  return fmt::format("{:04}-{:02}-{:02}", static_cast<int>(d.year()), static_cast<unsigned>(d.month()),
                     static_cast<unsigned>(d.day()));
}

}  // namespace

FrictionRigConfig FleetRigConfig::small_friction() {
  FrictionRigConfig f;
  f.guides = {"SRN 35C"};
  f.preload_um = {1.5, 4.0};
  f.load_N = {1000, 3000};
  f.temperature_C = {22, 32};
  f.runs = 4;
  return f;
}

ThermalRigConfig FleetRigConfig::small_thermal() {
  ThermalRigConfig t;
  t.velocity_m_s = {0.066, 0.083, 0.11};
  t.duration_s = 7200;
  t.record_every_s = 30;
  return t;
}

FleetRigOutput generate_fleet(const FleetRigConfig& c) {
  if (c.units == 0) throw InvalidParameter("units", "expected at least one unit");
  if (c.dated_units > c.units) throw InvalidParameter("dated_units", fmt::format("{} of {} units", c.dated_units, c.units));
  if (c.dated_units > 0 && c.dates < 1) throw InvalidParameter("dates", "expected at least one date");
  for (const auto& [name, sd] : c.spread) {
    if (name != "alpha") friction_constant_index("spread", name);
    require_non_negative("spread", sd);
  }
  for (const auto& o : c.outliers) {
    check_change(c, o, "outlier");
    require_positive("outlier factor", o.value);
  }
  for (const auto& d : c.drifts) {
    check_change(c, d, "drift");
    if (d.unit > c.dated_units) throw InvalidParameter("drift", fmt::format("unit {} is logged once: no drift to show", d.unit));
    require_positive("1 + drift", 1 + d.value);
  }
  for (std::size_t u : c.corrupt)
    if (u < 1 || u > c.units) throw InvalidParameter("corrupt", fmt::format("unit {}: expected 1 … {}", u, c.units));

  FleetRigOutput out;
  std::string fleet_toml = "# SYNTHETIC fleet made by the lmcal virtual rig (lmcal generate fleet), not measured.\n";
  nlohmann::json units = nlohmann::json::array();
  for (std::size_t u = 1; u <= c.units; ++u) {
    const std::string unit = fmt::format("u{:02}", u);
    const std::string machine = fmt::format("M{}", (u - 1) / 4 + 1);
    // The unit's own constants: one stream per unit, the spread's constants in name order.
    rig::Rng rng(rig::derive_seed(c.seed, 1000 + u));
    FrictionConstants<double> k = c.friction.constants;
    double alpha = c.thermal_rig.alpha;
    for (const auto& [name, sd] : c.spread) truth_value(k, alpha, name) *= 1 + sd * rng.normal();
    for (const auto& o : c.outliers)
      if (o.unit == u) truth_value(k, alpha, o.parameter) *= o.value;
    const std::size_t dates = u <= c.dated_units ? c.dates : 1;
    nlohmann::json sets = nlohmann::json::array();
    for (std::size_t d = 0; d < dates; ++d) {
      FrictionConstants<double> kd = k;
      double alpha_d = alpha;
      for (const auto& drift : c.drifts)
        if (drift.unit == u && dates > 1)
          truth_value(kd, alpha_d, drift.parameter) *= 1 + drift.value * static_cast<double>(d) / static_cast<double>(dates - 1);
      const std::string date = u <= c.dated_units ? date_after(c.first_date, static_cast<int>(d) * c.days_between) : "";
      const fs::path folder = date.empty() ? fs::path(unit) : fs::path(unit) / date;
      const std::uint64_t seed = rig::derive_seed(c.seed, u * 1000 + d);
      FrictionRigConfig f = c.friction;
      f.constants = kd;
      f.seed = seed;
      const FrictionRigOutput friction = generate_friction_log(f, {});
      std::string log = friction_log_csv(friction.log, {"SYNTHETIC friction log of fleet unit " + unit + " (lmcal generate fleet)"});
      const bool corrupt = d == 0 && std::find(c.corrupt.begin(), c.corrupt.end(), u) != c.corrupt.end();
      if (corrupt) {  // the last row cut short after its second cell, as a logger that lost power leaves it
        const std::size_t last_row = log.rfind('\n', log.size() - 2) + 1;
        log.resize(log.find(',', log.find(',', last_row) + 1));
        log += '\n';
      }
      out.files.emplace_back(folder / "friction.csv", std::move(log));
      if (c.thermal) {
        ThermalRigConfig t = c.thermal_rig;
        t.constants = kd;
        t.alpha = alpha_d;
        t.seed = seed;
        ThermalDataSet set = generate_thermal_dataset(t, {}, unit).set;
        for (ThermalRun& run : set.runs) out.files.emplace_back(folder / run.file, thermal_trace_csv(run.trace));
        out.files.emplace_back(folder / "thermal.toml", thermal_manifest_toml(set, "."));
      }
      fleet_toml += fmt::format("\n[[set]]\nfolder = {}\nunit = {}\nmachine = {}\n", manifest::toml_string(folder.generic_string()),
                                manifest::toml_string(unit), manifest::toml_string(machine));
      if (!date.empty()) fleet_toml += fmt::format("date = {}\n", date);
      nlohmann::json constants;
      for (std::size_t j = 0; j < kFrictionConstantNames.size(); ++j) constants[kFrictionConstantNames[j]] = fittable_constant(kd, j);
      sets.push_back({{"folder", folder.generic_string()}, {"date", date}, {"constants", constants}, {"alpha", alpha_d},
                      {"corrupt", corrupt}});
      ++out.sets;
    }
    units.push_back({{"unit", unit}, {"machine", machine}, {"sets", sets}});
  }
  auto changes = [](const std::vector<FleetRigChange>& list) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& x : list) j.push_back({{"unit", fmt::format("u{:02}", x.unit)}, {"parameter", x.parameter}, {"value", x.value}});
    return j;
  };
  nlohmann::json spread = nlohmann::json::object();
  FrictionConstants<double> paper = c.friction.constants;
  double paper_alpha = c.thermal_rig.alpha;
  for (const auto& [name, sd] : c.spread)
    spread[name] = {{"relative_sd", sd}, {"sd", sd * truth_value(paper, paper_alpha, name)}};
  const nlohmann::json truth{{"what", "the true values of a fleet made by lmcal generate fleet"},
                             {"seed", c.seed},
                             {"spread", spread},
                             {"outliers", changes(c.outliers)},
                             {"drifts", changes(c.drifts)},
                             {"units", units}};
  out.files.emplace_back("fleet.toml", fleet_toml);
  out.files.emplace_back("fleet_truth.json", truth.dump(2) + "\n");
  return out;
}

}  // namespace lmcal
