#include "tendril/core/error.h"

namespace tendril {

namespace {
thread_local uint64_t gErrorsCreated = 0;
}

uint64_t Error::createdOnThisThread() { return gErrorsCreated; }

Error::Error(std::string source, std::string location, std::string message)
    : source_(std::move(source)), location_(std::move(location)), message_(std::move(message)) {
  ++gErrorsCreated;
  // One line, always: a newline in a message (e.g. from a third-party parser) is folded.
  for (char& c : message_)
    if (c == '\n' || c == '\r') c = ' ';
  if (!source_.empty()) what_ += source_ + ":";
  if (!location_.empty()) what_ += location_ + ":";
  if (!what_.empty()) what_ += " ";
  what_ += message_;
}

}  // namespace tendril
