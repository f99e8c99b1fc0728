// Logging to stderr through spdlog, behind a small interface so that modules do not pull
// spdlog's headers. Messages are formatted with fmt.
#pragma once

#include <fmt/format.h>

#include <string>
#include <string_view>
#include <vector>

namespace tendril::log {

enum class Level { Debug, Info, Warn, Error, Off };

void setLevel(Level level);
Level level();
void write(Level level, std::string_view message);

// While one lives, the warnings and errors written on this thread go into `into` instead of
// stderr (the Python module hands a session's warnings to Python this way). Captures nest; the
// innermost one takes the messages.
class ThreadCapture {
 public:
  explicit ThreadCapture(std::vector<std::string>* into);
  ~ThreadCapture();
  ThreadCapture(const ThreadCapture&) = delete;
  ThreadCapture& operator=(const ThreadCapture&) = delete;

 private:
  std::vector<std::string>* previous_;
};

template <class... Args>
void debug(fmt::format_string<Args...> f, Args&&... args) {
  if (level() <= Level::Debug) write(Level::Debug, fmt::format(f, std::forward<Args>(args)...));
}
template <class... Args>
void info(fmt::format_string<Args...> f, Args&&... args) {
  if (level() <= Level::Info) write(Level::Info, fmt::format(f, std::forward<Args>(args)...));
}
template <class... Args>
void warn(fmt::format_string<Args...> f, Args&&... args) {
  if (level() <= Level::Warn) write(Level::Warn, fmt::format(f, std::forward<Args>(args)...));
}
template <class... Args>
void error(fmt::format_string<Args...> f, Args&&... args) {
  if (level() <= Level::Error) write(Level::Error, fmt::format(f, std::forward<Args>(args)...));
}

}  // namespace tendril::log
