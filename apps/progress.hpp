// Progress on the terminal: one line on stderr, rewritten in place ("[2/5] thermal
// diagnosis: round 1, coupling (3/8)  14 s", the seconds ticking while a step runs), and
// nothing at all when stderr is not a terminal (a log file or a pipe gets only the results).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

#include "lmcal/diagnose/diagnosis.hpp"

namespace lmcal::cli {

class TerminalProgress {
 public:
  explicit TerminalProgress(std::FILE* out = stderr);
  ~TerminalProgress();
  TerminalProgress(const TerminalProgress&) = delete;
  TerminalProgress& operator=(const TerminalProgress&) = delete;

  // Step `index` (0-based) of `count` starts.
  void step(std::size_t index, std::size_t count, const std::string& name);
  // Inside the current step: item `done` (0-based) of `total`.
  void detail(const std::string& what, std::size_t done, std::size_t total);
  // detail() as a callback for the library's long computations.
  Progress detail_callback() {
    return [this](const std::string& what, std::size_t done, std::size_t total) { detail(what, done, total); };
  }
  // Clears the line and stops (before the results are printed).
  void clear();

 private:
  using Clock = std::chrono::steady_clock;
  void draw();  // with mutex_ held

  std::FILE* out_;
  bool lines_;    // -v without a terminal: a line per step
  bool enabled_;  // a terminal, not -q or --json: one line rewritten in place
  std::mutex mutex_;
  bool shown_ = false;
  std::string step_, detail_;
  Clock::time_point step_start_ = Clock::now();
  std::jthread ticker_;  // redraws while a step runs, so the seconds move
};

// Runs `work(detail callback)` with `name` shown as the one step on the terminal; the line is
// cleared before the result comes back, so what follows prints on a clean line.
template <class Work>
auto with_progress(const std::string& name, Work&& work) {
  TerminalProgress progress;
  progress.step(0, 1, name);
  auto result = std::forward<Work>(work)(progress.detail_callback());
  progress.clear();
  return result;
}

}  // namespace lmcal::cli
