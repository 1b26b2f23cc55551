// The friction least-squares model (private to the fit layer). Kept in its own
// translation unit: the row loop over 10⁵ samples must be compiled where the compiler
// still inlines the Jet arithmetic, not inside a large file.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "friction_condition.hpp"
#include "friction_steps.hpp"
#include "least_squares.hpp"
#include "run_offsets.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/models/friction_effects.hpp"
#include "lmcal/models/friction_terms.hpp"

namespace lmcal::detail {

// What the residuals need, one entry per sample.
struct FrictionData {
  const FrictionLog* log;
  std::vector<std::size_t> samples;  // indices into the log
  std::vector<double> inv_sigma;     // per entry of `samples`
  double T_ref_C = 40.0;
  // Per run index: the share c of the run's mean residual taken out (1: a free zero offset per
  // run, profiled; below 1: a random one, GLS-whitened; see BatchedAutoDiffCostFunction).
  // Empty: no run offsets.
  std::vector<double> run_shrink;
  // Random offsets with λ profiled by the polish (run_offsets.hpp; it updates run_shrink in
  // place), or null: run_shrink as given.
  ProfiledRunOffsets* profiled = nullptr;
  // Empirical terms on top of the law and its effects (friction_terms.hpp; empty: none), and
  // what they need of the log.
  const std::vector<FrictionTerm>* terms = nullptr;
  const TermSeries* series = nullptr;
};

// Design facts that decide what the data can determine.
struct Design {
  std::set<double> preloads, temperatures, loads, block_lengths;
  double temperature_span_K = 0;  // max - min of the logged temperatures
  std::size_t low_speed = 0;  // samples with V < 0.03 m/s, where the Stribeck term is felt
  double min_velocity = 0;
};

class FrictionModel : public LeastSquaresModel {
 public:
  FrictionModel(const FrictionData& data, std::vector<std::size_t> effect_slots);
  std::size_t num_residuals() const override { return data_.samples.size(); }
  bool costs_evaluate_concurrently() const override { return true; }
  std::unique_ptr<ceres::CostFunction> cost_function(const std::vector<std::size_t>& rows,
                                                     const RowLoss& loss) const override;
  void explain(IdentifiabilityIssue& issue) const override;
  std::vector<IdentifiabilityIssue> design_issues(const std::vector<std::string>& free) const override;
  RowStructure row_structure() const override;
  void estimate_settled() const override {
    if (data_.profiled) data_.profiled->profiling = false;
  }

 private:
  const FrictionData& data_;
  std::vector<std::size_t> effect_slots_;
  Design design_;
};

}  // namespace lmcal::detail
