// Synthetic PlantModels for mesh and export tests and benchmarks (header-only so that bench/
// can use it too).
#pragma once

#include "tendril/core/math.h"
#include "tendril/core/random.h"
#include "tendril/plant/plant_model.h"

#include <cmath>

namespace tendril::meshtest {

using plant::PlantModel;

// n segments straight up +Y from `base`, radius tapering linearly from r0 to r1.
inline PlantModel straightChain(int n, float segment = 0.1f, float r0 = 0.02f, float r1 = 0.01f,
                                Vec3 base = Vec3::Zero()) {
  PlantModel p;
  p.name = "straight";
  int32_t prev = -1;
  for (int i = 0; i < n; ++i) {
    PlantModel::NodeDef d;
    d.position = base + Vec3(0, segment * i, 0);
    d.length = segment;
    d.radius = n > 1 ? r0 + (r1 - r0) * float(i) / float(n - 1) : r0;
    d.parent = prev;
    prev = p.addNode(d);
  }
  return p;
}

// n segments along a circular arc of radius `bend` in the XY plane (starting at the origin
// going +Y, curving toward +X); node +Z is the plane normal.
inline PlantModel arcChain(int n, float bend = 0.5f, float sweep = 2.0f, float radius = 0.01f) {
  PlantModel p;
  p.name = "arc";
  auto at = [&](int i) {
    float a = sweep * float(i) / float(n);
    return Vec3(bend * (1.0f - std::cos(a)), bend * std::sin(a), 0.0f);
  };
  int32_t prev = -1;
  for (int i = 0; i < n; ++i) {
    Vec3 a = at(i), b = at(i + 1);
    PlantModel::NodeDef d;
    d.position = a;
    d.length = (b - a).norm();
    d.orientation = frameFromYZ(b - a, Vec3::UnitZ());
    d.radius = radius;
    d.parent = prev;
    prev = p.addNode(d);
  }
  return p;
}

// A main stem of 6 nodes; node 1 has a lateral branch (kNodeBranchStart, 3 nodes); node 3 has
// two unflagged children (the first continues the stem, the second starts a chain of 2);
// node 4 has a flagged lateral of 1 node. Chains: [0 1 2 3 4 5], [6 7 8], [9 10], [11] in
// the node order below.
inline PlantModel branchingTree() {
  PlantModel p;
  p.name = "tree";
  auto add = [&](int32_t parent, Vec3 pos, Vec3 dir, float len, float r, uint32_t flags = 0, uint16_t order = 0) {
    PlantModel::NodeDef d;
    d.position = pos;
    d.orientation = frameFromYZ(dir, Vec3::UnitZ());
    d.length = len;
    d.radius = r;
    d.parent = parent;
    d.flags = flags;
    d.order = order;
    return p.addNode(d);
  };
  int32_t prev = -1;
  for (int i = 0; i < 6; ++i) prev = add(prev, Vec3(0, 0.2f * i, 0), Vec3::UnitY(), 0.2f, 0.03f - 0.003f * i);
  // Children listed after the stem: parents still come before children.
  Vec3 side = Vec3(1, 1, 0).normalized();
  int32_t b = add(1, p.tip(1) - 0.1f * Vec3::UnitY(), side, 0.15f, 0.012f, plant::kNodeBranchStart, 1);
  b = add(b, p.tip(b), side, 0.15f, 0.01f, 0, 1);
  add(b, p.tip(b), side, 0.15f, 0.008f, 0, 1);
  Vec3 other = Vec3(-1, 2, 0.5f).normalized();
  int32_t c = add(3, p.tip(3), other, 0.2f, 0.015f, 0, 1);
  add(c, p.tip(c), other, 0.2f, 0.012f, 0, 1);
  add(4, p.position[4] + Vec3(0, 0.1f, 0), Vec3(0, 0.3f, 1), 0.1f, 0.008f, plant::kNodeBranchStart, 1);
  return p;
}

// Leaves with `shapes` shapes on every other node, alternating sides.
inline void addLeaves(PlantModel& p, int shapes, float size = 0.06f) {
  static const char* kTextures[] = {"builtin:ivy-0", "builtin:ivy-1", "builtin:heart-0", "builtin:ovate-0"};
  for (int s = 0; s < shapes; ++s) {
    plant::LeafShape shape;
    shape.texture = kTextures[s % 4];
    shape.aspect = 0.8f + 0.1f * s;
    shape.tint = Vec3(1.0f, 0.9f, 0.8f + 0.05f * s);
    p.leafShapes.push_back(shape);
  }
  for (size_t n = 0, k = 0; n < p.nodeCount(); n += 2, ++k) {
    PlantModel::LeafDef l;
    l.node = static_cast<int32_t>(n);
    l.offset = Vec3(0, 0.5f * p.length[n], 0);
    float side = (k % 2) ? 1.0f : -1.0f;
    l.rotation = axisAngle(Vec3::UnitZ(), side * 0.8f) * axisAngle(Vec3::UnitX(), -0.3f);
    l.size = size;
    l.petiole = 0.3f * size;
    l.shape = static_cast<uint16_t>(k % static_cast<size_t>(shapes));
    p.addLeaf(l);
  }
}

// A climbing-ivy-like plant of about `segments` nodes: random-walk stems on the XY plane (a
// wall facing +Z), a lateral every ~12 nodes, a leaf on every other node. Deterministic.
inline PlantModel syntheticIvy(size_t segments, uint64_t seed = 1) {
  PlantModel p;
  p.name = "ivy";
  p.reserve(segments, segments / 2 + 1);
  for (const char* t : {"builtin:ivy-0", "builtin:ivy-1", "builtin:ivy-2"}) {
    plant::LeafShape s;
    s.texture = t;
    p.leafShapes.push_back(s);
  }
  struct Tip {
    int32_t node;
    int left;
  };
  std::vector<Tip> tips;
  uint64_t step = 0;
  auto grow = [&](int32_t parent, Vec3 pos, Vec3 dir, uint32_t flags, uint16_t order) {
    Rng rng(RandomKey{seed, 0, p.nodeCount(), step, purposeId("test.ivy")});
    dir = (dir + 0.25f * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), 0)).normalized();
    PlantModel::NodeDef d;
    d.position = pos;
    d.orientation = frameFromYZ(dir, Vec3::UnitZ());
    d.length = 0.02f;
    d.radius = std::max(0.0015f, 0.006f - 0.0015f * order);
    d.parent = parent;
    d.flags = flags;
    d.order = order;
    int32_t n = p.addNode(d);
    if (n % 2 == 0) {
      PlantModel::LeafDef l;
      l.node = n;
      l.offset = Vec3(0, 0.01f, 0);
      l.rotation = axisAngle(Vec3::UnitZ(), rng.uniform(-1.0f, 1.0f));
      l.size = 0.05f;
      l.petiole = 0.02f;
      l.shape = static_cast<uint16_t>(rng.below(3));
      p.addLeaf(l);
    }
    return n;
  };
  tips.push_back({grow(-1, Vec3::Zero(), Vec3::UnitY(), 0, 0), 400});
  while (p.nodeCount() < segments) {
    ++step;
    std::vector<Tip> next;
    for (const Tip& t : tips) {
      if (p.nodeCount() >= segments) break;
      int32_t n = grow(t.node, p.tip(t.node), p.direction(t.node), 0, p.order[t.node]);
      if (t.left > 1) next.push_back({n, t.left - 1});
      if (n % 12 == 0 && p.nodeCount() < segments) {
        Vec3 side = p.orientation[n] * Vec3(n % 24 == 0 ? 1.0f : -1.0f, 1.0f, 0.0f).normalized();
        int32_t b = grow(n, p.tip(n), side, plant::kNodeBranchStart, static_cast<uint16_t>(p.order[n] + 1));
        next.push_back({b, 200});
      }
    }
    if (next.empty()) next.push_back({static_cast<int32_t>(p.nodeCount() - 1), 400});
    tips = std::move(next);
  }
  return p;
}

}  // namespace tendril::meshtest
