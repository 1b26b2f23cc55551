// Process-wide settings for a program that runs lmcal's jobs and exits: the lmcal command and
// the benchmarks (which time lmcal's functions as the command runs them). Not for a library's
// host, such as Python: its memory policy is its own.
//
// Example: int main() { lmcal::keep_freed_memory(); … }
#pragma once

#include "lmcal/export.hpp"

namespace LMCAL_API lmcal {

// Keeps the memory the process frees for its next allocations instead of returning it to the
// system: with glibc's malloc, every block comes from the heap (none is mapped on its own, the
// default for blocks over 32 MB) and the heap is not trimmed.
// A fit allocates and frees its Jacobian, its residuals and its score series, a diagnosis does
// so for dozens of fits, and every page new to the process costs a fault (slow on a virtual
// machine): a 10⁵-sample friction fit took 100 ms, 80 ms so. The resident memory then stays at
// its peak until the process exits. The heap's first 512 MB, and the first 48 MB of each
// worker thread's own heap, are also marked for transparent huge pages (where the system grants
// them on request, Debian's default): one fault per 2 MB instead of 512. With the rest of
// session 27's changes, a 10⁵-sample `lmcal fit friction` went from 0.34-0.38 s to 0.19-0.24 s
// on a 2-core VM, its faults from 9,450 to 1,150.
// False where the settings are not available (not glibc).
bool keep_freed_memory();

}  // namespace lmcal
