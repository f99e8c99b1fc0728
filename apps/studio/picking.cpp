#include "picking.h"

#include <algorithm>
#include <cmath>

namespace tendril::studio {

Vec3 dragPoint(const render::Camera& camera, int width, int height, const Vec2& pixel, const Vec3& point) {
  render::Ray ray = render::pixelRay(camera, width, height, pixel);
  Vec3 n = camera.forward();
  float denom = ray.direction.dot(n);
  if (std::abs(denom) < 1e-6f) return point;
  float t = (point - ray.origin).dot(n) / denom;
  return ray.origin + std::max(t, 0.0f) * ray.direction;
}

}  // namespace tendril::studio
