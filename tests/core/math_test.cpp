#include "tendril/core/math.h"

#include <gtest/gtest.h>

namespace tendril {
namespace {

TEST(Math, RotationBetweenMapsFromOntoTo) {
  const Vec3 pairs[][2] = {{Vec3::UnitY(), Vec3::UnitX()},
                           {Vec3(1, 2, 3), Vec3(-3, 0.5f, 2)},
                           {Vec3::UnitY(), -Vec3::UnitY()},
                           {Vec3(0.3f, -1, 0), Vec3(0.3f, -1, 0)}};
  for (const auto& p : pairs) {
    Quat q = rotationBetween(p[0], p[1]);
    EXPECT_NEAR(q.norm(), 1.0f, 1e-6f);
    EXPECT_LT((q * p[0].normalized() - p[1].normalized()).norm(), 1e-5f);
  }
}

TEST(Math, FrameFromYZIsOrthonormalWithExactY) {
  Quat q = frameFromYZ(Vec3(0, 1, 0.2f), Vec3(0, 0, 1));
  Mat3 m = q.toRotationMatrix();
  EXPECT_LT((m.col(1) - Vec3(0, 1, 0.2f).normalized()).norm(), 1e-6f);
  EXPECT_LT((m.transpose() * m - Mat3::Identity()).norm(), 1e-5f);
  EXPECT_GT(m.col(2).dot(Vec3::UnitZ()), 0.9f);
  EXPECT_NEAR(m.determinant(), 1.0f, 1e-5f);
  // A hint parallel to y still gives a valid frame.
  Quat p = frameFromYZ(Vec3::UnitY(), Vec3::UnitY());
  EXPECT_NEAR(p.toRotationMatrix().determinant(), 1.0f, 1e-5f);
}

TEST(Math, RotateTowardNeverOvershoots) {
  Vec3 d = rotateToward(Vec3::UnitY(), Vec3::UnitX(), radians(10));
  EXPECT_NEAR(degrees(angleBetween(d, Vec3::UnitY())), 10.0f, 1e-3f);
  Vec3 e = rotateToward(Vec3::UnitY(), Vec3(0.01f, 1, 0), radians(10));
  EXPECT_LT((e - Vec3(0.01f, 1, 0).normalized()).norm(), 1e-6f);
}

TEST(Math, AxisAngleAndEuler) {
  Vec3 v = axisAngle(Vec3::UnitZ(), kPi / 2) * Vec3::UnitX();
  EXPECT_LT((v - Vec3::UnitY()).norm(), 1e-6f);
  EXPECT_TRUE(axisAngle(Vec3::Zero(), 1.0f).isApprox(Quat::Identity()));
  Vec3 w = quatFromEulerDegrees(Vec3(0, 90, 0)) * Vec3::UnitX();
  EXPECT_LT((w - (-Vec3::UnitZ())).norm(), 1e-6f);
}

TEST(Math, RigidTransformInverse) {
  RigidTransform t{axisAngle(Vec3(1, 1, 0), 0.7f), Vec3(1, 2, 3)};
  Vec3 p(0.3f, -2, 5);
  EXPECT_LT((t.inverse().applyPoint(t.applyPoint(p)) - p).norm(), 1e-5f);
}

}  // namespace
}  // namespace tendril
