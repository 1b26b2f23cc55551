#include "fleet_mpi.hpp"

#include <mpi.h>
#include <omp.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace lmcal::cli {

namespace {

constexpr int kRequest = 1;  // worker -> rank 0: the last set's outcome (or none), and "next, please"
constexpr int kAssign = 2;   // rank 0 -> worker: a set index, or -1 to stop

// A worker's message: its last set and how it went, then the record's (or error's) text.
struct Header {
  std::int64_t index = -1;  // -1: no set yet
  std::int32_t computed = 0, failed = 0, error = 0;
};

std::vector<char> pack(const Header& h, const std::string& text) {
  std::vector<char> bytes(sizeof(Header) + text.size());
  std::memcpy(bytes.data(), &h, sizeof(Header));
  std::memcpy(bytes.data() + sizeof(Header), text.data(), text.size());
  return bytes;
}

// The sets still to hand out, shared by rank 0's dispatcher and its own calibrating thread.
class Queue {
 public:
  explicit Queue(std::deque<std::size_t> sets) : sets_(std::move(sets)) {}
  std::int64_t next() {
    const std::lock_guard lock(mutex_);
    if (sets_.empty() || stopped_) return -1;
    const std::size_t i = sets_.front();
    sets_.pop_front();
    return static_cast<std::int64_t>(i);
  }
  void stop() {
    const std::lock_guard lock(mutex_);
    stopped_ = true;
  }

 private:
  std::mutex mutex_;
  std::deque<std::size_t> sets_;
  bool stopped_ = false;
};

// What rank 0 collects, from its own thread and from the workers.
class Gathered {
 public:
  Gathered(FleetRun& run, std::size_t total, const Fleet& fleet, const FleetProgress& progress)
      : run_(run), total_(total), fleet_(fleet), progress_(progress) {}
  void add(std::size_t index, FleetSetOutcome outcome) {
    const std::lock_guard lock(mutex_);
    (outcome.computed ? run_.computed : run_.skipped) += 1;
    run_.failed += outcome.failed ? 1 : 0;
    ++done_;
    if (progress_) progress_(done_, total_, fleet_.sets[index].id, outcome);
    run_.records[index] = std::move(outcome.record);
  }
  void fail(const std::string& what) {
    const std::lock_guard lock(mutex_);
    if (error_.empty()) error_ = what;
  }
  std::string error() {
    const std::lock_guard lock(mutex_);
    return error_;
  }

 private:
  std::mutex mutex_;
  FleetRun& run_;
  std::size_t total_, done_ = 0;
  const Fleet& fleet_;
  const FleetProgress& progress_;
  std::string error_;
};

void send_assignment(std::int64_t index, int to) { MPI_Send(&index, 1, MPI_INT64_T, to, kAssign, MPI_COMM_WORLD); }

// Rank 0: answers requests until every worker was told to stop, while `local` calibrates.
void dispatch(const MpiSession& mpi, Queue& queue, Gathered& gathered) {
  int active = mpi.size() - 1;
  while (active > 0) {
    MPI_Status status;
    int ready = 0;
    MPI_Iprobe(MPI_ANY_SOURCE, kRequest, MPI_COMM_WORLD, &ready, &status);
    if (!ready) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      continue;
    }
    int bytes = 0;
    MPI_Get_count(&status, MPI_BYTE, &bytes);
    std::vector<char> message(static_cast<std::size_t>(bytes));
    MPI_Recv(message.data(), bytes, MPI_BYTE, status.MPI_SOURCE, kRequest, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    Header h;
    std::memcpy(&h, message.data(), sizeof(Header));
    std::string text(message.begin() + sizeof(Header), message.end());
    if (h.error) {
      gathered.fail(text);
      queue.stop();
    } else if (h.index >= 0) {
      gathered.add(static_cast<std::size_t>(h.index),
                   {.record = std::move(text), .computed = h.computed != 0, .failed = h.failed != 0});
    }
    const std::int64_t next = queue.next();
    send_assignment(next, status.MPI_SOURCE);
    if (next < 0) --active;
  }
}

void work_as_worker(const Fleet& fleet, const FleetOptions& options, const std::string& hash) {
  Header h;
  std::string text;
  for (;;) {
    const std::vector<char> message = pack(h, text);
    MPI_Send(message.data(), static_cast<int>(message.size()), MPI_BYTE, 0, kRequest, MPI_COMM_WORLD);
    std::int64_t index = -1;
    MPI_Recv(&index, 1, MPI_INT64_T, 0, kAssign, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (index < 0) return;
    h = Header{.index = index};
    try {
      FleetSetOutcome outcome = run_fleet_set(fleet, static_cast<std::size_t>(index), options, hash);
      h.computed = outcome.computed;
      h.failed = outcome.failed;
      text = std::move(outcome.record);
    } catch (const std::exception& e) {
      h.error = 1;
      text = e.what();
    }
  }
}

}  // namespace

bool launched_by_mpi() {
  for (const char* variable : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS"})
    if (std::getenv(variable)) return true;
  return false;
}

MpiSession::MpiSession() {
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

MpiSession::~MpiSession() { MPI_Finalize(); }

FleetRun run_fleet_mpi(const MpiSession& mpi, const Fleet& fleet, const FleetOptions& options,
                       const FleetProgress& progress) {
  const std::string hash = fleet_options_hash(options.calibration);
  omp_set_num_threads(1);  // the ranks fill the cores
  FleetRun run;
  if (mpi.rank() != 0) {
    work_as_worker(fleet, options, hash);
    return run;
  }
  run.records.resize(fleet.sets.size());
  std::deque<std::size_t> mine;
  for (std::size_t i = 0; i < fleet.sets.size(); ++i)
    if (i % options.shards == options.shard) mine.push_back(i);
  Queue queue(mine);
  Gathered gathered(run, mine.size(), fleet, progress);
  // Rank 0 calibrates too, on a thread that makes no MPI call (MPI_THREAD_FUNNELED).
  std::thread local([&] {
    omp_set_num_threads(1);
    for (std::int64_t i; (i = queue.next()) >= 0;) {
      try {
        gathered.add(static_cast<std::size_t>(i), run_fleet_set(fleet, static_cast<std::size_t>(i), options, hash));
      } catch (const std::exception& e) {
        gathered.fail(e.what());
        queue.stop();
      }
    }
  });
  dispatch(mpi, queue, gathered);
  local.join();
  if (const std::string error = gathered.error(); !error.empty()) throw std::runtime_error(error);
  return run;
}

}  // namespace lmcal::cli
