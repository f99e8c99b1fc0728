// Collision response of seed 000 §5.2: obstacles through their signed distance fields, other
// particles (of any plant, including the same one) through a spatial hash.
#include "tendril/core/parallel.h"
#include "tendril/core/segments.h"
#include "tendril/models/stand_off.h"
#include "tendril/particles/world.h"

#include <algorithm>
#include <cmath>

namespace tendril::particles {

void ParticleWorld::collideObstacles(const env::Environment& env) {
  const size_t n = capacity();
  correction_.assign(n, Vec3::Zero());
  if (env.obstacleCount() == 0 && !env.seesStems()) return;
  // The distances proved by earlier samples hold only for the same obstacles in the same place,
  // and the same host plants' stems (plants as supports).
  const uint64_t stems = env.seesStems() ? 2 * env.stemRevision() + 1 : 0;
  bool same = clearanceEnv_ == &env && clearanceObstacles_.size() == env.obstacleCount() && clearanceStems_ == stems;
  clearanceStems_ = stems;
  clearanceObstacles_.resize(env.obstacleCount());
  for (uint32_t o = 0; o < env.obstacleCount(); ++o) {
    const env::ObstacleInfo& info = env.obstacle(o);
    ObstacleState& state = clearanceObstacles_[o];
    same = same && state.worldFromLocal.rotation.coeffs() == info.worldFromLocal.rotation.coeffs() &&
           state.worldFromLocal.translation == info.worldFromLocal.translation &&
           state.localBounds.min == info.localBounds.min && state.localBounds.max == info.localBounds.max &&
           state.triangles == info.triangles;
    state = {info.worldFromLocal, info.localBounds, info.triangles};
  }
  clearanceEnv_ = &env;
  if (!same) clearance_.assign(n, Clearance{});
  clearance_.resize(n);

  // The trilinear distance field is Lipschitz with constant √3 (each partial derivative is a
  // mix of grid differences of a true distance, at most 1; beyond the grid and in the minimum
  // over obstacles it stays so): a point δ from a sampled one lies at least d − √3 δ from any
  // obstacle. A particle whose three samples cannot reach its radius this way would get no push
  // from sampling, so it is not sampled; the margin covers rounding.
  constexpr float kLipschitz = 1.7321f, kMargin = 1e-4f;
  constexpr float kUnknown = -std::numeric_limits<float>::infinity();

  // The particle is a capsule along its long axis: test its centre and both ends against the
  // SDF (the paper tests the distance against the longest axis) and push the whole particle
  // out along the surface normal. The push is kept for the velocity response in integrate().
  parallelFor(0, n, [&](size_t i) {
    if (!(flags_[i] & kActive) || (flags_[i] & kRoot)) return;
    // Fast particles (a fall, a hard drag) could pass through a thin obstacle between two
    // steps, where no distance sample sees it: their path is cast as a ray first.
    const Vec3 move = xp_[i] - x_[i];
    const float moved = move.norm();
    // The capsule keeps its bark's clearance off obstacles (contactDistance), so the bark the
    // mesh sweeps round it stays outside them without the stand-off pass moving it.
    const float contact = contactDistance(uint32_t(i));
    if (moved > b_[i] && std::isfinite(moved)) {
      if (auto hit = env.rayCast(x_[i], move / moved, moved + contact)) {
        Vec3 n = hit->normal;
        if (n.dot(move) > 0.0f) n = -n;
        const Vec3 stop = hit->point + n * contact;
        correction_[i] = stop - xp_[i];
        xp_[i] = stop;
      }
    }
    const Vec3 axis = qp_[i] * Vec3(0, a_[i], 0);
    Clearance& clear = clearance_[i];
    const float movedCentre = (xp_[i] - clear.centre).norm();
    const float movedEnds = movedCentre + (axis - clear.axis).norm();
    if (clear.centreDistance - kLipschitz * movedCentre > a_[i] + contact + kMargin ||
        clear.distance - kLipschitz * movedEnds > contact + kMargin)
      return;
    const Vec3 samples[3] = {xp_[i], xp_[i] + axis, xp_[i] - axis};
    Vec3 push = Vec3::Zero();
    float centre = kUnknown, nearest = kUnknown;
    for (int k = 0; k < 3; ++k) {
      Vec3 g;
      const float d = env.signedDistance(samples[k] + push, &g);
      if (k == 0) {
        centre = nearest = d;
        // A centre farther than the half-length plus the radius: the ends are clear as well.
        if (d > a_[i] + contact) {
          nearest = d - kLipschitz * a_[i];  // what the ends are known to keep
          break;
        }
      }
      nearest = std::min(nearest, d);
      const float depth = contact - d;
      if (depth > 0.0f && g.squaredNorm() > 0.0f) push += g * depth;
    }
    if (push.squaredNorm() > 0.0f) {
      xp_[i] += push;
      correction_[i] += push;
      clear = Clearance{};  // sampled at points it has now left
    } else {
      clear = {samples[0], axis, centre, nearest};
    }
  }, 256);
}

void ParticleWorld::collideParticles() {
  // Stems collide with stems of any plant (§5.2: "plants resolve collisions with other plants
  // and themselves"); leaves collide with obstacles only — a mat of overlapping leaves is what
  // ivy looks like, and pushing every blade apart only makes it jitter.
  const size_t n = capacity();
  std::vector<uint32_t>& stems = hashParticles_;
  stems.clear();
  float maxReach = 0.0f;
  for (uint32_t i = 0; i < n; ++i)
    if ((flags_[i] & kActive) && !(flags_[i] & kLeaf)) {
      stems.push_back(i);
      maxReach = std::max(maxReach, a_[i] + b_[i]);
    }
  if (stems.size() < 2 || maxReach <= 0.0f) {
    hashEntries_.clear();
    return;
  }
  // Any touching pair lies in neighbouring cells of this size. Cells go into a hash table
  // twice as large as the particle count; entries are placed by a counting sort in particle
  // order, so the table is the same whatever the thread count.
  const float inv = 1.0f / (2.0f * maxReach);
  hashInv_ = inv;
  auto cellOf = [&](const Vec3& p) {
    return Eigen::Vector3i(int(std::floor(p.x() * inv)), int(std::floor(p.y() * inv)), int(std::floor(p.z() * inv)));
  };
  uint32_t tableSize = 64;
  while (tableSize < 2 * stems.size()) tableSize *= 2;
  const uint32_t mask = tableSize - 1;
  std::vector<uint32_t>& bucket = hashBucket_;
  bucket.resize(stems.size());
  parallelFor(0, stems.size(), [&](size_t k) { bucket[k] = spatialHash(cellOf(xp_[stems[k]]), mask); }, 4096);
  std::vector<uint32_t>& start = hashStart_;
  start.assign(tableSize + 1, 0);
  for (uint32_t b : bucket) ++start[b + 1];
  for (uint32_t t = 0; t < tableSize; ++t) start[t + 1] += start[t];
  std::vector<uint32_t>& entries = hashEntries_;
  entries.resize(stems.size());
  {
    std::vector<uint32_t>& fill = hashFill_;
    fill.assign(start.begin(), start.end() - 1);
    for (size_t k = 0; k < stems.size(); ++k) entries[fill[bucket[k]]++] = stems[k];
  }
  // What the pair test reads first, packed in table order: cell, centre, reach. (The scratch
  // arrays are kept from step to step: at 100k particles, allocating them anew each step cost a
  // thousand page faults.)
  static_assert(sizeof(HashPacked) == 28);
  std::vector<HashPacked>& packed = hashPacked_;
  std::vector<HashContact>& contact = hashContact_;
  packed.resize(entries.size());
  contact.resize(entries.size());
  auto grandparentOf = [&](uint32_t p) { return p == kNone ? kNone : parent_[p]; };
  parallelFor(0, entries.size(), [&](size_t e) {
    const uint32_t j = entries[e];
    packed[e] = {cellOf(xp_[j]), xp_[j], a_[j] + b_[j]};
    const Vec3 axis = qp_[j] * Vec3(0, a_[j], 0);
    contact[e] = {xp_[j] - axis, xp_[j] + axis, b_[j], m_[j], j, parent_[j], grandparentOf(parent_[j]),
                  (flags_[j] & (kAnchored | kRoot)) ? 1u : 0u};
  }, 4096);

  // Particles within two generations of each other meet at joints by construction.
  auto related = [](const uint32_t (&ai)[3], const HashContact& c) {
    const uint32_t aj[3] = {c.particle, c.parent, c.grandparent};
    for (uint32_t x : ai)
      for (uint32_t y : aj)
        if (x != kNone && x == y) return true;
    return false;
  };

  goal_.resize(n);
  parallelFor(0, n, [&](size_t ii) {
    const uint32_t i = uint32_t(ii);
    goal_[i] = xp_[i];
    // Anchored particles are held at their surface point and leave the push to the free
    // particles that meet them (most of a climber's stems are anchored: this is most of the cost).
    if (!(flags_[i] & kActive) || (flags_[i] & (kRoot | kLeaf | kAnchored))) return;
    const Vec3 axisI = qp_[i] * Vec3(0, a_[i], 0);
    const Vec3 ai = xp_[i] - axisI, bi = xp_[i] + axisI;
    const uint32_t lineage[3] = {i, parent_[i], grandparentOf(parent_[i])};
    const float radiusI = b_[i], massI = m_[i];
    // The cells a particle touching this one can have its centre in: within this one's reach
    // plus the longest, at most the 27 neighbouring cells and, for all but the longest
    // particles, 8 to 12 of them (in the same order, so the pushes add up the same). A bucket
    // may also hold other cells' particles (hash collisions), which the cell test skips, so no
    // particle is seen twice.
    Vec3 push = Vec3::Zero();
    const float reachI = a_[i] + b_[i];
    const Vec3 r = Vec3::Constant(1.001f * (reachI + maxReach));  // rounding kept on the safe side
    const Eigen::Vector3i lo = cellOf(xp_[i] - r), hi = cellOf(xp_[i] + r);
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) {
          const Eigen::Vector3i cell(x, y, z);
          const uint32_t h = spatialHash(cell, mask);
          for (uint32_t e = start[h]; e < start[h + 1]; ++e) {
            const HashPacked& q = packed[e];
            if (q.cell != cell) continue;
            const float reach = reachI + q.reach;
            if ((q.x - xp_[i]).squaredNorm() > reach * reach) continue;
            const HashContact& c = contact[e];
            if (c.particle == i || related(lineage, c)) continue;
            Vec3 ci, cj;
            closestSegmentPoints(ai, bi, c.a, c.b, &ci, &cj);
            const Vec3 d = ci - cj;
            const float dist = d.norm(), minDist = radiusI + c.radius;
            if (dist >= minDist || dist < 1e-9f) continue;
            // Displace along the contact normal, in proportion to the other's mass; each side
            // moves half, as the other particle does the same from its side.
            // An anchored (or root) particle does not move: this one takes the whole way.
            const float share = c.held ? 1.0f : 0.5f * c.mass / (massI + c.mass);
            push += d / dist * ((minDist - dist) * share);
          }
        }
    // Never more than a radius per step: a deep tangle resolves over a few steps.
    const float len = push.norm();
    if (len > b_[i]) push *= b_[i] / len;
    goal_[i] = xp_[i] + push;
  }, 256);
  std::swap(xp_, goal_);
}

}  // namespace tendril::particles
