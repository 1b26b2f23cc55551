// The row-parallel helper (src/parallel_slices.hpp): every item once, slices in order, errors
// rethrown from the lowest item, nested work on the calling thread (no deadlock, no extra
// threads), and the thread limit obeyed.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <mutex>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "parallel_slices.hpp"

namespace {

using namespace lmcal::detail;

TEST(ParallelSlices, SlicesCoverTheItemsInOrderWithMoreThreadsThanCores) {
  const std::size_t items = 1001;
  for (int threads : {1, 2, 3, 7, 16}) {
    std::vector<std::pair<std::size_t, std::size_t>> bounds(static_cast<std::size_t>(threads));
    std::vector<int> seen(items, 0);
    for_each_slice(items, threads, [&](int s, std::size_t begin, std::size_t end) {
      bounds[static_cast<std::size_t>(s)] = {begin, end};
      for (std::size_t i = begin; i < end; ++i) ++seen[i];
    });
    EXPECT_EQ(bounds.front().first, 0u);
    EXPECT_EQ(bounds.back().second, items);
    for (std::size_t s = 1; s < bounds.size(); ++s) EXPECT_EQ(bounds[s].first, bounds[s - 1].second) << threads << " threads";
    EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; })) << threads << " threads";
  }
}

TEST(ParallelSlices, EveryIndexOnceAndTheLowestFailureRethrown) {
  std::vector<std::atomic<int>> seen(5000);
  for_each_index(seen.size(), [&](std::size_t i) { seen[i].fetch_add(1); });
  for (const auto& n : seen) ASSERT_EQ(n.load(), 1);

  try {
    for_each_index(100, [](std::size_t i) {
      if (i == 37 || i == 90) throw std::runtime_error("item " + std::to_string(i));
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "item 37");
  }
  try {
    for_each_slice(100, 4, [](int s, std::size_t, std::size_t) {
      if (s >= 2) throw std::runtime_error("slice " + std::to_string(s));
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "slice 2");
  }
  // The pool is still usable after a job's items threw.
  std::atomic<int> count{0};
  for_each_index(64, [&](std::size_t) { ++count; });
  EXPECT_EQ(count.load(), 64);
}

// Work started inside a job (a run's fit inside the per-run loop, a slice inside a start's
// search) runs on the thread that starts it: no deadlock, and no thread beyond the job's.
TEST(ParallelSlices, NestedWorkRunsOnTheCallingThread) {
  std::mutex m;
  std::set<std::thread::id> outer_threads, inner_threads;
  std::atomic<int> inner_items{0}, nested_width{0};
  for_each_index(8, [&](std::size_t) {
    const auto me = std::this_thread::get_id();
    {
      const std::lock_guard lock(m);
      outer_threads.insert(me);
    }
    nested_width.fetch_add(slice_threads(1'000'000, 1));
    for_each_slice(1000, 3, [&](int, std::size_t begin, std::size_t end) {
      EXPECT_EQ(std::this_thread::get_id(), me);
      inner_items.fetch_add(static_cast<int>(end - begin));
    });
    for_each_index(10, [&](std::size_t) {
      EXPECT_EQ(std::this_thread::get_id(), me);
      const std::lock_guard lock(m);
      inner_threads.insert(std::this_thread::get_id());
    });
  });
  EXPECT_EQ(inner_items.load(), 8 * 1000);
  EXPECT_EQ(nested_width.load(), 8);  // 1 thread each
  for (const auto& id : inner_threads) EXPECT_TRUE(outer_threads.count(id));
}

// Two threads that are not the pool's (`lmcal fleet --jobs 2`'s workers) asking at once: one
// gets the pool, the other does its work alone; both finish with every item done once.
TEST(ParallelSlices, TwoCallersAtOnceBothFinish) {
  std::vector<std::atomic<int>> a(20000), b(20000);
  auto fill = [](std::vector<std::atomic<int>>& seen) {
    for (int repeat = 0; repeat < 50; ++repeat)
      for_each_slice(seen.size(), 2, [&](int, std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) seen[i].fetch_add(1);
      });
  };
  std::thread other([&] { fill(b); });
  fill(a);
  other.join();
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].load(), 50);
    ASSERT_EQ(b[i].load(), 50);
  }
}

TEST(ParallelSlices, TheThreadLimitIsObeyed) {
  const int before = limit_slice_threads(1);
  EXPECT_EQ(slice_threads(1'000'000, 1), 1);
  std::set<std::thread::id> threads;
  std::mutex m;
  for_each_index(200, [&](std::size_t) {
    const std::lock_guard lock(m);
    threads.insert(std::this_thread::get_id());
  });
  EXPECT_EQ(threads.size(), 1u);
  EXPECT_EQ(*threads.begin(), std::this_thread::get_id());
  limit_slice_threads(before);
}

}  // namespace
