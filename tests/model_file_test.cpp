// The calibrated model file (model.toml, lmcal/fit/model_file.hpp) and the rail simulated with
// a model's mechanisms (simulate_rail_with_mechanisms): every bad file of tests/data/model/
// refused with its place and what was expected, a bitwise round trip, and the mechanisms
// against the plain rail model they extend.
#include "lmcal/fit/model_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "lmcal/error.hpp"
#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/models/friction_effects.hpp"
#include "lmcal/models/thermal_effects.hpp"
#include "lmcal/models/thermal_mechanisms.hpp"
#include "support/srn35c.hpp"
#include "support/source_paths.hpp"

namespace lmcal {
namespace {

namespace fs = std::filesystem;

const fs::path kModelDir = test::test_data_dir() / "model";

// --- bad input --------------------------------------------------------------------------------

struct BadFile {
  std::string file, message;  // message: "<line>:<column>: <what>", after "<path>:"
};

// tests/data/model/expected.txt: "<file> | <line>:<column>: <what>", '#' comments; "{mechanisms}"
// in <what> is the library's mechanism names (so that registering one does not touch this list).
std::vector<BadFile> bad_files() {
  std::ifstream in(kModelDir / "expected.txt");
  EXPECT_TRUE(in) << "cannot open " << (kModelDir / "expected.txt");
  std::vector<BadFile> out;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    if (text.empty() || text[0] == '#') continue;
    const auto bar = text.find(" | ");
    if (bar == std::string::npos) {
      ADD_FAILURE() << "expected.txt:" << line << ": not '<file> | <message>': " << text;
      continue;
    }
    std::string message = text.substr(bar + 3);
    if (const auto at = message.find("{mechanisms}"); at != std::string::npos) {
      std::string names;
      for (const auto& info : ThermalMechanismLibrary::infos) names += (names.empty() ? "" : ", ") + std::string(info.name);
      message.replace(at, std::string_view("{mechanisms}").size(), names);
    }
    out.push_back({text.substr(0, bar), message});
  }
  return out;
}

TEST(ModelFile, RefusesEveryBadFileWithFileLineColumnAndWhatWasExpected) {
  const auto cases = bad_files();
  ASSERT_GE(cases.size(), 5u);
  std::set<std::string> listed;
  for (const auto& c : cases) {
    listed.insert(c.file);
    const fs::path path = kModelDir / c.file;
    try {
      read_model_file(path);
      ADD_FAILURE() << c.file << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), path.string() + ":" + c.message) << c.file;
      EXPECT_GT(e.line(), 0) << c.file;
      EXPECT_GT(e.column(), 0) << c.file;
    }
  }
  for (const auto& entry : fs::directory_iterator(kModelDir)) {
    if (entry.path().filename() == "expected.txt") continue;
    EXPECT_TRUE(listed.count(entry.path().filename().string())) << entry.path() << " is not listed in expected.txt";
  }
}

TEST(ModelFile, AMissingFileIsRefusedNamingIt) {
  try {
    read_model_file(kModelDir / "no_such_model.toml");
    FAIL() << "a missing file was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_model.toml: cannot open the model file"), std::string::npos) << e.what();
  }
}

// --- round trip -------------------------------------------------------------------------------

std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v); }

// A temporary file, removed afterwards.
class TempFile {
 public:
  explicit TempFile(const std::string& text)
      : path_(fs::temp_directory_path() / ("lmcal_model_file_test_" + std::to_string(::getpid()) + ".toml")) {
    std::ofstream(path_, std::ios::binary) << text;
  }
  ~TempFile() { fs::remove(path_); }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// A model with awkward numbers: not short in decimal, tiny, huge, subnormal, negative zero.
ModelFile awkward_model() {
  ModelFile m;
  m.set = "set with \"quotes\", a \\ and an ü";  // a set is a folder's name: no tab or escape (set_escape.toml)
  m.lmcal_version = "0.1.0";
  m.command = {"lmcal", "calibrate", "measurements/cheng2017"};
  m.inputs = {{"measurements/cheng2017/friction.csv", std::string(64, 'a')}};
  m.has_friction = true;
  m.constants = {.k1 = 0.1 + 0.2, .k2 = 1.0 / 3.0, .mu_st = 1.52e-3 * 1000.0 / 7.0, .v_st_m_s = 0.015000000000000001,
                 .mu_v = 2.9999999999999997e-3, .beta_per_K = std::nextafter(0.067, 1.0), .f0 = -0.0,
                 .nu_ref_mm2_s = 98.76543210987654, .T_ref_C = 40.000000000000007};
  m.friction_causes = {"seal_drag", "direction_asymmetry"};
  m.effects[*find_friction_effect("seal_drag")] = 149.12345678901234;
  m.effects[*find_friction_effect("direction_asymmetry")] = 0.030000000000000002;
  for (std::size_t j = 0; j < kFrictionConstantNames.size(); ++j) {
    const double v = fittable_constant(m.constants, j);
    m.friction_parameters.push_back({kFrictionConstantNames[j], "", v, v * 1e-3, v - 1e-300, v + 5e-324, j == 1});
  }
  for (const auto& name : m.friction_causes) {
    const double v = m.effects[*find_friction_effect(name)];
    m.friction_parameters.push_back({name, "", v, std::numeric_limits<double>::quiet_NaN(), v / 3, v * 3, false});
  }
  m.friction_covariance = "cluster-robust by run";
  m.has_thermal = true;
  m.alpha = 0.58123456789012345;
  m.h_W_m2K = 5.3 + 1e-15;
  m.source = SourceModel::moving;
  m.mechanisms = {"coupling", "convection_velocity", "tc_lag", "base_loss", "source_moving"};
  m.mechanism_parameters = {{"coupling", 1.0512345678901234},
                            {"convection_velocity", 5.8e-7},
                            {"tc_lag", 33.333333333333336},
                            {"base_loss", 4.9406564584124654e-324}};
  m.thermal_parameters = {{"alpha", "1", m.alpha, 0.0123, 0.55, 0.61, false},
                          {"h_W_m2K", "W/m2K", *m.h_W_m2K, 0, *m.h_W_m2K, *m.h_W_m2K, true}};
  for (const auto& [name, v] : m.mechanism_parameters)
    m.thermal_parameters.push_back({name, "", v, 1.7976931348623157e308, -v, v, false});
  m.thermal_covariance = "iid";
  m.heat_uncertainty = "two-stage:\nthe friction fit's covariance";
  return m;
}

void expect_same_parameters(const std::vector<ModelParameter>& a, const std::vector<ModelParameter>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].name, b[i].name);
    EXPECT_EQ(a[i].unit, b[i].unit) << a[i].name;
    EXPECT_EQ(bits(a[i].value), bits(b[i].value)) << a[i].name << ": " << a[i].value << " vs " << b[i].value;
    if (std::isnan(a[i].se)) {
      EXPECT_TRUE(std::isnan(b[i].se)) << a[i].name;
    } else {
      EXPECT_EQ(bits(a[i].se), bits(b[i].se)) << a[i].name;
    }
    EXPECT_EQ(bits(a[i].ci_low), bits(b[i].ci_low)) << a[i].name;
    EXPECT_EQ(bits(a[i].ci_high), bits(b[i].ci_high)) << a[i].name;
    EXPECT_EQ(a[i].held, b[i].held) << a[i].name;
  }
}

TEST(ModelFile, RoundTripGivesTheSameModelBitForBit) {
  const ModelFile m = awkward_model();
  const TempFile file(model_file_toml(m));
  const ModelFile r = read_model_file(file.path());

  EXPECT_EQ(r.set, m.set);
  EXPECT_EQ(r.lmcal_version, m.lmcal_version);
  EXPECT_EQ(r.command, m.command);
  EXPECT_EQ(r.inputs, m.inputs);

  ASSERT_TRUE(r.has_friction);
  for (std::size_t j = 0; j < kFrictionConstantNames.size(); ++j)
    EXPECT_EQ(bits(fittable_constant(r.constants, j)), bits(fittable_constant(m.constants, j))) << kFrictionConstantNames[j];
  EXPECT_EQ(bits(r.constants.nu_ref_mm2_s), bits(m.constants.nu_ref_mm2_s));
  EXPECT_EQ(bits(r.constants.T_ref_C), bits(m.constants.T_ref_C));
  for (std::size_t slot = 0; slot < kFrictionEffectCount; ++slot)
    EXPECT_EQ(bits(r.effects[slot]), bits(m.effects[slot])) << FrictionEffectLibrary::infos[slot].name;
  EXPECT_EQ(r.friction_causes, m.friction_causes);
  EXPECT_EQ(r.friction_covariance, m.friction_covariance);
  expect_same_parameters(r.friction_parameters, m.friction_parameters);

  ASSERT_TRUE(r.has_thermal);
  EXPECT_EQ(bits(r.alpha), bits(m.alpha));
  ASSERT_TRUE(r.h_W_m2K.has_value());
  EXPECT_EQ(bits(*r.h_W_m2K), bits(*m.h_W_m2K));
  EXPECT_EQ(r.source, m.source);
  EXPECT_EQ(r.mechanisms, m.mechanisms);
  ASSERT_EQ(r.mechanism_parameters.size(), m.mechanism_parameters.size());
  for (std::size_t i = 0; i < m.mechanism_parameters.size(); ++i) {
    EXPECT_EQ(r.mechanism_parameters[i].first, m.mechanism_parameters[i].first);
    EXPECT_EQ(bits(r.mechanism_parameters[i].second), bits(m.mechanism_parameters[i].second)) << m.mechanism_parameters[i].first;
  }
  EXPECT_EQ(r.thermal_covariance, m.thermal_covariance);
  EXPECT_EQ(r.heat_uncertainty, m.heat_uncertainty);
  expect_same_parameters(r.thermal_parameters, m.thermal_parameters);

  // Written again, the same text.
  EXPECT_EQ(model_file_toml(r), model_file_toml(m));
}

TEST(ModelFile, CovarianceRangesAndHeatReferencesRoundTripBitForBit) {
  ModelFile m = awkward_model();
  m.friction_covariance_matrix.parameters = {"k1", "mu_st", "seal_drag"};
  m.friction_covariance_matrix.matrix = (Eigen::MatrixXd(3, 3) << 1.0 / 3e6, 1e-300, -2.5e-7, 1e-300, 4e-6, 0.0, -2.5e-7, 0.0,
                                         0.2167580233978).finished();
  m.friction_range = {{"velocity_m_s", 0.002, 0.15}, {"load_N", 1000, 3000}};
  m.thermal_covariance_matrix.parameters = {"alpha", "coupling"};
  m.thermal_covariance_matrix.matrix = (Eigen::MatrixXd(2, 2) << 2.4625835536140834e-05, -1.07e-06, -1.07e-06, 3.2e-05).finished();
  m.thermal_covariance_given_heat = (Eigen::MatrixXd(2, 2) << 2.1e-05, -1.0e-06, -1.0e-06, 3.1e-05).finished();
  m.thermal_range = {{"temperature_C", 23.885, 33.1}};
  m.alpha_between_run_sd = 0.0123456789;
  m.heat_references = {{{.load_N = 3000, .preload_um = 4, .block_length_mm = 120.2, .velocity_m_s = 0.083,
                         .temperature_C = 23.884999999999998},
                        98.7,
                        3.420264166634061}};
  const TempFile file(model_file_toml(m));
  const ModelFile r = read_model_file(file.path());
  EXPECT_EQ(r.friction_covariance_matrix.parameters, m.friction_covariance_matrix.parameters);
  EXPECT_EQ(r.friction_covariance_matrix.matrix, m.friction_covariance_matrix.matrix);
  EXPECT_EQ(r.thermal_covariance_matrix.matrix, m.thermal_covariance_matrix.matrix);
  EXPECT_EQ(r.thermal_covariance_given_heat, m.thermal_covariance_given_heat);
  ASSERT_EQ(r.friction_range.size(), 2u);
  EXPECT_EQ(r.friction_range_of("load_N")->high, 3000);
  EXPECT_EQ(bits(r.thermal_range_of("temperature_C")->low), bits(23.885));
  EXPECT_EQ(bits(r.alpha_between_run_sd), bits(m.alpha_between_run_sd));
  ASSERT_EQ(r.heat_references.size(), 1u);
  EXPECT_EQ(bits(r.heat_references[0].conditions.temperature_C), bits(23.884999999999998));
  EXPECT_EQ(bits(r.heat_references[0].heat_rate_W), bits(3.420264166634061));
  EXPECT_EQ(model_file_toml(r), model_file_toml(m));
}

TEST(ModelFile, OneHalfAloneRoundTrips) {
  ModelFile m = awkward_model();
  m.has_thermal = false;
  const TempFile file(model_file_toml(m));
  const ModelFile r = read_model_file(file.path());
  EXPECT_TRUE(r.has_friction);
  EXPECT_FALSE(r.has_thermal);
  EXPECT_EQ(model_file_toml(r), model_file_toml(m));
}

// --- the rail with a model's mechanisms ------------------------------------------------------

constexpr double kDuration_s = 4 * 3600.0;

struct RailCase {
  RailGeometry geometry = test::srn35c_geometry();
  RailNumerics numerics{.source = SourceModel::averaged, .scheme = TimeScheme::crank_nicolson, .half_rail_segments = 50,
                        .time_step_s = 60};
  RailOutputs outputs{.duration_s = kDuration_s, .sensor_positions_m = {0.0, 0.05, 0.1}};
  FrictionConditions<double> conditions = test::srn35c_conditions();
  FrictionConstants<double> constants = paper_friction_constants();
  FrictionEffects<double> effects;
  AmbientTrace ambient = AmbientTrace::constant(26.0);

  RailCase() {
    for (double t = 0; t <= kDuration_s; t += 600) outputs.output_times_s.push_back(t);
  }
  // The rail with `mechanisms`; the heat rate from the law (heat_rate_W 0 in the parameters).
  RailSolution<double> with(const std::vector<std::string>& mechanisms,
                            const std::vector<std::pair<std::string, double>>& values) const {
    return simulate_rail_with_mechanisms(geometry, numerics, outputs, test::srn35c_params(0.0), ambient, constants, effects,
                                         conditions, mechanisms, values);
  }
  // The plain rail model with the heat rate `heat_rate_W` and convection `h_W_m2K`.
  RailSolution<double> plain(double heat_rate_W, double h_W_m2K = 5.3) const {
    RailParams<double> p = test::srn35c_params(heat_rate_W);
    p.h_W_m2K = h_W_m2K;
    return simulate_rail(geometry, numerics, outputs, p, ambient);
  }
};

// The largest difference of two runs at the sensors.
double max_difference_K(const RailSolution<double>& a, const RailSolution<double>& b) {
  EXPECT_EQ(a.sensor_temperature_C.size(), b.sensor_temperature_C.size());
  double most = 0;
  for (std::size_t i = 0; i < a.sensor_temperature_C.size(); ++i)
    most = std::max(most, std::abs(a.sensor_temperature_C[i] - b.sensor_temperature_C[i]));
  return most;
}

// The rise at the rail centre at the end of the run.
double rise_K(const RailSolution<double>& s) { return s.temperature_C(s.output_times_s.size() - 1, 0) - 26.0; }

TEST(ModelFile, WithoutMechanismsTheRailIsThePlainModelWithTheLawsHeatRate) {
  RailCase rail;
  const double q_W = heat_rate_W(rail.constants, rail.conditions);
  EXPECT_NEAR(q_W, 4.86, 0.01);  // PHYSICS.md: 4.86 W at 0.11 m/s
  const auto with = rail.with({}, {});
  const auto plain = rail.plain(q_W);
  ASSERT_GT(rise_K(plain), 5.0);
  EXPECT_EQ(with.sensor_temperature_C, plain.sensor_temperature_C);
  for (double q : with.heat_rate_W) EXPECT_EQ(q, q_W);

  // With effects the heat rate is the law's with them, and the temperatures follow.
  rail.effects[*find_friction_effect("seal_drag")] = 150;
  const double q_effects_W = heat_rate_with_effects_W(rail.constants, rail.effects, rail.conditions);
  EXPECT_GT(q_effects_W, q_W + 0.1);  // 150 N s²/m² × (0.11 m/s)² × 0.11 m/s adds 0.2 W
  const auto with_effects = rail.with({}, {});
  EXPECT_EQ(with_effects.sensor_temperature_C, rail.plain(q_effects_W).sensor_temperature_C);
  EXPECT_GT(max_difference_K(with_effects, plain), 0.2);
}

TEST(ModelFile, ConvectionVelocityIsTheRailWithHPlusCvTimesRootV) {
  const RailCase rail;
  const double q_W = heat_rate_W(rail.constants, rail.conditions);
  const double c_V = 6.0, h0 = 5.3;
  const auto with = rail.with({"convection_velocity"}, {{"convection_velocity", c_V}});
  const auto expected = rail.plain(q_W, h0 + c_V * std::sqrt(rail.geometry.velocity_m_s));
  EXPECT_LT(max_difference_K(with, expected), 1e-12);
  // and not the rail with h0: forced convection takes a third of the rise off.
  EXPECT_GT(max_difference_K(with, rail.plain(q_W, h0)), 0.2 * rise_K(expected));
}

TEST(ModelFile, CouplingLowersTheHeatRateAsTheRailWarms) {
  const RailCase rail;
  const double q_start_W = heat_rate_W(rail.constants, rail.conditions);
  const auto coupled = rail.with({"coupling"}, {{"coupling", 1.0}});
  ASSERT_EQ(coupled.heat_rate_W.size(), rail.outputs.output_times_s.size());
  EXPECT_NEAR(coupled.heat_rate_W.front(), q_start_W, 1e-12);
  for (std::size_t t = 1; t < coupled.heat_rate_W.size(); ++t) {
    EXPECT_GT(coupled.source_temperature_C[t], coupled.source_temperature_C[t - 1]) << "t = " << coupled.output_times_s[t];
    EXPECT_LT(coupled.heat_rate_W[t], coupled.heat_rate_W[t - 1]) << "t = " << coupled.output_times_s[t];
  }
  // κ = 1: the law at the rail temperature under the block (to the step's first-order lag).
  FrictionConditions<double> end = rail.conditions;
  end.temperature_C = coupled.source_temperature_C.back();
  EXPECT_NEAR(coupled.heat_rate_W.back(), heat_rate_W(rail.constants, end), 2e-3 * q_start_W);
  EXPECT_LT(coupled.heat_rate_W.back(), 0.8 * q_start_W);  // ~5 %/K over a rise of several K
  // so the rail ends cooler than with the constant heat rate; κ = 0 is the constant heat rate.
  EXPECT_LT(rise_K(coupled), 0.9 * rise_K(rail.plain(q_start_W)));
  EXPECT_LT(max_difference_K(rail.with({"coupling"}, {{"coupling", 0.0}}), rail.plain(q_start_W)), 1e-12);
}

TEST(ModelFile, ThermocoupleLagLeavesTheRailsOwnTemperature) {
  const RailCase rail;
  const auto lagged = rail.with({"tc_lag"}, {{"tc_lag", 300.0}});
  EXPECT_EQ(lagged.sensor_temperature_C, rail.with({}, {}).sensor_temperature_C);
}

TEST(ModelFile, ASourceSwitchSelectsItsSourceModel) {
  RailCase rail;
  const double q_W = heat_rate_W(rail.constants, rail.conditions);
  const auto switched = rail.with({"source_paper"}, {});
  rail.numerics.source = SourceModel::paper;
  EXPECT_EQ(switched.sensor_temperature_C, rail.plain(q_W).sensor_temperature_C);
  rail.numerics.source = SourceModel::averaged;
  EXPECT_GT(max_difference_K(switched, rail.plain(q_W)), 1.0);  // paper: L1/Lb1 = 2.4 times the power
}

TEST(ModelFile, AMechanismWithoutItsValueIsRefused) {
  const RailCase rail;
  EXPECT_THROW(rail.with({"coupling"}, {{"tc_lag", 30.0}}), InvalidParameter);
  EXPECT_THROW(rail.with({"radiation"}, {}), InvalidParameter);
}

}  // namespace
}  // namespace lmcal

namespace lmcal {
namespace {

// Empirical terms (not named causes) travel with the model: factors, values, the ranges they
// were learned on; in a steady sweep a decay has settled and a product term is its value.
TEST(ModelFile, EmpiricalTermsRoundTripAndSettleInASteadySweep) {
  ModelFile m = awkward_model();
  FrictionTerm running_in{.factors = {{TermCovariate::sliding_distance_m, TermTransform::decay},
                                      {TermCovariate::law_force_N, TermTransform::linear}},
                          .coefficient = 0.0966,
                          .scale = 154.3,
                          .seen = {{TermCovariate::sliding_distance_m, 0, 454.2}, {TermCovariate::law_force_N, 5.1, 78.4}}};
  FrictionTerm product{.factors = {{TermCovariate::velocity_m_s, TermTransform::linear},
                                   {TermCovariate::temperature_C, TermTransform::linear, 40}},
                       .coefficient = -1.52,
                       .seen = {{TermCovariate::velocity_m_s, 0.002, 0.15}, {TermCovariate::temperature_C, 21.8, 40.2}}};
  m.friction_terms = {running_in, product};
  m.friction_parameters.push_back({"term1", "1", running_in.coefficient, 0.002, 0.093, 0.1, false});
  m.friction_parameters.push_back({"term1_scale", "m", running_in.scale, 6.7, 141, 167, false});
  m.friction_parameters.push_back({"term2", "N/(m/s·K)", product.coefficient, 0.1, -1.7, -1.3, false});
  const TempFile file(model_file_toml(m));
  const ModelFile r = read_model_file(file.path());
  ASSERT_EQ(r.friction_terms.size(), 2u);
  for (std::size_t t = 0; t < 2; ++t) {
    const FrictionTerm &a = r.friction_terms[t], &b = m.friction_terms[t];
    ASSERT_EQ(a.factors.size(), b.factors.size());
    for (std::size_t f = 0; f < a.factors.size(); ++f) EXPECT_EQ(factor_text(a.factors[f]), factor_text(b.factors[f]));
    EXPECT_EQ(bits(a.coefficient), bits(b.coefficient));
    EXPECT_EQ(a.has_scale(), b.has_scale());
    if (a.has_scale()) {
      EXPECT_EQ(bits(a.scale), bits(b.scale));
    }
    ASSERT_EQ(a.seen.size(), b.seen.size());
    for (std::size_t k = 0; k < a.seen.size(); ++k) EXPECT_EQ(bits(a.seen[k].max), bits(b.seen[k].max));
  }
  EXPECT_EQ(model_file_toml(r), model_file_toml(m));
  // The readings' terms of a thermal model travel as symbols, apart from the rail's parameters.
  ModelFile with_reading_terms = awkward_model();
  with_reading_terms.reading_terms = {"t", "a_P"};
  const TempFile thermal_file(model_file_toml(with_reading_terms));
  EXPECT_EQ(read_model_file(thermal_file.path()).reading_terms, with_reading_terms.reading_terms);

  FrictionConditions<double> c{.load_N = 3000, .preload_um = 4, .block_length_mm = 120.2, .velocity_m_s = 0.1,
                               .temperature_C = 30};
  bool outside = false;
  const FrictionConstants<double> k = paper_friction_constants();
  const FrictionEffects<double> none{};
  EXPECT_EQ(steady_terms_N({r.friction_terms[0]}, k, none, c, &outside), 0.0);  // run in
  EXPECT_DOUBLE_EQ(steady_terms_N({r.friction_terms[1]}, k, none, c, &outside), -1.52 * 0.1 * (30 - 40));
  EXPECT_FALSE(outside);
  c.temperature_C = 60;
  steady_terms_N({r.friction_terms[1]}, k, none, c, &outside);
  EXPECT_TRUE(outside);  // beyond the 21.8-40.2 C it was learned on
}

// The input corrections and the law's reweighted parts round-trip and evaluate as the law at a
// corrected input and as a share of one part: a step of -2 K above 35 C, the viscous part
// scaled by (P - 2000)^2, the law times a decay over the run index.
TEST(ModelFile, InputCorrectionsAndReweightedPartsRoundTripAndEvaluate) {
  ModelFile m = awkward_model();
  FrictionTerm step{.factors = {{TermCovariate::temperature_C, TermTransform::input_shift},
                                {TermCovariate::temperature_C, TermTransform::step, 35.5}},
                    .coefficient = -2,
                    .seen = {{TermCovariate::temperature_C, 21.8, 40.2}}};
  FrictionTerm viscous{.factors = {{TermCovariate::viscous_N, TermTransform::linear},
                                   {TermCovariate::load_N, TermTransform::square, 2000}},
                       .coefficient = 3e-7,
                       .seen = {{TermCovariate::load_N, 1000, 3000}}};
  FrictionTerm campaign{.factors = {{TermCovariate::run_index, TermTransform::decay}, {TermCovariate::law_force_N, TermTransform::linear}},
                        .coefficient = 0.15,
                        .scale = 20,
                        .seen = {{TermCovariate::run_index, 0, 71}}};
  m.friction_terms = {step, viscous, campaign};
  m.friction_parameters.push_back({"term1", "K", -2, 0.1, -2.2, -1.8, false});
  m.friction_parameters.push_back({"term2", "1/(N²)", 3e-7, 1e-8, 2.8e-7, 3.2e-7, false});
  m.friction_parameters.push_back({"term3", "1", 0.15, 0.01, 0.13, 0.17, false});
  m.friction_parameters.push_back({"term3_scale", "1", 20, 1, 18, 22, false});
  const TempFile file(model_file_toml(m));
  const ModelFile r = read_model_file(file.path());
  ASSERT_EQ(r.friction_terms.size(), 3u);
  EXPECT_EQ(model_file_toml(r), model_file_toml(m));
  EXPECT_EQ(r.friction_terms[0].symbol(1), "F_law(T + c1·[T > 35.5]) - F_law(T)");
  EXPECT_EQ(r.friction_terms[0].coefficient_unit(), "K");

  const FrictionConstants<double> k = paper_friction_constants();
  const FrictionEffects<double> none{};
  FrictionConditions<double> c{.load_N = 3000, .preload_um = 4, .block_length_mm = 120.2, .velocity_m_s = 0.1,
                               .temperature_C = 40};
  FrictionConditions<double> cooler = c;
  cooler.temperature_C = 38;
  EXPECT_NEAR(steady_terms_N({r.friction_terms[0]}, k, none, c), friction_force_N(k, cooler) - friction_force_N(k, c), 1e-12);
  c.temperature_C = 30;  // below the step: the law as logged
  EXPECT_EQ(steady_terms_N({r.friction_terms[0]}, k, none, c), 0.0);
  const auto b = friction_breakdown(k, c);
  const double viscous_N = b.viscous_N - k.f0 * c.block_length_mm;
  EXPECT_NEAR(steady_terms_N({r.friction_terms[1]}, k, none, c), 3e-7 * viscous_N * 1000.0 * 1000.0, 1e-12);
  // After the campaign a decay over the run index has settled.
  EXPECT_EQ(steady_terms_N({r.friction_terms[2]}, k, none, c), 0.0);
}

TEST(ModelFile, ATermWithAnUnknownFactorIsRefusedWithItsPlace) {
  ModelFile m = awkward_model();
  m.friction_terms = {FrictionTerm{.factors = {{TermCovariate::velocity_m_s, TermTransform::square}}, .coefficient = 2}};
  m.friction_parameters.push_back({"term1", "N/(m/s)²", 2, 0.1, 1.8, 2.2, false});
  std::string text = model_file_toml(m);
  text.replace(text.find("square:velocity_m_s"), 19, "cubic:velocity_m_s");
  const TempFile file(text);
  try {
    read_model_file(file.path());
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("factor 'cubic:velocity_m_s': expected transform:covariate"), std::string::npos)
        << e.what();
    EXPECT_GT(e.line(), 0);
  }
}

}  // namespace
}  // namespace lmcal
