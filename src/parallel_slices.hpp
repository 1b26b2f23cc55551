// Work on independent items split into contiguous slices, one per thread of a pool kept for the
// process (parallel_slices.cc). Kept out of the headers that templates include, so that every
// translation unit sees one definition whether or not it is compiled with OpenMP.
#pragma once

#include <cstddef>
#include <functional>

namespace lmcal::detail {

// Threads for `items` independent items, at least `per_thread` each: 1 inside another
// parallel region (a diagnosis's candidates already use the cores) or for small work.
int slice_threads(std::size_t items, std::size_t per_thread);

// From now on, at most `threads` threads for slices (0: OpenMP's default, OMP_NUM_THREADS or
// the cores); gives the limit before. For the tests and benchmarks that compare 1 thread with
// many.
int limit_slice_threads(int threads);

// body(slice, begin, end) for slices 0..threads-1 of [0, items), which cover it in order, one
// per thread. The exception of the lowest slice that threw is rethrown once all have finished.
void for_each_slice(std::size_t items, int threads,
                    const std::function<void(int slice, std::size_t begin, std::size_t end)>& body);

// body(index) for every index of [0, items), each on a free thread (heavy items of unequal
// cost: a run's fit). The exception of the lowest index that threw is rethrown once all have
// finished.
void for_each_index(std::size_t items, const std::function<void(std::size_t index)>& body);

}  // namespace lmcal::detail
