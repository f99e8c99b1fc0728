// Errors in user input. An Error says where the bad input came from (a file, a JSON pointer
// or line:column inside it, or a CLI option) and what was expected. It is the only exception
// type that crosses module boundaries; programming errors are assertions instead.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace tendril {

class Error : public std::exception {
 public:
  // source: a file path or "command line"; location: "/plants/0/seed", "12:5" or "".
  Error(std::string source, std::string location, std::string message);
  explicit Error(std::string message) : Error("", "", std::move(message)) {}

  const std::string& source() const { return source_; }
  const std::string& location() const { return location_; }
  const std::string& message() const { return message_; }

  // "source:location: message" on one line (parts that are empty are left out).
  const char* what() const noexcept override { return what_.c_str(); }

  // How many Errors this thread has created so far (lets readers tell "an error was raised
  // and handled" from "a reader was left unfinished").
  static uint64_t createdOnThisThread();

 private:
  std::string source_, location_, message_, what_;
};

}  // namespace tendril
