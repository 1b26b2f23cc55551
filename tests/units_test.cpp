// Tests for unit suffixes: every conversion of units.hpp against its definition, and the
// splitting of column names into name and unit.
#include "lmcal/io/units.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <string>

namespace lmcal {
namespace {

// The value `given` in `unit` of `quantity`, in internal units.
double to_internal(Quantity quantity, const char* unit, double given) {
  const auto conversion = unit_conversion(quantity, unit);
  EXPECT_TRUE(conversion.has_value()) << unit;
  return conversion ? conversion->apply(given) : 0.0;
}

TEST(Units, InternalUnitIsListedFirstAndConvertsToItself) {
  const std::pair<Quantity, const char*> internal[] = {{Quantity::time, "s"},        {Quantity::velocity, "m_s"},
                                                       {Quantity::force, "N"},       {Quantity::preload, "um"},
                                                       {Quantity::length_mm, "mm"},  {Quantity::distance_m, "m"},
                                                       {Quantity::temperature, "C"}, {Quantity::viscosity, "mm2_s"},
                                                       {Quantity::angular_velocity, "rad_s"}, {Quantity::torque, "Nm"},
                                                       {Quantity::acceleration, "m_s2"}};
  for (const auto& [quantity, unit] : internal) {
    EXPECT_EQ(unit_names(quantity).front(), unit);
    const Conversion c = unit_conversion(quantity, unit).value();
    EXPECT_EQ(c.scale, 1.0);
    EXPECT_EQ(c.offset, 0.0);
  }
}

TEST(Units, Time) {
  EXPECT_EQ(to_internal(Quantity::time, "min", 1), 60.0);
  EXPECT_EQ(to_internal(Quantity::time, "h", 6), 21600.0);
  EXPECT_DOUBLE_EQ(to_internal(Quantity::time, "ms", 500), 0.5);
  EXPECT_EQ(unit_names(Quantity::time), (std::vector<std::string>{"s", "ms", "min", "h"}));
}

TEST(Units, Acceleration) {
  EXPECT_EQ(to_internal(Quantity::acceleration, "g", 1), 9.80665);  // standard gravity, exact
  EXPECT_DOUBLE_EQ(to_internal(Quantity::acceleration, "mm_s2", 250), 0.25);
  EXPECT_EQ(unit_names(Quantity::acceleration), (std::vector<std::string>{"m_s2", "mm_s2", "g"}));
}

TEST(Units, Velocity) {
  EXPECT_DOUBLE_EQ(to_internal(Quantity::velocity, "mm_s", 120), 0.12);
  EXPECT_DOUBLE_EQ(to_internal(Quantity::velocity, "m_min", 6.6), 0.11);
  EXPECT_EQ(unit_names(Quantity::velocity), (std::vector<std::string>{"m_s", "mm_s", "m_min"}));
}

TEST(Units, ForceAndFriction) {
  EXPECT_EQ(to_internal(Quantity::force, "kgf", 1), 9.80665);  // exact by definition
  EXPECT_EQ(to_internal(Quantity::force, "kN", 3), 3000.0);
  EXPECT_EQ(to_internal(Quantity::force, "lbf", 1), 4.4482216152605);
  EXPECT_DOUBLE_EQ(to_internal(Quantity::force, "kgf", 2000), 19613.3);  // the rig's load cell range
  EXPECT_EQ(unit_names(Quantity::force), (std::vector<std::string>{"N", "kN", "kgf", "lbf"}));
}

TEST(Units, PreloadLengthAndDistance) {
  EXPECT_DOUBLE_EQ(to_internal(Quantity::preload, "mm", 0.004), 4.0);
  EXPECT_DOUBLE_EQ(to_internal(Quantity::length_mm, "m", 0.1202), 120.2);
  EXPECT_DOUBLE_EQ(to_internal(Quantity::distance_m, "mm", 50), 0.05);
  EXPECT_EQ(unit_names(Quantity::preload), (std::vector<std::string>{"um", "mm"}));
  EXPECT_EQ(unit_names(Quantity::length_mm), (std::vector<std::string>{"mm", "m"}));
  EXPECT_EQ(unit_names(Quantity::distance_m), (std::vector<std::string>{"m", "mm"}));
}

TEST(Units, TemperatureHasAnOffset) {
  EXPECT_NEAR(to_internal(Quantity::temperature, "K", 300), 26.85, 1e-12);
  EXPECT_EQ(to_internal(Quantity::temperature, "K", 273.15), 0.0);
  EXPECT_NEAR(to_internal(Quantity::temperature, "F", 77), 25.0, 1e-12);
  EXPECT_NEAR(to_internal(Quantity::temperature, "F", 32), 0.0, 1e-12);
  EXPECT_NEAR(to_internal(Quantity::temperature, "F", -40), -40.0, 1e-12);
  EXPECT_EQ(to_internal(Quantity::temperature, "C", 26.85), 26.85);
  EXPECT_EQ(unit_names(Quantity::temperature), (std::vector<std::string>{"C", "K", "F"}));
}

TEST(Units, Viscosity) {
  EXPECT_EQ(to_internal(Quantity::viscosity, "cSt", 99), 99.0);
  EXPECT_DOUBLE_EQ(to_internal(Quantity::viscosity, "m2_s", 99e-6), 99.0);
  EXPECT_EQ(unit_names(Quantity::viscosity), (std::vector<std::string>{"mm2_s", "cSt", "m2_s"}));
}

// A motor's quantities: rpm to rad/s; percent of a nominal torque to a fraction of it.
TEST(Units, AngularVelocityAndTorque) {
  EXPECT_NEAR(to_internal(Quantity::angular_velocity, "rpm", 60), 2 * M_PI, 1e-15);
  EXPECT_EQ(to_internal(Quantity::torque, "percent", 50), 0.5);
  EXPECT_TRUE(is_relative_unit(Quantity::torque, "percent"));
  EXPECT_FALSE(is_relative_unit(Quantity::torque, "Nm"));
  EXPECT_FALSE(unit_conversion(Quantity::velocity, "rpm"));  // not a linear speed
  EXPECT_EQ(split_unit("velocity_rad_s", Quantity::angular_velocity)->name, "velocity");
}

TEST(Units, UnknownUnitHasNoConversion) {
  EXPECT_FALSE(unit_conversion(Quantity::force, "lb"));
  EXPECT_FALSE(unit_conversion(Quantity::force, "n"));  // units are case-sensitive
  EXPECT_FALSE(unit_conversion(Quantity::temperature, "degC"));
  EXPECT_FALSE(unit_conversion(Quantity::velocity, "s"));  // a time unit, not a speed
}

TEST(Units, SplitsNameAndUnit) {
  const auto velocity = split_unit("velocity_mm_s", Quantity::velocity).value();
  EXPECT_EQ(velocity.name, "velocity");
  EXPECT_EQ(velocity.unit, "mm_s");
  EXPECT_EQ(velocity.conversion.scale, 1e-3);

  const auto load = split_unit("load_kgf", Quantity::force).value();
  EXPECT_EQ(load.name, "load");
  EXPECT_EQ(load.conversion.scale, 9.80665);
  EXPECT_EQ(load.conversion.offset, 0.0);

  const auto tc = split_unit("tc1_K", Quantity::temperature).value();
  EXPECT_EQ(tc.name, "tc1");
  EXPECT_EQ(tc.unit, "K");
  EXPECT_EQ(tc.conversion.offset, -273.15);

  EXPECT_EQ(split_unit("time_min", Quantity::time)->unit, "min");
  EXPECT_EQ(split_unit("viscosity40_mm2_s", Quantity::viscosity)->name, "viscosity40");
  EXPECT_EQ(split_unit("block_length_m", Quantity::length_mm)->name, "block_length");
}

TEST(Units, SplitTakesTheLongestUnit) {
  // "m_s" and "mm_s" both end in "_s"-something; the name keeps whatever the unit does not take.
  EXPECT_EQ(split_unit("a_m_s", Quantity::velocity)->unit, "m_s");
  EXPECT_EQ(split_unit("a_mm_s", Quantity::velocity)->unit, "mm_s");
  const auto nested = split_unit("speed_m_m_min", Quantity::velocity).value();
  EXPECT_EQ(nested.name, "speed_m");
  EXPECT_EQ(nested.unit, "m_min");
  EXPECT_EQ(split_unit("stroke_mm", Quantity::distance_m)->unit, "mm");
  EXPECT_EQ(split_unit("stroke_m", Quantity::distance_m)->unit, "m");
}

TEST(Units, SplitRefusesUnknownOrMissingUnits) {
  EXPECT_FALSE(split_unit("load_lb", Quantity::force));
  EXPECT_FALSE(split_unit("load", Quantity::force));
  EXPECT_FALSE(split_unit("loadN", Quantity::force));  // the '_' is required
  EXPECT_FALSE(split_unit("_N", Quantity::force));     // and a name before it
  EXPECT_FALSE(split_unit("load_N", Quantity::temperature));
  EXPECT_FALSE(split_unit("", Quantity::time));
}

}  // namespace
}  // namespace lmcal
