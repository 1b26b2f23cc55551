#include "parallel_slices.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "process_heap.hpp"

namespace lmcal::detail {

namespace {

// True on a thread while it runs a job of the pool: work it starts runs on it alone.
thread_local bool in_job = false;

// Threads kept for the life of the process that run one job at a time, the caller taking part
// as worker 0. Why not an OpenMP region per job: between regions and at their barriers
// libgomp's threads spin (OMP_WAIT_POLICY, 300,000 rounds by default) before they sleep; on a
// machine with other work the spinning thread takes the core the working one needs, and a
// 100 k-sample fit took twice its time beside a 2-job build (417 ms spinning, 200 ms with
// OMP_WAIT_POLICY=passive). The pool's idle threads sleep on a futex
// (std::atomic::wait), after the short spin libstdc++ gives it.
class Pool {
 public:
  static Pool& instance() {
    // Never destroyed: a worker still asleep when the process exits is harmless, a destructor
    // racing another static's last job is not.
    static Pool* pool = new Pool;
    return *pool;
  }

  // body(worker) for worker 0..threads-1, worker 0 on this thread; returns when all have.
  // False, having run nothing, while another thread's job has the pool (`lmcal fleet --jobs`'
  // workers): the caller then does the work alone.
  bool run(int threads, const std::function<void(int)>& body) {
    const std::unique_lock lock(job_mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return false;
    if (owner_ != getpid()) forget_workers();  // a forked child has none of its parent's threads
    while (static_cast<int>(workers_.size()) < threads - 1) {
      const int id = static_cast<int>(workers_.size()) + 1;
      workers_.emplace_back([this, id, seen = generation_.load()] { work(id, seen); });
    }
    body_ = &body;
    job_threads_ = threads;
    remaining_.store(static_cast<int>(workers_.size()), std::memory_order_relaxed);
    generation_.fetch_add(1, std::memory_order_release);
    generation_.notify_all();
    run_as(0, body);
    for (int left = remaining_.load(std::memory_order_acquire); left != 0; left = remaining_.load(std::memory_order_acquire))
      remaining_.wait(left, std::memory_order_acquire);
    return true;
  }

 private:
  Pool() : owner_(getpid()) {}

  // Every worker sees every job (one that is not needed only says so): a job ends when all
  // have, so no worker can still be reading one job's body when the next is published.
  void work(int id, std::uint32_t seen) {
    for (;;) {
      generation_.wait(seen, std::memory_order_acquire);
      seen = generation_.load(std::memory_order_acquire);
      if (id < job_threads_) {
        prepare_worker_heap();
        run_as(id, *body_);
      }
      if (remaining_.fetch_sub(1, std::memory_order_acq_rel) == 1) remaining_.notify_all();
    }
  }

  // As one thread of an OpenMP team: nested parallel work (an OpenMP loop, a slice) runs on
  // this thread alone, as it did when the jobs were OpenMP regions.
  static void run_as(int id, const std::function<void(int)>& body) {
    in_job = true;
#ifdef _OPENMP
    const int before = omp_get_max_threads();
    omp_set_num_threads(1);
#endif
    body(id);
#ifdef _OPENMP
    omp_set_num_threads(before);
#endif
    in_job = false;
  }

  void forget_workers() {
    // The threads' handles are of the parent; leaked, not joined or detached.
    new std::vector<std::thread>(std::move(workers_));
    workers_.clear();
    owner_ = getpid();
  }

  std::mutex job_mutex_;
  std::vector<std::thread> workers_;  // workers 1..size()
  pid_t owner_;
  std::atomic<std::uint32_t> generation_{0};  // 32 bits: a futex of its own
  std::atomic<int> remaining_{0};
  const std::function<void(int)>* body_ = nullptr;
  int job_threads_ = 0;
};

#ifndef _OPENMP
// Without OpenMP (a clang build): OMP_NUM_THREADS as OpenMP reads it (its first number), else
// the cores; limit_slice_threads overrides it.
int threads_from_environment() {
  if (const char* text = std::getenv("OMP_NUM_THREADS")) {
    const int n = std::atoi(text);
    if (n > 0) return n;
  }
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}
const int cores = threads_from_environment();
std::atomic<int> thread_limit{0};
#endif

// The threads a job may use: OpenMP's (OMP_NUM_THREADS, omp_set_num_threads, the cores).
int most_threads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  const int limit = thread_limit.load();
  return limit > 0 ? limit : cores;
#endif
}

bool inside_parallel_work() {
#ifdef _OPENMP
  if (omp_in_parallel()) return true;
#endif
  return in_job;
}

}  // namespace

int slice_threads(std::size_t items, std::size_t per_thread) {
  if (inside_parallel_work() || per_thread == 0) return 1;
  const std::size_t most = items / per_thread;
  const auto threads = static_cast<std::size_t>(most_threads());
  return static_cast<int>(std::max<std::size_t>(1, std::min(most, threads)));
}

int limit_slice_threads(int threads) {
#ifdef _OPENMP
  static const int default_threads = omp_get_max_threads();
  const int before = omp_get_max_threads();
  omp_set_num_threads(threads > 0 ? threads : default_threads);
  return before;
#else
  const int before = most_threads();
  thread_limit.store(std::max(threads, 0));
  return before;
#endif
}

void for_each_slice(std::size_t items, int threads, const std::function<void(int, std::size_t, std::size_t)>& body) {
  if (threads <= 1) return body(0, 0, items);
  std::vector<std::exception_ptr> failure(static_cast<std::size_t>(threads));
  auto one = [&](int s) {
    const auto slice = static_cast<std::size_t>(s), count = static_cast<std::size_t>(threads);
    try {
      body(s, items * slice / count, items * (slice + 1) / count);
    } catch (...) {
      failure[slice] = std::current_exception();
    }
  };
  // Nested, or the pool busy with another thread's job: the same slices, one after the other.
  if (inside_parallel_work() || !Pool::instance().run(threads, one))
    for (int s = 0; s < threads; ++s) one(s);
  for (const std::exception_ptr& f : failure)
    if (f) std::rethrow_exception(f);
}

void for_each_index(std::size_t items, const std::function<void(std::size_t)>& body) {
  std::vector<std::exception_ptr> failure(items);
  auto one = [&](std::size_t i) {
    try {
      body(i);
    } catch (...) {
      failure[i] = std::current_exception();
    }
  };
  const int threads = slice_threads(items, 1);
  std::atomic<std::size_t> next{0};  // the next index to take, on whichever thread is free
  auto take = [&](int) {
    for (std::size_t i = next.fetch_add(1, std::memory_order_relaxed); i < items; i = next.fetch_add(1, std::memory_order_relaxed))
      one(i);
  };
  if (threads <= 1 || !Pool::instance().run(threads, take)) take(0);
  for (const std::exception_ptr& f : failure)
    if (f) std::rethrow_exception(f);
}

}  // namespace lmcal::detail
