#include "lmcal/process.hpp"

#include <cstdlib>  // defines __GLIBC__ where the C library is glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace lmcal {

bool keep_freed_memory() {
#if defined(__GLIBC__)
  constexpr int kLargestFromHeap = 32 << 20;  // glibc's ceiling for M_MMAP_THRESHOLD on 64 bits
  constexpr int kNeverTrim = 1 << 30;
  // Blocks over that ceiling (a 10⁶-sample fit's 56 MB Jacobian) from the heap too: no block
  // is mapped on its own, where each allocation would fault its pages afresh.
  constexpr int kNoMappedBlocks = 0;
  return mallopt(M_MMAP_THRESHOLD, kLargestFromHeap) == 1 && mallopt(M_TRIM_THRESHOLD, kNeverTrim) == 1 &&
         mallopt(M_MMAP_MAX, kNoMappedBlocks) == 1;
#else
  return false;
#endif
}

}  // namespace lmcal
