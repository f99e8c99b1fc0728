// Environment's stems of one owner and their Embree scenes (environment.cpp, stems.cpp only).
#pragma once

#include "tendril/env/environment.h"

#include <embree3/rtcore.h>

#include <vector>

namespace tendril::env {

// A StemTube as closest-point queries use it: its axis direction, length and radius slope
// worked out once (closestOnTube is TubeShape(t).closest(p)).
struct TubeShape {
  Vec3 a = Vec3::Zero();       // the axis start (a ball's centre when the tube is one ball)
  Vec3 u = Vec3::UnitY();      // unit axis
  float length = 0.0f;         // axis length; 0 when the tube is one ball
  float r = 0.0f;              // radius at a
  float k = 0.0f, root = 1.0f;  // dr/ds and sqrt(1 − k²)
  float rMax = 0.0f;           // the largest radius

  TubeShape() = default;
  explicit TubeShape(const StemTube& t);
  TubePoint closest(const Vec3& p) const;
  // Positive when the tube's signed distance from p is certainly above `best`.
  float lowerBound2(const Vec3& p, float best) const;
  // Whether the segment p-q touches the tube: passes through it, ends in it or lies in it.
  bool meets(const Vec3& p, const Vec3& q) const;
};

struct Environment::StemLayer {
  uint32_t owner = 0;
  uint32_t first = 0;  // global index of tubes[0]
  std::vector<StemTube> tubes;
  std::vector<TubeShape> shapes;  // of the tubes, for closest points
  std::vector<ShadeTriangle> shade;
  RTCScene rays = nullptr;    // the tubes as round linear curves
  RTCScene points = nullptr;  // the tubes as a user geometry (closest-point queries)
  RTCScene shadeScene = nullptr;
  bool dirty = true;

  ~StemLayer() { release(); }
  void release() {
    for (RTCScene* s : {&rays, &points, &shadeScene})
      if (*s) rtcReleaseScene(*s), *s = nullptr;
  }
};

// An Embree ray from origin along dir over [tMin, tMax], every geometry mask.
inline void initRay(RTCRay& ray, const Vec3& origin, const Vec3& dir, float tMin, float tMax) {
  ray.org_x = origin.x(), ray.org_y = origin.y(), ray.org_z = origin.z();
  ray.dir_x = dir.x(), ray.dir_y = dir.y(), ray.dir_z = dir.z();
  ray.tnear = tMin;
  ray.tfar = tMax;
  ray.time = 0.0f;
  ray.mask = 0xffffffffu;
  ray.id = 0;
  ray.flags = 0;
}

}  // namespace tendril::env
