// Environment's stems of one owner and their Embree scenes (environment.cpp, stems.cpp only).
#pragma once

#include "tendril/env/environment.h"

#include <embree3/rtcore.h>

#include <vector>

namespace tendril::env {

struct Environment::StemLayer {
  uint32_t owner = 0;
  uint32_t first = 0;  // global index of tubes[0]
  std::vector<StemTube> tubes;
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
