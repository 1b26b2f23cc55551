#include "friction_model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "friction_residual.hpp"
#include "lmcal/error.hpp"

namespace lmcal::detail {

namespace {

Design describe(const FrictionData& d) {
  Design design;
  design.min_velocity = std::numeric_limits<double>::infinity();
  double t_min = std::numeric_limits<double>::infinity(), t_max = -t_min;
  // A set takes a value only where it changes from the previous sample (a log holds each
  // condition for a stretch): 10⁵ tree look-ups were a tenth of a fit.
  auto insert = [](std::set<double>& set, double value, double& last) {
    if (value != last) set.insert(value), last = value;
  };
  double preload = std::numeric_limits<double>::quiet_NaN(), rounded = preload, load = preload, block = preload;
  for (std::size_t i : d.samples) {
    insert(design.preloads, d.log->preload_um[i], preload);
    insert(design.temperatures, std::round(d.log->temperature_C[i]), rounded);
    t_min = std::min(t_min, d.log->temperature_C[i]);
    t_max = std::max(t_max, d.log->temperature_C[i]);
    insert(design.loads, d.log->load_N[i], load);
    insert(design.block_lengths, d.log->block_length_mm[i], block);
    if (d.log->velocity_m_s[i] < 0.03) ++design.low_speed;
    design.min_velocity = std::min(design.min_velocity, d.log->velocity_m_s[i]);
  }
  design.temperature_span_K = t_max - t_min;
  return design;
}

}  // namespace

FrictionModel::FrictionModel(const FrictionData& data, std::vector<std::size_t> effect_slots)
    : data_(data), effect_slots_(std::move(effect_slots)), design_(describe(data)) {}

std::unique_ptr<ceres::CostFunction> FrictionModel::cost_function(const std::vector<std::size_t>& rows,
                                                                  const RowLoss& loss) const {
  const std::size_t n = rows.empty() ? data_.samples.size() : rows.size();
  std::vector<std::size_t> groups;
  if (!data_.run_shrink.empty())
    for (std::size_t j = 0; j < n; ++j) groups.push_back(data_.log->run[data_.samples[rows.empty() ? j : rows[j]]]);
  const std::size_t terms = data_.terms ? term_parameter_count(*data_.terms) : 0;
  const int parameters = static_cast<int>(FrictionConstants<double>::kFittable + effect_slots_.size() + terms);
  if (terms > 0) return term_cost_function(data_, rows, effect_slots_, parameters, n, loss, std::move(groups));
  return std::make_unique<BatchedAutoDiffCostFunction<FrictionResidual<false>>>(
      FrictionResidual<false>{&data_, rows, effect_slots_}, parameters, n, loss, std::move(groups), data_.run_shrink,
      rows.empty() ? data_.profiled : nullptr);
}

// A run is a cluster; its samples, in the log's order (time order within a run), are its
// time steps.
RowStructure FrictionModel::row_structure() const {
  RowStructure rows;
  std::vector<std::size_t> cluster_of_run(data_.log->run_names.size(), 0), steps;
  std::vector<bool> seen(data_.log->run_names.size(), false);
  for (std::size_t sample : data_.samples) {
    const std::uint32_t run = data_.log->run[sample];
    if (!seen[run]) {
      seen[run] = true;
      cluster_of_run[run] = rows.clusters++;
      steps.push_back(0);
    }
    const std::size_t c = cluster_of_run[run];
    rows.cluster.push_back(c);
    rows.time.push_back(steps[c]++);
  }
  return rows;
}

void FrictionModel::explain(IdentifiabilityIssue& issue) const {
  std::set<std::string> dominant;
  for (const auto& [name, weight] : issue.combination)
    if (std::abs(weight) >= 0.3) dominant.insert(name);
  // A combination law's outputs name the combinations, not the paper's constants.
  const auto shown = [&](std::string_view constant) -> std::string {
    const auto j = find_friction_constant(constant);
    return j && data_.log->law.combination() && kLawCombinationNames[*j] ? kLawCombinationNames[*j] : std::string(constant);
  };
  auto only = [&](std::initializer_list<const char*> names) {
    for (const auto& d : dominant)
      if (std::none_of(names.begin(), names.end(), [&](const char* n) { return d == n; })) return false;
    return !dominant.empty();
  };
  const Design& d = design_;
  if (dominant.count("beta_per_K") && d.temperatures.size() == 1) {
    issue.why = fmt::format(
        "all samples are at one temperature ({} C): beta only scales the viscosity, which {} and {} absorb",
        *d.temperatures.begin(), shown("mu_v"), shown("mu_st"));
    issue.measure = "repeat the sweep at a second temperature, at least 10 K away";
  } else if (only({"k1", "k2"}) && d.preloads.size() == 1) {
    issue.why =
        fmt::format("one preload class (pc = {} um): k1 and k2 enter only as (k1 - k2 pc)", *d.preloads.begin());
    issue.measure = "measure a second preload class (e.g. Normal and C0)";
  } else if (only({"mu_st", "v_st_m_s"}) || (dominant.count("mu_st") && dominant.count("v_st_m_s"))) {
    issue.why = d.low_speed == 0
                    ? fmt::format(
                          "no samples below 0.03 m/s (slowest {} m/s): the Stribeck term has decayed and "
                          "only a combination of {} and {} shows",
                          d.min_velocity, shown("mu_st"), shown("v_st_m_s"))
                    : fmt::format("only {} samples below 0.03 m/s: too few to separate {} from {}", d.low_speed,
                                  shown("mu_st"), shown("v_st_m_s"));
    issue.measure = "measure at several speeds between 0.002 and 0.03 m/s";
  } else if ((dominant.count("f0") || dominant.count("k1") || dominant.count("k2")) && d.loads.size() == 1 &&
             d.block_lengths.size() == 1) {
    issue.why = fmt::format("one load ({} N) and one block length: the Coulomb term and f0 are both constant offsets",
                            *d.loads.begin());
    issue.measure = "measure at a second load, or with a second block size";
  } else if (only({"k1", "k2"}) && d.loads.size() == 1) {
    issue.why = "one load: the Coulomb term cannot be told apart from the other constant terms";
    issue.measure = "measure at a second load";
  } else {
    std::string combo;
    for (const auto& [name, weight] : issue.combination) combo += fmt::format(" {:+.2f}·{}", weight, shown(name));
    issue.why = "the data determine only the combination" + combo + " (relative to each parameter's size)";
    issue.measure = "widen the range of speed, load, preload and temperature";
  }
}

}  // namespace lmcal::detail

namespace lmcal::detail {

// The three designs the paper's law cannot be fitted from, found before any fit. (Jitter
// in a logged temperature would otherwise "determine" β from noise.)
std::vector<IdentifiabilityIssue> FrictionModel::design_issues(const std::vector<std::string>& free) const {
  auto is_free = [&](const char* name) { return std::find(free.begin(), free.end(), name) != free.end(); };
  std::vector<IdentifiabilityIssue> issues;
  auto add = [&](std::vector<std::pair<std::string, double>> combination, const char* hold) {
    IdentifiabilityIssue issue;
    issue.combination = std::move(combination);
    issue.relative_se = std::numeric_limits<double>::infinity();
    explain(issue);
    issue.held = {hold};
    issues.push_back(std::move(issue));
  };
  const Design& d = design_;
  if (is_free("beta_per_K") && d.temperature_span_K < 3.0)
    add({{"beta_per_K", 1.0}, {"mu_v", -0.5}, {"mu_st", 0.5}}, "beta_per_K");
  if (is_free("k1") && is_free("k2") && d.preloads.size() == 1) add({{"k2", 1.0}, {"k1", 0.5}}, "k2");
  if (is_free("mu_st") && is_free("v_st_m_s") && d.low_speed == 0) add({{"v_st_m_s", 1.0}, {"mu_st", 0.5}}, "v_st_m_s");
  return issues;
}

}  // namespace lmcal::detail
