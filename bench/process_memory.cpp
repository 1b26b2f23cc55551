// The benchmarks time lmcal's functions in the memory setting the lmcal command runs them in
// (apps/main.cpp): freed memory kept for the next allocations (lmcal/process.hpp).
#include "lmcal/process.hpp"

namespace {
const bool kKept = lmcal::keep_freed_memory();
}
