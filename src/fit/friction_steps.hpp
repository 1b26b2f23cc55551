// The friction fit's shared pieces (private to the fit layer, free of Ceres): the names of the
// law's constants, the samples grouped by condition, and the steps its files hand each other.
// The fit is four files, one job each: friction_prepare.cc (the log and the options made
// ready), friction_fit.cc (the parameters, the fit with its starts and variance passes, the
// runs held out and fitted alone), friction_goodness.cc (predictions, run offsets, errors per
// condition, a combination law's combinations), friction_output.cc (JSON, CSV, the summary).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "friction_condition.hpp"
#include "run_offsets.hpp"
#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/models/friction_terms.hpp"

namespace lmcal::detail {

inline constexpr const char* kConstantUnits[] = {"1", "1/um", "N mm2/s / (um mm)", "m/s", "N/(mm um m/s mm2/s)", "1/K", "N/mm"};
// A combination law's (FrictionLawConditions::combination) name for constant j, as its outputs
// show it (friction_fit.cc, law_combinations); nullptr for the constants it holds or hides (k2,
// β, f0).
inline constexpr const char* kLawCombinationNames[] = {"coulomb_N", nullptr, "stribeck_N", "stribeck_speed_m_s",
                                                       "viscous_N_s_m", nullptr, nullptr};

// ---- friction_prepare.cc ---------------------------------------------------------------------

// Samples grouped by condition (guide, preload, load, temperature to 1 K, speed, direction),
// groups in key order; each group's samples in log order, stored one group after the other (a
// trajectory's samples are each a condition of their own: a vector per group cost a heap
// allocation per sample).
struct ConditionGroups {
  std::vector<ConditionKey> keys;
  std::vector<std::size_t> first;     // per group: where its samples start in `samples` (and a last entry: the end)
  std::vector<std::size_t> samples;   // group by group
  std::vector<std::size_t> group_of;  // per sample
  std::span<const std::size_t> members(std::size_t g) const { return {samples.data() + first[g], first[g + 1] - first[g]}; }
};
ConditionGroups group_conditions(const FrictionLog& log);
// σ per sample from the spread of repeats (see FrictionWeighting).
std::vector<double> sample_sigmas(const FrictionLog& log, FrictionWeighting weighting);
// The options as fitted: a drive's effects added, the law prepared for the conditions logged.
FrictionFitOptions options_for_log(const FrictionLog& logged, const FrictionFitOptions& given);
// Whether the log's temperatures are replaced by their block means (FrictionTemperature).
bool smooths_temperature(const FrictionLog& logged, const FrictionFitOptions& options);
// Refuses a log that cannot tell the law (nothing moving, or nothing varied).
void check_conditions_vary(const FrictionLog& log);
// The run offsets asked for, `automatic` resolved, checked against the loss.
RunOffsets run_offsets_for(const FrictionFitOptions& options, std::size_t runs);
// Refuses terms in time, distance or a lagged temperature without a time_s column.
void check_terms_timed(const FrictionFitOptions& options, const TermSeries& series);

// ---- friction_goodness.cc --------------------------------------------------------------------

// The combination that stands for constant j in a combination law's outputs (nullptr: none).
const LawCombination* combination_of(const FrictionFitResult& r, std::size_t j);
void add_predictions(const FrictionLog& log, const TermSeries& series, const FrictionFitOptions& options,
                     std::size_t effects, FrictionFitResult& out);
void add_run_offsets(const FrictionLog& log, RunOffsets offsets, bool random, const RunOffsetVariance& variance,
                     FrictionFitResult& out);
void add_goodness(const FrictionLog& log, FrictionFitResult& out);
void check_weight_against_mass(const FrictionLog& log, FrictionFitResult& out);
void add_law_combinations(const FrictionLog& log, FrictionFitResult& out);

}  // namespace lmcal::detail
