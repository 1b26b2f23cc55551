// The limits every input is checked against before it can exhaust memory (issue 21 #5, issue
// 23 #6), and the names that could not reach an output intact (issue 23 #5, #10): each is a
// file that loads or is refused, with the file, line, column and the reason.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "io/csv_reader.hpp"
#include "io/input_file.hpp"
#include "lmcal/error.hpp"
#include "lmcal/fit/model_file.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/io/limits.hpp"
#include "lmcal/io/thermal_run.hpp"
#include "support/temp_folder.hpp"

namespace lmcal {
namespace {

namespace fs = std::filesystem;

class InputLimits : public test::TempFolderTest {
 protected:
  // The message of the InputError `load` throws ("" when it throws none).
  template <typename Load>
  static std::string refusal(Load load) {
    try {
      load();
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }

  // A file of `bytes` bytes that takes no disk space.
  fs::path sparse(const std::string& name, std::uintmax_t bytes) const {
    const fs::path path = write(name, "");
    fs::resize_file(path, bytes);
    return path;
  }
};

constexpr const char* kFrictionHeader = "run,velocity_m_s,load_N,preload_um,block_length_mm,temperature_C,friction_N\n";
constexpr const char* kFrictionRow = "r1,0.066,3000,4,120.2,26,28.2\n";

std::string thermal_manifest(const std::string& run_id, const std::string& file) {
  return fmt::format(
      "[[run]]\nid = \"{}\"\nfile = \"{}\"\nguide = \"SRN 35C\"\nvelocity_m_s = 0.066\nload_N = 3000\n"
      "stroke_m = 0.2\nrail_length_m = 0.6\nmean_friction_N = 28\n[run.sensors_m]\ntc1_C = 0\n",
      run_id, file);
}

TEST_F(InputLimits, DevicesPipesAndFoldersAreRefusedBeforeAByteIsRead) {
  // /dev/zero grew memory until bad_alloc; a pipe would block.
  EXPECT_NE(refusal([] { load_friction_log("/dev/zero"); }).find("/dev/zero: cannot open file: this is a device"),
            std::string::npos);
  const fs::path link = dir_ / "zero.csv";
  fs::create_symlink("/dev/zero", link);
  EXPECT_NE(refusal([&] { load_friction_log(link); }).find("this is a device; expected a regular file"), std::string::npos);
  const fs::path fifo = dir_ / "pipe.csv";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(refusal([&] { load_thermal_trace(fifo); }).find("this is a pipe"), std::string::npos);
  EXPECT_NE(refusal([&] { load_catalog(fifo); }).find("cannot open catalog file: this is a pipe"), std::string::npos);
  EXPECT_NE(refusal([&] { load_thermal_dataset(dir_); }).find("cannot open manifest file: this is a folder, not a file"),
            std::string::npos);
}

TEST_F(InputLimits, AManifestNamingAFolderOrAPipeSaysSoAtItsLine) {
  // Both were reported as "not found".
  fs::create_directories(dir_ / "thermal" / "v066");
  const fs::path folder = write("folder.toml", thermal_manifest("v066", "thermal/v066"));
  EXPECT_NE(refusal([&] { load_thermal_dataset(folder); }).find("folder.toml:3:8: file 'thermal/v066': this is a folder"),
            std::string::npos);
  ASSERT_EQ(::mkfifo((dir_ / "pipe.csv").c_str(), 0600), 0);
  const fs::path pipe = write("pipe.toml", thermal_manifest("v066", "pipe.csv"));
  EXPECT_NE(refusal([&] { load_thermal_dataset(pipe); }).find("pipe.toml:3:8: file 'pipe.csv': this is a pipe"),
            std::string::npos);
}

TEST_F(InputLimits, FilesLargerThanTheLimitAreRefusedFromTheirSize) {
  const fs::path csv = sparse("huge.csv", io::kMaxCsvBytes + 1);
  EXPECT_NE(refusal([&] { load_friction_log(csv); }).find("huge.csv: file is 4294967297 bytes; the limit is 4 GiB"),
            std::string::npos);
  const fs::path toml = sparse("huge.toml", io::kMaxTextBytes + 1);
  EXPECT_NE(refusal([&] { load_catalog(toml); }).find("catalog file is 67108865 bytes; the limit is 64 MiB"),
            std::string::npos);
  EXPECT_NE(refusal([&] { read_model_file(toml); }).find("the limit is 64 MiB"), std::string::npos);
  // At the limit a text file is read (and then parsed as what it is).
  const fs::path small = write("small.toml", "[[guide]]\nmodel = 3\n");
  EXPECT_EQ(refusal([&] { load_catalog(small); }).find("limit"), std::string::npos);
}

TEST_F(InputLimits, ALineLongerThanTheLimitIsRefusedAtItsLineWithoutGrowingMemory) {
  std::string text = kFrictionHeader;
  text += kFrictionRow;
  text += std::string(io::kMaxLineBytes + 10, '7') + "\n";
  const fs::path file = write("long_line.csv", text);
  EXPECT_NE(refusal([&] { load_friction_log(file); }).find("long_line.csv:3:1: line longer than 1 MiB"), std::string::npos);
  // A file without any line break (a binary blob) the same, at line 1.
  const fs::path blob = write("blob.csv", std::string(3 * io::kMaxLineBytes, '\0'));
  EXPECT_NE(refusal([&] { load_thermal_trace(blob); }).find("blob.csv:1:1: line longer than 1 MiB"), std::string::npos);
}

TEST_F(InputLimits, AHeaderOfMoreColumnsThanTheLimitIsRefusedAtTheFirstColumnTooMany) {
  std::string header = "time_s";
  for (std::size_t i = 1; i <= io::kMaxColumns; ++i) header += fmt::format(",tc{}_C", i);
  const fs::path file = write("wide.csv", header + "\n");
  const std::string message = refusal([&] { load_thermal_trace(file); });
  EXPECT_NE(message.find(fmt::format("wide.csv:1:{}: 1001 columns; at most 1000", header.rfind(',') + 2)), std::string::npos)
      << message;
}

TEST_F(InputLimits, MoreRunsThanTheLimitAreRefusedAtTheFirstRunTooMany) {
  std::string text = kFrictionHeader;
  for (std::size_t i = 0; i <= io::kMaxRuns; ++i) text += fmt::format("r{},0.066,3000,4,120.2,26,28.2\n", i);
  const fs::path file = write("runs.csv", text);
  EXPECT_NE(refusal([&] { load_friction_log(file); }).find(fmt::format("runs.csv:{}:1: more than 1000 runs", io::kMaxRuns + 2)),
            std::string::npos);
  // 1000 runs load.
  text.resize(text.rfind("r1000,"));
  EXPECT_EQ(load_friction_log(write("runs_1000.csv", text)).run_names.size(), io::kMaxRuns);

  std::string manifest;
  for (std::size_t i = 0; i <= io::kMaxRuns; ++i) manifest += thermal_manifest(fmt::format("r{}", i), "none.csv");
  const fs::path toml = write("runs.toml", manifest);
  const std::string message = refusal([&] { load_thermal_dataset(toml); });
  EXPECT_NE(message.find(fmt::format("runs.toml:{}:1: more than 1000 [[run]] tables", 11 * io::kMaxRuns + 1)),
            std::string::npos)
      << message;
}

TEST_F(InputLimits, MoreDataRowsThanTheLimitAreRefusedAtTheFirstRowTooMany) {
  // 5·10^7 one-cell rows (100 MB), read through the reader alone.
  const fs::path file = dir_ / "rows.csv";
  {
    std::ofstream out(file, std::ios::binary);
    out << "time_s\n";
    std::string rows;
    for (int i = 0; i < 1'000'000; ++i) rows += "1\n";
    for (std::size_t i = 0; i < io::kMaxRows / 1'000'000; ++i) out << rows;
    out << "2\n";
  }
  csv::Reader reader(file);
  reader.read_header();
  std::size_t rows = 0;
  const std::string message = refusal([&] {
    while (reader.next()) ++rows;
  });
  EXPECT_EQ(rows, io::kMaxRows);
  EXPECT_NE(message.find(fmt::format("rows.csv:{}:1: more than {} data rows", io::kMaxRows + 2, io::kMaxRows)),
            std::string::npos)
      << message;
}

TEST_F(InputLimits, TheRowEstimateCountsDataLinesNotBlankOnes) {
  // 5 MB of blank lines around one row reserved some 3.6 GB.
  std::string text = kFrictionHeader;
  text += std::string(5'000'000, '\n');
  text += kFrictionRow;
  text += std::string(5'000'000, '\n');
  csv::Reader reader(write("blank.csv", text));
  reader.read_header();
  EXPECT_LT(reader.estimated_rows(), 100u);
  EXPECT_EQ(load_friction_log(dir_ / "blank.csv").size(), 1u);
}

TEST_F(InputLimits, LinesEndingInABareCarriageReturnLoadLikeAnyOther) {
  // Was "no data rows".
  std::string lf = std::string(kFrictionHeader) + kFrictionRow + "r2,0.11,3000,4,120.2,26,44.2\n";
  std::string cr = lf;
  std::replace(cr.begin(), cr.end(), '\n', '\r');
  const FrictionLog a = load_friction_log(write("lf.csv", lf));
  const FrictionLog b = load_friction_log(write("cr.csv", cr));
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b.friction_N, a.friction_N);
  EXPECT_EQ(b.run_names, a.run_names);
  EXPECT_EQ(b.line, a.line);
}

TEST_F(InputLimits, NamesThatCouldNotReachAnOutputIntactAreRefusedAtTheirCell) {
  const std::string header = kFrictionHeader;
  // Latin-1 ran the whole computation, then failed writing JSON; escapes reached terminals.
  EXPECT_NE(refusal([&] { load_friction_log(write("a.csv", header + "r\xE9,0.066,3000,4,120.2,26,28.2\n")); })
                .find("a.csv:2:1: run name: byte 0xE9 at character 2 is not UTF-8"),
            std::string::npos);
  EXPECT_NE(refusal([&] { load_friction_log(write("b.csv", header + "r1,0.066,3000,4,120.2,26,28.2\nx\x1B[2J,0.1,1,1,1,1,1\n")); })
                .find("b.csv:3:1: run name: control character U+001B at character 2"),
            std::string::npos);
  EXPECT_NE(refusal([&] { load_friction_log(write("c.csv", "guide," + header + "a\xE2\x80\xAE" "b," + kFrictionRow)); })
                .find("c.csv:2:1: guide name: bidirectional control U+202E at character 2"),
            std::string::npos);
  EXPECT_NE(refusal([&] { load_friction_log(write("d.csv", "op\xE9rateur," + header)); })
                .find("d.csv:1:1: column name: byte 0xE9 at character 3"),
            std::string::npos);
  // In a manifest: toml++ checks the encoding; lmcal the characters.
  EXPECT_NE(refusal([&] { load_thermal_dataset(write("e.toml", thermal_manifest("\\u0001<img src=x onerror=alert(1)>", "v.csv"))); })
                .find("e.toml:2:6: id: control character U+0001 at character 1"),
            std::string::npos);
  EXPECT_NE(refusal([&] { load_thermal_dataset(write("f.toml", thermal_manifest("r\xE9", "v.csv"))); }).find("f.toml:2:"),
            std::string::npos);
  // A file name: the message shows it printably.
  const fs::path latin = write("r\xE9.csv", header + kFrictionRow);
  EXPECT_NE(refusal([&] { load_friction_log(latin); }).find("r\\xE9.csv: file name: byte 0xE9 at character"),
            std::string::npos);
  // A description is free text: line breaks are fine there.
  EXPECT_EQ(io::name_problem("two\nlines", true), std::nullopt);
  EXPECT_NE(io::name_problem("two\nlines"), std::nullopt);
  EXPECT_EQ(io::name_problem("Überlast 35 °C, ½ Hub"), std::nullopt);
  EXPECT_NE(io::name_problem("\xC0\xAF"), std::nullopt);  // an overlong '/'
  EXPECT_NE(io::name_problem("\xED\xA0\x80"), std::nullopt);  // a surrogate
  EXPECT_EQ(io::printable("a\x1B[31m\xFF\xE2\x80\xAE"), "a\\u001B[31m\\xFF\\u202E");
}

}  // namespace
}  // namespace lmcal
