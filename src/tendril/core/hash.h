// A stable 64-bit content hash: the same bytes give the same value on every run, build and
// thread count. Used for determinism tests and undo checks, not for security. Values are
// hashed as their bytes, so only pass types without padding (floats, ints, Eigen fixed-size).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string_view>
#include <vector>

namespace tendril {

class Hasher {
 public:
  void add(const void* data, size_t bytes);
  void add(std::string_view s) {
    add(uint64_t(s.size()));
    add(s.data(), s.size());
  }
  template <class T>
    requires(std::is_standard_layout_v<T> && !std::is_pointer_v<T>)
  void add(const T& value) {
    add(&value, sizeof(T));
  }
  template <class T>
    requires(std::is_standard_layout_v<T> && !std::is_pointer_v<T>)
  void add(const std::vector<T>& values) {
    add(uint64_t(values.size()));
    if (!values.empty()) add(values.data(), values.size() * sizeof(T));
  }
  uint64_t digest() const;

 private:
  void mixWord(uint64_t w);
  uint64_t state_ = 0x243f6a8885a308d3ull;
  uint64_t length_ = 0;
  uint8_t pending_[8] = {};
  size_t pendingBytes_ = 0;
};

inline uint64_t hashBytes(const void* data, size_t bytes) {
  Hasher h;
  h.add(data, bytes);
  return h.digest();
}

}  // namespace tendril
