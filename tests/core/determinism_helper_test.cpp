// The shared determinism check (support/determinism.h) passes equal results, fails on a result
// that depends on the thread count, and leaves the thread limit as it found it.
#include "support/determinism.h"

#include "tendril/core/parallel.h"

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <atomic>
#include <tbb/info.h>

namespace tendril {
namespace {

TEST(DeterminismHelper, RunsAtEveryThreadCountAndReturnsTheResult) {
  std::vector<int> seen;
  const uint64_t r = tendril::test::sameAtEveryThreadCount([&] {
    seen.push_back(tbb::this_task_arena::max_concurrency());
    return uint64_t(42);
  });
  EXPECT_EQ(r, 42u);
  EXPECT_EQ(seen, (std::vector<int>{1, 2, 3, 8}));
}

TEST(DeterminismHelper, AResultThatDependsOnTheThreadCountFails) {
  EXPECT_NONFATAL_FAILURE(
      tendril::test::sameAtEveryThreadCount([] { return tbb::this_task_arena::max_concurrency() == 8 ? 1 : 0; }),
      "the result at 8 worker threads, 1, differs from the result at 1 thread, 0");
  // A parallel sum whose order decides the last bits would fail the same way; a sum of
  // integers does not.
  const int64_t sum = tendril::test::sameAtEveryThreadCount([] {
    std::atomic<int64_t> total = 0;
    parallelFor(0, 100000, [&](size_t i) { total += int64_t(i); });
    return total.load();
  });
  EXPECT_EQ(sum, int64_t(100000) * 99999 / 2);
}

TEST(DeterminismHelper, RestoresTheThreadLimit) {
  setThreadCount(2);
  tendril::test::sameAtEveryThreadCount([] { return 0; });
  EXPECT_EQ(threadCount(), 2);
  setThreadCount(0);
  tendril::test::sameAtEveryThreadCount([] { return 0; });
  EXPECT_EQ(threadCount(), tbb::info::default_concurrency());
}

}  // namespace
}  // namespace tendril
