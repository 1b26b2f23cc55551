#include "lmcal/process.hpp"

#include <atomic>
#include <cstdint>
#include <cstdlib>  // defines __GLIBC__ where the C library is glibc
#include <fstream>

#include "process_heap.hpp"

#if defined(__GLIBC__)
#include <malloc.h>
#endif
#if defined(__linux__)
#include <sys/mman.h>
#endif

// A sanitizer brings its own malloc: glibc's settings do not reach it, and a reserve would only
// make it poison (and quarantine) hundreds of megabytes at every start.
#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(memory_sanitizer) || __has_feature(thread_sanitizer)
#define LMCAL_SANITIZED_MALLOC 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define LMCAL_SANITIZED_MALLOC 1
#endif

#if defined(__GLIBC__) && defined(MADV_HUGEPAGE) && !defined(LMCAL_SANITIZED_MALLOC)
#define LMCAL_HUGE_HEAP 1
#endif

namespace lmcal {

namespace {

[[maybe_unused]] constexpr int kNeverTrim = 1 << 30;

#if defined(LMCAL_HUGE_HEAP)
std::atomic<bool> memory_kept{false};  // keep_freed_memory() has been called
// The reserves: the main heap's, and a thread's own arena's, at most 64 MB (glibc's
// HEAP_MAX_SIZE on 64 bits, twice the largest mmap threshold; a larger block comes from the main
// heap). Freed, each stays only below the trim threshold.
constexpr std::size_t kMainHeapReserve = std::size_t{512} << 20, kThreadHeapReserve = std::size_t{48} << 20;
static_assert(kMainHeapReserve < static_cast<std::size_t>(kNeverTrim) && kThreadHeapReserve < kMainHeapReserve);

// The next `bytes` of the calling thread's heap marked for transparent huge pages, what glibc's
// `glibc.malloc.hugetlb=1` does (a tunable only the environment can set, before the process
// starts): the heap is grown by that much at once and, with trimming off, keeps the range, so
// the allocations that follow fault a 2 MB page at a time instead of 4 kB. On a virtual machine
// a fault is a trap to the hypervisor: a 10⁵-sample `lmcal fit friction` faulted 9,400 times,
// about a third of its 0.36 s. Where the system grants huge pages only on request
// (/sys/kernel/mm/transparent_hugepage/enabled: madvise, Debian's default) this is what grants
// them; with `always` or `never` it changes nothing. The resident memory grows by at most one
// 2 MB page beyond the heap's use; the reserve itself is address space only, except where the
// system accounts every mapping up front (vm.overcommit_memory = 2): there each process's
// reserve would count against the node's limit (a fleet's ranks), so none is made.
void reserve_huge_pages(std::size_t bytes) {
  static const bool strict_accounting = [] {
    std::ifstream mode("/proc/sys/vm/overcommit_memory");
    int value = 0;
    return mode >> value && value == 2;
  }();
  if (strict_accounting) return;
  void* block = std::malloc(bytes);  // from this thread's heap (no mapped blocks), untouched
  if (!block) return;                // address space refused: 4 kB pages, as before
  detail::prefer_huge_pages(block, bytes);
  std::free(block);  // back to the top of the heap, below the trim threshold: kept
}
#endif

// madvise(advice) on the whole `unit`-aligned units inside [data, data + bytes), if any.
[[maybe_unused]] void advise_inside(const void* data, std::size_t bytes, std::uintptr_t unit, int advice) {
#if defined(__linux__)
  const auto begin = (reinterpret_cast<std::uintptr_t>(data) + unit - 1) & ~(unit - 1);
  const auto end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(unit - 1);
  if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, advice);
#else
  (void)data, (void)bytes, (void)unit, (void)advice;
#endif
}

}  // namespace

bool keep_freed_memory() {
#if defined(__GLIBC__)
  constexpr int kLargestFromHeap = 32 << 20;  // glibc's ceiling for M_MMAP_THRESHOLD on 64 bits
  // Blocks over that ceiling (a 10⁶-sample fit's 56 MB Jacobian) from the heap too: no block
  // is mapped on its own, where each allocation would fault its pages afresh.
  constexpr int kNoMappedBlocks = 0;
  const bool kept = mallopt(M_MMAP_THRESHOLD, kLargestFromHeap) == 1 && mallopt(M_TRIM_THRESHOLD, kNeverTrim) == 1 &&
                    mallopt(M_MMAP_MAX, kNoMappedBlocks) == 1;
#if defined(LMCAL_HUGE_HEAP)
  if (kept && !memory_kept.exchange(true)) reserve_huge_pages(kMainHeapReserve);
#endif
  return kept;
#else
  return false;
#endif
}

namespace detail {

void prefer_huge_pages(const void* data, std::size_t bytes) {
#ifdef MADV_HUGEPAGE
  advise_inside(data, bytes, std::uintptr_t{2} << 20, MADV_HUGEPAGE);
#else
  (void)data, (void)bytes;
#endif
}

void populate_pages(const void* data, std::size_t bytes) {
#ifdef MADV_POPULATE_WRITE
  advise_inside(data, bytes, 4096, MADV_POPULATE_WRITE);
#else
  (void)data, (void)bytes;
#endif
}

void prepare_worker_heap() {
#if defined(LMCAL_HUGE_HEAP)
  thread_local bool prepared = false;
  if (prepared || !memory_kept.load(std::memory_order_relaxed)) return;
  reserve_huge_pages(kThreadHeapReserve);
  prepared = true;
#endif
}

}  // namespace detail

}  // namespace lmcal
