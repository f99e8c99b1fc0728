// parallelForLargestFirst (core/parallel_largest_first.h): every item once at every thread count,
// the largest started first.
#include "tendril/core/parallel_largest_first.h"

#include "support/determinism.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace tendril {
namespace {

TEST(ParallelLargestFirst, EveryItemOnceAtEveryThreadCount) {
  const std::vector<size_t> sizes = {3, 40, 0, 7, 7, 1000, 2, 7, 19, 1};
  tendril::test::sameAtEveryThreadCount([&] {
    std::vector<std::atomic<int>> seen(sizes.size());
    parallelForLargestFirst(sizes, [&](size_t i) { ++seen[i]; });
    uint64_t all = 0;
    for (size_t i = 0; i < seen.size(); ++i) {
      EXPECT_EQ(seen[i].load(), 1) << "item " << i;
      all = all * 10 + uint64_t(seen[i].load());
    }
    return all;
  });
  parallelForLargestFirst(std::span<const size_t>(), [](size_t) { FAIL() << "no items, no calls"; });
}

TEST(ParallelLargestFirst, OneThreadStartsTheLargestFirst) {
  setThreadCount(1);
  const std::vector<size_t> sizes = {3, 40, 0, 7, 7, 1000, 2, 7};
  std::vector<size_t> order;
  parallelForLargestFirst(sizes, [&](size_t i) { order.push_back(i); });
  setThreadCount(0);
  EXPECT_EQ(order, (std::vector<size_t>{5, 1, 3, 4, 7, 0, 6, 2}));  // equal sizes in index order
}

TEST(ParallelLargestFirst, TheLargestIsStartedBeforeAnyOtherAtEveryThreadCount) {
  // Every other item waits (up to 5 s) for the largest, the last by index, to have started:
  // where the largest is not taken first (halving the index range gives the items in index
  // order to each thread), they wait in vain.
  for (int threads : {1, 2}) {
    setThreadCount(threads);
    const std::vector<size_t> sizes = {1, 2, 1, 3, 1, 2, 1, 100};
    std::atomic<bool> largestStarted{false};
    std::atomic<int> waitedInVain{0};
    parallelForLargestFirst(sizes, [&](size_t i) {
      if (i == sizes.size() - 1) {
        largestStarted = true;
        return;
      }
      const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
      while (!largestStarted.load() && std::chrono::steady_clock::now() < until) std::this_thread::yield();
      if (!largestStarted.load()) ++waitedInVain;
    });
    EXPECT_EQ(waitedInVain.load(), 0) << threads << " threads";
  }
  setThreadCount(0);
}

}  // namespace
}  // namespace tendril
