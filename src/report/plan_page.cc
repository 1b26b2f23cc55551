// plan.html: the next measurements and what they would do to each SE (predict_pages.hpp).

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>

#include "lmcal/report/predict_pages.hpp"
#include "report/sections.hpp"

namespace lmcal {

namespace {

using report::Cell;
using report::num;
using report::Page;
using report::Plot;

Cell se_cell(double se, const std::string& why) { return std::isfinite(se) ? Cell(num(se), true, "") : Cell("n/a (" + why + ")"); }

// Each parameter's SE now -> after (the same quantity), then the quantities a fit quoted with
// constants held, now -> after; and the plot of after over now where both are given.
void standard_errors(Page& page, const std::vector<PlannedParameter>& parameters) {
  std::vector<std::vector<Cell>> rows;
  Plot ratio{.id = "plan-se-ratio", .title = "Expected SE after the plan over the SE now (the same quantity)",
             .x_label = "parameter", .y_label = "SE after / SE now"};
  report::Series points{.label = "", .mark = report::Mark::points};
  const auto add = [&](const std::string& name, const std::string& unit, double before, double after, const std::string& now_why) {
    rows.push_back({name, unit, se_cell(before, now_why), se_cell(after, "still not determined"),
                    std::isfinite(before) && std::isfinite(after) ? Cell(num(after / before), true, "") : Cell("–")});
    if (!(std::isfinite(before) && std::isfinite(after) && before > 0)) return;
    ratio.x_tick_labels.emplace_back(static_cast<double>(points.x.size()), name);
    points.x.push_back(static_cast<double>(points.x.size()));
    points.y.push_back(after / before);
  };
  for (const auto& p : parameters)
    add(p.name, p.unit, p.se_before, p.se_after,
        p.held_now.empty() ? "not determined yet" : fmt::format("only with {} held", fmt::join(p.held_now, ", ")));
  for (const auto& p : parameters)
    if (!p.held_now.empty())
      add(fmt::format("{} ({} held, as quoted now)", p.name, fmt::join(p.held_now, ", ")), p.unit, p.se_held_now, p.se_held_after, "");
  page.table({"parameter", "unit", "SE now", "SE after", "after / now"}, rows);
  if (points.x.empty()) return;
  ratio.series.push_back(points);
  ratio.references.push_back({.horizontal = true, .at = 1, .label = "no change"});
  ratio.y_min = 0;
  ratio.width_px = std::max(520, 60 * static_cast<int>(points.x.size()) + 160);
  page.figures({ratio});
}

// The SE table and plot, the separated pair's correlation, the notes and the command: the page.
template <class Plan>
std::string the_rest(Page& page, const Plan& plan, const std::vector<std::string>& command, const std::string& title) {
  standard_errors(page, plan.parameters);
  if (std::isfinite(plan.correlation_before))
    page.paragraph(fmt::format("Correlation of the separated pair: {} now, {} after.", num(plan.correlation_before, 3),
                               num(plan.correlation_after, 3)));
  for (const auto& note : plan.notes) page.paragraph("Note: " + note);
  std::string line;
  for (const auto& part : command) line += (line.empty() ? "" : " ") + part;
  page.paragraph("These numbers are plan.json's. Command: " + line);
  return report::html_document(title, page);
}

}  // namespace

std::string friction_plan_html(const FrictionPlan& plan, const std::vector<std::string>& command) {
  Page page;
  page.heading(1, "lmcal plan: the next friction conditions");
  page.paragraph(fmt::format("The {} conditions, {}, each logged as {} samples (the fit's noise {} N). plan_friction_template.csv "
                             "is the friction log to fill on the rig.",
                             plan.picks.size(), plan.criterion, plan.samples_per_condition, num(plan.sigma_N, 3)));
  std::vector<std::vector<Cell>> rows;
  for (std::size_t k = 0; k < plan.picks.size(); ++k) {
    const FrictionCandidate& c = plan.picks[k].candidate;
    rows.push_back({{std::to_string(k + 1), true, ""}, c.guide, {num(c.conditions.velocity_m_s), true, ""},
                    {num(c.conditions.load_N), true, ""}, {num(c.conditions.preload_um), true, ""},
                    {num(c.conditions.temperature_C), true, ""}, c.conditions.direction > 0 ? "+1" : "-1",
                    c.proposed_for.empty() ? Cell("") : Cell("new: " + c.proposed_for)});
  }
  page.table({"", "guide", "velocity (m/s)", "load (N)", "preload (µm)", "temperature (°C)", "direction", "why"}, rows);
  page.heading(2, "Expected standard errors", "standard-errors");
  page.paragraph("Each parameter as a refit of the logs and the planned conditions would quote it, so both sides are the same "
                 "quantity; a constant the fit quoted with another held (that the plan determines) is n/a now, and the "
                 "quantity it quoted is a row of its own.");
  return the_rest(page, plan, command, "lmcal plan: friction");
}

std::string thermal_plan_html(const ThermalPlan& plan, const std::vector<std::string>& command) {
  Page page;
  page.heading(1, "lmcal plan: the next thermal runs");
  page.paragraph(fmt::format("The {} runs, {} (thermocouple noise {} K). plan_thermal_manifest.toml lists them as runs to log.",
                             plan.picks.size(), plan.criterion, num(plan.noise_K, 3)));
  std::vector<std::vector<Cell>> rows;
  for (std::size_t r = 0; r < plan.picks.size(); ++r) {
    const ThermalCandidate& c = plan.picks[r].candidate;
    rows.push_back({{std::to_string(r + 1), true, ""}, {num(c.velocity_m_s), true, ""}, {num(c.load_N), true, ""},
                    {num(c.duration_s / 3600), true, ""}});
  }
  page.table({"", "velocity (m/s)", "load (N)", "duration (h)"}, rows);
  page.heading(2, "Expected standard errors", "standard-errors");
  return the_rest(page, plan, command, "lmcal plan: thermal");
}

}  // namespace lmcal
