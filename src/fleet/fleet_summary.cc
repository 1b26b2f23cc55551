#include "lmcal/fleet/fleet_summary.hpp"

#include "lmcal/version.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "fleet/fleet_report.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/csv_writer.hpp"
#include "lmcal/io/date.hpp"
#include "lmcal/models/friction.hpp"

namespace lmcal {

namespace {

using nlohmann::json;

// The constants every unit has, in a fixed order: the law's seven, then the rail model's own.
// A cause's effect (seal_drag) exists only where it was accepted, an empirical term differs
// from set to set: neither forms a population.
std::vector<std::pair<std::string, std::string>> population_parameters(const std::vector<FleetRecord>& records) {
  std::vector<std::pair<std::string, std::string>> names;
  for (const char* name : kFrictionConstantNames) names.emplace_back("friction", name);
  for (const char* name : {"alpha", "h_W_m2K"}) names.emplace_back("thermal", name);
  std::erase_if(names, [&](const auto& n) {
    return std::none_of(records.begin(), records.end(), [&](const FleetRecord& r) { return r.find(n.first, n.second); });
  });
  return names;
}

// An estimate a population or a drift can use: calibrated, with a finite positive SE.
const FleetParameter* usable(const FleetRecord& r, const std::string& model, const std::string& name) {
  if (r.status != "ok") return nullptr;
  const FleetParameter* p = r.find(model, name);
  return p && std::isfinite(p->value) && std::isfinite(p->se) && p->se > 0 ? p : nullptr;
}

// The records of each series, by date (undated ones in order of id, before the dated).
std::map<std::string, std::vector<const FleetRecord*>> by_series(const std::vector<FleetRecord>& records) {
  std::map<std::string, std::vector<const FleetRecord*>> series;
  for (const FleetRecord& r : records) series[fleet_series(r.unit, r.axis)].push_back(&r);
  for (auto& [name, list] : series)
    std::stable_sort(list.begin(), list.end(), [](const FleetRecord* a, const FleetRecord* b) { return a->date < b->date; });
  return series;
}

std::string signed_percent(double percent) { return fmt::format("{:+.0f} %", percent); }
std::string p_text(double p) { return p < 1e-4 ? fmt::format("{:.1e}", p) : fmt::format("{:.2g}", p); }

void fit_populations(FleetSummary& s, const std::map<std::string, std::vector<const FleetRecord*>>& series) {
  const auto names = population_parameters(s.records);
  for (const auto& [model, name] : names) {
    PopulationOfParameter pop{.model = model, .name = name};
    for (const auto& [unit, list] : series) {
      for (const FleetRecord* r : list) {
        if (const FleetParameter* p = usable(*r, model, name)) {
          pop.unit = p->unit;
          pop.series.push_back(unit);
          pop.set_ids.push_back(r->id);
          pop.estimates.push_back({p->value, p->se});
          break;  // the unit's earliest
        }
      }
    }
    s.population.push_back(std::move(pop));
  }
  const auto family = static_cast<std::size_t>(std::count_if(s.population.begin(), s.population.end(),
                                                             [](const auto& p) { return p.estimates.size() >= 3; }));
  for (PopulationOfParameter& pop : s.population) {
    if (pop.estimates.size() < 3) {
      pop.note = fmt::format("{} unit{} estimated it: a population needs 3", pop.estimates.size(),
                             pop.estimates.size() == 1 ? "" : "s");
      continue;
    }
    pop.fit = fit_population(pop.estimates, family, s.alpha);
    for (std::size_t i : pop.fit.outliers) {
      OutlierFinding o{.series = pop.series[i], .set_id = pop.set_ids[i], .model = pop.model, .parameter = pop.name,
                       .unit = pop.unit, .value = pop.estimates[i].value, .se = pop.estimates[i].se,
                       .z = pop.fit.z[i], .p_adjusted = pop.fit.p_adjusted[i], .population_mean = pop.fit.population.mean};
      o.text = fmt::format("{}: {} {:.4g} ± {:.2g} {} is {} from the population's {:.4g} (z = {:.1f}, p = {} adjusted)",
                           o.series, o.parameter, o.value, o.se, o.unit,
                           signed_percent(100 * (o.value - o.population_mean) / std::abs(o.population_mean)),
                           o.population_mean, o.z, p_text(o.p_adjusted));
      s.outliers.push_back(std::move(o));
    }
  }
}

void test_drift(FleetSummary& s, const std::map<std::string, std::vector<const FleetRecord*>>& series) {
  for (const PopulationOfParameter& pop : s.population) {
    for (const auto& [unit, list] : series) {
      DriftFinding d{.series = unit, .model = pop.model, .parameter = pop.name, .unit = pop.unit};
      for (const FleetRecord* r : list) {
        const FleetParameter* p = usable(*r, pop.model, pop.name);
        const auto day = io::parse_iso_date(r->date);
        if (!p || !day) continue;
        d.set_ids.push_back(r->id);
        d.dates.push_back(r->date);
        d.points.push_back({static_cast<double>(*day), p->value, p->se});
      }
      if (d.points.size() < 3) continue;
      d.drift = drift_test(d.points);
      s.drift.push_back(std::move(d));
    }
  }
  std::vector<double> p;
  for (const DriftFinding& d : s.drift) p.push_back(d.drift.p);
  const std::vector<double> holm = holm_adjust(p);
  for (std::size_t i = 0; i < s.drift.size(); ++i) {
    DriftFinding& d = s.drift[i];
    d.p_holm = holm[i];
    d.significant = std::isfinite(d.p_holm) && d.p_holm < s.alpha;
    const Drift& t = d.drift;
    const bool step = t.change_index && std::isfinite(t.change_p) && !(t.change_p > t.trend_p);
    d.text = step ? fmt::format("{}: {} {} since {} (a step; {} from {} to {} along the trend), p = {}", d.series,
                                d.parameter, signed_percent(t.shift_percent), d.dates[*t.change_index],
                                signed_percent(t.trend_percent), d.dates.front(), d.dates.back(), p_text(d.p_holm))
                  : fmt::format("{}: {} {} from {} to {} (a trend), p = {}", d.series, d.parameter,
                                signed_percent(t.trend_percent), d.dates.front(), d.dates.back(), p_text(d.p_holm));
  }
}

void count_causes(FleetSummary& s, const std::map<std::string, std::vector<const FleetRecord*>>& series) {
  std::map<std::pair<std::string, std::string>, std::vector<std::string>> found;
  for (const auto& [unit, list] : series) {
    std::set<std::pair<std::string, std::string>> of_unit;
    for (const FleetRecord* r : list) {
      if (r->status != "ok") continue;
      for (const auto& c : r->friction_causes) of_unit.emplace("friction", c);
      for (const auto& c : r->thermal_causes) of_unit.emplace("thermal", c);
    }
    for (const auto& key : of_unit) found[key].push_back(unit);
  }
  for (auto& [key, units] : found) s.causes.push_back({key.first, key.second, std::move(units)});
}

json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json population_json(const PopulationOfParameter& pop) {
  const RandomEffects& r = pop.fit.population;
  json outliers = json::array();
  for (std::size_t i : pop.fit.outliers) outliers.push_back(pop.series[i]);
  json units = json::array();
  for (std::size_t i = 0; i < pop.series.size(); ++i)
    units.push_back({{"series", pop.series[i]}, {"set", pop.set_ids[i]}, {"value", pop.estimates[i].value},
                     {"se", pop.estimates[i].se},
                     {"z", i < pop.fit.z.size() ? number(pop.fit.z[i]) : json(nullptr)},
                     {"p_adjusted", i < pop.fit.p_adjusted.size() ? number(pop.fit.p_adjusted[i]) : json(nullptr)}});
  return {{"model", pop.model},
          {"name", pop.name},
          {"unit", pop.unit},
          {"units", pop.series.size()},
          {"units_in_population", r.k},
          {"mean", number(r.mean)},
          {"mean_se", number(r.mean_se)},
          {"mean_ci95", {number(r.mean_low), number(r.mean_high)}},
          {"between_unit_sd", number(r.tau)},
          {"between_unit_sd_ci95", {number(r.tau_low), number(r.tau_high)}},
          {"between_unit_sd_percent_of_mean", number(100 * r.tau / std::abs(r.mean))},
          {"share_real_difference", number(r.i2)},
          {"cochran_q", number(r.q)},
          {"cochran_q_p", number(r.q_p)},
          {"method", r.method},
          {"outliers", outliers},
          {"note", pop.note.empty() ? pop.fit.note : pop.note},
          {"estimates", units}};
}

json summary_json(const FleetSummary& s) {
  json sets = json::array(), failed = json::array();
  for (const FleetRecord& r : s.records) {
    json parameters = json::object();
    for (const FleetParameter& p : r.parameters)
      parameters[p.name] = {{"value", number(p.value)}, {"se", number(p.se)}, {"ci95", {number(p.low), number(p.high)}}};
    sets.push_back({{"id", r.id}, {"series", fleet_series(r.unit, r.axis)}, {"unit", r.unit}, {"axis", r.axis},
                    {"machine", r.machine}, {"date", r.date}, {"status", r.status}, {"error", r.error},
                    {"friction_verdict", r.friction_verdict}, {"thermal_verdict", r.thermal_verdict},
                    {"friction_causes", r.friction_causes}, {"thermal_causes", r.thermal_causes},
                    {"parameters", parameters}});
    if (r.status != "ok") failed.push_back({{"id", r.id}, {"error", r.error}});
  }
  json population = json::array(), outliers = json::array(), drift = json::array(), causes = json::array();
  for (const auto& pop : s.population) population.push_back(population_json(pop));
  for (const auto& o : s.outliers)
    outliers.push_back({{"series", o.series}, {"set", o.set_id}, {"parameter", o.parameter}, {"value", o.value},
                        {"se", o.se}, {"z", o.z}, {"p_adjusted", o.p_adjusted}, {"text", o.text}});
  for (const auto& d : s.drift)
    drift.push_back({{"series", d.series}, {"parameter", d.parameter}, {"dates", d.dates},
                     {"trend_percent", number(d.drift.trend_percent)}, {"slope_per_day", number(d.drift.slope_per_day)},
                     {"trend_p", number(d.drift.trend_p)},
                     {"change_date", d.drift.change_index ? json(d.dates[*d.drift.change_index]) : json(nullptr)},
                     {"shift_percent", number(d.drift.shift_percent)}, {"change_p", number(d.drift.change_p)},
                     {"p", number(d.drift.p)}, {"p_holm", number(d.p_holm)}, {"significant", d.significant},
                     {"text", d.text}});
  for (const auto& c : s.causes)
    causes.push_back({{"model", c.model}, {"cause", c.cause}, {"units", c.series.size()}, {"series", c.series}});
  const json j{{"kind", "fleet"},
               {"lmcal_version", LMCAL_VERSION}, {"schema_version", kOutputSchemaVersion},
               {"command", s.command},
               {"root", s.root},
               {"sets_from", s.source},
               {"counts", {{"sets", s.records.size()}, {"units", s.units}, {"ok", s.ok}, {"failed", s.failed}}},
               {"family_wise_level", s.alpha},
               {"population_from", "each unit's (unit and axis) earliest calibrated set; outliers left out"},
               {"population", population},
               {"outliers", outliers},
               {"drift", drift},
               {"causes", causes},
               {"failed", failed},
               {"sets", sets}};
  return j;
}

std::string summary_csv(const FleetSummary& s) {
  std::vector<std::string> header = {"id",       "unit",  "axis",     "machine",          "date",
                                     "status",   "error", "friction_verdict", "thermal_verdict", "causes"};
  for (const auto& pop : s.population)
    for (const char* what : {"", "_se", "_low", "_high"}) header.push_back(pop.name + what);
  CsvText csv(header);
  csv.expect_rows(s.records.size());
  for (const FleetRecord& r : s.records) {
    std::vector<std::string> causes = r.friction_causes;
    causes.insert(causes.end(), r.thermal_causes.begin(), r.thermal_causes.end());
    csv.cell(r.id).cell(r.unit).cell(r.axis).cell(r.machine).cell(r.date).cell(r.status).cell(r.error);
    csv.cell(r.friction_verdict).cell(r.thermal_verdict).cell(fmt::format("{}", fmt::join(causes, " ")));
    for (const auto& pop : s.population) {
      const FleetParameter* p = r.status == "ok" ? r.find(pop.model, pop.name) : nullptr;
      for (double v : {p ? p->value : NAN, p ? p->se : NAN, p ? p->low : NAN, p ? p->high : NAN}) csv.cell(v);
    }
    csv.end_row();
  }
  return csv.str();
}

}  // namespace

FleetSummary summarize_fleet(const Fleet& fleet, const std::vector<std::string>& records, std::vector<std::string> command) {
  LMCAL_ASSERT(records.size() == fleet.sets.size(), "a record per set");
  FleetSummary s{.root = fleet.root.string(), .source = fleet.source, .command = std::move(command)};
  for (std::size_t i = 0; i < records.size(); ++i) {
    s.records.push_back(parse_fleet_record(records[i], fleet.sets[i].id + "/" + kFleetRecordFile));
    (s.records.back().status == "ok" ? s.ok : s.failed) += 1;
  }
  const auto series = by_series(s.records);
  s.units = series.size();
  fit_populations(s, series);
  test_drift(s, series);
  count_causes(s, series);
  return s;
}

std::vector<std::pair<std::string, std::string>> fleet_summary_outputs(const FleetSummary& summary) {
  return {{"fleet.json", summary_json(summary).dump(2) + "\n"},
          {"fleet.csv", summary_csv(summary)},
          {"fleet.html", fleet_report_html(summary)}};
}

std::string fleet_summary_text(const FleetSummary& s) {
  std::string t = fmt::format("{} sets of {} units: {} calibrated, {} failed\n", s.records.size(), s.units, s.ok, s.failed);
  for (const auto& pop : s.population) {
    const RandomEffects& r = pop.fit.population;
    if (r.k == 0) continue;
    t += fmt::format("  {:<12} mean {:<10.4g} between-unit SD {:.3g} [{:.3g}, {:.3g}] ({:.1f} % of the mean), "
                     "{:.0f} % of the spread real\n",
                     pop.name, r.mean, r.tau, r.tau_low, r.tau_high, 100 * r.tau / std::abs(r.mean), 100 * r.i2);
  }
  for (const auto& o : s.outliers) t += "  outlier: " + o.text + "\n";
  for (const auto& d : s.drift)
    if (d.significant) t += "  drift: " + d.text + "\n";
  for (const auto& c : s.causes)
    t += fmt::format("  cause {}: {} of {} units ({})\n", c.cause, c.series.size(), s.units, fmt::join(c.series, ", "));
  for (const auto& r : s.records)
    if (r.status != "ok") t += fmt::format("  failed {}: {}\n", r.id, r.error);
  return t;
}

}  // namespace lmcal
