#include "tendril/env/triangle_bvh.h"

#include "tendril/core/error.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <new>

namespace tendril::env {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

RTCDevice builderDevice() {
  static RTCDevice device = [] {
    RTCDevice d = rtcNewDevice(nullptr);
    if (!d) throw Error("Embree", "", "cannot create the BVH builder device");
    return d;
  }();
  return device;
}

TriangleBvh::Node* newNode(RTCThreadLocalAllocator alloc, bool leaf) {
  auto* n = new (rtcThreadLocalAlloc(alloc, sizeof(TriangleBvh::Node), 16)) TriangleBvh::Node;
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 4; ++c) {
      n->lo[a][c] = kInf;
      n->hi[a][c] = -kInf;
    }
  for (const TriangleBvh::Node*& c : n->child) c = nullptr;
  n->leaf = leaf ? 1u : 0u;
  return n;
}

void* createNode(RTCThreadLocalAllocator alloc, unsigned int, void*) { return newNode(alloc, false); }

void setChildren(void* node, void** children, unsigned int count, void*) {
  auto* n = static_cast<TriangleBvh::Node*>(node);
  for (unsigned int c = 0; c < count; ++c) n->child[c] = static_cast<const TriangleBvh::Node*>(children[c]);
}

void setBounds(void* node, const RTCBounds** bounds, unsigned int count, void*) {
  auto* n = static_cast<TriangleBvh::Node*>(node);
  for (unsigned int c = 0; c < count; ++c) {
    n->lo[0][c] = bounds[c]->lower_x;
    n->lo[1][c] = bounds[c]->lower_y;
    n->lo[2][c] = bounds[c]->lower_z;
    n->hi[0][c] = bounds[c]->upper_x;
    n->hi[1][c] = bounds[c]->upper_y;
    n->hi[2][c] = bounds[c]->upper_z;
  }
}

void* createLeaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* prims, size_t count, void*) {
  TriangleBvh::Node* n = newNode(alloc, true);
  for (size_t i = 0; i < count; ++i) {  // count <= maxLeafSize = 4
    n->lo[0][i] = prims[i].lower_x;
    n->lo[1][i] = prims[i].lower_y;
    n->lo[2][i] = prims[i].lower_z;
    n->hi[0][i] = prims[i].upper_x;
    n->hi[1][i] = prims[i].upper_y;
    n->hi[2][i] = prims[i].upper_z;
    n->triangle[i] = prims[i].primID;
  }
  return n;
}

}  // namespace

TriangleBvh::~TriangleBvh() {
  if (bvh_) rtcReleaseBVH(static_cast<RTCBVH>(bvh_));
}

void TriangleBvh::build(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices) {
  if (bvh_) rtcReleaseBVH(static_cast<RTCBVH>(bvh_));
  bvh_ = nullptr;
  root_ = nullptr;
  bounds_ = Bounds3();
  const size_t n = indices.size() / 3;
  if (n == 0) return;
  // Triangles far larger than the typical one (the long thin fan closing a slab's back) are
  // entered as several pieces, each the box of the triangle clipped to a part of its own box:
  // one box over a 30 m sliver would overlap every subtree it passes and send queries anywhere
  // along it down all of them. A piece box contains every point of the triangle in its part,
  // so a query still meets every triangle within its radius (possibly more than once).
  std::vector<Bounds3> boxes(n);
  std::vector<float> extent(n);
  for (size_t t = 0; t < n; ++t) {
    for (int k = 0; k < 3; ++k) boxes[t].extend(positions[indices[3 * t + k]]);
    bounds_.extend(boxes[t]);
    extent[t] = boxes[t].size().maxCoeff();
  }
  std::vector<float> sorted = extent;
  std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.end());
  float limit = 32.0f * sorted[n / 2];
  limit = std::max(limit, bounds_.size().maxCoeff() / 4096.0f);
  if (!(limit > 0.0f)) limit = kInf;

  std::vector<RTCBuildPrimitive> prims;
  prims.reserve(n + n / 8);
  auto add = [&](const Bounds3& b, size_t t) {
    RTCBuildPrimitive p;
    p.lower_x = b.min.x();
    p.lower_y = b.min.y();
    p.lower_z = b.min.z();
    p.upper_x = b.max.x();
    p.upper_y = b.max.y();
    p.upper_z = b.max.z();
    p.geomID = 0;
    p.primID = static_cast<unsigned>(t);
    prims.push_back(p);
  };
  std::vector<Bounds3> pending;
  for (size_t t = 0; t < n; ++t) {
    if (extent[t] <= limit) {
      add(boxes[t], t);
      continue;
    }
    const Vec3 v[3] = {positions[indices[3 * t]], positions[indices[3 * t + 1]], positions[indices[3 * t + 2]]};
    // At most 32 parts along any axis, so one huge triangle never floods the tree.
    const float partLimit = std::max(limit, extent[t] / 32.0f);
    pending.assign(1, boxes[t]);
    while (!pending.empty()) {
      const Bounds3 b = pending.back();
      pending.pop_back();
      int axis;
      const float size = b.size().maxCoeff(&axis);
      if (size <= partLimit) {
        add(b, t);
        continue;
      }
      // Halve the part along its longest axis: each half gets the box of the triangle's
      // points on its side of the plane (vertices and edge crossings), cut to the half.
      const float at = 0.5f * (b.min[axis] + b.max[axis]);
      Bounds3 lo, hi;
      for (int k = 0; k < 3; ++k) {
        const Vec3& a = v[k];
        const Vec3& c = v[(k + 1) % 3];
        if (a[axis] <= at) lo.extend(a);
        if (a[axis] >= at) hi.extend(a);
        if ((a[axis] < at && at < c[axis]) || (c[axis] < at && at < a[axis])) {
          const float s = (at - a[axis]) / (c[axis] - a[axis]);
          Vec3 x = a + s * (c - a);
          x[axis] = at;
          lo.extend(x);
          hi.extend(x);
        }
      }
      for (Bounds3* half : {&lo, &hi}) {
        if (half->empty()) continue;
        half->min = half->min.cwiseMax(b.min);
        half->max = half->max.cwiseMin(b.max);
        if (half == &lo) half->max[axis] = std::min(half->max[axis], at);
        else half->min[axis] = std::max(half->min[axis], at);
        if ((half->min.array() <= half->max.array()).all()) pending.push_back(*half);
      }
    }
  }
  RTCBVH bvh = rtcNewBVH(builderDevice());
  RTCBuildArguments args = rtcDefaultBuildArguments();
  args.buildQuality = RTC_BUILD_QUALITY_MEDIUM;  // binned SAH, no spatial splits
  args.maxBranchingFactor = 4;
  args.maxDepth = 64;  // forEachNear's stack holds 3 entries per level
  args.minLeafSize = 1;
  args.maxLeafSize = 4;  // a leaf is one four-wide box test, like an inner node
  args.traversalCost = 1.0f;
  args.intersectionCost = 1.0f;
  args.bvh = bvh;
  args.primitives = prims.data();
  args.primitiveCount = prims.size();
  args.primitiveArrayCapacity = prims.size();  // no spatial splits of its own
  args.createNode = createNode;
  args.setNodeChildren = setChildren;
  args.setNodeBounds = setBounds;
  args.createLeaf = createLeaf;
  args.splitPrimitive = nullptr;
  void* root = rtcBuildBVH(&args);
  if (!root) {
    rtcReleaseBVH(bvh);
    throw Error("Embree", "", "cannot build the closest-point BVH");
  }
  bvh_ = bvh;
  root_ = static_cast<const Node*>(root);
}

}  // namespace tendril::env
