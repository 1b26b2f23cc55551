// The calibrated model as a file, model.toml: what `lmcal calibrate` found — the friction law
// with the accepted effects, the rail model with the accepted mechanisms — every parameter
// with its value, standard error and 95 % interval (and the covariance method they come from),
// and where it came from (inputs with SHA-256, command, lmcal version). Calibrate once, use
// everywhere: `lmcal simulate friction --model FILE` and `lmcal simulate thermal --model FILE`
// read it.
//
//   kind = "lmcal calibrated model"
//   guide = "SRN 35C"   # optional: the guide calibrated (a duty on another is refused by predict)
//   [friction]   causes = [...], covariance = "...", reference_temperature_C, viscosity40_mm2_s
//   [[friction.parameter]]  name, unit, value, se, ci95 = [low, high], held
//   [[friction.term]]       an empirical term (not a named cause): symbol, factors =
//                           ["decay:sliding_distance_m", "linear:friction_law_N"], coefficient =
//                           "term1", scale = "term1_scale", seen = [{covariate, min, max}, …]
//   [thermal]    source = "averaged", mechanisms = [...], covariance = "...", heat_uncertainty
//   [[thermal.parameter]]   name, unit, value, se, ci95, held      (alpha, h_W_m2K, mechanisms')
//   reading_terms = [...]   in [thermal]: empirical terms fitted on the readings (not the rail's)
//   [friction.covariance_matrix], [thermal.covariance_matrix]   parameters = [...], matrix = [[...]]
//                           (the quoted covariance of the free parameters; thermal also
//                           given_heat = [[...]], the same before the heat's uncertainty was added)
//   [friction.range], [thermal.range]   quantity = [min, max] of the calibration data
//   [thermal.between_runs]  alpha_sd: the spread of α from run to run beyond the runs' noise
//   [[thermal.heat_reference]]  each calibration run's friction-law conditions and heat rate
//
// The covariance, ranges and references are what `lmcal predict` propagates and checks; a
// file of another major version of lmcal is refused.
//
// Trap: α belongs to the source model it was fitted with (the file records it, and the reader
// returns it: simulate with that source).
#pragma once

#include "lmcal/export.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/fit/thermal_fit.hpp"

namespace LMCAL_API lmcal {

struct ModelParameter {
  std::string name, unit;
  double value = 0, se = 0, ci_low = 0, ci_high = 0;
  bool held = false;
};

// The covariance of a model's free parameters, in the order of `parameters`.
struct ModelCovariance {
  std::vector<std::string> parameters;
  Eigen::MatrixXd matrix;
  bool empty() const { return parameters.empty(); }
};

// The span of a quantity in the calibration data ("velocity_m_s", "load_N", "temperature_C", …).
struct CalibratedRange {
  std::string quantity;
  double low = 0, high = 0;
};

// A calibration run's heat: the friction law's conditions it was evaluated at and the heat rate.
struct HeatReference {
  FrictionConditions<double> conditions;
  double viscosity40_mm2_s = 99;
  double heat_rate_W = 0;
};

struct ModelFile {
  std::string set, lmcal_version;
  // The catalog guide the calibration ran on ("SRN 35C"; empty: not recorded, or several): α, h
  // and the friction constants are that guide's rail and block (lmcal predict refuses another).
  std::string guide;
  std::vector<std::string> command;
  std::vector<std::pair<std::string, std::string>> inputs;  // file -> sha256

  bool has_friction = false;
  FrictionConstants<double> constants = paper_friction_constants();
  FrictionEffects<double> effects;
  std::vector<std::string> friction_causes;
  // "constants": the paper's law with its scalings in load, preload and block length;
  // "combinations": fitted where none of them was logged (FrictionLawConditions), so it holds
  // for the calibrated setup only and cannot predict other conditions (`law = "combinations"`).
  std::string friction_law = "constants";
  // Refuses (InvalidParameter naming `use`) a combination law, which knows no conditions.
  void require_friction_scalings(std::string_view use) const;
  // Empirical terms the diagnosis learned beyond the library (not named causes); their
  // parameters are "term1", "term1_scale", … among friction_parameters.
  std::vector<FrictionTerm> friction_terms;
  std::vector<ModelParameter> friction_parameters;
  std::string friction_covariance;
  ModelCovariance friction_covariance_matrix;
  std::vector<CalibratedRange> friction_range;

  bool has_thermal = false;
  double alpha = 0;
  std::optional<double> h_W_m2K;
  SourceModel source = SourceModel::averaged;
  std::vector<std::string> mechanisms;                       // thermal extension names
  std::vector<std::pair<std::string, double>> mechanism_parameters;  // their parameters, name -> value
  std::vector<ModelParameter> thermal_parameters;
  // Empirical terms the model was fitted with on the thermocouple readings (a drift, a swing
  // the ambient sensors miss): they describe the readings, not the rail, and are not applied
  // when the rail is simulated. Their symbols only.
  std::vector<std::string> reading_terms;
  std::string thermal_covariance, heat_uncertainty;
  ModelCovariance thermal_covariance_matrix;
  Eigen::MatrixXd thermal_covariance_given_heat;  // empty when the heat's uncertainty was not added
  double alpha_between_run_sd = 0;  // > 0 when the runs disagree about α beyond their noise
  std::vector<HeatReference> heat_references;  // empty unless the heat came from the friction law
  std::vector<CalibratedRange> thermal_range;

  const CalibratedRange* friction_range_of(std::string_view quantity) const;
  const CalibratedRange* thermal_range_of(std::string_view quantity) const;

  const ModelParameter* find(const std::string& name) const;
};

// The model file's text. Either fit may be missing (a folder with one half).
std::string model_file_toml(const ModelFile& model);
ModelFile model_file_of(const FrictionFitResult* friction, const FrictionFitOptions& friction_options,
                        const ThermalFitResult* thermal, const ThermalFitOptions& thermal_options);
// The guide every run of `data` ran on (ModelFile::guide); empty when they differ.
std::string calibrated_guide(const ThermalDataSet& data);
// Reads a model file; InputError (file, line, column, what was expected) on bad input.
ModelFile read_model_file(const std::filesystem::path& file);

}  // namespace lmcal
