// io::parse_iso_date: "YYYY-MM-DD" to days since 1970-01-01, real days only.
#include "lmcal/io/date.hpp"

#include <gtest/gtest.h>

namespace lmcal::io {
namespace {

TEST(IsoDate, OnlyRealDaysParse) {
  EXPECT_EQ(parse_iso_date("1970-01-02"), 1);
  EXPECT_EQ(parse_iso_date("2024-02-29"), parse_iso_date("2024-02-28").value() + 1);
  EXPECT_FALSE(parse_iso_date("2023-02-29"));
  EXPECT_FALSE(parse_iso_date("2026-9-01"));
  EXPECT_FALSE(parse_iso_date("2026-09-01x"));
}

}  // namespace
}  // namespace lmcal::io
