#include "tendril/env/seed_check.h"

#include "tendril/core/error.h"
#include "tendril/env/topology.h"

#include <fmt/format.h>

#include <limits>

namespace tendril::env {

namespace {

// Depth below a surface that counts as inside: points on a surface (round-off either side)
// are not.
constexpr float kInsideDepth = 1e-4f;

// True when p lies more than kInsideDepth inside the closed obstacle `id`: the closest of its
// triangles and the sign at that feature's angle-weighted pseudonormal, in its own frame.
bool insideObstacle(const Environment& env, uint32_t id, const Vec3& p) {
  const ObstacleInfo& info = env.obstacle(id);
  if (!info.closed) return false;
  const Vec3 local = info.worldFromLocal.inverse().applyPoint(p);
  if (!info.localBounds.contains(local)) return false;
  const TriangleMesh mesh = env.obstacleMesh(id);
  WeldedMesh welded;
  welded.positions = mesh.positions;
  welded.indices = mesh.indices;
  float best = std::numeric_limits<float>::infinity();
  uint32_t bestTriangle = 0;
  ClosestOnTriangle bestPoint{local, TriangleFeature::Face};
  for (uint32_t t = 0; t < uint32_t(mesh.triangleCount()); ++t) {
    const uint32_t* tri = &mesh.indices[3 * size_t(t)];
    ClosestOnTriangle c =
        closestPointOnTriangle(local, mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]);
    const float d = (c.point - local).squaredNorm();
    if (d < best) {
      best = d;
      bestTriangle = t;
      bestPoint = c;
    }
  }
  if (!(best > kInsideDepth * kInsideDepth)) return false;
  const Pseudonormals normals = computePseudonormals(welded);
  const Vec3 n = normals.at(bestTriangle, bestPoint.feature, &mesh.indices[3 * size_t(bestTriangle)]);
  return (local - bestPoint.point).dot(n) < 0.0f;
}

}  // namespace

bool seedInsideObstacle(const Environment& env, const Vec3& position, const Vec3& direction) {
  // On a surface is not inside, whatever the round-off (a point a ray found on a stem's round
  // cone may lie a hair within it).
  const float d = env.exactSignedDistance(position, 1.0f);
  if (d < -kInsideDepth) return true;
  // Farther than the probe from every surface, the probe cannot reach inside anything.
  if (!(d < kSeedProbeDistance) || !(direction.squaredNorm() > 0.0f)) return false;
  const Vec3 probe = position + kSeedProbeDistance * direction.normalized();
  for (uint32_t id = 0; id < uint32_t(env.obstacleCount()); ++id)
    if (insideObstacle(env, id, probe)) return true;
  // Support plants' stems (their distances are exact).
  return env.seesStems() && env.exactSignedDistance(probe, kSeedProbeDistance) < -kInsideDepth;
}

void checkSeedPosition(const Environment& env, const Vec3& position, const Vec3& direction,
                       const std::string& source) {
  if (seedInsideObstacle(env, position, direction))
    throw Error(source, "", fmt::format("seed position ({:.3g}, {:.3g}, {:.3g}) lies inside an obstacle",
                                        position.x(), position.y(), position.z()));
}

}  // namespace tendril::env
