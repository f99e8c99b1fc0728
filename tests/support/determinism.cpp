#include "support/determinism.h"

#include "tendril/core/parallel.h"

#include <tbb/info.h>

namespace tendril::test {

ScopedThreadCount::ScopedThreadCount(int threads) {
  const int current = threadCount();
  before_ = current == tbb::info::default_concurrency() ? 0 : current;
  setThreadCount(threads);
}

ScopedThreadCount::~ScopedThreadCount() { setThreadCount(before_); }

namespace detail {
std::string threadCountMismatch(int threads, const std::string& got, const std::string& expected) {
  return "the result at " + std::to_string(threads) + " worker threads, " + got +
         ", differs from the result at 1 thread, " + expected +
         ": something depends on the order in which threads finish (docs/architecture.md, \"Determinism\")";
}
}  // namespace detail

}  // namespace tendril::test
