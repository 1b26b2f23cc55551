#include "progress.hpp"

#include <fmt/format.h>
#include <sys/ioctl.h>
#include <unistd.h>

namespace lmcal::cli {

TerminalProgress::TerminalProgress(std::FILE* out) : out_(out), enabled_(isatty(fileno(out)) != 0) {}

TerminalProgress::~TerminalProgress() { clear(); }

void TerminalProgress::step(std::size_t index, std::size_t count, const std::string& name) {
  step_ = fmt::format("[{}/{}] {}", index + 1, count, name);
  detail_.clear();
  step_start_ = Clock::now();
  draw(true);
}

void TerminalProgress::detail(const std::string& what, std::size_t done, std::size_t total) {
  detail_ = fmt::format(": {} ({}/{})", what, done + 1, total);
  draw(false);
}

void TerminalProgress::clear() {
  if (!enabled_ || !shown_) return;
  std::fputs("\r\x1b[K", out_);
  std::fflush(out_);
  shown_ = false;
}

void TerminalProgress::draw(bool force) {
  if (!enabled_) return;
  const auto now = Clock::now();
  if (!force && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  const double seconds = std::chrono::duration<double>(now - step_start_).count();
  std::string line = step_ + detail_ + fmt::format("  {:.0f} s", seconds);
  winsize size{};
  const std::size_t width = ioctl(fileno(out_), TIOCGWINSZ, &size) == 0 && size.ws_col > 0 ? size.ws_col : 80;
  if (line.size() >= width) line.resize(width - 1);
  std::fprintf(out_, "\r%s\x1b[K", line.c_str());
  std::fflush(out_);
  shown_ = true;
}

}  // namespace lmcal::cli
