#include "progress.hpp"

#include "output_mode.hpp"

#include <fmt/format.h>
#include <sys/ioctl.h>
#include <unistd.h>

namespace lmcal::cli {

TerminalProgress::TerminalProgress(std::FILE* out)
    : out_(out),
      lines_(output_mode().verbosity == Verbosity::verbose && isatty(fileno(out)) == 0),
      enabled_(isatty(fileno(out)) != 0 && output_mode().verbosity != Verbosity::quiet && !output_mode().json) {}

TerminalProgress::~TerminalProgress() { clear(); }

void TerminalProgress::step(std::size_t index, std::size_t count, const std::string& name) {
  if (lines_) {  // -v in a pipe or a log: one line per step
    std::lock_guard lock(mutex_);
    std::fprintf(out_, "[%zu/%zu] %s\n", index + 1, count, name.c_str());
    std::fflush(out_);
  }
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  step_ = fmt::format("[{}/{}] {}", index + 1, count, name);
  detail_.clear();
  step_start_ = Clock::now();
  draw();
  if (!ticker_.joinable())
    ticker_ = std::jthread([this](std::stop_token stop) {
      while (!stop.stop_requested()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(250));
        std::lock_guard tick(mutex_);
        if (!stop.stop_requested()) draw();
      }
    });
}

void TerminalProgress::detail(const std::string& what, std::size_t done, std::size_t total) {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  detail_ = fmt::format(": {} ({}/{})", what, done + 1, total);
  draw();
}

void TerminalProgress::clear() {
  if (!enabled_) return;
  if (ticker_.joinable()) {
    ticker_.request_stop();
    ticker_.join();
  }
  std::lock_guard lock(mutex_);
  if (!shown_) return;
  std::fputs("\r\x1b[K", out_);
  std::fflush(out_);
  shown_ = false;
}

void TerminalProgress::draw() {
  const double seconds = std::chrono::duration<double>(Clock::now() - step_start_).count();
  std::string line = step_ + detail_ + fmt::format("  {:.0f} s", seconds);
  winsize size{};
  const std::size_t width = ioctl(fileno(out_), TIOCGWINSZ, &size) == 0 && size.ws_col > 0 ? size.ws_col : 80;
  if (line.size() >= width) line.resize(width - 1);
  std::fprintf(out_, "\r%s\x1b[K", line.c_str());
  std::fflush(out_);
  shown_ = true;
}

}  // namespace lmcal::cli
