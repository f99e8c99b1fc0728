#include "support/climb_checks.h"

#include <cmath>
#include <fstream>

namespace tendril::test {

void leafCorners(const plant::PlantModel& p, size_t i, Vec3 out[4]) {
  Vec3 a = p.leafWorldPosition(i);
  Mat3 r = p.leafWorldRotation(i).toRotationMatrix();
  float aspect = p.leafAspect(i);
  float hw = 0.5f * p.leafSize[i] * aspect, pet = p.leafPetiole[i], len = p.leafSize[i];
  out[0] = a + r * Vec3(-hw, pet, 0);
  out[1] = a + r * Vec3(hw, pet, 0);
  out[2] = a + r * Vec3(hw, pet + len, 0);
  out[3] = a + r * Vec3(-hw, pet + len, 0);
}

ClimbReport checkClimbingPlant(const plant::PlantModel& p, const env::Environment& env, float adhesionDistance) {
  ClimbReport r;
  r.segments = p.nodeCount();
  std::vector<uint8_t> climbed(p.nodeCount(), 0);
  for (size_t i = 0; i < p.nodeCount(); ++i) {
    Vec3 a = p.position[i], b = p.tip(i);
    if (env.countSegmentHits(a, b) > 0) ++r.crossings;
    if (env.exactSignedDistance(b, 1.0f) < 0.0f) ++r.insideSegments;
    climbed[i] = (p.flags[i] & plant::kNodeClimbing) || (p.parent[i] >= 0 && climbed[p.parent[i]]);
    if (climbed[i]) {
      ++r.climbingSegments;
      if (env.closestPoint(0.5f * (a + b), adhesionDistance)) ++r.nearSurface;
    }
  }
  r.leaves = p.leafCount();
  for (size_t i = 0; i < p.leafCount(); ++i) {
    Vec3 attach = p.leafWorldPosition(i);
    Vec3 c[4];
    leafCorners(p, i, c);
    // A corner inside an obstacle, or a blade whose outline passes through a surface, or that
    // cannot be reached from its attachment point without crossing one (it is behind it).
    if (env.countSegmentHits(attach, c[0]) > 0) r.leafCornersBehind += 4;
    for (int k = 0; k < 4; ++k) {
      bool behind = env.exactSignedDistance(c[k], 1.0f) < 0.0f || env.countSegmentHits(c[k], c[(k + 1) % 4]) > 0;
      if (behind) ++r.leafCornersBehind;
    }
    // A clinging leaf (within reach of a surface) shows its upper side to the world, away
    // from the surface nearest to where it is attached.
    Vec3 leafNormal = p.leafWorldRotation(i) * Vec3::UnitZ();
    if (auto support = env.closestPoint(attach, adhesionDistance))
      if (leafNormal.dot(support->away) < 0.0f) ++r.leavesFacingSurface;
  }
  return r;
}

void writeTorusObj(const std::filesystem::path& path, float major, float minor, int nu, int nv) {
  std::ofstream out(path);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      float u = kTwoPi * i / nu, v = kTwoPi * j / nv;
      float r = major + minor * std::cos(v);
      out << "v " << r * std::cos(u) << " " << minor * std::sin(v) << " " << r * std::sin(u) << "\n";
    }
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      int a = i * nv + j + 1, b = ((i + 1) % nu) * nv + j + 1, c = ((i + 1) % nu) * nv + (j + 1) % nv + 1,
          d = i * nv + (j + 1) % nv + 1;
      out << "f " << a << " " << d << " " << c << " " << b << "\n";
    }
}

}  // namespace tendril::test
