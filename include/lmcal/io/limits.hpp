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
// Guides and bars of a user catalog: 10^5 (27 MB of TOML; a maker's whole range is some
// thousands).
inline constexpr std::size_t kMaxCatalogEntries = 100'000;
// Samples of a raw log's velocity filter (velocity_window): 10^4, 10 s at 1 kHz; the filter
// costs samples × window.
inline constexpr std::size_t kMaxVelocityWindow = 10'001;
// and a run's samples × velocity_window: 2·10^10, some 20 s of filtering (10^7 samples, hours at
// 1 kHz, take a window of 2001).
inline constexpr double kMaxFilterWork = 2e10;

// The fits' and the prediction's repetitions (--starts, --bootstrap, --samples), each at
// least 100 times its default:
// multi-start local searches of a friction fit (--starts), each a whole local fit;
inline constexpr int kMaxStarts = 1000;
// cluster-bootstrap replicates (--bootstrap), each an m × m solve (10^5: a second or so);
inline constexpr std::size_t kMaxBootstrapReplicates = 100'000;
// parameter draws of a prediction's band (--samples of predict), each the whole duty simulated.
inline constexpr std::size_t kMaxPredictionSamples = 100'000;
// Segments of the half rail in the rail model (--segments of a fit, calibrate, predict): 10^4,
// 30 µm cells on a 0.6 m rail; every time step of every run and draw costs them all.
inline constexpr int kMaxRailSegments = 10'000;
// The rail model's own bound (simulate, a steady solution, a convergence study): 10^5, a profile
// of 2·10^5 nodes is 1.6 MB.
inline constexpr int kMaxRailModelSegments = 100'000;

// A duty cycle (lmcal predict), checked before the repeats are laid out:
// segments after the repeats (each one simulation per draw, some 70 µs);
inline constexpr std::size_t kMaxDutySegments = 100'000;
// output times (duration / output_every_s);
inline constexpr std::size_t kMaxDutyOutputs = 1'000'000;
// temperature positions (positions_m), and the scale's positions_m, each;
inline constexpr std::size_t kMaxDutyPositions = 1000;
// points of an ambient_trace (each segment reads it whole).
inline constexpr std::size_t kMaxAmbientTracePoints = 1'000'000;
// A prediction's estimate (check_prediction_size in prediction.hpp), from the duty and the
// options: memory, all the draws' outputs held together (4 GiB); and time on one core
// (3 hours, at the 2.5 ns per rail segment and time step and 70 µs per segment measured on
// the test machine).
inline constexpr std::uintmax_t kMaxPredictionBytes = std::uintmax_t{4} << 30;
inline constexpr double kMaxPredictionCpu_s = 3 * 3600.0;

}  // namespace lmcal::io
