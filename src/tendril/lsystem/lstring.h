// The string an L-system rewrites, stored flat: one small module id per module, an offset into
// one shared float pool for its parameters, and the derivation step it was produced in (for
// node ages). No per-module allocation: a derivation step writes three arrays front to back.
#pragma once

#include <cassert>
#include <cstdint>
#include <span>
#include <vector>

namespace tendril::lsystem {

// Index into Grammar::modules(). A module name used with different parameter counts (turtle
// modules such as F and F(l)) has one id per count.
using ModuleId = uint16_t;

struct LString {
  std::vector<ModuleId> ids;
  std::vector<uint32_t> paramStart{0};  // size() + 1 entries; module i owns params[paramStart[i] ..)
  std::vector<float> params;
  std::vector<uint32_t> birth;  // derivation step that produced the module

  size_t size() const { return ids.size(); }
  bool empty() const { return ids.empty(); }
  uint32_t paramCount(size_t i) const { return paramStart[i + 1] - paramStart[i]; }
  const float* paramsOf(size_t i) const { return params.data() + paramStart[i]; }
  float* paramsOf(size_t i) { return params.data() + paramStart[i]; }

  void clear() {
    ids.clear();
    paramStart.assign(1, 0);
    params.clear();
    birth.clear();
  }
  void reserve(size_t modules, size_t floats) {
    ids.reserve(modules);
    paramStart.reserve(modules + 1);
    birth.reserve(modules);
    params.reserve(floats);
  }
  void push(ModuleId id, const float* p, uint32_t n, uint32_t born) {
    ids.push_back(id);
    params.insert(params.end(), p, p + n);
    paramStart.push_back(static_cast<uint32_t>(params.size()));
    birth.push_back(born);
  }
  // Appends modules [from, to) of `other`, keeping their birth steps.
  void append(const LString& other, size_t from, size_t to) {
    if (from >= to) return;
    uint32_t base = static_cast<uint32_t>(params.size());
    uint32_t first = other.paramStart[from];
    ids.insert(ids.end(), other.ids.begin() + from, other.ids.begin() + to);
    birth.insert(birth.end(), other.birth.begin() + from, other.birth.begin() + to);
    params.insert(params.end(), other.params.begin() + first, other.params.begin() + other.paramStart[to]);
    for (size_t i = from + 1; i <= to; ++i) paramStart.push_back(other.paramStart[i] - first + base);
  }
  void swap(LString& o) noexcept {
    ids.swap(o.ids);
    paramStart.swap(o.paramStart);
    params.swap(o.params);
    birth.swap(o.birth);
  }
};

}  // namespace tendril::lsystem
