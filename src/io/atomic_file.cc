#include "lmcal/io/atomic_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <fmt/format.h>

#include <fstream>
#include <list>
#include <mutex>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>

#include "io/input_file.hpp"
#include "lmcal/error.hpp"
#include "parallel_slices.hpp"

namespace lmcal {

namespace fs = std::filesystem;

namespace detail {
void (*commit_step_hook)(int step) = nullptr;
}

namespace {

// The tests' seam: called at every step a kill could interrupt (see atomic_file_steps.hpp).
void step(int k) {
  if (detail::commit_step_hook) detail::commit_step_hook(k);
}

constexpr const char* kJournal = ".lmcal-commit";

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw InputError(path.string(), 0, 0, fmt::format("{}: {}", what, std::strerror(errno)));
}

// An open descriptor, closed when it goes.
class Descriptor {
 public:
  explicit Descriptor(int fd) : fd_(fd) {}
  ~Descriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

// `contents` into `path` (created or truncated) and onto the disk.
void write_durably(const fs::path& path, const std::string& contents) {
  Descriptor fd(::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
  if (fd.get() < 0) fail(path, "cannot write output file");
  for (std::size_t done = 0; done < contents.size();) {
    const ssize_t n = ::write(fd.get(), contents.data() + done, contents.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(path, "cannot write output file");
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd.get()) != 0) fail(path, "cannot write output file");
}

// A folder's entries (renames, removals) onto the disk.
void sync_folder(const fs::path& folder) {
  Descriptor fd(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (fd.get() < 0 || ::fsync(fd.get()) != 0) fail(folder, "cannot sync output folder");
}

// An exclusive lock on a folder for as long as it lives (flock on the folder itself: no lock
// file is left behind). Threads and processes alike wait their turn.
class FolderLock {
 public:
  explicit FolderLock(const fs::path& folder) : fd_(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)) {
    if (fd_.get() < 0) fail(folder, "cannot open output folder");
    while (::flock(fd_.get(), LOCK_EX) != 0)
      if (errno != EINTR) fail(folder, "cannot lock output folder");
  }

 private:
  Descriptor fd_;
};

// SIGINT, SIGTERM and SIGHUP held back while any commit of the process is alive, then
// delivered: a commit is not cut short by Ctrl-C, whichever thread the signal lands on (a
// process-wide disposition; blocking the committing thread alone let the fleet's other threads
// take it). The first commit in swaps in a handler that records the signal, the last one out
// puts the previous handlers back and raises what was recorded.
class SignalsHeld {
 public:
  SignalsHeld() {
    const std::lock_guard lock(mutex_);
    if (active_++ > 0) return;
    struct sigaction defer {};
    defer.sa_handler = [](int signal) { pending_ = signal; };
    defer.sa_flags = SA_RESTART;  // the commit's writes and fsyncs go on
    sigfillset(&defer.sa_mask);
    for (std::size_t i = 0; i < kSignals.size(); ++i) ::sigaction(kSignals[i], &defer, &saved_[i]);
  }
  ~SignalsHeld() {
    const std::lock_guard lock(mutex_);
    if (--active_ > 0) return;
    for (std::size_t i = 0; i < kSignals.size(); ++i) ::sigaction(kSignals[i], &saved_[i], nullptr);
    if (const int signal = pending_.exchange(0)) ::raise(signal);
  }
  SignalsHeld(const SignalsHeld&) = delete;
  SignalsHeld& operator=(const SignalsHeld&) = delete;

 private:
  static constexpr std::array<int, 3> kSignals{SIGINT, SIGTERM, SIGHUP};
  static inline std::mutex mutex_;
  static inline int active_ = 0;
  static inline std::array<struct sigaction, 3> saved_{};
  static inline std::atomic<int> pending_{0};  // lock-free: safe in a signal handler
  static_assert(std::atomic<int>::is_always_lock_free);
};

bool is_temporary(const std::string& name) {
  const auto at = name.rfind(".lmcal-");
  return name.starts_with('.') && name.ends_with(".tmp") && at != std::string::npos && at > 0;
}

fs::path temporary_for(const fs::path& target) {
  return target.parent_path() / fmt::format(".{}.lmcal-{}.tmp", target.filename().string(), ::getpid());
}

struct Journal {
  std::vector<std::pair<fs::path, fs::path>> renames;  // temporary -> target
  std::vector<fs::path> removals;
};

// Carries out a journal (again: every step may already be done), syncs, drops the journal.
void complete(const fs::path& folder, const Journal& j) {
  std::set<fs::path> folders{folder};
  int k = 100;
  for (const auto& [temporary, target] : j.renames) {
    step(k++);
    std::error_code ec;
    if (fs::exists(temporary, ec) && std::rename(temporary.c_str(), target.c_str()) != 0)
      fail(target, "cannot move output into place");
    folders.insert(target.parent_path());
  }
  for (const fs::path& file : j.removals) {
    step(k++);
    if (::unlink(file.c_str()) != 0 && errno != ENOENT) fail(file, "cannot remove the earlier output");
    folders.insert(file.parent_path());
  }
  for (const fs::path& f : folders) sync_folder(f);
  step(k);
  if (::unlink((folder / kJournal).c_str()) != 0 && errno != ENOENT) fail(folder / kJournal, "cannot remove commit journal");
  sync_folder(folder);
}

Journal read_journal(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  const nlohmann::json j = nlohmann::json::parse(std::string(std::istreambuf_iterator<char>(in), {}), nullptr, false);
  if (j.is_discarded() || !j.is_object())
    throw InputError(file.string(), 0, 0, "a damaged commit journal: delete it and the .lmcal-*.tmp files beside it, then run again");
  Journal out;
  for (const auto& r : j.value("renames", nlohmann::json::array()))
    out.renames.emplace_back(r.at(0).get<std::string>(), r.at(1).get<std::string>());
  for (const auto& r : j.value("removals", nlohmann::json::array())) out.removals.emplace_back(r.get<std::string>());
  return out;
}

// With the folder locked: a journal completed, stray temporaries removed.
void recover_locked(const fs::path& folder) {
  std::error_code ec;
  if (fs::exists(folder / kJournal, ec)) complete(folder, read_journal(folder / kJournal));
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (is_temporary(name) || (name.starts_with(std::string(kJournal) + ".") && name.ends_with(".tmp")))
      fs::remove(entry.path(), ec);
  }
}

// Creates `folder` and its missing parents; returns those it created, deepest first.
std::vector<fs::path> create_folders(const fs::path& folder) {
  std::vector<fs::path> created;
  for (fs::path f = folder; !f.empty() && !fs::exists(f); f = f.parent_path()) created.push_back(f);
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw InputError(folder.string(), 0, 0, "cannot create folder: " + ec.message());
  return created;
}

}  // namespace

void OutputSet::add(fs::path path, std::string contents) {
  for (const auto& [p, c] : files_)
    if (p == path) throw std::invalid_argument("an output set names " + path.string() + " twice");
  files_.emplace_back(std::move(path), std::move(contents));
}

void OutputSet::remove(fs::path path) { removals_.push_back(std::move(path)); }

void OutputSet::commit() {
  if (files_.empty() && removals_.empty()) return;
  std::set<fs::path> folders;  // sorted: locks are taken in one order
  for (const auto& [path, contents] : files_) folders.insert(fs::absolute(path).parent_path());
  for (const fs::path& path : removals_) folders.insert(fs::absolute(path).parent_path());
  std::vector<fs::path> created;
  for (const fs::path& f : folders)
    for (fs::path& c : create_folders(f)) created.push_back(std::move(c));
  const SignalsHeld held;
  Journal journal;
  bool committed = false;  // the journal is in place: what is left is recover_outputs' to finish
  try {
    std::list<FolderLock> locks;
    for (const fs::path& f : folders) {
      locks.emplace_back(f);
      recover_locked(f);
    }
    for (const auto& [path, contents] : files_) {
      const fs::path target = fs::absolute(path);
      std::error_code ec;
      if (fs::is_directory(target, ec)) throw InputError(target.string(), 0, 0, "cannot write output file: it is a folder");
      journal.renames.emplace_back(temporary_for(target), target);
      step(static_cast<int>(journal.renames.size()));
    }
    // The temporaries written side by side (their fsyncs overlap); the first failure in file
    // order is the one reported.
    detail::for_each_index(files_.size(), [&](std::size_t k) { write_durably(journal.renames[k].first, files_[k].second); });
    for (const fs::path& path : removals_) {
      const fs::path target = fs::absolute(path);
      const bool kept = std::any_of(journal.renames.begin(), journal.renames.end(), [&](const auto& r) { return r.second == target; });
      if (!kept) journal.removals.push_back(target);
    }
    for (const fs::path& f : folders) sync_folder(f);
    // The commit point: the journal in place.
    const fs::path home = *folders.begin();
    nlohmann::json j = {{"renames", nlohmann::json::array()}, {"removals", nlohmann::json::array()}};
    for (const auto& [temporary, target] : journal.renames) j["renames"].push_back({temporary.string(), target.string()});
    for (const fs::path& file : journal.removals) j["removals"].push_back(file.string());
    const fs::path pending = home / fmt::format("{}.{}.tmp", kJournal, ::getpid());
    write_durably(pending, j.dump());
    step(50);
    if (std::rename(pending.c_str(), (home / kJournal).c_str()) != 0) fail(home / kJournal, "cannot write commit journal");
    sync_folder(home);
    committed = true;
    step(51);
    complete(home, journal);
  } catch (...) {
    if (committed) throw;
    std::error_code ignored;
    for (const auto& [temporary, target] : journal.renames) fs::remove(temporary, ignored);
    for (const fs::path& f : created) fs::remove(f, ignored);  // only if still empty
    throw;
  }
  files_.clear();
  removals_.clear();
}

void write_file_atomically(const fs::path& path, const std::string& contents) {
  OutputSet set;
  set.add(path, contents);
  set.commit();
}

std::optional<std::string> output_folder_problem(const fs::path& folder, std::uintmax_t needed_bytes) {
  std::error_code ec;
  fs::path existing = fs::absolute(folder.empty() ? fs::path(".") : folder, ec).lexically_normal();
  while (!ec && !fs::exists(existing, ec) && existing.has_relative_path()) existing = existing.parent_path();
  if (ec) return fmt::format("cannot write outputs there: {}", ec.message());
  if (!fs::is_directory(existing, ec))
    return fmt::format("cannot write outputs there: {} is not a folder", io::printable(existing.string()));
  if (::access(existing.c_str(), W_OK | X_OK) != 0)
    return fmt::format("cannot write outputs into {}: {}", io::printable(existing.string()), std::strerror(errno));
  const fs::space_info space = fs::space(existing, ec);
  if (!ec && space.available < needed_bytes)
    return fmt::format("only {} free in {}; the outputs need about {}", io::byte_size(space.available),
                       io::printable(existing.string()), io::byte_size(needed_bytes));
  return std::nullopt;
}

void recover_outputs(const fs::path& folder) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return;
  const SignalsHeld held;
  const FolderLock lock(folder);
  recover_locked(folder);
}

}  // namespace lmcal
