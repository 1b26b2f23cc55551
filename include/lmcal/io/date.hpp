// Calendar dates as the inputs write them: "YYYY-MM-DD" (ISO 8601), e.g. a fleet set's date
// (fleet.toml, a folder named 2026-09-01) or a virtual fleet's first day.
//
// Example:
//   lmcal::io::parse_iso_date("1970-01-02");  // 1 (days since 1970-01-01)
//   lmcal::io::parse_iso_date("2023-02-29");  // nullopt: no such day
//
// Trap: exactly ten characters with two-digit month and day ("2026-9-01" is refused), and no
// time or zone after the day.
#pragma once

#include <chrono>
#include <cstddef>
#include <optional>
#include <string_view>

namespace lmcal::io {

// Days since 1970-01-01 of a "YYYY-MM-DD" date; nullopt for another text or a day that does not exist.
inline std::optional<int> parse_iso_date(std::string_view text) {
  if (text.size() != 10 || text[4] != '-' || text[7] != '-') return std::nullopt;
  int parts[3] = {0, 0, 0};
  std::size_t at = 0;
  for (int p = 0; p < 3; ++p, ++at) {
    const std::size_t width = p == 0 ? 4 : 2;
    for (std::size_t i = 0; i < width; ++i, ++at) {
      if (text[at] < '0' || text[at] > '9') return std::nullopt;
      parts[p] = parts[p] * 10 + (text[at] - '0');
    }
  }
  const std::chrono::year_month_day day{std::chrono::year(parts[0]), std::chrono::month(static_cast<unsigned>(parts[1])),
                                        std::chrono::day(static_cast<unsigned>(parts[2]))};
  if (!day.ok()) return std::nullopt;
  return static_cast<int>(std::chrono::sys_days(day).time_since_epoch().count());
}

}  // namespace lmcal::io
