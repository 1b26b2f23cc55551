#include "parallel_slices.hpp"

#include <algorithm>
#include <exception>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace lmcal::detail {

int slice_threads(std::size_t items, std::size_t per_thread) {
#ifdef _OPENMP
  if (omp_in_parallel() || per_thread == 0) return 1;
  const std::size_t most = items / per_thread;
  const auto threads = static_cast<std::size_t>(omp_get_max_threads());
  return static_cast<int>(std::max<std::size_t>(1, std::min(most, threads)));
#else
  (void)items, (void)per_thread;
  return 1;
#endif
}

int limit_slice_threads(int threads) {
#ifdef _OPENMP
  static const int default_threads = omp_get_max_threads();
  const int before = omp_get_max_threads();
  omp_set_num_threads(threads > 0 ? threads : default_threads);
  return before;
#else
  (void)threads;
  return 1;
#endif
}

void for_each_slice(std::size_t items, int threads, const std::function<void(int, std::size_t, std::size_t)>& body) {
  if (threads <= 1) return body(0, 0, items);
  std::vector<std::exception_ptr> failure(static_cast<std::size_t>(threads));
#pragma omp parallel for schedule(static, 1) num_threads(threads)
  for (int s = 0; s < threads; ++s) {
    const auto slice = static_cast<std::size_t>(s), count = static_cast<std::size_t>(threads);
    try {
      body(s, items * slice / count, items * (slice + 1) / count);
    } catch (...) {
      failure[slice] = std::current_exception();
    }
  }
  for (const std::exception_ptr& f : failure)
    if (f) std::rethrow_exception(f);
}

void for_each_index(std::size_t items, const std::function<void(std::size_t)>& body) {
  std::vector<std::exception_ptr> failure(items);
  const int threads = slice_threads(items, 1);
#pragma omp parallel for schedule(dynamic) num_threads(threads) if (threads > 1)
  for (std::size_t i = 0; i < items; ++i) {
    try {
      body(i);
    } catch (...) {
      failure[i] = std::current_exception();
    }
  }
  for (const std::exception_ptr& f : failure)
    if (f) std::rethrow_exception(f);
}

}  // namespace lmcal::detail
