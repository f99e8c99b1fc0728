// Progress report for long runs: a redrawn bar on a terminal, plain lines at every 10%
// otherwise (logs and CI), nothing when disabled (--quiet).
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace tendril {

class Progress {
 public:
  // total: number of work units; enabled = false makes every call a no-op.
  Progress(std::string label, uint64_t total, bool enabled);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void update(uint64_t done, const std::string& detail = {});
  void finish(const std::string& detail = {});

 private:
  void draw(uint64_t done, const std::string& detail, bool final);

  std::string label_;
  uint64_t total_;
  bool enabled_;
  bool terminal_;
  bool finished_ = false;
  int lastDecile_ = -1;
  std::chrono::steady_clock::time_point start_, lastDraw_;
};

}  // namespace tendril
