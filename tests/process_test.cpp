// lmcal::keep_freed_memory (lmcal/process.hpp): what the lmcal command and the benchmarks set.
#include "lmcal/process.hpp"
#include "parallel_slices.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

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

// The VmFlags line of the mapping of /proc/self/smaps that holds `address`, or "" when none does.
std::string vm_flags_of(const void* address) {
  const auto at = reinterpret_cast<std::uintptr_t>(address);
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t begin = 0, end = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> begin >> dash >> end && dash == '-' && line.find(':') > line.find(' ')) {
      inside = begin <= at && at < end;
    } else if (inside && line.starts_with("VmFlags:")) {
      return line;
    }
  }
  return "";
}

// The VmFlags of the mapping that holds the middle of a fresh block of `bytes` ("" when none
// does, or the block could not be allocated).
std::string flags_of_a_block(std::size_t bytes) {
  void* block = std::malloc(bytes);
  if (!block) return "";
  std::string flags = vm_flags_of(static_cast<char*>(block) + bytes / 2);
  std::free(block);
  return flags;
}

// Why the huge-page marks cannot be looked at here, or nullptr when they can.
const char* huge_pages_untestable() {
#if !defined(__GLIBC__) || defined(LMCAL_TEST_SANITIZED_MALLOC)
  return "glibc's malloc only (a sanitizer brings its own)";
#else
  if (!std::filesystem::exists("/sys/kernel/mm/transparent_hugepage/enabled") || !std::filesystem::exists("/proc/self/smaps"))
    return "a kernel without transparent huge pages";
  std::ifstream overcommit("/proc/sys/vm/overcommit_memory");
  if (int mode = 0; overcommit >> mode && mode == 2) return "strict overcommit accounting: no reserve is made";
  return nullptr;
#endif
}

// The heap's pages that follow are marked for transparent huge pages (madvise's "hg"), so a
// large job faults a 2 MB page at a time: a block allocated afterwards lies in a marked mapping.
TEST(Process, TheHeapIsMarkedForHugePages) {
  if (const char* why = huge_pages_untestable()) GTEST_SKIP() << why;
  ASSERT_TRUE(keep_freed_memory());
  const std::string flags = flags_of_a_block(std::size_t{64} << 20);
  ASSERT_FALSE(flags.empty()) << "no mapping holds the block";
  EXPECT_NE((flags + " ").find(" hg "), std::string::npos) << flags;
}

// So is the heap of a pool thread that works a slice (glibc gives each thread an arena of its
// own): a 100 k-row CSV written in two slices took longer than in one, its second thread faulting
// its text in 4 kB at a time.
TEST(Process, APoolThreadsHeapIsMarkedForHugePages) {
  if (const char* why = huge_pages_untestable()) GTEST_SKIP() << why;
  ASSERT_TRUE(keep_freed_memory());
  const int before = detail::limit_slice_threads(2);
  std::string flags;
  bool other_thread = false;
  const auto caller = std::this_thread::get_id();
  detail::for_each_slice(2, 2, [&](int slice, std::size_t, std::size_t) {
    if (slice != 1) return;
    other_thread = std::this_thread::get_id() != caller;
    flags = flags_of_a_block(std::size_t{8} << 20);
  });
  detail::limit_slice_threads(before);
  if (!other_thread) GTEST_SKIP() << "the pool was busy: the slice ran on the calling thread";
  ASSERT_FALSE(flags.empty()) << "no mapping holds the block";
  EXPECT_NE((flags + " ").find(" hg "), std::string::npos) << flags;
}

}  // namespace
}  // namespace lmcal
