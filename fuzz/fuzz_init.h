// The fuzz targets' one-time set-up (libFuzzer calls LLVMFuzzerInitialize before the first
// input): no log output, and one thread, so that a report replays the same way. Included by
// exactly one file per target.
#pragma once

#include "tendril/core/log.h"
#include "tendril/core/parallel.h"

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  tendril::log::setLevel(tendril::log::Level::Off);
  tendril::setThreadCount(1);
  return 0;
}
