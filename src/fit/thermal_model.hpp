// The thermal least-squares model (private to the fit layer): rail thermocouple residuals
// through the templated rail solver, one simulation per run, Jets seeded only with the
// parameters that run depends on (α, h, the extensions', its offsets, its T0). Its cost is a
// NormalEquationsCost: each run's JᵀJ over the few columns its rows touch, added in run order,
// so the engine polishes it with its own Levenberg-Marquardt (no n × p Jacobian per iteration).
// Its description (rows, linearity, identifiability) is in thermal_model_structure.cc.
#pragma once

#include <string>
#include <vector>

#include "least_squares.hpp"
#include "thermal_extension.hpp"
#include "thermal_prepared.hpp"
#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/models/rail_thermal.hpp"

namespace lmcal::detail {

// Where each kind of parameter sits in the global parameter vector (-1: not fitted).
struct ThermalLayout {
  int alpha = 0;
  int h = -1;
  std::vector<const ThermalExtension*> extensions;
  std::vector<int> extension_first;       // [extension]: index of its first parameter
  std::vector<std::vector<int>> offsets;  // [run][sensor]
  std::vector<int> initial;               // [run]
  std::vector<int> heat_scale;            // [run], -1: Q_f as prepared
  // Empirical sensor terms (thermal_terms.hpp): each one's coefficient, and its scale (-1:
  // none, or held at the term's scale_s; the ambient-periodic terms share one).
  std::vector<ThermalSensorTerm> terms;
  std::vector<int> term_coefficient, term_scale;
  int size = 1;
};

// One run's data rows: residuals and their Jacobian over the run's own columns (the global
// parameters its rows depend on, ascending), row-major.
struct ThermalRunRows {
  std::vector<int> columns;
  Eigen::VectorXd r;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J;
};

class ThermalModel : public LeastSquaresModel {
 public:
  ThermalModel(const std::vector<PreparedRun>& runs, ThermalLayout layout, RailNumerics numerics);
  // The data rows, then one prior row per fitted heat scale.
  std::size_t num_residuals() const override { return rows_.size() + priors_.size(); }
  std::unique_ptr<ceres::CostFunction> cost_function(const std::vector<std::size_t>& rows,
                                                     const RowLoss& loss) const override;
  bool linear(const std::vector<bool>& held) const override;
  bool rows_evaluate_separately() const override { return false; }  // every row needs the runs' simulations
  // The most parameters one run's simulation depends on (the Jet size it needs; at most 8).
  std::size_t max_local_parameters() const;
  void explain(IdentifiabilityIssue& issue) const override;
  RowStructure row_structure() const override;

  // Simulated temperature at every (run, record, sensor) of the data for parameters θ.
  std::vector<std::vector<std::vector<double>>> simulate(const std::vector<double>& theta) const;
  // The sensor terms' sum at every (run, record, sensor), for parameters θ and the simulated
  // temperatures `simulated` (simulate(θ); rise_time needs them).
  std::vector<std::vector<std::vector<double>>> term_sums(const std::vector<double>& theta,
                                                          const std::vector<std::vector<std::vector<double>>>& simulated) const;
  // Each run's temperature along the rail at its last record, for parameters θ: from the last
  // evaluation with derivatives where the model is linear in every parameter that changed
  // since (exact; a linear fit never simulates at its solution), else simulated.
  std::vector<RailProfile> end_profiles(const std::vector<double>& theta) const;
  // Run r's end profile at θ with its slopes over the parameters `local` (slope[j][node]), kept
  // for end_profiles(). Called by the cost function, for each run from one thread.
  void remember_end_profile(std::size_t r, const double* theta, const std::vector<int>& local, RailProfile profile,
                            std::vector<std::vector<double>> slope) const;

  // Every run's rows at θ with `loss`, kept from the last normal equations over all rows (the
  // polish's last trial is usually its answer, whose Jacobian the fit then asks for).
  void remember_rows(const double* theta, const RowLoss& loss, std::vector<ThermalRunRows> runs) const;
  // The rows kept at exactly θ and `loss`, or null.
  const std::vector<ThermalRunRows>* rows_at(const double* theta, const RowLoss& loss) const;

  struct Row {
    std::size_t run, time, sensor;
  };
  const std::vector<Row>& rows() const { return rows_; }  // the data rows
  std::size_t first_row(std::size_t run) const { return first_row_[run]; }
  const std::vector<std::size_t>& prior_runs() const { return priors_; }  // the run of each prior row
  const std::vector<PreparedRun>& runs() const { return runs_; }
  const ThermalLayout& layout() const { return layout_; }
  const RailNumerics& numerics() const { return numerics_; }

 private:
  const std::vector<PreparedRun>& runs_;
  ThermalLayout layout_;
  RailNumerics numerics_;
  std::vector<Row> rows_;                     // measured (not NaN) samples, run by run
  std::vector<std::size_t> first_row_;        // per run, into rows_
  std::vector<std::size_t> priors_;
  struct EndProfileMemo {
    std::vector<double> theta;  // empty: none yet
    std::vector<int> local;
    RailProfile profile;
    std::vector<std::vector<double>> slope;
  };
  mutable std::vector<EndProfileMemo> end_memo_;  // per run, sized at construction
  struct RowsMemo {
    std::vector<double> theta;  // empty: none yet
    RowLoss loss;
    std::vector<ThermalRunRows> runs;
  };
  mutable RowsMemo rows_memo_;
};

}  // namespace lmcal::detail
