// What the thermal model says of itself (thermal_model.hpp): its rows and their structure,
// where it is linear, and why the data cannot determine a direction of it. Its residuals and
// simulations are in thermal_model.cc.
#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <limits>
#include <set>

#include "thermal_model.hpp"

namespace lmcal::detail {

ThermalModel::ThermalModel(const std::vector<PreparedRun>& runs, ThermalLayout layout, RailNumerics numerics)
    : runs_(runs), layout_(std::move(layout)), numerics_(numerics), end_memo_(runs.size()) {
  for (std::size_t r = 0; r < runs_.size(); ++r) {
    first_row_.push_back(rows_.size());
    for (std::size_t t = 0; t < runs_[r].times_s.size(); ++t)
      for (std::size_t s = 0; s < runs_[r].sensor_positions_m.size(); ++s)
        if (!std::isnan(runs_[r].measured[t][s])) rows_.push_back({r, t, s});
  }
  for (std::size_t r = 0; r < runs_.size(); ++r)
    if (!layout_.heat_scale.empty() && layout_.heat_scale[r] >= 0) priors_.push_back(r);
}

// A run is a cluster and its records are the time steps (its sensors read at once share one);
// every sensor of every run is its own series. A heat scale's prior row belongs to its run
// (for the cluster methods) but is not data (RowStructure::prior).
RowStructure ThermalModel::row_structure() const {
  RowStructure rows;
  rows.clusters = runs_.size();
  std::vector<std::size_t> first_series(runs_.size() + 1, 0);
  for (std::size_t r = 0; r < runs_.size(); ++r) first_series[r + 1] = first_series[r] + runs_[r].sensor_names.size();
  for (const Row& row : rows_) {
    rows.cluster.push_back(row.run);
    rows.time.push_back(row.time);
    rows.series.push_back(first_series[row.run] + row.sensor);
  }
  rows.prior_variance.assign(rows_.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < priors_.size(); ++k) {
    rows.cluster.push_back(priors_[k]);
    rows.time.push_back(0);
    rows.series.push_back(first_series.back() + k);
    rows.prior_variance.push_back(std::pow(runs_[priors_[k]].heat_prior_sigma_K, 2));
  }
  return rows;
}

// Temperatures are linear in α (Q fixed), in the initial temperature and in the offsets;
// h enters the operator and is not.
bool ThermalModel::linear(const std::vector<bool>& held) const {
  for (std::size_t e = 0; e < layout_.extensions.size(); ++e) {
    // A heat that follows the rail makes α act on the field through the heat: never linear.
    if (layout_.extensions[e]->heat_follows_rail) return false;
    if (layout_.extensions[e]->linear) continue;
    for (std::size_t j = 0; j < layout_.extensions[e]->parameters.size(); ++j)
      if (!held[static_cast<std::size_t>(layout_.extension_first[e]) + j]) return false;
  }
  for (int scale : layout_.heat_scale)
    if (scale >= 0 && !held[static_cast<std::size_t>(scale)]) return false;  // α · scale
  // A sensor term is linear in its coefficient; not in its scale, and c · rise(α) not in both.
  for (std::size_t j = 0; j < layout_.terms.size(); ++j) {
    if (layout_.term_scale[j] >= 0 && !held[static_cast<std::size_t>(layout_.term_scale[j])]) return false;
    if (layout_.terms[j].kind == ThermalTermKind::rise_time && !held[static_cast<std::size_t>(layout_.term_coefficient[j])])
      return false;
  }
  return layout_.h < 0 || held[static_cast<std::size_t>(layout_.h)];
}

void ThermalModel::explain(IdentifiabilityIssue& issue) const {
  std::set<std::string> names;
  std::string combo;
  for (const auto& [name, weight] : issue.combination) {
    if (std::abs(weight) >= 0.3) names.insert(name);
    combo += fmt::format(" {:+.2f}·{}", weight, name);
  }
  const bool alpha = names.count("alpha") > 0, h = names.count("h_W_m2K") > 0;
  bool offsets = false, initial = false;
  for (const auto& n : names) {
    offsets |= n.rfind("offset", 0) == 0;
    initial |= n.rfind("T0", 0) == 0;
  }
  const ThermalExtension* extension = nullptr;
  for (const auto* e : layout_.extensions)
    for (const auto& p : e->parameters)
      if (names.count(p.name)) extension = e;
  // A sensor term's parameters: "c<j> <symbol>", "P_s" ("P2_s", …), "tau<j>_s" (thermal_fit.cc).
  const bool term = !layout_.terms.empty() && std::any_of(names.begin(), names.end(), [](const std::string& n) {
    return (n.size() > 1 && n[0] == 'c' && std::isdigit(static_cast<unsigned char>(n[1]))) ||
           (n[0] == 'P' && n.ends_with("_s")) || n.rfind("tau", 0) == 0;
  });
  if (term) {
    issue.why = "the records do not separate the empirical sensor terms from the rest: they determine only" + combo;
    issue.measure = "longer runs, or runs that start at other times of day or with other ambient courses";
  } else if (extension) {
    issue.why = fmt::format("the records do not separate {} ({}) from the rest: they determine only{}", extension->name,
                            extension->description, combo);
    issue.measure = extension->measure;
  } else if (alpha && h) {
    issue.why = "α and h trade off: a larger α with a larger h gives the same temperatures at these sensors and times";
    issue.measure = "record the whole warm-up and the cool-down after the block stops, or sensors farther from the stroke";
  } else if (offsets && initial) {
    issue.why = "a thermocouple offset and the initial temperature shift the same reading the same way";
    issue.measure = "log the rail at rest against a reference thermometer before the run";
  } else if (offsets && alpha) {
    issue.why = "the offsets absorb the heating: the records do not show the warm-up clearly enough";
    issue.measure = "start logging before the block moves and run until the rail is close to steady state";
  } else {
    issue.why = "the records determine only the combination" + combo;
    issue.measure = "longer runs, more sensors along the rail, or runs at other speeds";
  }
}

}  // namespace lmcal::detail
