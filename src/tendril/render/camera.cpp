#include "tendril/render/camera.h"

#include "tendril/core/error.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace tendril::render {

Vec3 Camera::right() const {
  Vec3 r = forward().cross(up);
  return r.squaredNorm() > 1e-12f ? Vec3(r.normalized()) : anyPerpendicular(forward());
}

Vec3 Camera::trueUp() const { return right().cross(forward()); }

Mat4 Camera::viewFromWorld() const {
  Vec3 f = forward(), r = right(), u = r.cross(f);
  Mat4 m = Mat4::Identity();
  m.block<1, 3>(0, 0) = r.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -r.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

Mat4 Camera::clipFromView(float aspect) const {
  float t = 1.0f / std::tan(0.5f * fovY);
  Mat4 m = Mat4::Zero();
  m(0, 0) = t / aspect;
  m(1, 1) = t;
  m(2, 2) = (far + near) / (near - far);
  m(2, 3) = 2.0f * far * near / (near - far);
  m(3, 2) = -1.0f;
  return m;
}

void validateCamera(const Camera& c, const std::string& source) {
  auto fail = [&](const std::string& what) { throw Error(source, "camera", what); };
  if (!isFinite(c.eye) || !isFinite(c.target) || !isFinite(c.up) || !isFinite(c.fovY) || !isFinite(c.near) ||
      !isFinite(c.far))
    fail("has a non-finite value");
  if ((c.target - c.eye).norm() < 1e-6f) fail("eye and target are the same point");
  if (c.up.squaredNorm() < 1e-12f || (c.target - c.eye).normalized().cross(c.up.normalized()).norm() < 1e-4f)
    fail("up is zero or parallel to the view direction");
  if (!(c.fovY > 0.0f && c.fovY < kPi)) fail("field of view must be between 0 and 180 degrees");
  if (!(c.near > 0.0f && c.near < c.far)) fail("needs 0 < near < far");
}

Camera frameBounds(const Bounds3& boundsIn, const Vec3& viewDirection, float aspect, float fovY) {
  Bounds3 bounds = boundsIn;
  if (bounds.empty()) {
    bounds.extend(Vec3(-1.0f, 0.0f, -1.0f));
    bounds.extend(Vec3(1.0f, 2.0f, 1.0f));
  }
  Camera cam;
  cam.fovY = fovY;
  Vec3 f = viewDirection.squaredNorm() > 1e-12f ? Vec3(viewDirection.normalized()) : Vec3(-Vec3::UnitZ());
  cam.up = std::abs(f.dot(Vec3::UnitY())) > 0.999f ? Vec3(-Vec3::UnitZ()) : Vec3(Vec3::UnitY());
  Vec3 c = bounds.center();
  cam.target = c;
  cam.eye = c - f;
  Vec3 r = cam.right(), u = cam.trueUp();
  float tanY = std::tan(0.5f * fovY), tanX = tanY * std::max(aspect, 1e-3f);
  // Distance at which each corner fits: its depth d + o·f must reach |o·r| / tanX and
  // |o·u| / tanY (o = corner − centre).
  float dist = 0.0f, radius = 0.5f * bounds.size().norm();
  for (int k = 0; k < 8; ++k) {
    Vec3 corner((k & 1) ? bounds.max.x() : bounds.min.x(), (k & 2) ? bounds.max.y() : bounds.min.y(),
                (k & 4) ? bounds.max.z() : bounds.min.z());
    Vec3 o = corner - c;
    dist = std::max(dist, std::abs(o.dot(r)) / tanX - o.dot(f));
    dist = std::max(dist, std::abs(o.dot(u)) / tanY - o.dot(f));
  }
  constexpr float kMargin = 1.08f;
  dist = std::max(dist * kMargin, 1e-3f + radius * 0.1f);
  cam.eye = c - dist * f;
  cam.near = std::max(1e-3f, 0.02f * dist);
  cam.far = std::max(100.0f * dist, 4.0f * (dist + radius));
  return cam;
}

Camera orbit(const Camera& camera, float yaw, float pitch) {
  Camera c = camera;
  Vec3 up = camera.up.normalized();
  Vec3 offset = axisAngle(up, yaw) * Vec3(camera.eye - camera.target);
  float dist = offset.norm();
  Vec3 horizontal = offset - offset.dot(up) * up;
  if (horizontal.squaredNorm() < 1e-10f * dist * dist) horizontal = anyPerpendicular(up);
  horizontal.normalize();
  // Polar angle of the eye from up, kept within [1°, 179°].
  float polar = std::clamp(angleBetween(offset, up) - pitch, radians(1.0f), radians(179.0f));
  c.eye = camera.target + dist * (std::cos(polar) * up + std::sin(polar) * horizontal);
  return c;
}

Camera pan(const Camera& camera, float dx, float dy) {
  Camera c = camera;
  float height = 2.0f * camera.distance() * std::tan(0.5f * camera.fovY);
  Vec3 move = height * (dx * camera.right() + dy * camera.trueUp());
  c.eye += move;
  c.target += move;
  return c;
}

Camera zoom(const Camera& camera, float factor) {
  Camera c = camera;
  float s = std::max(factor, 1e-6f);
  float d = std::max(camera.distance() * s, 1e-3f);
  c.eye = camera.target - d * camera.forward();
  float k = d / camera.distance();
  c.near = camera.near * k;
  c.far = camera.far * k;
  return c;
}

Projection projectToPixel(const Camera& camera, int width, int height, const Vec3& world) {
  Projection p;
  float aspect = float(width) / float(height);
  Vec4 clip = camera.clipFromWorld(aspect) * Vec4(world.x(), world.y(), world.z(), 1.0f);
  p.depth = (world - camera.eye).dot(camera.forward());
  p.visible = clip.w() > 0.0f;
  if (clip.w() != 0.0f) {
    float nx = clip.x() / clip.w(), ny = clip.y() / clip.w();
    p.pixel = Vec2(0.5f * (nx + 1.0f) * float(width), 0.5f * (1.0f - ny) * float(height));
  }
  return p;
}

Ray pixelRay(const Camera& camera, int width, int height, const Vec2& pixel) {
  float nx = 2.0f * pixel.x() / float(width) - 1.0f;
  float ny = 1.0f - 2.0f * pixel.y() / float(height);
  float tanY = std::tan(0.5f * camera.fovY), tanX = tanY * float(width) / float(height);
  Ray ray;
  ray.origin = camera.eye;
  ray.direction = (camera.forward() + nx * tanX * camera.right() + ny * tanY * camera.trueUp()).normalized();
  return ray;
}

}  // namespace tendril::render
