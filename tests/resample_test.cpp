// Tests for coarser time steps: decimation keeps records 0, n, 2n, ...; block averages
// leave NaN samples out and average a trailing partial block as it is.
#include "lmcal/io/resample.hpp"

#include "lmcal/error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace lmcal {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Records i = 0..n-1 at t = 5 i s; ambient 20 + i, tc1 = 100 + 10 i, tc2 = the values given.
ThermalTrace trace_of(std::size_t n, std::vector<double> tc2 = {}) {
  ThermalTrace trace;
  trace.ambient = {{"ambient1_C", {}}};
  trace.rail = {{"tc1_C", {}}, {"tc2_C", std::move(tc2)}};
  for (std::size_t i = 0; i < n; ++i) {
    const double x = static_cast<double>(i);
    trace.time_s.push_back(5 * x);
    trace.ambient[0].values.push_back(20 + x);
    trace.rail[0].values.push_back(100 + 10 * x);
    if (trace.rail[1].values.size() < n) trace.rail[1].values.push_back(x);
  }
  trace.report.file = "made.csv";
  return trace;
}

TEST(Resample, DecimateKeepsRecordsZeroNTwoN) {
  const ThermalTrace out = decimate(trace_of(10), 3);
  EXPECT_EQ(out.time_s, (std::vector<double>{0, 15, 30, 45}));  // records 0, 3, 6, 9
  EXPECT_EQ(out.ambient[0].values, (std::vector<double>{20, 23, 26, 29}));
  EXPECT_EQ(out.rail[0].values, (std::vector<double>{100, 130, 160, 190}));
  EXPECT_EQ(out.rail[1].name, "tc2_C");
  EXPECT_EQ(out.report.file, "made.csv");
}

TEST(Resample, DecimateLikeThePaper) {
  // ~6 h of 5 s records, every 120th kept: 600 s spacing.
  const ThermalTrace out = decimate(trace_of(4320), 120);
  ASSERT_EQ(out.size(), 36u);
  for (std::size_t k = 0; k < out.size(); ++k) EXPECT_EQ(out.time_s[k], 600.0 * static_cast<double>(k));
}

TEST(Resample, DecimateByOneOrMoreThanTheLength) {
  const ThermalTrace in = trace_of(5);
  EXPECT_EQ(decimate(in, 1).time_s, in.time_s);
  EXPECT_EQ(decimate(in, 100).time_s, (std::vector<double>{0}));
  EXPECT_EQ(decimate(trace_of(0), 4).size(), 0u);
}

TEST(Resample, BlockAverageWithPartialTrailingBlock) {
  // Blocks [0,4), [4,8), [8,10).
  const ThermalTrace out = block_average(trace_of(10), 4);
  EXPECT_EQ(out.time_s, (std::vector<double>{7.5, 27.5, 42.5}));
  EXPECT_EQ(out.ambient[0].values, (std::vector<double>{21.5, 25.5, 28.5}));
  EXPECT_EQ(out.rail[0].values, (std::vector<double>{115, 155, 185}));
}

TEST(Resample, BlockAverageLeavesNaNOut) {
  // tc2: block 0 has one NaN, block 1 is all NaN, the partial block 2 has one valid sample.
  const ThermalTrace out = block_average(trace_of(8, {1, kNaN, 3, kNaN, kNaN, kNaN, kNaN, 7}), 3);
  ASSERT_EQ(out.rail[1].values.size(), 3u);
  EXPECT_EQ(out.rail[1].values[0], 2.0);  // (1 + 3) / 2, not / 3
  EXPECT_TRUE(std::isnan(out.rail[1].values[1]));
  EXPECT_EQ(out.rail[1].values[2], 7.0);
  EXPECT_EQ(out.rail[0].values, (std::vector<double>{110, 140, 165}));  // other channels unaffected
  EXPECT_EQ(out.time_s, (std::vector<double>{5, 20, 32.5}));
}

TEST(Resample, ZeroStepIsAnInvalidParameter) {
  EXPECT_THROW(decimate(trace_of(3), 0), InvalidParameter);
  EXPECT_THROW(block_average(trace_of(3), 0), InvalidParameter);
}

}  // namespace
}  // namespace lmcal
