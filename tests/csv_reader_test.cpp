// The CSV layer's help with common mistakes: an ignored column that looks like a known one or
// like a timestamp is a warning in the load report; a decimal comma is named in the error.
#include <gtest/gtest.h>

#include <string>

#include "lmcal/error.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/io/thermal_run.hpp"
#include "support/temp_folder.hpp"

namespace lmcal {
namespace {

class CsvHelp : public test::TempFolderTest {};

constexpr const char* kHeader = "run,velocity_m_s,load_N,preload_um,block_length_mm,temperature_C,friction_N";

bool contains(const std::vector<std::string>& warnings, const std::string& text) {
  for (const auto& w : warnings)
    if (w.find(text) != std::string::npos) return true;
  return false;
}

TEST_F(CsvHelp, IgnoredColumnsThatLookLikeKnownOnesAreWarnings) {
  const auto file = write("f.csv", std::string(kHeader) +
                                       ",Friction_N,dir,temp_C,frcition_kgf,timestamp,load_cell_N,operator\n"
                                       "r1,0.1,3000,4,120,26,30,30,1,26,3,2026-01-01T00:00,3,ann\n");
  const FrictionLog log = load_friction_log(file);
  const auto& w = log.reports.at(0).warnings;
  EXPECT_TRUE(contains(w, "'Friction_N' is ignored, but looks like 'friction_N'"));
  EXPECT_TRUE(contains(w, "'dir' is ignored, but looks like 'direction'"));
  EXPECT_TRUE(contains(w, "'temp_C' is ignored, but looks like 'temperature_C'"));
  EXPECT_TRUE(contains(w, "'frcition_kgf' is ignored, but looks like 'friction_kgf'"));
  EXPECT_TRUE(contains(w, "'timestamp' (a timestamp?) is ignored"));
  // Another force (a load cell's raw reading) and a plain note column are not mistakes.
  EXPECT_FALSE(contains(w, "load_cell_N"));
  EXPECT_FALSE(contains(w, "operator"));
  EXPECT_EQ(w.size(), 5u);
}

TEST_F(CsvHelp, CleanFilesHaveNoWarnings) {
  const auto file = write("f.csv", std::string(kHeader) + ",direction,time_s\nr1,0.1,3000,4,120,26,30,1,0\n");
  EXPECT_TRUE(load_friction_log(file).reports.at(0).warnings.empty());
  const auto trace = write("t.csv", "time_s,ambient1_C,tc1_F\n0,20,70\n5,20,70.2\n");
  EXPECT_TRUE(load_thermal_trace(trace).report.warnings.empty());
}

TEST_F(CsvHelp, AThermocoupleWithAnUpperCaseNameIsAWarning) {
  const auto trace = write("t.csv", "time_s,ambient1_C,tc2_C,TC1_F\n0,20,20,70\n5,20,20,70.2\n");
  const ThermalTrace t = load_thermal_trace(trace);
  ASSERT_EQ(t.report.warnings.size(), 1u);
  EXPECT_NE(t.report.warnings[0].find("'TC1_F' is ignored, but looks like 'tc1_F'"), std::string::npos) << t.report.warnings[0];
}

TEST_F(CsvHelp, ADecimalCommaIsNamedInTheError) {
  const auto split = write("f.csv", std::string(kHeader) + "\nr1,0,1,3000,4,120,26,5\n");
  try {
    load_friction_log(split);
    ADD_FAILURE() << "a row with a decimal comma loaded";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_NE(std::string(e.what()).find("decimal commas?"), std::string::npos) << e.what();
  }
  const auto quoted = write("g.csv", std::string(kHeader) + "\nr1,\"0,1\",3000,4,120,26,5\n");
  try {
    load_friction_log(quoted);
    ADD_FAILURE() << "a quoted decimal comma loaded";
  } catch (const InputError& e) {
    EXPECT_EQ(e.column(), 4);
    EXPECT_NE(std::string(e.what()).find("a decimal comma?"), std::string::npos) << e.what();
  }
  // One cell too many that is not a split number keeps the plain message.
  const auto extra = write("h.csv", std::string(kHeader) + "\nr1,0.1,3000,4,120,26,5,x\n");
  try {
    load_friction_log(extra);
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find("decimal"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lmcal
