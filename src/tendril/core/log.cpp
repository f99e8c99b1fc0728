#include "tendril/core/log.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <atomic>

namespace tendril::log {
namespace {

std::atomic<Level> gLevel{Level::Info};
thread_local std::vector<std::string>* tCapture = nullptr;

spdlog::logger& logger() {
  static std::shared_ptr<spdlog::logger> instance = [] {
    auto l = spdlog::stderr_color_mt("tendril");
    l->set_pattern("%^%l%$: %v");
    l->set_level(spdlog::level::trace);
    return l;
  }();
  return *instance;
}

}  // namespace

void setLevel(Level level) { gLevel = level; }
Level level() { return gLevel; }

ThreadCapture::ThreadCapture(std::vector<std::string>* into) : previous_(tCapture) { tCapture = into; }
ThreadCapture::~ThreadCapture() { tCapture = previous_; }

void write(Level level, std::string_view message) {
  if (level < gLevel.load()) return;
  if (tCapture && level >= Level::Warn && level != Level::Off) {
    tCapture->emplace_back(message);
    return;
  }
  switch (level) {
    case Level::Debug: logger().debug("{}", message); break;
    case Level::Info: logger().info("{}", message); break;
    case Level::Warn: logger().warn("{}", message); break;
    case Level::Error: logger().error("{}", message); break;
    case Level::Off: break;
  }
}

}  // namespace tendril::log
