#include "tendril/core/hash.h"

#include "tendril/core/random.h"

namespace tendril {

void Hasher::mixWord(uint64_t w) {
  // Multiply-rotate mixing per 8-byte word; the final mix64 gives full avalanche.
  state_ ^= mix64(w + 0x9e3779b97f4a7c15ull);
  state_ = (state_ << 27 | state_ >> 37) * 0x9fb21c651e98df25ull;
}

void Hasher::add(const void* data, size_t bytes) {
  const auto* p = static_cast<const uint8_t*>(data);
  length_ += bytes;
  while (bytes > 0 && pendingBytes_ > 0) {
    pending_[pendingBytes_++] = *p++;
    --bytes;
    if (pendingBytes_ == 8) {
      uint64_t w;
      std::memcpy(&w, pending_, 8);
      mixWord(w);
      pendingBytes_ = 0;
    }
  }
  while (bytes >= 8) {
    uint64_t w;
    std::memcpy(&w, p, 8);
    mixWord(w);
    p += 8;
    bytes -= 8;
  }
  while (bytes > 0) {
    pending_[pendingBytes_++] = *p++;
    --bytes;
  }
}

uint64_t Hasher::digest() const {
  uint64_t s = state_;
  if (pendingBytes_ > 0) {
    uint8_t tail[8] = {};
    std::memcpy(tail, pending_, pendingBytes_);
    uint64_t w;
    std::memcpy(&w, tail, 8);
    s ^= mix64(w + 0x9e3779b97f4a7c15ull);
    s = (s << 27 | s >> 37) * 0x9fb21c651e98df25ull;
  }
  return mix64(s ^ length_);
}

}  // namespace tendril
