// Every options enum's names (lmcal/enum_names.hpp): each value's to_string parses back to it,
// the names are the ones the CLI, the Python module and the outputs have always used, and an
// unknown name is refused naming the parameter and the names it takes.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "lmcal/error.hpp"
#include "lmcal/fit/fit_result.hpp"
#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/fit/thermal_fit.hpp"

namespace lmcal {
namespace {

template <typename Enum, std::size_t N, typename Parse>
void expect_round_trip(const Enum (&values)[N], Parse parse) {
  for (const Enum v : values) EXPECT_EQ(parse(to_string(v)), v) << to_string(v);
}

TEST(EnumNames, EachNameParsesBackToItsValue) {
  expect_round_trip(kProfileModes, [](const char* n) { return parse_profile_mode(n); });
  expect_round_trip(kCovarianceMethods, [](const char* n) { return parse_covariance_method(n); });
  expect_round_trip(kRobustLosses, [](const char* n) { return parse_robust_loss(n); });
  expect_round_trip(kFrictionWeightings, [](const char* n) { return parse_friction_weighting(n); });
  expect_round_trip(kRunOffsets, [](const char* n) { return parse_run_offsets(n); });
  expect_round_trip(kFrictionTemperatures, [](const char* n) { return parse_friction_temperature(n); });
  expect_round_trip(kThermalOffsets, [](const char* n) { return parse_thermal_offsets(n); });
  expect_round_trip(kHeatInputs, [](const char* n) { return parse_heat_input(n); });
}

TEST(EnumNames, TheNamesTheFrontEndsAndOutputsUse) {
  EXPECT_EQ(enum_names(kProfileModes), (std::vector<std::string>{"auto", "all", "none"}));
  EXPECT_EQ(enum_names(kCovarianceMethods), (std::vector<std::string>{"auto", "iid", "hac", "cluster", "bootstrap"}));
  EXPECT_EQ(enum_names(kRobustLosses), (std::vector<std::string>{"none", "huber", "cauchy"}));
}

TEST(EnumNames, AnUnknownNameIsRefusedWithTheNamesItTakes) {
  try {
    parse_robust_loss("l1", "--loss");
    FAIL() << "no InvalidParameter";
  } catch (const InvalidParameter& e) {
    EXPECT_EQ(e.parameter(), "--loss");
    EXPECT_NE(std::string(e.what()).find("unknown loss 'l1'; expected none, huber or cauchy"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_covariance_method("sandwich"), InvalidParameter);
  EXPECT_THROW(parse_profile_mode("some"), InvalidParameter);
}

}  // namespace
}  // namespace lmcal
