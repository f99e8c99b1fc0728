// Parallel work over a few items of very unequal size (plants, the connected pieces of a
// particle world), each done whole by one thread.
#pragma once

#include "tendril/core/parallel.h"

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <span>
#include <vector>

namespace tendril {

// Calls f(i) for i in [0, sizes.size()), each item whole on one thread: the largest (by `sizes`,
// any measure of its work) is started first, and the next is taken by whichever thread is free
// (greedy largest-first). The threads then finish at about the same time, where parallelFor's
// halving of the index range can leave one thread waiting while the other works through a large
// item it started last. Items must be independent of each other: which thread runs an item, and
// when, never changes its result.
template <class F>
void parallelForLargestFirst(std::span<const size_t> sizes, F&& f) {
  const size_t n = sizes.size();
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return sizes[a] > sizes[b]; });
  const size_t workers = std::min(n, size_t(std::max(1, threadCount())));
  if (workers <= 1) {
    for (uint32_t i : order) f(size_t(i));
    return;
  }
  std::atomic<size_t> next{0};
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, workers, 1),
      [&](const tbb::blocked_range<size_t>&) {
        for (size_t k = next.fetch_add(1, std::memory_order_relaxed); k < n;
             k = next.fetch_add(1, std::memory_order_relaxed))
          f(size_t(order[k]));
      },
      tbb::simple_partitioner());
}

}  // namespace tendril
