#include "tendril/core/curve.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace tendril {
namespace {

TEST(MeshCurve, CatmullRomInterpolatesItsPoints) {
  Vec3 p0(0, 0, 0), p1(1, 0, 0), p2(1.5f, 2, 0), p3(4, 2, 1);
  CurveSegment c = centripetalCatmullRom(p0, p1, p2, p3);
  EXPECT_LT((c.point(0.0f) - p1).norm(), 1e-6f);
  EXPECT_LT((c.point(1.0f) - p2).norm(), 1e-6f);
  // The derivative matches finite differences.
  for (float s : {0.1f, 0.5f, 0.9f}) {
    Vec3 fd = (c.point(s + 1e-3f) - c.point(s - 1e-3f)) / 2e-3f;
    EXPECT_LT((fd - c.derivative(s)).norm(), 1e-2f * c.derivative(s).norm());
  }
}

TEST(MeshCurve, CoincidentPointsStayFinite) {
  Vec3 p(1000.0f, 2.0f, -3.0f);
  CurveSegment c = centripetalCatmullRom(p, p, p, p);
  EXPECT_TRUE(isFinite(c.point(0.5f)));
  EXPECT_TRUE(isFinite(c.derivative(0.5f)));
  c = centripetalCatmullRom(p, p, p + Vec3(0, 1, 0), p + Vec3(0, 1, 0));
  EXPECT_TRUE(isFinite(c.point(0.5f)));
  EXPECT_LT((c.point(1.0f) - (p + Vec3(0, 1, 0))).norm(), 1e-4f);
}

TEST(MeshCurve, CollinearPointsGiveAStraightSegment) {
  CurveSegment c = centripetalCatmullRom(Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(0, 3, 0), Vec3(0, 3.1f, 0));
  for (float s = 0.0f; s <= 1.0f; s += 0.125f) {
    Vec3 p = c.point(s);
    EXPECT_NEAR(p.x(), 0.0f, 1e-6f);
    EXPECT_NEAR(p.z(), 0.0f, 1e-6f);
    EXPECT_GE(p.y(), 1.0f - 1e-5f);  // centripetal: no overshoot past the next short segment
    EXPECT_LE(p.y(), 3.0f + 1e-5f);
  }
}

// Samples of a planar curve (in the XY plane) with unit tangents.
void planarCurve(std::vector<Vec3>& pts, std::vector<Vec3>& tangents) {
  for (int i = 0; i <= 200; ++i) {
    float t = 0.05f * i;
    pts.emplace_back(std::sin(t) * (1.0f + 0.3f * t), t, 0.0f);
    Vec3 d(std::cos(t) * (1.0f + 0.3f * t) + 0.3f * std::sin(t), 1.0f, 0.0f);
    tangents.push_back(d.normalized());
  }
}

TEST(MeshCurve, RotationMinimizingFramesDoNotTwistOnAPlanarCurve) {
  std::vector<Vec3> pts, tangents;
  planarCurve(pts, tangents);
  std::vector<Vec3> normals(pts.size());
  // Starting perpendicular to the plane, the frame normal must stay perpendicular to it.
  rotationMinimizingFrames(pts, tangents, Vec3::UnitZ(), normals);
  for (const Vec3& n : normals) {
    EXPECT_NEAR(n.norm(), 1.0f, 1e-5f);
    EXPECT_GT(n.z(), 0.9999f);
  }
  // Starting in the plane, it must stay in the plane (and perpendicular to the tangent).
  rotationMinimizingFrames(pts, tangents, Vec3::UnitX(), normals);
  for (size_t i = 0; i < normals.size(); ++i) {
    EXPECT_NEAR(normals[i].z(), 0.0f, 1e-4f);
    EXPECT_NEAR(normals[i].dot(tangents[i]), 0.0f, 1e-5f);
  }
}

TEST(MeshCurve, RotationMinimizingFramesOnAHelixHaveNoTwistRate) {
  // On a helix the RMF rotates relative to the Frenet frame at the rate of the torsion
  // (Wang et al. 2008, §2): after arc length s the angle between them is tau·s.
  float a = 1.0f, b = 0.5f;
  float c = std::sqrt(a * a + b * b);
  std::vector<Vec3> pts, tangents, normals;
  int steps = 2000;
  float total = 4.0f * kPi;  // parameter range
  for (int i = 0; i <= steps; ++i) {
    float t = total * i / steps;
    pts.emplace_back(a * std::cos(t), a * std::sin(t), b * t);
    tangents.push_back(Vec3(-a * std::sin(t), a * std::cos(t), b) / c);
  }
  normals.resize(pts.size());
  Vec3 principal0(-1, 0, 0);  // Frenet principal normal at t = 0 points to the axis
  rotationMinimizingFrames(pts, tangents, principal0, normals);
  float tau = b / (c * c);
  float s = c * total;
  float t = total;
  Vec3 principal(-std::cos(t), -std::sin(t), 0.0f);
  Vec3 binormal = tangents.back().cross(principal);
  float angle = std::atan2(normals.back().dot(binormal), normals.back().dot(principal));
  float expected = -tau * s;
  float diff = std::remainder(angle - expected, kTwoPi);
  EXPECT_NEAR(diff, 0.0f, 2e-3f);
}

TEST(MeshCurve, DoubleReflectionSurvivesCoincidentPoints) {
  Vec3 r = doubleReflection(Vec3(1, 2, 3), Vec3::UnitY(), Vec3::UnitZ(), Vec3(1, 2, 3), Vec3::UnitY());
  EXPECT_TRUE(isFinite(r));
  EXPECT_NEAR(r.z(), 1.0f, 1e-6f);
  // Reversed tangent: still a finite unit normal perpendicular to it.
  r = doubleReflection(Vec3::Zero(), Vec3::UnitY(), Vec3::UnitZ(), Vec3(0, 1, 0), -Vec3::UnitY());
  EXPECT_TRUE(isFinite(r));
  EXPECT_NEAR(r.norm(), 1.0f, 1e-5f);
  EXPECT_NEAR(r.dot(Vec3::UnitY()), 0.0f, 1e-5f);
}

}  // namespace
}  // namespace tendril
