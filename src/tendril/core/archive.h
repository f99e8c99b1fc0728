// A small binary archive for simulation state (undo snapshots, session files): little-endian
// fixed-width numbers, length-prefixed strings and vectors, and vectors of plain records
// (trivially copyable or standard-layout value types such as Vec3, Quat or a flat struct) as
// one raw block each, so that a field added to such a record is saved without further code.
//
// The reader checks every length against the bytes left and throws
// Error(source, "byte N", message) on truncated or garbage input; it never reads past the end
// or allocates more than the input could hold.
#pragma once

#include "tendril/core/error.h"

#include <bit>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace tendril {

static_assert(std::endian::native == std::endian::little, "archives are written little-endian");

// Value types that go into an archive as their bytes: no pointers, no owning members.
template <class T>
concept ArchivePlain = (std::is_trivially_copyable_v<T> || std::is_standard_layout_v<T>) && !std::is_pointer_v<T> &&
                       std::is_trivially_destructible_v<T>;

class ArchiveWriter {
 public:
  void bytes(const void* data, size_t n) {
    const auto* p = static_cast<const uint8_t*>(data);
    data_.insert(data_.end(), p, p + n);
  }
  template <ArchivePlain T>
  void value(const T& v) {
    bytes(&v, sizeof(T));
  }
  void u8(uint8_t v) { value(v); }
  void u32(uint32_t v) { value(v); }
  void u64(uint64_t v) { value(v); }
  void f32(float v) { value(v); }
  void boolean(bool v) { u8(v ? 1 : 0); }
  void string(std::string_view s) {
    u64(s.size());
    bytes(s.data(), s.size());
  }
  template <ArchivePlain T>
  void vector(const std::vector<T>& v) {
    u64(v.size());
    u32(uint32_t(sizeof(T)));  // a record size change is caught on reading
    if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
  }
  void strings(const std::vector<std::string>& v) {
    u64(v.size());
    for (const std::string& s : v) string(s);
  }
  // A tag that the reader checks (catches a reader out of step with the writer).
  void tag(uint32_t t) { u32(t); }

  const std::vector<uint8_t>& data() const { return data_; }
  std::vector<uint8_t> take() { return std::move(data_); }
  size_t size() const { return data_.size(); }

 private:
  std::vector<uint8_t> data_;
};

class ArchiveReader {
 public:
  // `source` names the input in errors (a file path or "session state").
  ArchiveReader(std::span<const uint8_t> data, std::string source) : data_(data), source_(std::move(source)) {}

  void bytes(void* out, size_t n) {
    need(n, "data");
    std::memcpy(out, data_.data() + pos_, n);
    pos_ += n;
  }
  template <ArchivePlain T>
  T value() {
    T v;
    bytes(&v, sizeof(T));
    return v;
  }
  template <ArchivePlain T>
  void value(T& v) {
    bytes(&v, sizeof(T));
  }
  uint8_t u8() { return value<uint8_t>(); }
  uint32_t u32() { return value<uint32_t>(); }
  uint64_t u64() { return value<uint64_t>(); }
  float f32() { return value<float>(); }
  bool boolean() {
    size_t at = pos_;
    uint8_t b = u8();
    if (b > 1) fail(at, "expected a boolean (0 or 1), got " + std::to_string(b));
    return b != 0;
  }
  // A count of items of at least `minItemBytes` each that the remaining input could hold.
  uint64_t count(size_t minItemBytes, const char* what) {
    size_t at = pos_;
    uint64_t n = u64();
    if (minItemBytes > 0 && n > remaining() / minItemBytes)
      fail(at, "length " + std::to_string(n) + " of " + what + " is longer than the data left");
    return n;
  }
  std::string string() {
    uint64_t n = count(1, "a string");
    std::string s(size_t(n), '\0');
    if (n) bytes(s.data(), size_t(n));
    return s;
  }
  template <ArchivePlain T>
  void vector(std::vector<T>& v) {
    uint64_t n = count(0, "a vector");
    size_t at = pos_;
    uint32_t size = u32();
    if (size != sizeof(T))
      fail(at, "record size " + std::to_string(size) + " where this build uses " + std::to_string(sizeof(T)));
    if (n > remaining() / sizeof(T))
      fail(at, "length " + std::to_string(n) + " of a vector is longer than the data left");
    v.resize(size_t(n));
    if (n) bytes(v.data(), size_t(n) * sizeof(T));
  }
  template <ArchivePlain T>
  std::vector<T> vector() {
    std::vector<T> v;
    vector(v);
    return v;
  }
  std::vector<std::string> strings() {
    uint64_t n = count(8, "a string list");
    std::vector<std::string> v;
    v.reserve(size_t(n));
    for (uint64_t i = 0; i < n; ++i) v.push_back(string());
    return v;
  }
  void tag(uint32_t expected, const char* what) {
    size_t at = pos_;
    if (u32() != expected) fail(at, std::string("expected the start of ") + what + " (the data is damaged)");
  }

  size_t position() const { return pos_; }
  size_t remaining() const { return data_.size() - pos_; }
  bool atEnd() const { return pos_ == data_.size(); }
  const std::string& source() const { return source_; }

  [[noreturn]] void fail(size_t at, const std::string& message) const {
    throw Error(source_, "byte " + std::to_string(at), message);
  }
  [[noreturn]] void fail(const std::string& message) const { fail(pos_, message); }

 private:
  void need(size_t n, const char* what) const {
    if (n > remaining())
      fail(pos_, std::string("truncated: ") + what + " needs " + std::to_string(n) + " bytes, " +
                     std::to_string(remaining()) + " left");
  }

  std::span<const uint8_t> data_;
  std::string source_;
  size_t pos_ = 0;
};

}  // namespace tendril
