// Tests for friction logs: loading (columns, defaults, report), the writer's exact round
// trip, alternative units, several files into one log. Refused input is covered by the
// bad-input corpus (bad_input_test.cpp).
#include "lmcal/io/friction_log.hpp"

#include "lmcal/error.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <unistd.h>

#include "support/temp_folder.hpp"
#include "support/source_paths.hpp"

namespace lmcal {
namespace {

namespace fs = std::filesystem;

const fs::path kGood = test::test_data_dir() / "good";

class FrictionLogTest : public test::TempFolderTest {};

// Same bits (so 0.1 + 0.2 must not come back as 0.3, and -0.0 stays -0.0).
bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_same_bits(const std::vector<double>& a, const std::vector<double>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i)
    EXPECT_TRUE(same_bits(a[i], b[i])) << what << "[" << i << "]: " << a[i] << " vs " << b[i];
}

void expect_same_log(const FrictionLog& a, const FrictionLog& b) {
  EXPECT_EQ(a.run_names, b.run_names);
  EXPECT_EQ(a.guide_names, b.guide_names);
  EXPECT_EQ(a.run, b.run);
  EXPECT_EQ(a.guide, b.guide);
  expect_same_bits(a.time_s, b.time_s, "time_s");
  expect_same_bits(a.velocity_m_s, b.velocity_m_s, "velocity_m_s");
  expect_same_bits(a.load_N, b.load_N, "load_N");
  expect_same_bits(a.preload_um, b.preload_um, "preload_um");
  expect_same_bits(a.block_length_mm, b.block_length_mm, "block_length_mm");
  expect_same_bits(a.temperature_C, b.temperature_C, "temperature_C");
  expect_same_bits(a.friction_N, b.friction_N, "friction_N");
  expect_same_bits(a.viscosity40_mm2_s, b.viscosity40_mm2_s, "viscosity40_mm2_s");
  EXPECT_EQ(a.direction, b.direction);
}

// A CSV text cell: in quotes, inner quotes doubled.
std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

// A log with numbers that print badly in fixed formats, two runs named as a writer must quote
// (a leading '#' reads as a comment, edge spaces are trimmed), two guides.
FrictionLog awkward_log() {
  FrictionLog log;
  log.run_names = {"#v066", " run \"b\", slow "};
  log.guide_names = {"SRN 35C", "SRG 25C"};
  const double values[] = {0.1 + 0.2, 1.0 / 3.0, 26.85, 1e-300, 12345.678901234567, 2.0 / 7.0};
  for (std::size_t i = 0; i < 6; ++i) {
    log.run.push_back(i < 3 ? 0 : 1);
    log.guide.push_back(i % 2);
    log.time_s.push_back(i < 3 ? 0.1 * static_cast<double>(i) : 1.0 / 3.0 * static_cast<double>(i));
    // Scaled into the ranges a rig's values take (units.hpp physical_range).
    log.velocity_m_s.push_back(values[i] * 1e-3);
    log.load_N.push_back(3000 + values[i]);
    log.preload_um.push_back(0.01 * values[(i + 1) % 6]);
    log.block_length_mm.push_back(120.2 + values[i]);
    log.temperature_C.push_back(i == 0 ? -0.0 : 20 + 0.01 * values[(i + 2) % 6]);
    log.friction_N.push_back(44.2 + values[(i + 3) % 6]);
    log.viscosity40_mm2_s.push_back(99 + values[i]);
    log.direction.push_back(i % 3 ? 1 : -1);
  }
  return log;
}

TEST_F(FrictionLogTest, LoadsColumnsCommentsQuotesAndReport) {
  const FrictionLog log = load_friction_log(kGood / "friction_si.csv");
  ASSERT_EQ(log.size(), 3u);  // 5 data rows, two without friction (empty, NaN)
  EXPECT_EQ(log.run_names, (std::vector<std::string>{"v066", "v110 \"fast\""}));
  EXPECT_EQ(log.guide_names, (std::vector<std::string>{"SRN 35C"}));
  EXPECT_EQ(log.run, (std::vector<std::uint32_t>{0, 0, 1}));
  EXPECT_EQ(log.time_s, (std::vector<double>{0, 0.5, 0}));
  EXPECT_EQ(log.friction_N, (std::vector<double>{28.2, 28.4, 44.2}));
  EXPECT_EQ(log.viscosity40_mm2_s, (std::vector<double>{99, 99, 68}));
  EXPECT_EQ(log.direction, (std::vector<std::int8_t>{1, -1, 1}));  // "+1" reads as +1
  EXPECT_EQ(log.line, (std::vector<std::uint32_t>{4, 7, 9}));  // each sample's row, past comments and blank lines

  const FrictionConditions<double> c = log.conditions(2);
  EXPECT_EQ(c.velocity_m_s, 0.11);
  EXPECT_EQ(c.load_N, 3000.0);
  EXPECT_EQ(c.preload_um, 4.0);
  EXPECT_EQ(c.block_length_mm, 120.2);
  EXPECT_EQ(c.temperature_C, 26.0);

  ASSERT_EQ(log.reports.size(), 1u);
  const LoadReport& r = log.reports[0];
  EXPECT_EQ(r.file, (kGood / "friction_si.csv").string());
  EXPECT_EQ(r.rows_read, 5u);
  EXPECT_EQ(r.rows_kept, 3u);
  EXPECT_EQ(r.skipped, (std::map<std::string, std::size_t>{{"friction_N empty or NaN", 2}}));
  EXPECT_EQ(r.ignored_columns, (std::vector<std::string>{"operator"}));
  EXPECT_TRUE(r.conversions.empty());
  EXPECT_EQ(r.bytes, static_cast<double>(fs::file_size(kGood / "friction_si.csv")));
}

TEST_F(FrictionLogTest, OptionalColumnsTakeTheirDefaults) {
  const FrictionLog log = load_friction_log(write(
      "minimal.csv",
      "friction_N,temperature_C,block_length_mm,preload_um,load_N,velocity_m_s,run\n44.2,26,120.2,4,3000,0.11,a\n"));
  ASSERT_EQ(log.size(), 1u);
  EXPECT_TRUE(std::isnan(log.time_s[0]));
  EXPECT_EQ(log.viscosity40_mm2_s[0], 99.0);
  EXPECT_EQ(log.direction[0], 1);
  EXPECT_EQ(log.guide_names, (std::vector<std::string>{""}));
  EXPECT_EQ(log.guide[0], 0u);
  EXPECT_EQ(log.velocity_m_s[0], 0.11);  // columns found in any order
}

TEST_F(FrictionLogTest, WrittenLogLoadsBackBitForBit) {
  const FrictionLog log = awkward_log();
  const std::string text = friction_log_csv(log, {"written by friction_log_test", "second line"});
  EXPECT_EQ(text.rfind("# written by friction_log_test\n# second line\n", 0), 0u) << text;
  const FrictionLog back = load_friction_log(write("round_trip.csv", text));
  expect_same_log(log, back);
  EXPECT_TRUE(back.reports[0].conversions.empty());  // canonical units
  EXPECT_TRUE(back.reports[0].ignored_columns.empty());
  // And the writer is stable: the loaded log writes the same text.
  EXPECT_EQ(friction_log_csv(back, {"written by friction_log_test", "second line"}), text);
}

// A tidy log may give the carriage's acceleration where its friction was taken (a moving
// mass's error shows against it): any unit of acceleration, written back in m/s² when a sample
// has one; a raw log's comes from its motion, and its column is ignored with the reason.
TEST_F(FrictionLogTest, ATidyLogsAccelerationLoadsInItsUnitAndWritesBack) {
  const FrictionLog log = load_friction_log(write("accelerating.csv",
                                                  "run,velocity_m_s,load_N,preload_um,block_length_mm,temperature_C,"
                                                  "friction_N,acceleration_mm_s2\n"
                                                  "r1,0.1,1000,2.5,120,25,30.5,-400\n"
                                                  "r1,0.1,1000,2.5,120,25,30.1,250\n"));
  EXPECT_DOUBLE_EQ(log.acceleration_m_s2[0], -0.4);
  EXPECT_DOUBLE_EQ(log.conditions(1).acceleration_m_s2, 0.25);
  const std::string text = friction_log_csv(log, {});
  EXPECT_NE(text.find(",acceleration_m_s2\n"), std::string::npos) << text;
  expect_same_bits(load_friction_log(write("back.csv", text)).acceleration_m_s2, log.acceleration_m_s2, "acceleration");
  EXPECT_EQ(friction_log_csv(load_friction_log(write("none.csv", friction_log_csv(awkward_log(), {}))), {})
                .find("acceleration"),
            std::string::npos)
      << "no column where no sample accelerates";
  RawFrictionOptions raw;
  raw.segmentation = RawSegmentation::trajectory;
  std::string rows = "time_s,position_m,force_N,acceleration_m_s2\n";
  for (int i = 0; i < 4000; ++i) {  // 0.05 m strokes at 0.5 Hz, friction 20 N against the motion
    const double t = 0.001 * i, w = 3.14159265358979;
    rows += fmt::format("{},{},{},0\n", t, 0.05 * std::sin(w * t), std::cos(w * t) > 0 ? 20.0 : -20.0);
  }
  const auto report = load_friction_log(write("raw.csv", rows), raw).reports.at(0);
  ASSERT_EQ(report.ignored_columns.size(), 1u);
  EXPECT_NE(report.ignored_columns[0].find("comes from its motion"), std::string::npos);
}

// Names a spreadsheet would run as formulas (=, +, -, @) are written with a leading apostrophe
// (issue 23 #10), and read back as they were; so are names that start with an apostrophe.
TEST_F(FrictionLogTest, FormulaLikeNamesAreNeutralisedInTheFileAndReadBackIntact) {
  FrictionLog log = awkward_log();
  log.run_names = {"=HYPERLINK(\"http://x\",\"y\")", "-r2"};
  log.guide_names = {"@SUM(A1)", "'=already"};
  const std::string text = friction_log_csv(log, {});
  EXPECT_NE(text.find("\"'=HYPERLINK(\"\"http://x\"\",\"\"y\"\")\""), std::string::npos) << text;
  EXPECT_NE(text.find("\n'-r2,"), std::string::npos) << text;
  EXPECT_NE(text.find(",'@SUM(A1),"), std::string::npos) << text;
  EXPECT_NE(text.find(",''=already,"), std::string::npos) << text;
  EXPECT_EQ(text.find("\n=") , std::string::npos);
  EXPECT_EQ(text.find(",="), std::string::npos);
  const FrictionLog back = load_friction_log(write("formulas.csv", text));
  EXPECT_EQ(back.run_names, log.run_names);
  EXPECT_EQ(back.guide_names, log.guide_names);
  // Every one-character start either way: written and read back, the same text.
  for (const std::string name : {"'", "''", "'a", "a'", "''-", "+", "'+1", "x=1"}) {
    log.run_names = {name, "b"};
    EXPECT_EQ(load_friction_log(write("one.csv", friction_log_csv(log, {}))).run_names, log.run_names) << name;
  }
}

// Samples of which only some name a guide write an empty guide cell for the others, and read
// back as written (an empty guide cell was refused: the log lmcal wrote did not load).
TEST_F(FrictionLogTest, ALogWhereOnlySomeSamplesNameAGuideLoadsBack) {
  FrictionLog log = awkward_log();
  log.guide_names = {"SRN 35C", ""};
  expect_same_log(log, load_friction_log(write("some_guides.csv", friction_log_csv(log))));
}

TEST_F(FrictionLogTest, WriterLeavesOutColumnsWithoutInformation) {
  FrictionLog log = awkward_log();
  log.guide_names = {""};
  std::fill(log.guide.begin(), log.guide.end(), 0u);
  log.time_s.back() = std::numeric_limits<double>::quiet_NaN();  // time only when every sample has one
  const std::string text = friction_log_csv(log);
  const std::string header = text.substr(0, text.find('\n'));
  EXPECT_EQ(header,
            "run,velocity_m_s,load_N,preload_um,block_length_mm,temperature_C,friction_N,viscosity40_mm2_s,direction");
}

TEST_F(FrictionLogTest, AlternativeUnitsLoadToTheSameSiValues) {
  const FrictionLog si = awkward_log();
  // The same samples written by hand in kgf, mm/s, mm, m, K, min, cSt.
  std::string text =
      "run,guide,time_min,velocity_mm_s,load_kgf,preload_mm,block_length_m,temperature_K,friction_kgf,"
      "viscosity40_cSt,direction\n";
  for (std::size_t i = 0; i < si.size(); ++i) {
    text += fmt::format("{},{},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{}\n",
                        quoted(si.run_names[si.run[i]]), si.guide_names[si.guide[i]], si.time_s[i] / 60,
                        si.velocity_m_s[i] * 1e3, si.load_N[i] / 9.80665, si.preload_um[i] / 1e3,
                        si.block_length_mm[i] / 1e3, si.temperature_C[i] + 273.15, si.friction_N[i] / 9.80665,
                        si.viscosity40_mm2_s[i], static_cast<int>(si.direction[i]));
  }
  const FrictionLog alt = load_friction_log(write("alternative.csv", text));
  ASSERT_EQ(alt.size(), si.size());
  EXPECT_EQ(alt.run_names, si.run_names);
  const auto near = [](const std::vector<double>& a, const std::vector<double>& b, double abs, const char* what) {
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_NEAR(a[i], b[i], abs + 1e-14 * std::abs(b[i])) << what << "[" << i << "]";
    }
  };
  near(alt.time_s, si.time_s, 0, "time_s");
  near(alt.velocity_m_s, si.velocity_m_s, 0, "velocity_m_s");
  near(alt.load_N, si.load_N, 0, "load_N");
  near(alt.preload_um, si.preload_um, 0, "preload_um");
  near(alt.block_length_mm, si.block_length_mm, 0, "block_length_mm");
  near(alt.temperature_C, si.temperature_C, 1e-12, "temperature_C");  // offset: absolute rounding
  near(alt.friction_N, si.friction_N, 0, "friction_N");
  near(alt.viscosity40_mm2_s, si.viscosity40_mm2_s, 0, "viscosity40_mm2_s");

  const LoadReport& r = alt.reports[0];
  EXPECT_EQ(r.conversions.at("load_kgf"), "kgf -> N");
  EXPECT_EQ(r.conversions.at("velocity_mm_s"), "mm_s -> m_s");
  EXPECT_EQ(r.conversions.at("temperature_K"), "K -> C");
  EXPECT_EQ(r.conversions.at("time_min"), "min -> s");
  EXPECT_EQ(r.conversions.size(), 8u);
}

TEST_F(FrictionLogTest, ExampleUnitsOfTheBrief) {
  // One sample in the units a rig operator would type: 305.9 kgf, 110 mm/s, 299.15 K.
  const FrictionLog log =
      load_friction_log(write("rig.csv",
                              "run,velocity_mm_s,load_kgf,preload_um,block_length_mm,temperature_K,friction_kgf\n"
                              "a,110,305.9,4,120.2,299.15,4.5\n"));
  EXPECT_DOUBLE_EQ(log.velocity_m_s[0], 0.11);
  EXPECT_DOUBLE_EQ(log.load_N[0], 305.9 * 9.80665);
  EXPECT_NEAR(log.temperature_C[0], 26.0, 1e-12);
  EXPECT_DOUBLE_EQ(log.friction_N[0], 4.5 * 9.80665);
}

TEST_F(FrictionLogTest, SeveralFilesShareRunNames) {
  const std::string header = "run,guide,velocity_m_s,load_N,preload_um,block_length_mm,temperature_C,friction_N\n";
  const fs::path a =
      write("a.csv", header + "r1,SRN 35C,0.066,3000,4,120.2,26,28.2\nr2,SRN 35C,0.11,3000,4,120.2,26,44.2\n");
  const fs::path b = write("b.csv", header + "r2,SRG 25C,0.11,3000,4,97,26,40\nr3,SRG 25C,0.083,3000,4,97,26,33\n");
  const FrictionLog log = load_friction_logs({a, b});
  EXPECT_EQ(log.run_names, (std::vector<std::string>{"r1", "r2", "r3"}));
  EXPECT_EQ(log.run, (std::vector<std::uint32_t>{0, 1, 1, 2}));
  EXPECT_EQ(log.guide_names, (std::vector<std::string>{"SRN 35C", "SRG 25C"}));
  EXPECT_EQ(log.guide, (std::vector<std::uint32_t>{0, 0, 1, 1}));
  ASSERT_EQ(log.reports.size(), 2u);
  EXPECT_EQ(log.reports[1].file, b.string());
  EXPECT_EQ(log.reports[1].rows_kept, 2u);
}

TEST_F(FrictionLogTest, TimeMayRepeatAndRunsMayInterleave) {
  const FrictionLog log =
      load_friction_log(write("interleaved.csv",
                              "run,time_s,velocity_m_s,load_N,preload_um,block_length_mm,temperature_C,friction_N\n"
                              "a,10,0.1,3000,4,120.2,26,40\nb,0,0.1,3000,4,120.2,26,40\na,10,0.1,3000,4,120.2,26,40\n"
                              "b,1,0.1,3000,4,120.2,26,40\n"));
  EXPECT_EQ(log.time_s, (std::vector<double>{10, 0, 10, 1}));
}

TEST_F(FrictionLogTest, ErrorInASecondFileNamesThatFile) {
  const std::string header = "run,velocity_m_s,load_N,preload_um,block_length_mm,temperature_C,friction_N\n";
  const fs::path good = write("good.csv", header + "a,0.1,3000,4,120.2,26,40\n");
  const fs::path bad = write("bad.csv", header + "a,0.1,3000,4,120.2,26,40\na,0.1,3000,-4,120.2,26,40\n");
  try {
    load_friction_logs({good, bad});
    FAIL() << "accepted a negative preload";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), bad.string());
    EXPECT_EQ(e.line(), 3);
    EXPECT_EQ(e.column(), 12);
    EXPECT_NE(std::string(e.what()).find("preload_um = -4 is negative; expected >= 0"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lmcal
