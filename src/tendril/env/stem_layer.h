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

}  // namespace tendril::env
