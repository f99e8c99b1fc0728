// The eight view directions level-of-detail silhouettes are compared from (issue 26; tests/io/
// lod_test.cpp, impostor_test.cpp): four round the plant (0°, 45°, 90°, 135°), three from 45°
// above between them, and straight down. Tendril's frame: y up.
#pragma once

#include "tendril/core/math.h"

#include <cmath>
#include <vector>

namespace tendril::test {

inline std::vector<Vec3> eightViews() {
  std::vector<Vec3> views;
  for (int k = 0; k < 4; ++k) {
    const float a = float(k) * 0.25f * kPi;
    views.push_back(Vec3(std::cos(a), 0.0f, std::sin(a)));
  }
  for (int k = 0; k < 3; ++k) {
    const float a = (float(k) + 0.5f) * (2.0f / 3.0f) * kPi;
    views.push_back(Vec3(std::cos(a), -1.0f, std::sin(a)).normalized());
  }
  views.push_back(Vec3(0, -1, 0));
  return views;
}

}  // namespace tendril::test
