#include "tendril/core/math.h"

#include <algorithm>

namespace tendril {

Vec3 anyPerpendicular(const Vec3& v) {
  // Cross with the axis least aligned with v for the best conditioning.
  Vec3 a = v.cwiseAbs();
  Vec3 other = (a.x() <= a.y() && a.x() <= a.z()) ? Vec3::UnitX()
               : (a.y() <= a.z())                 ? Vec3::UnitY()
                                                  : Vec3::UnitZ();
  return v.cross(other).normalized();
}

Quat rotationBetween(const Vec3& from, const Vec3& to) {
  Vec3 f = from.normalized();
  Vec3 t = to.normalized();
  float d = f.dot(t);
  if (d < -1.0f + 1e-6f) {
    return Quat(Eigen::AngleAxisf(kPi, anyPerpendicular(f)));
  }
  // Half-angle construction: q = [f x t, 1 + f.t] normalised; exact for unit inputs.
  Vec3 c = f.cross(t);
  Quat q(1.0f + d, c.x(), c.y(), c.z());
  return q.normalized();
}

Quat axisAngle(const Vec3& axis, float angle) {
  float n = axis.norm();
  if (!(n > 0.0f)) return Quat::Identity();
  return Quat(Eigen::AngleAxisf(angle, axis / n));
}

Quat laidOn(const Quat& blade, const Vec3& up) {
  Vec3 along = blade * Vec3::UnitY();
  along -= up * up.dot(along);
  if (along.squaredNorm() < 1e-8f) along = anyPerpendicular(up);
  return frameFromYZ(along.normalized(), up);
}

Quat frameFromYZ(const Vec3& y, const Vec3& zHint) {
  Vec3 yn = y.normalized();
  Vec3 z = zHint - yn * yn.dot(zHint);
  float zn = z.norm();
  z = zn > 1e-6f ? Vec3(z / zn) : anyPerpendicular(yn);
  Vec3 x = yn.cross(z);
  Mat3 m;
  m.col(0) = x;
  m.col(1) = yn;
  m.col(2) = z;
  return Quat(m).normalized();
}

float angleBetween(const Vec3& a, const Vec3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

Vec3 rotateToward(const Vec3& dir, const Vec3& target, float maxAngle) {
  float angle = angleBetween(dir, target);
  if (angle <= maxAngle) return target.normalized();
  Vec3 axis = dir.cross(target);
  if (axis.squaredNorm() < 1e-12f) axis = anyPerpendicular(dir);
  return (axisAngle(axis, maxAngle) * dir).normalized();
}

Quat quatFromEulerDegrees(const Vec3& d) {
  Quat qx(Eigen::AngleAxisf(radians(d.x()), Vec3::UnitX()));
  Quat qy(Eigen::AngleAxisf(radians(d.y()), Vec3::UnitY()));
  Quat qz(Eigen::AngleAxisf(radians(d.z()), Vec3::UnitZ()));
  return (qz * qy * qx).normalized();
}

}  // namespace tendril
