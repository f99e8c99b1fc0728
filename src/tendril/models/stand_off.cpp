#include "tendril/models/stand_off.h"

#include "tendril/core/curve.h"
#include "tendril/core/parallel.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tendril::models {
namespace {

struct Ring {
  float radius;
  Vec3 dir;
};

// A plane with a convex obstacle wholly behind it (env::ObstacleInfo::convex): the distance
// from any point to the obstacle is at least its distance to the plane.
struct SupportPlane {
  uint32_t obstacle = UINT32_MAX;  // none
  Vec3 point = Vec3::Zero(), normal = Vec3::Zero();
};

// The push that clears point p of the surfaces near it for bark rings of these radii about
// these directions. `deeper`: how far p may lie inside a surface (a point on a spline that
// bows through it) beyond the rings' reach. `plane`, if given, receives the plane through the
// closest point of a convex obstacle p is outside of.
Vec3 clearance(const env::Environment& env, const Vec3& p, const Ring* rings, size_t count, float margin,
               float deeper = 0.0f, SupportPlane* plane = nullptr) {
  float reach = 0.0f;
  for (size_t k = 0; k < count; ++k) reach = std::max(reach, rings[k].radius);
  reach = 1.01f * reach + margin;
  if (!(reach > margin)) return Vec3::Zero();
  reach += deeper;
  Vec3 push = Vec3::Zero();
  // Two passes: a point pushed off one surface (a wall) may come near another (the ground).
  for (int pass = 0; pass < 2; ++pass) {
    const Vec3 q = p + push;
    // Asked a little farther than the rings reach when a plane is wanted: stems rest just
    // beyond it (particle plants collide at barkClearance), and a surface found there needs
    // no push all the same.
    const std::optional<env::SurfacePoint> s = env.closestPoint(q, plane && pass == 0 ? 2.0f * reach : reach);
    if (!s) break;
    // Outside a face the direction to the query is the face's normal; only near an edge or
    // inside does it take the exact sign (angle-weighted pseudonormal).
    const bool inside = s->away.dot(s->normal) < 0.5f && env.exactSignedDistance(q, reach) < 0.0f;
    // The plane through the closest point of a convex obstacle, facing a point outside it.
    if (plane && pass == 0 && !inside && s->distance > 0.0f && !s->onStem() && env.obstacle(s->obstacle).convex)
      *plane = {s->obstacle, s->point, s->away};
    const Vec3 n = inside ? s->normal : s->away;
    const float d = inside ? -s->distance : s->distance;
    float need = 0.0f;
    for (size_t k = 0; k < count; ++k) need = std::max(need, rings[k].radius * rings[k].dir.cross(n).norm());
    if (need <= 0.0f) break;
    need = barkClearance(need, margin);
    if (d >= need) break;
    push += (need - d) * n;
  }
  return push;
}

// The obstacles' boxes, read once for a plant (provenClear looks at them for every point).
struct ObstacleBoxes {
  static constexpr size_t kMax = 8;  // scenes of more obstacles are not tried
  size_t count = 0;
  Bounds3 box[kMax];
  // Stems are not boxed: a plant among other plants' stems is not tried either.
  explicit ObstacleBoxes(const env::Environment& env) : count(env.seesStems() ? kMax + 1 : env.obstacleCount()) {
    if (count <= kMax)
      for (uint32_t o = 0; o < count; ++o) box[o] = env.obstacle(o).worldBounds;
  }
};

// Whether points lie `need` or more from every obstacle, shown without asking for closest
// points: a point's distance to a convex obstacle is at least its distance to a plane the
// obstacle lies behind (`planes`: those known near the points), and to any other obstacle at
// least its distance to the obstacle's box. The hull of a curve's Bézier control points being
// clear, the curve is; segments between clear points are, of convex obstacles and boxes alike.
// Scenes of many obstacles are not tried (false: ask).
bool provenClear(const ObstacleBoxes& boxes, const Vec3* pts, size_t count,
                 std::initializer_list<const SupportPlane*> planes, float need) {
  const size_t obstacles = boxes.count;
  if (obstacles > ObstacleBoxes::kMax) return false;
  Bounds3 hull;
  for (size_t j = 0; j < count; ++j) hull.extend(pts[j]);
  // A little to spare for rounding: where a query would find the bark just clear, it asks.
  const float wanted = need + 5e-6f;
  for (uint32_t o = 0; o < obstacles; ++o) {
    const Bounds3& box = boxes.box[o];
    const Vec3 gap = (box.min - hull.max).cwiseMax(hull.min - box.max).cwiseMax(Vec3::Zero());
    if (gap.squaredNorm() >= wanted * wanted) continue;
    float bound = 0.0f;
    for (const SupportPlane* plane : planes) {
      if (plane->obstacle != o) continue;
      float least = std::numeric_limits<float>::infinity();
      for (size_t j = 0; j < count; ++j) least = std::min(least, plane->normal.dot(pts[j] - plane->point));
      bound = std::max(bound, least);
    }
    if (!(bound >= wanted)) return false;
  }
  return true;
}

// The corners of leaf blade j for a world rotation, size and petiole (as the leaf mesh draws
// the blade: a quad from the petiole's end, half its aspect-scaled size either side of +Y).
void bladeCorners(const plant::PlantModel& p, size_t j, const Vec3& attach, const Quat& rotation, float size,
                  float petiole, Vec3 c[4]) {
  const float aspect = p.leafAspect(j);
  const float hw = 0.5f * size * aspect;
  const Mat3 r = rotation.toRotationMatrix();
  c[0] = attach + r * Vec3(-hw, petiole, 0);
  c[1] = attach + r * Vec3(hw, petiole, 0);
  c[2] = attach + r * Vec3(hw, petiole + size, 0);
  c[3] = attach + r * Vec3(-hw, petiole + size, 0);
}

// True if the blade touches a surface: its closed outline, reached from the attachment point
// (attachment -> c0 -> c1 -> c2 -> c3 -> c0), crosses one, so some corner is inside or behind it.
bool bladeBlocked(const env::Environment& env, const Vec3& attach, const Vec3 c[4]) {
  const Vec3 from[5] = {attach, c[0], c[1], c[2], c[3]};
  const Vec3 to[5] = {c[0], c[1], c[2], c[3], c[0]};
  return env.anySegmentBlocked(from, to, 5);
}

// Leaves that pass through a surface (a particle plant's blades turned to the light into the
// wall they grow on, a blade carried along by a stem moved off its support), or that a moved
// stem carried round to face a surface within their reach, are laid parallel
// to the surface nearest their attachment, upper side away from it, as climbing plants place
// them (climb/climb_system.cpp, placeLeaves); where that is not enough they shrink (0.7, 0.45)
// or, failing that, are dropped. Returns the number of leaves changed or dropped.
// Only the leaves of nodes that moved (`movedNode`, empty: none) are checked for facing a
// surface: a leaf the model placed keeps the side it was grown with.
// `planeOf`: per node, a plane near its start that an obstacle lies behind (or none).
size_t keepLeavesOutside(plant::PlantModel& p, const env::Environment& env, const ObstacleBoxes& boxes,
                         const std::vector<uint8_t>& movedNode, const std::vector<SupportPlane>& planeOf) {
  const size_t count = p.leafCount();
  std::vector<uint8_t> keep(count, 1), changed(count, 0);
  std::vector<Quat> rotation(count);
  std::vector<float> scale(count, 1.0f);
  parallelFor(size_t(0), count, [&](size_t j) {
    if (!(p.leafSize[j] > 0.0f)) return;
    const Vec3 attach = p.leafWorldPosition(j);
    const Quat world = p.leafWorldRotation(j);
    Vec3 c[4];
    bladeCorners(p, j, attach, world, p.leafSize[j], p.leafPetiole[j], c);
    const float reach = p.leafPetiole[j] + p.leafSize[j];
    std::optional<env::SurfacePoint> s;
    bool facing = false;
    if (!movedNode.empty() && movedNode[size_t(p.leafNode[j])]) {
      // A blade within its own reach of a surface turns its upper side away from it, as
      // clinging leaves do (a stem moved off its support may have carried one round to face it).
      s = env.closestPoint(attach, reach);
      facing = s && (world * Vec3::UnitZ()).dot(s->away) < 0.0f;
    }
    if (!facing) {
      // An outline shown clear of every obstacle crosses none.
      const Vec3 outline[5] = {attach, c[0], c[1], c[2], c[3]};
      const size_t node = size_t(p.leafNode[j]);
      if (node < planeOf.size() && provenClear(boxes, outline, 5, {&planeOf[node]}, 0.0f)) return;
      if (!bladeBlocked(env, attach, c)) return;
    }
    if (!s) s = env.closestPoint(attach, reach);
    changed[j] = 1;
    const Quat laid = s ? laidOn(world, s->away) : world;
    for (float k : {1.0f, 0.7f, 0.45f}) {
      bladeCorners(p, j, attach, laid, k * p.leafSize[j], k * p.leafPetiole[j], c);
      if (!bladeBlocked(env, attach, c)) {
        rotation[j] = laid;
        scale[j] = k;
        return;
      }
    }
    keep[j] = 0;
  }, 256);
  size_t touched = 0;
  std::vector<uint32_t> kept;
  kept.reserve(count);
  for (size_t j = 0; j < count; ++j) {
    touched += changed[j];
    if (!keep[j]) continue;
    if (changed[j]) {
      p.leafRotation[j] = (p.orientation[size_t(p.leafNode[j])].conjugate() * rotation[j]).normalized();
      p.leafSize[j] *= scale[j];
      p.leafPetiole[j] *= scale[j];
    }
    kept.push_back(uint32_t(j));
  }
  p.keepLeaves(kept);
  return touched;
}

}  // namespace

size_t keepStemsOutside(plant::PlantModel& p, const env::Environment& env, int subdivisions, float margin) {
  const size_t n = p.nodeCount();
  if (n == 0 || env.obstacleCount() == 0) return 0;
  const ObstacleBoxes boxes(env);
  // Points: every node's tip, and the start of every node that does not begin at its parent's
  // tip. Segments meeting at a point move together.
  std::vector<Vec3> dir(n), point;
  std::vector<uint32_t> startPoint(n), tipPoint(n);
  // The child continuing node i's bark chain, as the mesh sweeps it (mesh/branch_sweep.h: the
  // first child that is not a branch start), whether or not it begins exactly at i's tip
  // (particle plants' internodes leave small gaps).
  std::vector<int32_t> next(n, -1);
  point.reserve(2 * n);
  for (size_t i = 0; i < n; ++i) {
    dir[i] = p.direction(i);
    const int32_t q = p.parent[i];
    if (q >= 0 && next[size_t(q)] < 0 && !(p.flags[i] & plant::kNodeBranchStart)) next[size_t(q)] = int32_t(i);
    if (q >= 0 && (p.position[i] - point[tipPoint[size_t(q)]]).squaredNorm() <= 1e-12f) {
      startPoint[i] = tipPoint[size_t(q)];
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
  // The mesh sweeps its rings round the starts of nodes and the tips that end a chain; a tip
  // across a gap from the next node's start (particle plants) is not on the bark, and moves
  // only with its node.
  std::vector<uint8_t> swept(m, 0);
  for (size_t i = 0; i < n; ++i) {
    swept[startPoint[i]] = 1;
    if (next[i] < 0) swept[tipPoint[i]] = 1;
  }
  std::vector<Vec3> move(m, Vec3::Zero());
  // Every eighth node along a chain asks for the closest point at its points, and keeps the
  // plane found there (below); the points of the seven after it are first tried against that
  // plane and the obstacles' boxes, and ask only if that does not show them clear.
  std::vector<uint32_t> pointNode(m, UINT32_MAX), depth(n), askedBy(n);
  for (size_t i = 0; i < n; ++i) {
    const int32_t q = p.parent[i];
    depth[i] = q < 0 ? 0 : depth[size_t(q)] + 1;
    askedBy[i] = q < 0 || depth[i] % 8 == 0 ? uint32_t(i) : askedBy[size_t(q)];
    if (pointNode[startPoint[i]] == UINT32_MAX) pointNode[startPoint[i]] = uint32_t(i);
    if (pointNode[tipPoint[i]] == UINT32_MAX) pointNode[tipPoint[i]] = uint32_t(i);
  }
  std::vector<SupportPlane> plane(m);
  auto ask = [&](size_t k) {
    move[k] = clearance(env, point[k], rings.data() + ringStart[k], ringStart[k + 1] - ringStart[k], margin, 0.0f,
                        &plane[k]);
  };
  parallelFor(size_t(0), m, [&](size_t k) {
    if (planted[k] || !swept[k] || askedBy[pointNode[k]] != pointNode[k]) return;
    ask(k);
  }, 256);
  parallelFor(size_t(0), m, [&](size_t k) {
    if (planted[k] || !swept[k] || askedBy[pointNode[k]] == pointNode[k]) return;
    const SupportPlane& near = plane[startPoint[askedBy[pointNode[k]]]];
    float need = 0.0f;
    for (uint32_t r = ringStart[k]; r < ringStart[k + 1]; ++r) need = std::max(need, barkClearance(rings[r].radius, margin));
    if (provenClear(boxes, &point[k], 1, {&near}, need)) {
      plane[k] = near;
      return;
    }
    ask(k);
  }, 256);
  // A plane bounds the distance to its obstacle anywhere: a tip off the bark borrows its
  // node's.
  for (size_t i = 0; i < n; ++i)
    if (!swept[tipPoint[i]]) plane[tipPoint[i]] = plane[startPoint[i]];

  // Between its points the bark follows a spline (mesh/branch_sweep.h: centripetal
  // Catmull-Rom through the starts of a chain's nodes and its last tip) that can bow toward a
  // surface where the chain bends: the spline is cleared too, at the rings the mesh sweeps
  // there (k / subdivisions; the middle for a polyline, whose straight tube can still graze a
  // convex edge), by moving both ends of the span. The pushes are found in parallel and added
  // in node order.
  // The rings at the span's ends are checked again here: the mesh turns them to the spline's
  // tangent, which moves with the neighbouring points (the point check above used the nodes'
  // own directions before anything moved).
  std::vector<float> ringAt = {0.0f};
  for (int k = 1; k < subdivisions; ++k) ringAt.push_back(float(k) / float(subdivisions));
  if (subdivisions <= 1) ringAt.push_back(0.5f);
  ringAt.push_back(1.0f);
  auto at = [&](uint32_t k) { return Vec3(point[k] + move[k]); };
  std::vector<uint32_t> spanEnd(n);  // the point the bark's span from node i's start ends at
  for (size_t i = 0; i < n; ++i) spanEnd[i] = next[i] >= 0 ? startPoint[size_t(next[i])] : tipPoint[i];
  // Pushing a span's ends changes its neighbours' bows: up to three rounds, until no span needs
  // a push.
  // After the first round only spans with a control point pushed in the round before are
  // looked at again.
  std::vector<Vec3> midPush(n);
  std::vector<uint8_t> pushedPoint(m, 1);
  for (int round = 0; round < 3; ++round) {
    parallelFor(size_t(0), n, [&](size_t i) {
      midPush[i] = Vec3::Zero();
      if (!(p.length[i] > 0.0f)) return;
      const int32_t q = p.parent[i], c = next[i];
      if (round > 0 && !pushedPoint[startPoint[i]] && !pushedPoint[spanEnd[i]] &&
          !(q >= 0 && next[size_t(q)] == int32_t(i) && pushedPoint[startPoint[size_t(q)]]) &&
          !(c >= 0 && pushedPoint[spanEnd[size_t(c)]]))
        return;
      const Vec3 a = at(startPoint[i]), b = at(spanEnd[i]);
      const Vec3 chord = b - a;
      const float len = chord.norm();
      if (!(len > 1e-6f)) return;
      const Vec3 before = q >= 0 && next[size_t(q)] == int32_t(i) ? at(startPoint[size_t(q)]) : Vec3(2.0f * a - b);
      const Vec3 after = c >= 0 ? at(spanEnd[size_t(c)]) : Vec3(2.0f * b - a);
      const CurveSegment curve = centripetalCatmullRom(before, a, b, after);
      // The mesh sweeps the radius from this node's to the next one's along the span
      // (mesh/branch_sweep.cpp); the control points' hull is tried at the larger of the two.
      const float r0 = p.radius[i], r1 = c >= 0 ? p.radius[size_t(c)] : r0;
      const float need = barkClearance(std::max(r0, r1), margin);
      const Vec3 control[4] = {curve.p1, curve.p1 + curve.m1 / 3.0f, curve.p2 - curve.m2 / 3.0f, curve.p2};
      if (provenClear(boxes, control, 4, {&plane[startPoint[i]], &plane[spanEnd[i]]}, need)) return;
      for (float s : ringAt) {
        if (s == 0.0f && planted[startPoint[i]]) continue;  // a planted base stays as it stands
        const Vec3 onCurve = curve.point(s);
        const float r = s == 1.0f ? r1 : r0 + (r1 - r0) * s;  // the ring's radius, as the mesh sweeps it
        if (provenClear(boxes, &onCurve, 1, {&plane[startPoint[i]], &plane[spanEnd[i]]}, barkClearance(r, margin)))
          continue;
        const Vec3 d = curve.derivative(s);
        const float dn = d.norm();
        const Ring ring{r, dn > 1e-6f * len ? Vec3(d / dn) : Vec3(chord / len)};
        // The span's ends are clear, so a surface the curve bows through lies no further from
        // the curve point than the chord does.
        const float bow = (onCurve - (a + s * chord)).norm();
        Vec3 push = clearance(env, onCurve, &ring, 1, margin, bow);
        if (push == Vec3::Zero()) continue;
        // The span's neighbours stay, so the curve there moves by less than its ends: push the
        // ends by as much more as it takes (at most 4 times the push).
        const Vec3 shifted = centripetalCatmullRom(before, a + push, b + push, after).point(s) - onCurve;
        push /= std::clamp(shifted.dot(push) / push.squaredNorm(), 0.25f, 1.0f);
        if (push.squaredNorm() > midPush[i].squaredNorm()) midPush[i] = push;
      }
    }, 256);
    // A span ends at its node's tip where the chain's next node starts there (climbing and
    // L-system plants); across a gap (particle plants) it ends at the next node's start, and
    // both nodes move whole, so that no node changes its length.
    bool pushed = false;
    std::fill(pushedPoint.begin(), pushedPoint.end(), 0);
    auto push = [&](uint32_t k, const Vec3& v) { move[k] += v, pushedPoint[k] = 1; };
    for (size_t i = 0; i < n; ++i) {
      if (midPush[i] == Vec3::Zero()) continue;
      if (!planted[startPoint[i]]) push(startPoint[i], midPush[i]);
      push(tipPoint[i], midPush[i]);
      if (spanEnd[i] != tipPoint[i]) {
        push(spanEnd[i], midPush[i]);
        push(tipPoint[size_t(next[i])], midPush[i]);
      }
      pushed = true;
    }
    if (!pushed) break;
  }
  // No move may carry a point through a surface or a segment into one (a tight hole, a point
  // pushed off one surface onto another): such points stay where they were, and so, in turn,
  // do the points of segments that would then cross.
  // (A move shown clear of every obstacle, as above, crosses nothing and ends outside.)
  parallelFor(size_t(0), m, [&](size_t k) {
    if (move[k] == Vec3::Zero()) return;
    const Vec3 to = point[k] + move[k];
    const Vec3 path[2] = {point[k], to};
    if (provenClear(boxes, path, 2, {&plane[k]}, 0.0f)) return;
    if (env.countSegmentHits(point[k], to) > 0 || env.exactSignedDistance(to, 1e-3f) < 0.0f) move[k] = Vec3::Zero();
  }, 256);
  std::vector<uint8_t> crosses(n, 0);
  for (int pass = 0; pass < 4; ++pass) {
    parallelFor(size_t(0), n, [&](size_t i) {
      const uint32_t a = startPoint[i], b = tipPoint[i];
      if (move[a] == Vec3::Zero() && move[b] == Vec3::Zero()) {
        crosses[i] = 0;
        return;
      }
      const Vec3 segment[2] = {at(a), at(b)};
      if (provenClear(boxes, segment, 2, {&plane[a], &plane[b]}, 0.0f)) {
        crosses[i] = 0;
        return;
      }
      const size_t hits = env.countSegmentHits(at(a), at(b));
      crosses[i] = hits > 0 && hits > env.countSegmentHits(point[a], point[b]);
    }, 256);
    bool reverted = false;
    for (size_t i = 0; i < n; ++i)
      if (crosses[i]) move[startPoint[i]] = move[tipPoint[i]] = Vec3::Zero(), reverted = true;
    if (!reverted) break;
  }
  // Apply: positions, lengths and orientations follow the points.
  const std::vector<Vec3> oldPosition = p.position;
  const std::vector<Quat> oldOrientation = p.orientation;
  size_t moved = 0;
  for (size_t k = 0; k < m; ++k) moved += move[k] != Vec3::Zero();
  std::vector<SupportPlane> planeOfNode(n);
  for (size_t i = 0; i < n; ++i) planeOfNode[i] = plane[startPoint[i]];
  if (moved == 0) return keepLeavesOutside(p, env, boxes, {}, planeOfNode);
  for (size_t i = 0; i < n; ++i) {
    if (move[startPoint[i]] == Vec3::Zero() && move[tipPoint[i]] == Vec3::Zero()) continue;  // as the model left it
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
  std::vector<uint8_t> movedNode(n);
  for (size_t i = 0; i < n; ++i) movedNode[i] = move[startPoint[i]] != Vec3::Zero() || move[tipPoint[i]] != Vec3::Zero();
  return moved + keepLeavesOutside(p, env, boxes, movedNode, planeOfNode);
}

}  // namespace tendril::models
