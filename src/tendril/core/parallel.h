// Parallel loops over TBB. The thread count is process-wide (--threads); results never depend
// on it because every parallel loop writes to its own slots and random numbers are keyed.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>

namespace tendril {

// Limits the worker threads used by Tendril, TBB and Embree. 0 = all hardware threads.
void setThreadCount(int threads);
// The current limit (the hardware concurrency when unlimited).
int threadCount();

// Calls f(i) for i in [begin, end), in parallel chunks of at least `grain` items.
template <class F>
void parallelFor(size_t begin, size_t end, F&& f, size_t grain = 64) {
  if (end <= begin) return;
  if (end - begin <= grain) {
    for (size_t i = begin; i < end; ++i) f(i);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, grain),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t i = r.begin(); i != r.end(); ++i) f(i);
                    });
}

// Calls f(begin, end) on disjoint sub-ranges covering [begin, end).
template <class F>
void parallelForRange(size_t begin, size_t end, F&& f, size_t grain = 64) {
  if (end <= begin) return;
  if (end - begin <= grain) {
    f(begin, end);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, grain),
                    [&](const tbb::blocked_range<size_t>& r) { f(r.begin(), r.end()); });
}

}  // namespace tendril
