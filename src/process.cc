#include "lmcal/process.hpp"

#include <cstdint>
#include <cstdlib>  // defines __GLIBC__ where the C library is glibc

#if defined(__GLIBC__)
#include <malloc.h>
#include <sys/mman.h>
#endif

// A sanitizer brings its own malloc: glibc's settings do not reach it, and a reserve would only
// make it poison (and quarantine) half a gigabyte at every start.
#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(memory_sanitizer) || __has_feature(thread_sanitizer)
#define LMCAL_SANITIZED_MALLOC 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define LMCAL_SANITIZED_MALLOC 1
#endif

namespace lmcal {

namespace {

#if defined(__GLIBC__) && defined(MADV_HUGEPAGE) && !defined(LMCAL_SANITIZED_MALLOC)
// The first kHugeHeapBytes of the heap marked for transparent huge pages, what glibc's
// `glibc.malloc.hugetlb=1` does (a tunable only the environment can set, before the process
// starts): the heap is grown by that much at once and, with trimming off, keeps the range, so
// the allocations that follow fault a 2 MB page at a time instead of 4 kB. On a virtual machine
// a fault is a trap to the hypervisor: a 10⁵-sample `lmcal fit friction` faulted 9,400 times,
// about a third of its 0.36 s. Where the system grants huge pages only on request
// (/sys/kernel/mm/transparent_hugepage/enabled: madvise, Debian's default) this is what grants
// them; with `always` it changes nothing, with `never` nothing either. The resident memory grows
// by at most one 2 MB page beyond the heap's use; the reserve itself is address space only.
constexpr std::size_t kHugeHeapBytes = std::size_t{512} << 20;

void back_heap_with_huge_pages() {
  constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;
  void* block = std::malloc(kHugeHeapBytes);  // from the heap (no mapped blocks), untouched
  if (!block) return;                         // address space refused: 4 kB pages, as before
  const auto begin = (reinterpret_cast<std::uintptr_t>(block) + kHugePage - 1) & ~(kHugePage - 1);
  const auto end = (reinterpret_cast<std::uintptr_t>(block) + kHugeHeapBytes) & ~(kHugePage - 1);
  ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
  std::free(block);  // back to the top of the heap, below the trim threshold: kept
}
#endif

}  // namespace

bool keep_freed_memory() {
#if defined(__GLIBC__)
  constexpr int kLargestFromHeap = 32 << 20;  // glibc's ceiling for M_MMAP_THRESHOLD on 64 bits
  constexpr int kNeverTrim = 1 << 30;
  // Blocks over that ceiling (a 10⁶-sample fit's 56 MB Jacobian) from the heap too: no block
  // is mapped on its own, where each allocation would fault its pages afresh.
  constexpr int kNoMappedBlocks = 0;
  const bool kept = mallopt(M_MMAP_THRESHOLD, kLargestFromHeap) == 1 && mallopt(M_TRIM_THRESHOLD, kNeverTrim) == 1 &&
                    mallopt(M_MMAP_MAX, kNoMappedBlocks) == 1;
#if defined(MADV_HUGEPAGE) && !defined(LMCAL_SANITIZED_MALLOC)
  static_assert(kHugeHeapBytes < static_cast<std::size_t>(kNeverTrim), "a freed reserve over the threshold is trimmed");
  if (kept) back_heap_with_huge_pages();
#endif
  return kept;
#else
  return false;
#endif
}

}  // namespace lmcal
