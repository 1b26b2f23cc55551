// A large friction log is read in slices, one per thread, joined in file order: the log, its
// report and every refusal must be those of the file read line by line, on 1 thread or 2.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cmath>
#include <cstring>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "lmcal/error.hpp"
#include "lmcal/io/csv_writer.hpp"
#include "lmcal/io/friction_log.hpp"
#include "parallel_slices.hpp"
#include "support/temp_folder.hpp"

namespace lmcal {
namespace {

class CsvSlices : public test::TempFolderTest {
 protected:
  // The log read on `threads` threads, or what it was refused with ("file:line:column: ...").
  struct Read {
    std::optional<FrictionLog> log;
    std::string error;
  };
  static Read read_on(int threads, const std::filesystem::path& file) {
    const int before = detail::limit_slice_threads(threads);
    Read read;
    try {
      read.log = load_friction_log(file);
    } catch (const InputError& e) {
      read.error = e.what();
    }
    detail::limit_slice_threads(before);
    return read;
  }

  // `file` refused with `message` on 1 thread, and identically on 2.
  static void expect_refused_alike(const std::filesystem::path& file, const std::string& message) {
    const Read one = read_on(1, file), two = read_on(2, file);
    EXPECT_FALSE(two.log);
    EXPECT_NE(one.error.find(message), std::string::npos) << one.error;
    EXPECT_EQ(one.error, two.error);
  }

  // A tidy log of `rows` rows (about 70 bytes each): runs that come back later in the file, a
  // run first named in its second half, comments, blank lines, CRLF line ends, missing friction
  // values and negative ones backwards; `edit(row, line)` may change any row.
  std::filesystem::path log_file(int rows, const std::function<void(int, std::string&)>& edit = {}) const {
    std::string text = "# a rig's log\r\nrun,guide,time_s,velocity_m_s,load_kgf,preload_um,block_length_mm,temperature_C,"
                       "friction_N,direction\r\n";
    for (int i = 0; i < rows; ++i) {
      const int run = i < rows / 2 ? (i / 1000) % 3 : 3 + (i / 700) % 4;  // runs 3..6 only in the second half
      std::string line = fmt::format("\"r{}\",SRN {}C,{:.3f},{:.4g},{},4,120.2,{:.3f},{},{}", run, 35 + run % 2,
                                     i * 0.01, 0.01 + 0.001 * (i % 97), 300 + run, 26 + 1e-4 * i,
                                     i % 501 == 0 ? std::string("nan") : fmt::format("{:.3f}", 28 + 0.01 * (i % 89)),
                                     (i / 250) % 2 ? -1 : 1);
      if (i % 333 == 0) line = "# a comment\r\n\r\n" + line;
      if (edit) edit(i, line);
      text += line + "\r\n";
    }
    return write("log.csv", text);
  }
};

template <typename T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

void expect_same(const FrictionLog& a, const FrictionLog& b) {
  EXPECT_EQ(a.run_names, b.run_names);
  EXPECT_EQ(a.guide_names, b.guide_names);
  EXPECT_TRUE(same_bits(a.run, b.run));
  EXPECT_TRUE(same_bits(a.guide, b.guide));
  EXPECT_TRUE(same_bits(a.line, b.line));
  EXPECT_TRUE(same_bits(a.direction, b.direction));
  for (auto column : {&FrictionLog::time_s, &FrictionLog::velocity_m_s, &FrictionLog::load_N, &FrictionLog::preload_um,
                      &FrictionLog::block_length_mm, &FrictionLog::temperature_C, &FrictionLog::friction_N,
                      &FrictionLog::viscosity40_mm2_s, &FrictionLog::acceleration_m_s2, &FrictionLog::position_m,
                      &FrictionLog::distance_since_reversal_m, &FrictionLog::time_since_reversal_s})
    EXPECT_TRUE(same_bits(a.*column, b.*column));
  ASSERT_EQ(a.reports.size(), b.reports.size());
  for (std::size_t i = 0; i < a.reports.size(); ++i) {
    const LoadReport &x = a.reports[i], &y = b.reports[i];
    EXPECT_EQ(x.rows_read, y.rows_read);
    EXPECT_EQ(x.rows_kept, y.rows_kept);
    EXPECT_EQ(x.bytes, y.bytes);
    EXPECT_EQ(x.skipped, y.skipped);
    EXPECT_EQ(x.conversions, y.conversions);
    EXPECT_EQ(x.notes, y.notes);
    EXPECT_EQ(x.warnings, y.warnings);
  }
}

TEST_F(CsvSlices, TwoThreadsReadTheLogOneThreadReads) {
  const auto file = log_file(150'000);
  const Read one = read_on(1, file), two = read_on(2, file);
  ASSERT_TRUE(one.log && two.log) << one.error << two.error;
  EXPECT_EQ(one.log->run_names.size(), 7u);
  EXPECT_EQ(one.log->reports.at(0).skipped.size(), 1u) << "the missing friction values";
  expect_same(*one.log, *two.log);
}

TEST_F(CsvSlices, AFileWithoutARunColumnIsOneRunNamedOnce) {
  std::string text = "velocity_m_s,friction_N\n";
  for (int i = 0; i < 700'000; ++i) text += fmt::format("{:.4f},{:.3f}\n", 0.01 + 1e-7 * i, 20 + 1e-5 * i);
  const auto file = write("plain.csv", text);
  const Read one = read_on(1, file), two = read_on(2, file);
  ASSERT_TRUE(one.log && two.log) << one.error << two.error;
  EXPECT_EQ(two.log->run_names, std::vector<std::string>{"plain"});
  expect_same(*one.log, *two.log);
}

TEST_F(CsvSlices, ABadCellLateInTheFileIsRefusedWhereItIs) {
  const auto file = log_file(150'000, [](int i, std::string& line) {
    if (i == 140'000) line.replace(line.find(",4,"), 3, ",4x,");
  });
  expect_refused_alike(file, "expected a number, found '4x'");
}

TEST_F(CsvSlices, ARunsTimeGoingBackAcrossSlicesIsRefusedWhereItIs) {
  // r0 holds rows early in the file; in the second half it comes back at an earlier time.
  const auto file = log_file(150'000, [](int i, std::string& line) {
    if (i == 120'000) line = "r0,SRN 35C,5.000,0.05,300,4,120.2,26,28,1";
  });
  expect_refused_alike(file, "is earlier than the previous sample of run 'r0'");
}

TEST_F(CsvSlices, ATooLongLineIsRefusedAsLineByLine) {
  const auto file = log_file(150'000, [](int i, std::string& line) {
    if (i == 100'000) line += std::string(std::size_t{2} << 20, ' ');
  });
  expect_refused_alike(file, "line longer than");
}

// Written in slices on 2 threads, a CSV's text is the text written row by row: numbers that
// repeat down a column (the writer reuses their text), numbers that change, text that needs
// quotes or a formula's apostrophe, empty cells; on 1 thread, and on 2 with a slice boundary
// inside a stretch of repeats.
TEST(CsvTextSlices, TwoThreadsWriteTheTextOneRowAtATimeWrites) {
  const std::vector<std::string> header{"run", "speed_m_s", "force_N", "note"};
  constexpr std::size_t kRows = 70'001;
  const auto row = [](CsvText& csv, std::size_t i) {
    csv.cell(fmt::format("run {}", i / 5000)).cell(0.001 * static_cast<double>(i / 700));
    csv.cell(i % 3 == 0 ? std::nan("") : 1.0 / static_cast<double>(i + 1));
    csv.cell(i % 4 == 0 ? "" : i % 4 == 1 ? "a, \"quoted\" note" : i % 4 == 2 ? "=1+1" : "plain").end_row();
  };
  CsvText serial(header);
  for (std::size_t i = 0; i < kRows; ++i) row(serial, i);
  for (const int threads : {1, 2}) {
    SCOPED_TRACE(threads);
    const int before = detail::limit_slice_threads(threads);
    const std::string text = csv_text(header, kRows, row);
    detail::limit_slice_threads(before);
    EXPECT_EQ(text.size(), serial.str().size());
    EXPECT_TRUE(text == serial.str());
  }
  EXPECT_EQ(csv_text(header, 0, row), "run,speed_m_s,force_N,note\n") << "no rows: the header alone";
}

// A text cell is written so that a spreadsheet and lmcal's reader both read back what was
// meant: quotes inside doubled, a formula's first character behind an apostrophe.
TEST(CsvTextCells, QuotesAndFormulasAreEscapedAsWritten) {
  CsvText csv({"note"});
  for (const char* text : {"plain", "a, \"quoted\" note", "=1+1", "'=x", "#comment", " padded", "\"", ""}) csv.cell(text).end_row();
  EXPECT_EQ(csv.str(), "note\nplain\n\"a, \"\"quoted\"\" note\"\n'=1+1\n''=x\n\"#comment\"\n\" padded\"\n\"\"\"\"\n\n");
}

}  // namespace
}  // namespace lmcal
