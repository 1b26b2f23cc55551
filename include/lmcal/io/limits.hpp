// The sizes every input is checked against before it can exhaust memory or time
// (docs/formats.md#limits). Each is refused up front with the file, line and column.
#pragma once

#include <cstddef>
#include <cstdint>

namespace lmcal::io {

// A CSV log or trace: 4 GiB, about 10^8 rows of a friction log (several files through a
// manifest hold more).
inline constexpr std::uintmax_t kMaxCsvBytes = std::uintmax_t{4} << 30;
// A manifest, catalog, fit JSON, model file or fleet list: 64 MiB.
inline constexpr std::uintmax_t kMaxTextBytes = std::uintmax_t{64} << 20;
// One line of a CSV file: 1 MiB (a header of 1000 columns takes some 10 kB).
inline constexpr std::size_t kMaxLineBytes = std::size_t{1} << 20;
// Columns of a CSV header.
inline constexpr std::size_t kMaxColumns = 1000;
// Data rows of one CSV file: 5·10^7 (4.5 GB loaded, at 90 bytes a friction sample).
inline constexpr std::size_t kMaxRows = 50'000'000;
// Runs of one data set (friction or thermal), and guides of a friction log.
inline constexpr std::size_t kMaxRuns = 1000;

}  // namespace lmcal::io
