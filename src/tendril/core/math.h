// Vector, rotation and frame helpers on top of Eigen. Units: metres and radians.
// Conventions (see docs/architecture.md): right-handed, +Y up; a node's local +Y is its
// growth direction and its local +Z faces away from the support surface.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>

namespace tendril {

using Vec2 = Eigen::Vector2f;
using Vec3 = Eigen::Vector3f;
using Vec4 = Eigen::Vector4f;
using Mat3 = Eigen::Matrix3f;
using Mat4 = Eigen::Matrix4f;
using Quat = Eigen::Quaternionf;
using Vec3d = Eigen::Vector3d;

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kTwoPi = 2.0f * kPi;

constexpr float radians(float degrees) { return degrees * (kPi / 180.0f); }
constexpr float degrees(float radians) { return radians * (180.0f / kPi); }

// Sine and cosine of x: below 0.5 rad by short series (error under 1e-8: small angles, such as
// sway and gust turns, cost a few multiplications), the library's beyond.
inline void sinCos(float x, float* s, float* c) {
  if (std::fabs(x) < 0.5f) {
    const float x2 = x * x;
    *s = x * (1.0f + x2 * (-1.0f / 6.0f + x2 * (1.0f / 120.0f + x2 * (-1.0f / 5040.0f))));
    *c = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24.0f + x2 * (-1.0f / 720.0f + x2 * (1.0f / 40320.0f))));
  } else {
    *s = std::sin(x);
    *c = std::cos(x);
  }
}

inline bool isFinite(float v) { return std::isfinite(v); }
inline bool isFinite(const Vec2& v) { return std::isfinite(v.x()) && std::isfinite(v.y()); }
inline bool isFinite(const Vec3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}
inline bool isFinite(const Quat& q) {
  return std::isfinite(q.w()) && std::isfinite(q.x()) && std::isfinite(q.y()) && std::isfinite(q.z());
}

// A unit vector perpendicular to v (v need not be normalised, must not be zero).
Vec3 anyPerpendicular(const Vec3& v);

// The shortest rotation taking direction `from` to direction `to` (neither needs to be unit
// length). Opposite vectors rotate by pi about an arbitrary perpendicular axis.
Quat rotationBetween(const Vec3& from, const Vec3& to);

// Rotation by `angle` radians about `axis` (normalised here; a zero axis gives identity).
Quat axisAngle(const Vec3& axis, float angle);

// The orientation whose local +Y is `y` and whose local +Z is as close as possible to `zHint`
// (Gram-Schmidt). When zHint is parallel to y, any perpendicular is used.
Quat frameFromYZ(const Vec3& y, const Vec3& zHint);

// A leaf blade (local +Y along it, +Z its upper side) laid on a surface of unit normal `up`:
// +Y projected onto the surface (any direction on it if +Y is along `up`), +Z along `up`.
Quat laidOn(const Quat& blade, const Vec3& up);

// Angle in [0, pi] between two non-zero vectors, robust near 0 and pi (atan2 form).
float angleBetween(const Vec3& a, const Vec3& b);

// Rotates unit direction `dir` toward unit direction `target` by at most `maxAngle` radians,
// never past it. Returns the rotated unit vector.
Vec3 rotateToward(const Vec3& dir, const Vec3& target, float maxAngle);

// A rigid transform (rotation then translation), e.g. worldFromObstacle.
struct RigidTransform {
  Quat rotation = Quat::Identity();
  Vec3 translation = Vec3::Zero();

  Vec3 applyPoint(const Vec3& p) const { return rotation * p + translation; }
  Vec3 applyVector(const Vec3& v) const { return rotation * v; }
  RigidTransform inverse() const {
    RigidTransform inv;
    inv.rotation = rotation.conjugate();
    inv.translation = -(inv.rotation * translation);
    return inv;
  }
  RigidTransform operator*(const RigidTransform& o) const {
    return {rotation * o.rotation, rotation * o.translation + translation};
  }
};

// Axis-aligned bounding box.
struct Bounds3 {
  Vec3 min = Vec3::Constant(std::numeric_limits<float>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<float>::infinity());

  bool empty() const { return !(min.x() <= max.x()); }
  void extend(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  void extend(const Bounds3& b) {
    min = min.cwiseMin(b.min);
    max = max.cwiseMax(b.max);
  }
  Vec3 size() const { return empty() ? Vec3::Zero() : Vec3(max - min); }
  Vec3 center() const { return 0.5f * (min + max); }
  bool contains(const Vec3& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
  // Squared distance from p to the box (0 inside).
  float squaredDistance(const Vec3& p) const { return (min - p).cwiseMax(p - max).cwiseMax(Vec3::Zero()).squaredNorm(); }
};

// Rotation from Euler angles in degrees applied X, then Y, then Z (as in scene files).
Quat quatFromEulerDegrees(const Vec3& degreesXYZ);

}  // namespace tendril
