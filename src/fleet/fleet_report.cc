#include "fleet/fleet_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "lmcal/report/page.hpp"

namespace lmcal {

namespace {

using report::escape_xml;
using report::num;
using report::Page;
using report::Plot;
using report::Series;

// At most this many units in a forest plot (every n-th, and every outlier); all are in fleet.csv.
constexpr std::size_t kForestUnits = 300;
// At most this many units' lines in a drift plot: the significant ones, then the smallest p.
constexpr std::size_t kDriftLines = 8;

void population_table(Page& page, const FleetSummary& s) {
  page.heading(2, "The population", "population");
  page.paragraph(
      "Each unit (unit and axis) by its earliest calibrated set. Mean: random-effects mean with its 95 % interval; "
      "between-unit SD: the real unit-to-unit spread once each unit's own estimation noise is taken out, with its "
      "95 % interval; share real: how much of the spread the units show is real difference rather than estimation "
      "noise (I²). Outliers are left out of the population they are outside of.");
  std::vector<std::vector<std::string>> rows;
  for (const auto& pop : s.population) {
    const RandomEffects& r = pop.fit.population;
    if (r.k == 0) {
      rows.push_back({pop.name, pop.unit, std::to_string(pop.series.size()), "–", "–", "–", "–", pop.note});
      continue;
    }
    std::vector<std::string> outliers;
    for (std::size_t i : pop.fit.outliers) outliers.push_back(pop.series[i]);
    rows.push_back({pop.name, pop.unit, fmt::format("{} of {}", r.k, pop.series.size()),
                    fmt::format("{} {}", num(r.mean), report::bracket(r.mean_low, r.mean_high)),
                    fmt::format("{} {}", num(r.tau, 3), report::bracket(r.tau_low, r.tau_high)),
                    fmt::format("{:.1f} %", 100 * r.tau / std::abs(r.mean)), fmt::format("{:.0f} %", 100 * r.i2),
                    outliers.empty() ? "none" : fmt::format("{}", fmt::join(outliers, ", "))});
  }
  page.table({"constant", "unit", "units", "mean [95 %]", "between-unit SD [95 %]", "SD / mean", "share real", "outliers"},
             rows);
}

void findings(Page& page, const FleetSummary& s) {
  page.heading(2, "Findings", "findings");
  std::vector<std::string> lines;
  for (const auto& o : s.outliers) lines.push_back("Outlier — " + o.text);
  std::size_t tested = s.drift.size();
  for (const auto& d : s.drift)
    if (d.significant) lines.push_back("Drift — " + d.text);
  for (const auto& c : s.causes)
    lines.push_back(fmt::format("Cause {} ({} model) in {} of {} units: {}", c.cause, c.model, c.series.size(), s.units,
                                fmt::join(c.series, ", ")));
  if (lines.empty()) lines.push_back("No outlier, no significant drift, no cause accepted.");
  page << "<ul>";
  for (const auto& l : lines) page << "<li>" << escape_xml(l) << "</li>";
  page << "</ul>\n";
  page.paragraph(fmt::format("Outliers: Bonferroni over units and constants; drift: a trend and a change-point test per "
                             "unit and constant, Holm-adjusted over all {} tested; both at a family-wise level of {:g} %.",
                             tested, 100 * s.alpha));
}

// Each unit's estimate with its 95 % interval, the population mean and the band where a new
// unit is expected (μ ± 1.96 τ); the x axis is the unit's row in fleet.csv order.
Plot forest_plot(const PopulationOfParameter& pop) {
  const RandomEffects& r = pop.fit.population;
  Plot plot{.id = report::plot_id("forest-" + pop.name),
            .title = fmt::format("{}: each unit and the population", pop.name),
            .x_label = "unit (in order of name)",
            .y_label = fmt::format("{} ({})", pop.name, pop.unit)};
  const std::set<std::size_t> flagged(pop.fit.outliers.begin(), pop.fit.outliers.end());
  const std::size_t step = report::stride(pop.series.size(), kForestUnits);
  Series units{.label = "unit (95 %)", .mark = report::Mark::points, .color = "#0072B2"};
  Series outliers{.label = "outlier (95 %)", .mark = report::Mark::points, .color = "#D55E00"};
  for (std::size_t i = 0; i < pop.series.size(); ++i) {
    Series& to = flagged.contains(i) ? outliers : units;
    if (&to == &units && i % step != 0) continue;
    to.x.push_back(static_cast<double>(i + 1));
    to.y.push_back(pop.estimates[i].value);
    to.y_error.push_back(1.96 * pop.estimates[i].se);
  }
  const double x0 = 0.5, x1 = static_cast<double>(pop.series.size()) + 0.5;
  plot.series.push_back({.label = "mean; a new unit (95 %)", .x = {x0, x1}, .y = {r.mean, r.mean}, .color = "#999999",
                         .band_low = {r.mean - 1.96 * r.tau, r.mean - 1.96 * r.tau},
                         .band_high = {r.mean + 1.96 * r.tau, r.mean + 1.96 * r.tau}});
  plot.series.push_back(std::move(units));
  if (!outliers.x.empty()) plot.series.push_back(std::move(outliers));
  return plot;
}

// The constant over the dates of the units tested for drift (days since the first date).
std::optional<Plot> drift_plot(const FleetSummary& s, const PopulationOfParameter& pop) {
  std::vector<const DriftFinding*> tested;
  for (const auto& d : s.drift)
    if (d.model == pop.model && d.parameter == pop.name) tested.push_back(&d);
  if (tested.empty()) return std::nullopt;
  std::stable_sort(tested.begin(), tested.end(), [](const DriftFinding* a, const DriftFinding* b) {
    return a->significant != b->significant ? a->significant : a->p_holm < b->p_holm;
  });
  if (tested.size() > kDriftLines) tested.resize(kDriftLines);
  double first = INFINITY;
  for (const auto* d : tested) first = std::min(first, d->points.front().day);
  Plot plot{.id = report::plot_id("drift-" + pop.name),
            .title = fmt::format("{} over time", pop.name),
            .x_label = "days since the first date",
            .y_label = fmt::format("{} ({})", pop.name, pop.unit)};
  for (const auto* d : tested) {
    Series line{.label = d->series + (d->significant ? " (drifts)" : ""), .mark = report::Mark::line_points,
                .dashed = !d->significant};
    for (const auto& p : d->points) {
      line.x.push_back(p.day - first);
      line.y.push_back(p.value);
      line.y_error.push_back(1.96 * p.se);
    }
    plot.series.push_back(std::move(line));
  }
  return plot;
}

void plots(Page& page, const FleetSummary& s) {
  page.heading(2, "Each constant across the units", "plots");
  for (const auto& pop : s.population) {
    if (pop.fit.population.k == 0) continue;
    std::vector<Plot> row{forest_plot(pop)};
    if (auto d = drift_plot(s, pop)) row.push_back(std::move(*d));
    page.figures(row);
  }
}

void failed_sets(Page& page, const FleetSummary& s) {
  page.heading(2, "Sets that could not be calibrated", "failed");
  std::vector<std::vector<std::string>> rows;
  for (const auto& r : s.records)
    if (r.status != "ok") rows.push_back({r.id, fleet_series(r.unit, r.axis), r.date, r.error});
  if (rows.empty())
    page.paragraph("None: every set was calibrated.");
  else
    page.table({"set", "unit", "date", "error"}, rows);
}

}  // namespace

std::string fleet_report_html(const FleetSummary& s) {
  Page page;
  page.heading(1, "lmcal fleet: " + s.root);
  page.paragraph(fmt::format("{} sets of {} units ({}): {} calibrated, {} could not be. Every set's own report is in its "
                             "folder; every number here is in fleet.json and, per set, fleet.csv.",
                             s.records.size(), s.units, s.source == "fleet.toml" ? "listed in fleet.toml" : "found by folder",
                             s.ok, s.failed));
  page << "<nav><a href=\"#findings\">Findings</a><a href=\"#population\">Population</a><a href=\"#plots\">Plots</a>"
          "<a href=\"#failed\">Failed sets</a></nav>\n";
  findings(page, s);
  population_table(page, s);
  plots(page, s);
  failed_sets(page, s);
  return report::html_document("lmcal fleet: " + s.root, page);
}

}  // namespace lmcal
