// CPU time of the whole process, every thread (s): on a machine shared with other work (or a
// virtual machine whose host is busy) it says what a frame costs better than the wall clock.
#pragma once

#include <ctime>

namespace tendril::bench {

inline double processCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

}  // namespace tendril::bench
