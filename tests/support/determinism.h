// Results never depend on the thread count (docs/architecture.md, "Determinism"): the one
// helper the tests check it with. It runs a job at 1, 2, 3 and 8 worker threads and expects
// bit-identical results.
//
//   uint64_t hash = tendril::test::sameAtEveryThreadCount([&] { return plant::contentHash(grow(scene)); });
#pragma once

#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace tendril::test {

// The worker-thread counts every determinism check runs at: one, the machine's usual few, an
// odd count (uneven chunks) and more threads than most machines have cores.
inline constexpr int kThreadCounts[] = {1, 2, 3, 8};

// Limits the worker threads (tendril::setThreadCount) for its lifetime; the limit in force
// before comes back afterwards (also when a test fails half-way).
class ScopedThreadCount {
 public:
  explicit ScopedThreadCount(int threads);
  ~ScopedThreadCount();
  ScopedThreadCount(const ScopedThreadCount&) = delete;
  ScopedThreadCount& operator=(const ScopedThreadCount&) = delete;

 private:
  int before_ = 0;  // 0 = no limit
};

namespace detail {
// The failure message for a result at `threads` that differs from the one at one thread.
std::string threadCountMismatch(int threads, const std::string& got, const std::string& expected);
// A short description of a result: numbers as they are, strings and vectors by their size.
template <class T>
std::string describe(const T& value) {
  if constexpr (std::is_arithmetic_v<T>) return std::to_string(value);
  else if constexpr (requires { value.size(); }) return std::to_string(value.size()) + " elements";
  else return "another value";
}
}  // namespace detail

// Runs job() once at each of kThreadCounts worker threads — in a task arena of that many, so
// that 3 and 8 threads really run even on a machine with fewer cores — and adds a test failure
// (naming the thread count) for each result that is not equal (==) to the result at one
// thread. Returns the result at one thread. The thread limit in force before is restored.
template <class Job>
auto sameAtEveryThreadCount(Job&& job) -> std::decay_t<std::invoke_result_t<Job&>> {
  using Result = std::decay_t<std::invoke_result_t<Job&>>;
  std::vector<Result> results;
  for (int threads : kThreadCounts) {
    ScopedThreadCount limit(threads);
    tbb::task_arena arena(threads);
    results.push_back(arena.execute([&]() -> Result { return job(); }));
  }
  for (size_t i = 1; i < results.size(); ++i)
    if (!(results[i] == results[0]))
      ADD_FAILURE() << detail::threadCountMismatch(kThreadCounts[i], detail::describe(results[i]),
                                                   detail::describe(results[0]));
  return std::move(results[0]);
}

}  // namespace tendril::test
