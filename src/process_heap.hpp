// The process's memory, below lmcal::keep_freed_memory (lmcal/process.hpp): the page advice the
// heap's reserves and the loaders' columns share, and the setting for threads that start later
// (the pool's workers, parallel_slices.cc).
#pragma once

#include <cstddef>

namespace lmcal::detail {

// Asks the kernel to back the whole 2 MiB pages inside [data, data + bytes) by transparent huge
// pages (Linux; elsewhere, or when refused, nothing happens): the first write to a loader's
// column of a million rows then costs a few page faults rather than thousands.
void prefer_huge_pages(const void* data, std::size_t bytes);

// Asks the kernel to map the pages inside [data, data + bytes) now, writable (Linux 5.14's
// MADV_POPULATE_WRITE; elsewhere, or when refused, nothing happens): one call instead of a page
// fault at each page's first write, which on a virtual machine is a trap to the hypervisor.
void populate_pages(const void* data, std::size_t bytes);

// Once keep_freed_memory() has been called: the calling thread's own heap (glibc gives each
// new thread an arena of its own) marked for transparent huge pages, as the main heap is, the
// first time; nothing otherwise. For a thread that does a share of the work, before each share
// (a pool's thread may start before the process keeps its memory).
void prepare_worker_heap();

}  // namespace lmcal::detail
