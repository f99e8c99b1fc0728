// A bounding volume hierarchy over one obstacle's triangles, in the obstacle's own frame, for
// closest-point queries with a small radius (a climbing tip asking for the surface within a
// centimetre or two of it, after walking the mesh toward it: Environment::closestPoint with a
// hint).
//
// Embree answers the same question (rtcPointQuery) but pays a function call per triangle of
// every leaf the query sphere touches, and its leaves hold four or more triangles: on a
// 1M-triangle wall that was 11 callbacks and ~3,500 instructions per query. Here the leaves
// keep each triangle's bounding box, so triangles are rejected by their own box before the
// exact test, and the traversal is inline. Embree's builder (binned SAH) lays out the tree,
// which keeps long thin triangles (the fan closing a slab's back) in subtrees of their own.
//
// The tree lives in the obstacle's local frame, so moving the obstacle never rebuilds it.
#pragma once

#include "tendril/core/math.h"

#include <algorithm>
#include <cstdint>
#include <vector>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace tendril::env {

class TriangleBvh {
 public:
  TriangleBvh() = default;
  ~TriangleBvh();
  TriangleBvh(const TriangleBvh&) = delete;
  TriangleBvh& operator=(const TriangleBvh&) = delete;

  // positions and indices (3 per triangle) in the obstacle's frame; replaces any previous tree.
  void build(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices);
  bool empty() const { return root_ == nullptr; }
  const Bounds3& bounds() const { return bounds_; }

  // Calls test(triangle) for every triangle whose bounding box is no farther from p than
  // sqrt(cull2) (depth first). cull2 is read again after every call, so the caller
  // shrinks the search by lowering it as closer triangles turn up. A triangle may be offered
  // whenever its box is within reach; which ones are offered beyond that is not specified.
  template <class Test>
  void forEachNear(const Vec3& p, const float& cull2, Test&& test) const;

  // Node layout (public for the inline traversal only). Inner nodes and leaves look alike:
  // four boxes, one lane each (unused lanes empty: lo = +inf, hi = -inf), so that one
  // four-wide test serves both. A leaf holds up to four triangles, each with its own box.
  struct alignas(16) Node {
    float lo[3][4];
    float hi[3][4];
    union {
      const Node* child[4];  // inner node
      uint32_t triangle[4];  // leaf
    };
    uint32_t leaf;  // 1 for a leaf
  };

 private:
  void* bvh_ = nullptr;  // RTCBVH: owns the nodes
  const Node* root_ = nullptr;
  Bounds3 bounds_;
};

namespace detail {
// Bit c set when the node's box c lies within sqrt(cull2) of p (never for empty lanes, whose
// distance is +inf); the squared distances go to d2.
inline unsigned boxesWithin(const TriangleBvh::Node& n, const Vec3& p, float cull2, float d2[4]) {
#if defined(__SSE2__)
  __m128 s = _mm_setzero_ps();
  for (int a = 0; a < 3; ++a) {
    const __m128 q = _mm_set1_ps(p[a]);
    __m128 d = _mm_max_ps(_mm_sub_ps(_mm_load_ps(n.lo[a]), q), _mm_sub_ps(q, _mm_load_ps(n.hi[a])));
    d = _mm_max_ps(d, _mm_setzero_ps());
    s = _mm_add_ps(s, _mm_mul_ps(d, d));
  }
  _mm_storeu_ps(d2, s);
  return unsigned(_mm_movemask_ps(_mm_cmple_ps(s, _mm_set1_ps(cull2))));
#else
  unsigned mask = 0;
  for (int c = 0; c < 4; ++c) {
    float s = 0.0f;
    for (int a = 0; a < 3; ++a) {
      const float d = std::max(std::max(n.lo[a][c] - p[a], p[a] - n.hi[a][c]), 0.0f);
      s += d * d;
    }
    d2[c] = s;
    if (s <= cull2) mask |= 1u << c;
  }
  return mask;
#endif
}
}  // namespace detail

template <class Test>
void TriangleBvh::forEachNear(const Vec3& p, const float& cull2, Test&& test) const {
  if (!root_ || bounds_.squaredDistance(p) > cull2) return;
  struct Entry {
    const Node* node;
    float d2;
  };
  Entry stack[256];  // the builder's depth limit (64) times three pushes per level fits
  int top = 0;
  stack[top++] = {root_, 0.0f};
  float d2[4];
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.d2 > cull2) continue;  // cull2 may have shrunk since it was pushed
    const Node& n = *e.node;
    unsigned mask = detail::boxesWithin(n, p, cull2, d2);
    if (n.leaf) {
      for (; mask; mask &= mask - 1) {
        const int c = __builtin_ctz(mask);
        if (d2[c] <= cull2) test(n.triangle[c]);  // cull2 shrinks as closer ones turn up
      }
      continue;
    }
    for (; mask; mask &= mask - 1) {
      const int c = __builtin_ctz(mask);
      stack[top++] = {n.child[c], d2[c]};
    }
  }
}

}  // namespace tendril::env
