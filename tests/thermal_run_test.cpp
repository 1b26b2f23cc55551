// Tests for thermal traces and data-set manifests: missing samples and gaps in the report,
// units, exact round trips of the writers, and a trace long enough to cross the reader's
// chunk boundaries. Refused input is covered by the bad-input corpus (bad_input_test.cpp).
#include "lmcal/io/thermal_run.hpp"

#include "io/csv_reader.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"

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
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

class ThermalRunTest : public test::TempFolderTest {};

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_same_values(const std::vector<double>& a, const std::vector<double>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i) {
    // NaN payloads may differ; "missing" is what must survive.
    const bool same = std::isnan(a[i]) ? std::isnan(b[i]) : same_bits(a[i], b[i]);
    EXPECT_TRUE(same) << what << "[" << i << "]: " << a[i] << " vs " << b[i];
  }
}

void expect_same_channels(const std::vector<TemperatureChannel>& a, const std::vector<TemperatureChannel>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t c = 0; c < a.size(); ++c) {
    EXPECT_EQ(a[c].name, b[c].name);
    expect_same_values(a[c].values, b[c].values, a[c].name);
  }
}

void expect_same_trace(const ThermalTrace& a, const ThermalTrace& b) {
  expect_same_values(a.time_s, b.time_s, "time_s");
  expect_same_channels(a.ambient, b.ambient);
  expect_same_channels(a.rail, b.rail);
}

// Two ambient and two rail channels with awkward numbers, one missing sample each.
ThermalTrace awkward_trace(std::size_t n, double step_s) {
  ThermalTrace trace;
  trace.ambient = {{"ambient1_C", {}}, {"ambient2_C", {}}};
  trace.rail = {{"tc1_C", {}}, {"tc2_C", {}}};
  for (std::size_t i = 0; i < n; ++i) {
    const double x = static_cast<double>(i);
    trace.time_s.push_back(x * step_s + 0.1);
    trace.ambient[0].values.push_back(24 + x / 3);
    trace.ambient[1].values.push_back(i == 1 ? kNaN : 24.1 + 0.1 * x);
    trace.rail[0].values.push_back(i == 2 ? kNaN : 24 + std::sqrt(x));
    trace.rail[1].values.push_back(i == 0 ? -0.0 : 24 - 1.0 / (x + 7));
  }
  return trace;
}

TEST_F(ThermalRunTest, KeepsMissingSamplesAsNaNAndCountsThem) {
  const ThermalTrace trace = load_thermal_trace(kGood / "thermal" / "v066.csv");
  EXPECT_EQ(trace.time_s, (std::vector<double>{0, 5, 10, 15, 20, 35, 40}));
  EXPECT_EQ(trace.line, (std::vector<std::uint32_t>{4, 5, 6, 7, 8, 9, 10}));  // below two comments and the header
  ASSERT_EQ(trace.ambient.size(), 2u);
  ASSERT_EQ(trace.rail.size(), 3u);
  EXPECT_EQ(trace.ambient[1].name, "ambient2_C");
  EXPECT_EQ(trace.rail[2].name, "tc3_C");
  EXPECT_TRUE(std::isnan(trace.ambient[1].values[2]));  // empty cell
  EXPECT_TRUE(std::isnan(trace.rail[0].values[3]));     // "nan"
  EXPECT_EQ(trace.rail[0].values[4], 25.1);
  EXPECT_EQ(trace.rail[2].values.back(), 24.4);

  const LoadReport& r = trace.report;
  EXPECT_EQ(r.rows_read, 7u);
  EXPECT_EQ(r.rows_kept, 7u);
  EXPECT_EQ(r.missing, (std::map<std::string, std::size_t>{{"ambient2_C", 1}, {"tc1_C", 1}}));
  EXPECT_EQ(r.time_gaps, 1u);  // 20 s -> 35 s against a 5 s median step
  EXPECT_TRUE(r.ignored_columns.empty());
  EXPECT_TRUE(r.skipped.empty());
}

TEST_F(ThermalRunTest, ConvertsKelvinAndMinutesAndReadsCrlf) {
  const ThermalTrace trace = load_thermal_trace(kGood / "thermal" / "v110.csv");
  EXPECT_EQ(trace.time_s, (std::vector<double>{0, 30, 60}));
  ASSERT_EQ(trace.ambient.size(), 1u);
  ASSERT_EQ(trace.rail.size(), 1u);
  EXPECT_EQ(trace.ambient[0].name, "ambient_K");  // the header as written
  EXPECT_NEAR(trace.ambient[0].values[0], 24.0, 1e-12);
  EXPECT_NEAR(trace.rail[0].values[2], 25.0, 1e-12);  // last line has no line break
  const LoadReport& r = trace.report;
  EXPECT_EQ(r.ignored_columns, (std::vector<std::string>{"note"}));
  EXPECT_EQ(r.conversions, (std::map<std::string, std::string>{
                               {"ambient_K", "K -> C"}, {"tc1_K", "K -> C"}, {"time_min", "min -> s"}}));
  EXPECT_TRUE(r.missing.empty());  // the empty cell is in the ignored column
}

TEST_F(ThermalRunTest, GapsAreIntervalsLongerThanOneAndAHalfMedianSteps) {
  // Steps 5, 5, 7.5 (exactly 1.5x: not a gap), 5, 7.6 (a gap), 5, 60 (a gap).
  const ThermalTrace trace =
      load_thermal_trace(write("gaps.csv",
                               "time_s,ambient1_C,tc1_C\n0,1,1\n5,1,1\n10,1,1\n17.5,1,1\n22.5,1,1\n30.1,1,1\n35.1,1,1\n"
                               "95.1,1,1\n"));
  EXPECT_EQ(trace.report.time_gaps, 2u);
}

TEST_F(ThermalRunTest, WrittenTraceLoadsBackBitForBit) {
  const ThermalTrace trace = awkward_trace(50, 5.0 / 3.0);
  const std::string text = thermal_trace_csv(trace, {"made by thermal_run_test"});
  EXPECT_EQ(text.substr(0, text.find('\n', text.find('\n') + 1)),
            "# made by thermal_run_test\ntime_s,ambient1_C,ambient2_C,tc1_C,tc2_C");
  const ThermalTrace back = load_thermal_trace(write("trace.csv", text));
  expect_same_trace(trace, back);
  EXPECT_EQ(back.report.missing, (std::map<std::string, std::size_t>{{"ambient2_C", 1}, {"tc1_C", 1}}));
}

// A logger's preamble before the column names: skipped by skip_lines; errors name the file's lines.
TEST_F(ThermalRunTest, APreambleIsSkippedAndErrorsNameTheFilesLines) {
  const ThermalTrace trace = awkward_trace(50, 5.0 / 3.0);
  const std::string text = thermal_trace_csv(trace);
  const std::string preamble = "Data logger TC-08, serial 1234\nstart,2024-05-01 10:00\nchannels: 4\n";
  expect_same_trace(trace, load_thermal_trace(write("preamble.csv", preamble + text), 3));
  EXPECT_THROW(load_thermal_trace(write("preamble.csv", preamble + text)), InputError);  // the preamble is no header
  std::string bad = text;
  bad.insert(bad.find('\n', bad.find('\n') + 1) + 1, "x,1,2,3,4\n");  // the second data row: line 3 of the log
  try {
    load_thermal_trace(write("bad.csv", preamble + bad), 3);
    FAIL() << "accepted a non-numeric time";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 6);
    EXPECT_EQ(e.column(), 1);
  }
}

TEST_F(ThermalRunTest, WriterUsesCanonicalUnits) {
  ThermalTrace trace = load_thermal_trace(kGood / "thermal" / "v110.csv");
  const std::string text = thermal_trace_csv(trace);
  EXPECT_EQ(text.substr(0, text.find('\n')), "time_s,ambient_C,tc1_C");
  const ThermalTrace back = load_thermal_trace(write("canonical.csv", text));
  trace.ambient[0].name = "ambient_C";
  trace.rail[0].name = "tc1_C";
  expect_same_trace(trace, back);
}

TEST_F(ThermalRunTest, LongTraceCrossesChunkBoundariesIntact) {
  // ~7 MB: several of the reader's 1 MiB chunks, plus one line of nearly the longest allowed.
  constexpr std::size_t kRows = 200000;
  std::string text = "# long trace\ntime_s,ambient1_C,tc1_C,tc2_C,note\n";
  for (std::size_t i = 0; i < kRows; ++i) {
    const std::string note = i == 123457 ? std::string(io::kMaxLineBytes - 100, 'x') : "";
    text +=
        fmt::format("{},{},{},{},{}\n", 5 * i, 20 + 0.001 * static_cast<double>(i % 1000),
                    i % 997 == 0 ? "" : fmt::format("{:.3f}", 25 + 1e-3 * static_cast<double>(i % 5000)), -i % 7, note);
  }
  const fs::path file = write("long.csv", text);
  const ThermalTrace trace = load_thermal_trace(file);
  ASSERT_EQ(trace.size(), kRows);
  std::size_t missing = 0;
  for (std::size_t i = 0; i < kRows; ++i) {
    ASSERT_EQ(trace.time_s[i], 5.0 * static_cast<double>(i)) << i;
    ASSERT_EQ(trace.ambient[0].values[i], 20 + 0.001 * static_cast<double>(i % 1000)) << i;
    if (i % 997 == 0) {
      ASSERT_TRUE(std::isnan(trace.rail[0].values[i])) << i;
      ++missing;
    } else {
      ASSERT_EQ(trace.rail[0].values[i], std::stod(fmt::format("{:.3f}", 25 + 1e-3 * static_cast<double>(i % 5000))))
          << i;
    }
  }
  EXPECT_EQ(trace.report.missing.at("tc1_C"), missing);
  EXPECT_EQ(trace.report.time_gaps, 0u);
  EXPECT_EQ(trace.report.bytes, static_cast<double>(text.size()));
  EXPECT_EQ(trace.report.ignored_columns, (std::vector<std::string>{"note"}));
}

TEST_F(ThermalRunTest, NumbersReadExactlyLikeStrtod) {
  // Plain decimals of every length up to 17 digits (the reader has a fast path up to 15),
  // exponents, signs, spaces and leading zeros: each must give the correctly rounded double.
  std::vector<std::string> cells = {"0",
                                    "-0",
                                    "007.50",
                                    "+1.5",
                                    " 2.25 ",
                                    "1e-3",
                                    "-1.5E+2",
                                    ".5",
                                    "5.",
                                    "123456789012345",
                                    "1234567890123456",
                                    "0.000000000000001",
                                    "0.1000000000000000055511151231257827"};
  unsigned state = 1;
  for (int i = 0; i < 3000; ++i) {
    state = state * 1664525u + 1013904223u;
    const double x = (static_cast<double>(state >> 8) / 16777216.0 - 0.3) * std::pow(10.0, i % 6 - 3);
    cells.push_back(fmt::format("{:.{}f}", x, i % 16));
  }
  // Through the reader with a column of no unit and no range (a loader's columns refuse values
  // beyond a rig's, such as 123456789012345 °C).
  std::string text = "x\n";
  for (const std::string& cell : cells) text += cell + "\n";
  csv::Reader reader(write("numbers.csv", text));
  reader.read_header();
  const csv::ColumnSpec spec[] = {{.name = "x"}};
  LoadReport report;
  const std::vector<csv::Column> columns = csv::bind_header(reader, spec, report);
  ASSERT_EQ(columns.size(), 1u);
  for (const std::string& cell : cells) {
    ASSERT_TRUE(reader.next());
    EXPECT_TRUE(same_bits(reader.number(columns[0], false), std::strtod(cell.c_str(), nullptr))) << "'" << cell << "'";
  }
  EXPECT_FALSE(reader.next());
}

TEST_F(ThermalRunTest, ErrorsDeepInALongFileHaveTheRightLine) {
  std::string text = "time_s,ambient1_C,tc1_C\n";
  for (int i = 0; i < 100000; ++i) text += fmt::format("{},24.000,25.000\n", i);
  text += "99999,24,25\n";  // line 100002: time repeats
  try {
    load_thermal_trace(write("late_error.csv", text));
    FAIL() << "accepted a repeated time";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 100002);
    EXPECT_EQ(e.column(), 1);
  }
}

// Limits checked where they are met, at the cell: a run spanning more than kMaxRunSpan_s (three
// records over 10^12 s crashed the solver), and a value that overflows in internal units.
TEST_F(ThermalRunTest, ARunTooLongAndATimeInfiniteInSecondsAreRefusedAtTheirCell) {
  try {
    load_thermal_trace(write("span.csv", "time_s,ambient1_C,tc1_C\n0,24,24\n5e6,24,24.1\n2e7,24,24.2\n"));
    FAIL() << "accepted a run of 2·10^7 s";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 4);
    EXPECT_EQ(e.column(), 1);
    EXPECT_NE(std::string(e.what()).find("at most 1e+07 s"), std::string::npos) << e.what();
  }
  try {
    load_thermal_trace(write("minutes.csv", "time_min,ambient1_C,tc1_C\n0,24,24\n1e307,24,24.1\n"));
    FAIL() << "accepted 1e307 min, infinite in seconds";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(std::string(e.what()).find("finite"), std::string::npos) << e.what();
  }
}

TEST_F(ThermalRunTest, DataSetLoadsUnitsSensorsAndOverrides) {
  const ThermalDataSet set = load_thermal_dataset(kGood / "dataset.toml");
  EXPECT_EQ(set.name, "loader-test");
  EXPECT_EQ(set.description, "two short runs");
  EXPECT_EQ(set.manifest, kGood / "dataset.toml");
  ASSERT_EQ(set.runs.size(), 2u);

  const ThermalRun& a = set.runs[0];
  EXPECT_EQ(a.id, "v066");
  EXPECT_EQ(a.file, kGood / "thermal/v066.csv");
  EXPECT_EQ(a.guide, "SRN 35C");
  EXPECT_DOUBLE_EQ(a.velocity_m_s, 0.066);    // velocity_mm_s = 66
  EXPECT_DOUBLE_EQ(a.load_N, 300 * 9.80665);  // load_kgf = 300
  EXPECT_EQ(a.preload_um, 4.0);
  EXPECT_DOUBLE_EQ(a.rail_length_m, 0.6);  // rail_length_mm = 600
  EXPECT_EQ(a.mean_friction_N, 28.2);
  EXPECT_FALSE(a.contact_length_mm);
  EXPECT_FALSE(a.block_length_mm);
  ASSERT_EQ(a.sensor_position_m.size(), 3u);
  EXPECT_EQ(a.sensor_position_m.at("tc1_C"), 0.0);
  EXPECT_DOUBLE_EQ(a.sensor_position_m.at("tc2_C"), 0.05);
  EXPECT_DOUBLE_EQ(a.sensor_position_m.at("tc3_C"), 0.1);  // given as "tc3"
  EXPECT_EQ(a.guide_overrides, (std::map<std::string, double>{{"conductivity_W_mK", 36.0}}));
  EXPECT_EQ(a.trace.size(), 7u);
  EXPECT_EQ(a.trace.report.time_gaps, 1u);

  const ThermalRun& b = set.runs[1];
  EXPECT_EQ(b.guide, "srn35c");  // as written; the catalog finds it
  EXPECT_EQ(b.velocity_m_s, 0.11);
  EXPECT_EQ(b.contact_length_mm, 82.2);
  EXPECT_EQ(b.block_length_mm, 120.2);
  EXPECT_FALSE(b.preload_um);
  EXPECT_EQ(b.sensor_position_m, (std::map<std::string, double>{{"tc1_K", 0.0}}));
  EXPECT_TRUE(b.guide_overrides.empty());
}

TEST_F(ThermalRunTest, FrictionUncertaintyTakesAnyForceUnit) {
  write("thermal/run.csv", thermal_trace_csv(awkward_trace(5, 5.0)));
  constexpr const char* run = R"(
[[run]]
id = "{}"
file = "thermal/run.csv"
guide = "SRN 35C"
velocity_m_s = 0.11
load_N = 3000
stroke_m = 0.2
rail_length_m = 0.6
{}
[run.sensors_m]
tc1_C = 0.0
tc2_C = 0.05
)";
  const ThermalDataSet set = load_thermal_dataset(
      write("set.toml", fmt::format(run, "kgf",
                                    "mean_friction_kgf = 3\nmean_friction_uncertainty_kgf = 0.1\nstart_friction_kgf = 3.5") +
                            fmt::format(run, "N", "mean_friction_N = 30\nmean_friction_uncertainty_N = 0") +
                            fmt::format(run, "none", "mean_friction_N = 30")));
  ASSERT_EQ(set.runs.size(), 3u);
  EXPECT_DOUBLE_EQ(*set.runs[0].mean_friction_N, 3 * 9.80665);
  EXPECT_DOUBLE_EQ(*set.runs[0].mean_friction_uncertainty_N, 0.1 * 9.80665);
  EXPECT_DOUBLE_EQ(*set.runs[0].start_friction_N, 3.5 * 9.80665);
  EXPECT_FALSE(set.runs[1].start_friction_N);
  EXPECT_EQ(set.runs[1].mean_friction_uncertainty_N, 0.0);  // zero is a statement too
  EXPECT_FALSE(set.runs[2].mean_friction_uncertainty_N);
  const std::string written = thermal_manifest_toml(set, dir_);
  EXPECT_NE(written.find("mean_friction_uncertainty_N = 0.0\n"), std::string::npos) << written;
}

TEST_F(ThermalRunTest, WrittenManifestLoadsBackIdentically) {
  ThermalDataSet set;
  set.name = "round \"trip\"";
  set.description = "two runs\nwritten by thermal_run_test";
  set.manifest = dir_ / "set.toml";
  for (int k = 0; k < 2; ++k) {
    ThermalRun run;
    run.id = fmt::format("run{}", k);
    run.file = dir_ / fmt::format("thermal/run {}.csv", k);
    run.guide = k ? "SRG 45C" : "SRN 35C";
    run.velocity_m_s = 0.1 + 0.2 * k + 1.0 / 3.0;
    run.load_N = 3000.0 * k;
    run.stroke_m = 0.2;
    run.rail_length_m = 0.6 + 0.1 / 3.0;
    if (k == 0) {
      run.preload_um = 2.5;
      run.contact_length_mm = 82.2;
      run.block_length_mm = 120.2;
      run.mean_friction_N = 44.1 + 1e-9;
      run.mean_friction_uncertainty_N = 0.9 / 7;
      run.start_friction_N = 47.3 + 1.0 / 3.0;
      run.guide_overrides = {{"conductivity_W_mK", 36.0}, {"perimeter_m", 0.14 / 3}};
    } else {  // the catalog has no material for SRG 45C, and a run is refused at load without it
      run.guide_overrides = {{"conductivity_W_mK", 40.0}, {"density_kg_m3", 7800.0}, {"specific_heat_J_kgK", 461.0}};
    }
    run.trace = awkward_trace(20 + 10 * k, 5.0);
    run.sensor_position_m = {{"tc1_C", -0.0}, {"tc2_C", -0.05 / 3}};
    write(run.file.lexically_relative(dir_), thermal_trace_csv(run.trace));
    set.runs.push_back(std::move(run));
  }
  const std::string manifest = thermal_manifest_toml(set, dir_);
  EXPECT_NE(manifest.find("file = \"thermal/run 0.csv\""), std::string::npos) << manifest;
  EXPECT_NE(manifest.find("[run.sensors_m]"), std::string::npos) << manifest;
  EXPECT_NE(manifest.find("[run.guide_overrides]"), std::string::npos) << manifest;
  write("set.toml", manifest);

  const ThermalDataSet back = load_thermal_dataset(dir_ / "set.toml");
  EXPECT_EQ(back.name, set.name);
  EXPECT_EQ(back.description, set.description);
  EXPECT_EQ(back.manifest, set.manifest);
  ASSERT_EQ(back.runs.size(), set.runs.size());
  for (std::size_t k = 0; k < set.runs.size(); ++k) {
    const ThermalRun& a = set.runs[k];
    const ThermalRun& b = back.runs[k];
    EXPECT_EQ(b.id, a.id);
    EXPECT_EQ(b.file, a.file);
    EXPECT_EQ(b.guide, a.guide);
    EXPECT_TRUE(same_bits(b.velocity_m_s, a.velocity_m_s));
    EXPECT_TRUE(same_bits(b.load_N, a.load_N));
    EXPECT_EQ(b.preload_um, a.preload_um);
    EXPECT_TRUE(same_bits(b.stroke_m, a.stroke_m));
    EXPECT_TRUE(same_bits(b.rail_length_m, a.rail_length_m));
    EXPECT_EQ(b.contact_length_mm, a.contact_length_mm);
    EXPECT_EQ(b.block_length_mm, a.block_length_mm);
    EXPECT_EQ(b.mean_friction_N, a.mean_friction_N);
    EXPECT_EQ(b.mean_friction_uncertainty_N, a.mean_friction_uncertainty_N);
    EXPECT_EQ(b.start_friction_N, a.start_friction_N);
    EXPECT_EQ(b.sensor_position_m, a.sensor_position_m);
    for (const auto& [name, x] : a.sensor_position_m) {
      EXPECT_TRUE(same_bits(b.sensor_position_m.at(name), x)) << name;  // -0.0 included
    }
    EXPECT_EQ(b.guide_overrides, a.guide_overrides);
    expect_same_trace(a.trace, b.trace);
  }
  // Written again, the loaded set gives the same text.
  EXPECT_EQ(thermal_manifest_toml(back, dir_), manifest);
}


// ---- Runs as rigs produce them: given heat, schedules, ambient_C, h, ν40, user catalogs ----

// A run of the keys given in `extra` (one per line, from line 9 of the manifest), on a CSV
// with or without ambient columns and a heat_rate_W column.
class RigRunTest : public test::TempFolderTest {
 protected:
  void SetUp() override {
    TempFolderTest::SetUp();
    write("thermal/plain.csv", "time_s,ambient1_C,tc1_C\n0,24,24\n60,24.1,24.5\n120,24.2,25\n");
    write("thermal/bare.csv", "time_s,tc1_C\n0,24\n60,24.5\n120,25\n");
    write("thermal/power.csv", "time_min,tc1_C,heat_rate_W\n0,24,5\n1,24.5,5.5\n2,25,0\n");
  }
  ThermalDataSet load(const std::string& extra, const std::string& csv = "plain.csv", const std::string& top = "") {
    return load_thermal_dataset(write("set.toml", manifest(extra, csv, top)));
  }
  static std::string manifest(const std::string& extra, const std::string& csv, const std::string& top) {
    return fmt::format("{}\n[[run]]\nid = \"r\"\nfile = \"thermal/{}\"\nguide = \"SRN 35C\"\nload_N = 3000\n"
                       "stroke_m = 0.2\nrail_length_m = 0.6\n{}\n[run.sensors_m]\ntc1_C = 0.0\n",
                       top, csv, extra);
  }
  // Refused with an InputError at `line` of set.toml whose message holds `what`.
  void expect_refused(const std::string& extra, long line, const std::string& what, const std::string& csv = "plain.csv",
                      const std::string& top = "") {
    try {
      load(extra, csv, top);
      ADD_FAILURE() << "accepted: " << extra;
    } catch (const InputError& e) {
      EXPECT_EQ(fs::path(e.file()).filename(), "set.toml") << e.what();
      EXPECT_EQ(e.line(), line) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  }
};

TEST_F(RigRunTest, GivenHeatAmbientConvectionAndViscosityKeysLoad) {
  const ThermalDataSet set =
      load("heat_rate_W = 8\nheat_rate_uncertainty_W = 0.2\nambient_K = 297.15\nh_W_m2K = 6.5\nviscosity40_mm2_s = 68",
           "bare.csv");
  const ThermalRun& run = set.runs.front();
  EXPECT_EQ(run.heat_rate_W, 8.0);
  EXPECT_EQ(run.heat_rate_uncertainty_W, 0.2);
  EXPECT_NEAR(*run.ambient_C, 24.0, 1e-12);
  EXPECT_EQ(run.h_W_m2K, 6.5);
  EXPECT_EQ(run.viscosity40_mm2_s, 68.0);
  EXPECT_EQ(run.velocity_m_s, 0.0);  // a given heat needs no speed
  EXPECT_TRUE(run.trace.ambient.empty());
  EXPECT_EQ(run.guide_spec.model, "SRN 35C");
  EXPECT_TRUE(set.catalog_file.empty());
}

TEST_F(RigRunTest, ScheduleTakesAnyTimeUnitAndVelocityOrHeat) {
  const ThermalDataSet set = load("mean_friction_N = 40\n[[run.schedule]]\nfrom_s = 0\nvelocity_m_s = 0.11\n"
                                  "[[run.schedule]]\nfrom_min = 1.5\nvelocity_mm_s = 0\n[[run.schedule]]\nfrom_h = 1\n"
                                  "heat_rate_W = 3");
  const auto& phases = set.runs.front().schedule;
  ASSERT_EQ(phases.size(), 3u);
  EXPECT_EQ(phases[0].velocity_m_s, 0.11);
  EXPECT_EQ(phases[1].from_s, 90.0);
  EXPECT_EQ(phases[1].velocity_m_s, 0.0);  // the block stopped
  EXPECT_EQ(phases[2].from_s, 3600.0);
  EXPECT_EQ(phases[2].heat_rate_W, 3.0);
  EXPECT_FALSE(phases[2].velocity_m_s);
}

TEST_F(RigRunTest, HeatRateColumnIsRead) {
  const ThermalDataSet set = load("ambient_C = 24", "power.csv");
  EXPECT_EQ(set.runs.front().trace.heat_rate_W, (std::vector<double>{5, 5.5, 0}));
  EXPECT_EQ(set.runs.front().trace.time_s, (std::vector<double>{0, 60, 120}));
}

TEST_F(RigRunTest, NewKeysRoundTrip) {
  const ThermalDataSet set = load("ambient_C = 23.5\nh_W_m2K = 6\nviscosity40_mm2_s = 68\nheat_rate_uncertainty_W = 0.1\n"
                                  "[[run.schedule]]\nfrom_s = 0\nheat_rate_W = 10\n[[run.schedule]]\nfrom_s = 60\n"
                                  "velocity_m_s = 0.05\n[[run.schedule]]\nfrom_s = 90\nheat_rate_W = 0",
                                  "bare.csv");
  const std::string text = thermal_manifest_toml(set, dir_);
  const ThermalDataSet back = load_thermal_dataset(write("back.toml", text));
  const ThermalRun &a = set.runs.front(), &b = back.runs.front();
  EXPECT_EQ(b.ambient_C, a.ambient_C);
  EXPECT_EQ(b.h_W_m2K, a.h_W_m2K);
  EXPECT_EQ(b.viscosity40_mm2_s, a.viscosity40_mm2_s);
  EXPECT_EQ(b.heat_rate_uncertainty_W, a.heat_rate_uncertainty_W);
  ASSERT_EQ(b.schedule.size(), 3u) << text;
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(b.schedule[i].from_s, a.schedule[i].from_s);
    EXPECT_EQ(b.schedule[i].velocity_m_s, a.schedule[i].velocity_m_s);
    EXPECT_EQ(b.schedule[i].heat_rate_W, a.schedule[i].heat_rate_W);
  }
  // The power column survives the trace writer, and heat_rate_W the manifest writer.
  const ThermalTrace power = load_thermal_dataset(write("p.toml", manifest("ambient_C = 24", "power.csv", ""))).runs[0].trace;
  write("thermal/power2.csv", thermal_trace_csv(power));
  EXPECT_EQ(load_thermal_trace(dir_ / "thermal/power2.csv").heat_rate_W, power.heat_rate_W);
  const ThermalDataSet heater = load("heat_rate_W = 7.5");
  EXPECT_EQ(load_thermal_dataset(write("h.toml", thermal_manifest_toml(heater, dir_))).runs[0].heat_rate_W, 7.5);
}

TEST_F(RigRunTest, RefusesBadSchedulesNamingFileAndLine) {
  const std::string first = "velocity_m_s = 0.1\n[[run.schedule]]\n";  // the first phase's table is at line 10
  expect_refused(first + "from_s = 5\nheat_rate_W = 1", 10, "must start at 0");
  expect_refused(first + "from_s = 0\nheat_rate_W = 1\n[[run.schedule]]\nfrom_s = 0\nheat_rate_W = 2", 13,
                 "not later than");
  expect_refused(first + "from_s = 0\nheat_rate_W = 1\nvelocity_m_s = 0.1", 10, "not both");
  expect_refused(first + "from_s = 0", 10, "found neither");
  expect_refused(first + "from_s = 0\nheat_rate_W = -1", 12, "heat_rate_W = -1");
  expect_refused(first + "heat_rate_W = 1", 10, "without from_s");
  expect_refused(first + "from_s = 0\npower_W = 1", 12, "unknown key 'power_W'");
}

TEST_F(RigRunTest, RefusesConflictingHeatAndMissingAmbient) {
  expect_refused("mean_friction_N = 40\nheat_rate_W = 8", 10, "not both");
  expect_refused("start_friction_N = 40\nheat_rate_W = 8", 10, "start_friction_N");
  expect_refused("heat_rate_W = -2", 9, "heat_rate_W = -2");
  expect_refused("velocity_m_s = 0.1", 2, "no ambient column", "bare.csv");
  expect_refused("velocity_m_s = 0.1\nambient_C = 24", 10, "has ambient columns");
  expect_refused("velocity_m_s = 0.1\nheat_rate_uncertainty_W = 0.1", 10, "without a heat rate");
  expect_refused("ambient_C = 24\nheat_rate_W = 3", 10, "heat_rate_W column", "power.csv");
  expect_refused("preload_um = 4", 2, "missing key 'velocity_m_s'");
}

TEST_F(RigRunTest, UserCatalogFromTheManifestOrTheArgument) {
  write("cat/bars.toml", "[[bar]]\nname = \"steel bar\"\narea_m2 = 4e-4\nperimeter_m = 0.08\nconductivity_W_mK = 45\n"
                         "density_kg_m3 = 7850\nspecific_heat_J_kgK = 470\ncontact_length_mm = 50\n");
  const std::string bar_run = "heat_rate_W = 5";
  std::string text = manifest(bar_run, "plain.csv", "catalog = \"cat/bars.toml\"");
  text.replace(text.find("SRN 35C"), 7, "steel bar");
  const ThermalDataSet set = load_thermal_dataset(write("set.toml", text));
  EXPECT_EQ(set.runs.front().guide_spec.kind, "bar");
  EXPECT_EQ(set.runs.front().guide_spec.conductivity_W_mK, 45.0);
  EXPECT_EQ(set.catalog_file, dir_ / "cat/bars.toml");
  EXPECT_NE(thermal_manifest_toml(set, dir_).find("catalog = \"cat/bars.toml\""), std::string::npos);
  // The argument wins over the manifest's key.
  GuideCatalog other = parse_catalog("[[bar]]\nname = \"steel bar\"\narea_m2 = 4e-4\nperimeter_m = 0.08\n"
                                     "conductivity_W_mK = 20\ndensity_kg_m3 = 7850\nspecific_heat_J_kgK = 470\n"
                                     "contact_length_mm = 50\n",
                                     "cli.toml");
  const ThermalDataSet cli = load_thermal_dataset(dir_ / "set.toml", &other);
  EXPECT_EQ(cli.runs.front().guide_spec.conductivity_W_mK, 20.0);
  EXPECT_EQ(cli.catalog_file, "cli.toml");
}

TEST_F(RigRunTest, RefusesMissingCatalogsAndIncompleteGuidesAtLoad) {
  expect_refused("velocity_m_s = 0.1", 1, "file 'none.toml' not found", "plain.csv", "catalog = \"none.toml\"");
  write("broken.toml", "[[bar]]\nname = \"b\"\ndensity_kg_m3 = \"heavy\"\n");
  try {
    load("velocity_m_s = 0.1", "plain.csv", "catalog = \"broken.toml\"");
    ADD_FAILURE() << "a broken catalog was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(fs::path(e.file()).filename(), "broken.toml") << e.what();  // the catalog's own error
    EXPECT_EQ(e.line(), 3) << e.what();
  }
  // A bar without its perimeter: refused at load, at the run's guide line, with require()'s words.
  write("thin.toml", "[[bar]]\nname = \"thin\"\narea_m2 = 4e-4\nconductivity_W_mK = 45\ndensity_kg_m3 = 7850\n"
                     "specific_heat_J_kgK = 470\ncontact_length_mm = 50\n");
  std::string text = manifest("heat_rate_W = 5", "plain.csv", "catalog = \"thin.toml\"");
  text.replace(text.find("SRN 35C"), 7, "thin");
  try {
    load_thermal_dataset(write("set.toml", text));
    ADD_FAILURE() << "a guide without a perimeter was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(fs::path(e.file()).filename(), "set.toml");
    EXPECT_EQ(e.line(), 5) << e.what();
    EXPECT_NE(std::string(e.what()).find("perimeter_m"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lmcal
