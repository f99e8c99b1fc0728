// A perspective camera and the math the studio and the CLI share: view and projection
// matrices, framing a bounding box, orbit / pan / zoom about the target, projecting points to
// pixels and casting picking rays. No OpenGL here.
//
// Pixel coordinates have their origin at the top-left corner of the image (as in io::Image),
// x to the right and y down, and a pixel's centre at (x + 0.5, y + 0.5).
#pragma once

#include "tendril/core/math.h"

#include <string>

namespace tendril::render {

struct Camera {
  Vec3 eye = Vec3(0.0f, 1.5f, 5.0f);
  Vec3 target = Vec3(0.0f, 1.0f, 0.0f);
  Vec3 up = Vec3::UnitY();
  float fovY = radians(40.0f);  // vertical field of view (rad)
  float near = 0.05f;           // m
  float far = 200.0f;           // m

  Vec3 forward() const { return (target - eye).normalized(); }
  float distance() const { return (target - eye).norm(); }
  // Camera-space basis: right, true up (perpendicular to forward) and forward.
  Vec3 right() const;
  Vec3 trueUp() const;

  // View matrix (camera looks down its −Z, OpenGL convention).
  Mat4 viewFromWorld() const;
  // OpenGL perspective projection (clip z in [−w, w]) for width / height = aspect.
  Mat4 clipFromView(float aspect) const;
  Mat4 clipFromWorld(float aspect) const { return clipFromView(aspect) * viewFromWorld(); }
};

// Throws Error(source, "camera", what is wrong) for a camera that cannot be rendered: non-finite
// values, eye == target, up parallel to the view direction, fovY outside (0, pi), or not
// 0 < near < far.
void validateCamera(const Camera& camera, const std::string& source);

// A camera looking along `viewDirection` (need not be unit length) that sees every corner of
// `bounds` for an image of the given aspect, with a small margin. near / far are set from
// the distance so that orbiting and zooming keep the depth range sensible.
Camera frameBounds(const Bounds3& bounds, const Vec3& viewDirection, float aspect = 16.0f / 9.0f,
                   float fovY = radians(40.0f));

// Turns the eye about the target: `yaw` (rad) about the camera's up axis (counter-clockwise
// seen from above), then `pitch` (rad) raises the eye over the target; the eye stops 1 degree
// short of straight above or below it.
Camera orbit(const Camera& camera, float yaw, float pitch);
// Moves eye and target together across the view: dx to the right, dy up, both in fractions
// of the image height (a drag of the whole image height moves the target plane by its height).
Camera pan(const Camera& camera, float dx, float dy);
// Moves the eye toward (factor < 1) or away from (factor > 1) the target; near and far scale
// with the distance. factor must be positive.
Camera zoom(const Camera& camera, float factor);

// Where a world point lands in a width × height image: pixel coordinates and depth along the
// view direction (m). `visible` is false for points behind the eye.
struct Projection {
  Vec2 pixel = Vec2::Zero();
  float depth = 0.0f;
  bool visible = false;
};
Projection projectToPixel(const Camera& camera, int width, int height, const Vec3& world);

// The ray from the eye through pixel coordinates (x, y) (picking).
struct Ray {
  Vec3 origin = Vec3::Zero();
  Vec3 direction = Vec3::UnitZ();  // unit
};
Ray pixelRay(const Camera& camera, int width, int height, const Vec2& pixel);

}  // namespace tendril::render
