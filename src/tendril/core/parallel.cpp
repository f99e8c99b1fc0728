#include "tendril/core/parallel.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <memory>
#include <mutex>

namespace tendril {
namespace {
std::mutex gMutex;
std::unique_ptr<tbb::global_control> gControl;
}  // namespace

void setThreadCount(int threads) {
  std::lock_guard lock(gMutex);
  gControl.reset();
  if (threads > 0)
    gControl = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                     static_cast<size_t>(threads));
}

int threadCount() {
  return static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

}  // namespace tendril
