// The memory setting of lmcal::keep_freed_memory (lmcal/process.hpp) for threads that start
// later: the pool's workers (parallel_slices.cc).
#pragma once

namespace lmcal::detail {

// Once keep_freed_memory() has been called: the calling thread's own heap (glibc gives each
// new thread an arena of its own) marked for transparent huge pages, as the main heap is, the
// first time; nothing otherwise. For a thread that does a share of the work, before each share
// (a pool's thread may start before the process keeps its memory).
void prepare_worker_heap();

}  // namespace lmcal::detail
