#include "tendril/core/curve.h"

#include <algorithm>
#include <cassert>

namespace tendril {

Vec3 CurveSegment::point(float s) const {
  // Cubic Hermite basis.
  float s2 = s * s, s3 = s2 * s;
  float h00 = 2.0f * s3 - 3.0f * s2 + 1.0f;
  float h10 = s3 - 2.0f * s2 + s;
  float h01 = -2.0f * s3 + 3.0f * s2;
  float h11 = s3 - s2;
  return h00 * p1 + h10 * m1 + h01 * p2 + h11 * m2;
}

Vec3 CurveSegment::derivative(float s) const {
  float s2 = s * s;
  float d00 = 6.0f * s2 - 6.0f * s;
  float d10 = 3.0f * s2 - 4.0f * s + 1.0f;
  float d01 = -6.0f * s2 + 6.0f * s;
  float d11 = 3.0f * s2 - 2.0f * s;
  return d00 * p1 + d10 * m1 + d01 * p2 + d11 * m2;
}

CurveSegment centripetalCatmullRom(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
  // Knot intervals |p_{i+1} − p_i|^alpha with alpha = 1/2 (centripetal). The Hermite tangents
  // of the non-uniform Catmull-Rom segment (Yuksel et al. 2011), rescaled to the unit
  // parameter of [p1, p2].
  // The floor only guards against rounding (e.g. a reflected end point that collapses onto
  // its neighbour far from the origin): a zero interval then contributes a zero difference.
  constexpr float kMinInterval = 1e-20f;
  float t01 = std::max(std::sqrt((p1 - p0).norm()), kMinInterval);
  float t12 = std::max(std::sqrt((p2 - p1).norm()), kMinInterval);
  float t23 = std::max(std::sqrt((p3 - p2).norm()), kMinInterval);
  CurveSegment c;
  c.p1 = p1;
  c.p2 = p2;
  c.m1 = (p2 - p1) + t12 * ((p1 - p0) / t01 - (p2 - p0) / (t01 + t12));
  c.m2 = (p2 - p1) + t12 * ((p3 - p2) / t23 - (p3 - p1) / (t12 + t23));
  return c;
}

Vec3 perpendicularTo(const Vec3& t, const Vec3& hint) {
  Vec3 r = hint - t * t.dot(hint);
  float n = r.norm();
  if (n > 1e-4f * hint.norm() && n > 0.0f) return r / n;
  return anyPerpendicular(t);
}

Vec3 doubleReflection(const Vec3& x0, const Vec3& t0, const Vec3& r0, const Vec3& x1, const Vec3& t1) {
  // Wang et al. 2008, Algorithm 1. A reflection with a (near) zero plane normal is the
  // identity: coincident points or equal tangents need no correction.
  Vec3 v1 = x1 - x0;
  float c1 = v1.squaredNorm();
  Vec3 rL = r0, tL = t0;
  if (c1 > 1e-20f) {
    rL = r0 - (2.0f / c1) * v1.dot(r0) * v1;
    tL = t0 - (2.0f / c1) * v1.dot(t0) * v1;
  }
  Vec3 v2 = t1 - tL;
  float c2 = v2.squaredNorm();
  Vec3 r1 = c2 > 1e-20f ? Vec3(rL - (2.0f / c2) * v2.dot(rL) * v2) : rL;
  // Reflections are exact in theory; re-orthonormalise so rounding cannot accumulate.
  return perpendicularTo(t1, r1);
}

void rotationMinimizingFrames(std::span<const Vec3> points, std::span<const Vec3> tangents,
                              const Vec3& r0, std::span<Vec3> normals) {
  assert(points.size() == tangents.size() && points.size() == normals.size());
  if (points.empty()) return;
  normals[0] = perpendicularTo(tangents[0], r0);
  for (size_t i = 1; i < points.size(); ++i)
    normals[i] = doubleReflection(points[i - 1], tangents[i - 1], normals[i - 1], points[i], tangents[i]);
}

}  // namespace tendril
