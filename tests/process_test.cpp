// lmcal::keep_freed_memory (lmcal/process.hpp): what the lmcal command and the benchmarks set.
#include "lmcal/process.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace lmcal {
namespace {

#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(memory_sanitizer) || __has_feature(thread_sanitizer)
#define LMCAL_TEST_SANITIZED_MALLOC 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define LMCAL_TEST_SANITIZED_MALLOC 1
#endif

// Kept: a block of 8 MB (which glibc would map on its own and return when freed) comes from the
// heap, and once freed stays there for the next allocation.
TEST(Process, FreedMemoryIsKeptForTheNextAllocation) {
#if !defined(__GLIBC__) || defined(LMCAL_TEST_SANITIZED_MALLOC)
  GTEST_SKIP() << "glibc's malloc only (a sanitizer brings its own)";
#else
  ASSERT_TRUE(keep_freed_memory());
  // 8 MB (glibc's default would map it) and 64 MB (over the ceiling of M_MMAP_THRESHOLD: a
  // 10⁶-sample fit's Jacobian is 56 MB).
  for (const std::size_t bytes : {std::size_t{8} << 20, std::size_t{64} << 20}) {
    SCOPED_TRACE(bytes);
    const auto mapped_before = mallinfo2().hblkhd;
    void* block = std::malloc(bytes);
    ASSERT_NE(block, nullptr);
    std::memset(block, 1, bytes);
    EXPECT_EQ(mallinfo2().hblkhd, mapped_before) << "not a mapping of its own";
    std::free(block);
    EXPECT_GE(mallinfo2().fordblks, bytes) << "the freed block stays in the heap, free for the next allocation";
  }
#endif
}

}  // namespace
}  // namespace lmcal
