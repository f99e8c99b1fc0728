#include "tendril/core/progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace tendril {

Progress::Progress(std::string label, uint64_t total, bool enabled)
    : label_(std::move(label)),
      total_(std::max<uint64_t>(total, 1)),
      enabled_(enabled),
      terminal_(isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()),
      lastDraw_(start_) {}

Progress::~Progress() {
  if (enabled_ && !finished_ && terminal_) std::fputc('\n', stderr);
}

void Progress::update(uint64_t done, const std::string& detail) {
  if (!enabled_ || finished_) return;
  auto now = std::chrono::steady_clock::now();
  if (terminal_) {
    // Redraw at most 10 times a second.
    if (now - lastDraw_ < std::chrono::milliseconds(100)) return;
    lastDraw_ = now;
    draw(done, detail, false);
  } else {
    int decile = static_cast<int>(std::min<uint64_t>(done, total_) * 10 / total_);
    if (decile == lastDecile_) return;
    lastDecile_ = decile;
    draw(done, detail, false);
  }
}

void Progress::finish(const std::string& detail) {
  if (!enabled_ || finished_) return;
  draw(total_, detail, true);
  finished_ = true;
}

void Progress::draw(uint64_t done, const std::string& detail, bool final) {
  done = std::min(done, total_);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  int percent = static_cast<int>(done * 100 / total_);
  std::string line;
  if (terminal_) {
    constexpr int kWidth = 30;
    int filled = static_cast<int>(done * kWidth / total_);
    line = fmt::format("\r{} [{}{}] {:3d}% {:.1f}s {}", label_, std::string(filled, '#'),
                       std::string(kWidth - filled, '.'), percent, seconds, detail);
    line += "\x1b[K";  // clear the rest of the line
    if (final) line += "\n";
  } else {
    line = fmt::format("{}: {}% ({}/{}) {:.1f}s {}\n", label_, percent, done, total_, seconds, detail);
  }
  std::fputs(line.c_str(), stderr);
  std::fflush(stderr);
}

}  // namespace tendril
