// Coarser time steps for long logs: keep every n-th record (the paper kept every 120th
// 5 s record, i.e. 600 s), or average consecutive blocks of n records.
//
// decimate keeps records 0, n, 2n, …; block_average replaces records [kn, kn + n) by their
// mean (time = mean time; NaN samples are left out of a channel's mean, and a block with
// no valid sample stays NaN); a trailing partial block is averaged as it is.
#pragma once

#include "lmcal/export.hpp"

#include <cstddef>

#include "lmcal/io/friction_log.hpp"
#include "lmcal/io/thermal_run.hpp"

namespace LMCAL_API lmcal {

ThermalTrace decimate(const ThermalTrace& trace, std::size_t every);
ThermalTrace block_average(const ThermalTrace& trace, std::size_t block);

}  // namespace lmcal
