#include "tendril/models/stand_off.h"

#include "tendril/core/parallel.h"

#include <algorithm>
#include <cmath>

namespace tendril::models {
namespace {

struct Ring {
  float radius;
  Vec3 dir;
};

// The push that clears point p of the surfaces near it for bark rings of these radii about
// these directions.
Vec3 clearance(const env::Environment& env, const Vec3& p, const Ring* rings, size_t count, float margin) {
  float reach = 0.0f;
  for (size_t k = 0; k < count; ++k) reach = std::max(reach, rings[k].radius);
  reach = 1.01f * reach + margin;
  if (!(reach > margin)) return Vec3::Zero();
  Vec3 push = Vec3::Zero();
  // Two passes: a point pushed off one surface (a wall) may come near another (the ground).
  for (int pass = 0; pass < 2; ++pass) {
    const Vec3 q = p + push;
    const std::optional<env::SurfacePoint> s = env.closestPoint(q, reach);
    if (!s) break;
    const bool inside = env.exactSignedDistance(q, reach) < 0.0f;
    const Vec3 n = inside ? s->normal : s->away;
    const float d = inside ? -s->distance : s->distance;
    float need = 0.0f;
    for (size_t k = 0; k < count; ++k) need = std::max(need, rings[k].radius * rings[k].dir.cross(n).norm());
    if (need <= 0.0f) break;
    need = 1.01f * need + margin;
    if (d >= need) break;
    push += (need - d) * n;
  }
  return push;
}

}  // namespace

size_t keepStemsOutside(plant::PlantModel& p, const env::Environment& env, float margin) {
  const size_t n = p.nodeCount();
  if (n == 0 || env.obstacleCount() == 0) return 0;
  // Points: every node's tip, and the start of every node that does not begin at its parent's
  // tip. Segments meeting at a point move together.
  std::vector<Vec3> dir(n), point;
  std::vector<uint32_t> startPoint(n), tipPoint(n);
  std::vector<int32_t> next(n, -1);  // the child continuing node i's chain from its tip
  point.reserve(2 * n);
  for (size_t i = 0; i < n; ++i) {
    dir[i] = p.direction(i);
    const int32_t q = p.parent[i];
    if (q >= 0 && (p.position[i] - point[tipPoint[size_t(q)]]).squaredNorm() <= 1e-12f) {
      startPoint[i] = tipPoint[size_t(q)];
      if (next[size_t(q)] < 0 && !(p.flags[i] & plant::kNodeBranchStart)) next[size_t(q)] = int32_t(i);
    } else {
      startPoint[i] = uint32_t(point.size());
      point.push_back(p.position[i]);
    }
    tipPoint[i] = uint32_t(point.size());
    point.push_back(p.tip(i));
  }
  // The rings at each point (CSR).
  const size_t m = point.size();
  std::vector<uint32_t> ringStart(m + 1, 0);
  for (size_t i = 0; i < n; ++i) ++ringStart[startPoint[i] + 1], ++ringStart[tipPoint[i] + 1];
  for (size_t k = 0; k < m; ++k) ringStart[k + 1] += ringStart[k];
  std::vector<Ring> rings(ringStart[m]);
  {
    std::vector<uint32_t> fill(ringStart.begin(), ringStart.end() - 1);
    for (size_t i = 0; i < n; ++i) {
      rings[fill[startPoint[i]]++] = {p.radius[i], dir[i]};
      rings[fill[tipPoint[i]]++] = {p.radius[i], dir[i]};
    }
  }
  // A root's base is planted: it stays where the model put it.
  std::vector<uint8_t> planted(m, 0);
  for (size_t i = 0; i < n; ++i)
    if (p.parent[i] < 0) planted[startPoint[i]] = 1;
  std::vector<Vec3> move(m, Vec3::Zero());
  parallelFor(size_t(0), m, [&](size_t k) {
    if (planted[k]) return;
    move[k] = clearance(env, point[k], rings.data() + ringStart[k], ringStart[k + 1] - ringStart[k], margin);
  }, 256);
  // Between its points the bark follows a spline (mesh/branch_sweep.h) that can bow toward a
  // surface where the chain bends: the middle of each segment (Catmull-Rom) is cleared too, by
  // moving both its points. In node order, so the result does not depend on the thread count.
  auto at = [&](uint32_t k) { return Vec3(point[k] + move[k]); };
  for (size_t i = 0; i < n; ++i) {
    if (!(p.length[i] > 0.0f)) continue;
    const int32_t q = p.parent[i];
    const Vec3 a = at(startPoint[i]), b = at(tipPoint[i]);
    const Vec3 before = q >= 0 && next[size_t(q)] == int32_t(i) ? at(startPoint[size_t(q)]) : Vec3(2.0f * a - b);
    const Vec3 after = next[i] >= 0 ? at(tipPoint[size_t(next[i])]) : Vec3(2.0f * b - a);
    const Vec3 mid = (9.0f * (a + b) - before - after) / 16.0f;
    const Vec3 chord = b - a;
    const float len = chord.norm();
    if (!(len > 0.0f)) continue;
    const float r = next[i] >= 0 ? std::max(p.radius[i], p.radius[size_t(next[i])]) : p.radius[i];
    const Ring ring{r, chord / len};
    const Vec3 push = clearance(env, mid, &ring, 1, margin);
    if (push == Vec3::Zero()) continue;
    if (!planted[startPoint[i]]) move[startPoint[i]] += push;
    move[tipPoint[i]] += push;
  }
  // No move may carry a point through a surface or a segment into one (a tight hole, a point
  // pushed off one surface onto another): such points stay where they were, and so, in turn,
  // do the points of segments that would then cross.
  parallelFor(size_t(0), m, [&](size_t k) {
    if (move[k] == Vec3::Zero()) return;
    const Vec3 to = point[k] + move[k];
    if (env.countSegmentHits(point[k], to) > 0 || env.exactSignedDistance(to, 1e-3f) < 0.0f) move[k] = Vec3::Zero();
  }, 256);
  for (int pass = 0; pass < 4; ++pass) {
    bool reverted = false;
    for (size_t i = 0; i < n; ++i) {
      const uint32_t a = startPoint[i], b = tipPoint[i];
      if (move[a] == Vec3::Zero() && move[b] == Vec3::Zero()) continue;
      if (env.countSegmentHits(at(a), at(b)) <= env.countSegmentHits(point[a], point[b])) continue;
      move[a] = move[b] = Vec3::Zero();
      reverted = true;
    }
    if (!reverted) break;
  }
  // Apply: positions, lengths and orientations follow the points.
  const std::vector<Vec3> oldPosition = p.position;
  const std::vector<Quat> oldOrientation = p.orientation;
  size_t moved = 0;
  for (size_t k = 0; k < m; ++k) moved += move[k] != Vec3::Zero();
  if (moved == 0) return 0;
  for (size_t i = 0; i < n; ++i) {
    const Vec3 a = at(startPoint[i]), b = at(tipPoint[i]);
    p.position[i] = a;
    const Vec3 ab = b - a;
    const float len = ab.norm();
    if (p.length[i] > 0.0f && len > 1e-9f) {
      const Quat turn = Quat::FromTwoVectors(dir[i], ab / len);
      p.orientation[i] = (turn * p.orientation[i]).normalized();
      p.length[i] = len;
    }
  }
  // Leaves keep their world rotation and move with their node's start.
  for (size_t j = 0; j < p.leafCount(); ++j) {
    const size_t i = size_t(p.leafNode[j]);
    const Vec3 shift = move[startPoint[i]];
    if (shift == Vec3::Zero() && p.orientation[i].coeffs() == oldOrientation[i].coeffs()) continue;
    const Vec3 world = oldPosition[i] + oldOrientation[i] * p.leafOffset[j] + shift;
    const Quat worldRotation = oldOrientation[i] * p.leafRotation[j];
    const Quat inverse = p.orientation[i].conjugate();
    p.leafOffset[j] = inverse * (world - p.position[i]);
    p.leafRotation[j] = (inverse * worldRotation).normalized();
  }
  return moved;
}

}  // namespace tendril::models
