#include "tendril/render/camera.h"

#include "tendril/core/error.h"

#include <gtest/gtest.h>

namespace tendril::render {
namespace {

TEST(RenderCamera, FrameBoundsSeesEveryCornerWithLittleMargin) {
  Bounds3 b;
  b.extend(Vec3(-2.0f, 0.0f, -0.1f));
  b.extend(Vec3(2.0f, 3.0f, 0.1f));  // a wall
  for (Vec3 dir : {Vec3(0, 0, -1), Vec3(-0.45f, -0.32f, -1.0f), Vec3(1, -1, 0.2f)}) {
    for (float aspect : {16.0f / 9.0f, 0.6f}) {
      Camera cam = frameBounds(b, dir, aspect);
      validateCamera(cam, "test");
      const int w = int(600 * aspect), h = 600;
      float lo = 1e9f, hi = -1e9f;
      for (int k = 0; k < 8; ++k) {
        Vec3 c((k & 1) ? b.max.x() : b.min.x(), (k & 2) ? b.max.y() : b.min.y(), (k & 4) ? b.max.z() : b.min.z());
        Projection p = projectToPixel(cam, w, h, c);
        ASSERT_TRUE(p.visible);
        EXPECT_GE(p.pixel.x(), 0.0f);
        EXPECT_LE(p.pixel.x(), float(w));
        EXPECT_GE(p.pixel.y(), 0.0f);
        EXPECT_LE(p.pixel.y(), float(h));
        EXPECT_GT(p.depth, cam.near);
        EXPECT_LT(p.depth, cam.far);
        lo = std::min({lo, p.pixel.x() / float(w), p.pixel.y() / float(h)});
        hi = std::max({hi, p.pixel.x() / float(w), p.pixel.y() / float(h)});
      }
      // Tight: the box reaches within 15% of some image edge on both sides.
      EXPECT_LT(lo, 0.15f);
      EXPECT_GT(hi, 0.85f);
    }
  }
}

TEST(RenderCamera, PixelRayGoesThroughTheProjectedPoint) {
  Camera cam;
  cam.eye = Vec3(1.0f, 2.0f, 4.0f);
  cam.target = Vec3(0.2f, 0.8f, 0.0f);
  Vec3 p(0.5f, 1.3f, -0.4f);
  Projection proj = projectToPixel(cam, 640, 360, p);
  Ray ray = pixelRay(cam, 640, 360, proj.pixel);
  Vec3 toP = p - ray.origin;
  EXPECT_NEAR(ray.direction.norm(), 1.0f, 1e-5f);
  EXPECT_LT((toP - toP.dot(ray.direction) * ray.direction).norm(), 1e-4f);
  // The image centre looks at the target.
  EXPECT_LT((pixelRay(cam, 640, 360, Vec2(320, 180)).direction - cam.forward()).norm(), 1e-5f);
}

TEST(RenderCamera, OrbitKeepsDistanceAndStopsShortOfThePoles) {
  Camera cam;
  cam.eye = Vec3(0, 1, 5);
  cam.target = Vec3(0, 1, 0);
  Camera turned = orbit(cam, kPi / 2, 0.0f);
  EXPECT_NEAR(turned.distance(), 5.0f, 1e-4f);
  EXPECT_NEAR(turned.eye.x(), 5.0f, 1e-4f);  // a quarter turn counter-clockwise seen from above
  Camera raised = orbit(cam, 0.0f, 0.3f);
  EXPECT_GT(raised.eye.y(), cam.eye.y());
  EXPECT_NEAR(raised.distance(), 5.0f, 1e-4f);
  Camera top = orbit(cam, 0.0f, 10.0f);
  validateCamera(top, "test");
  EXPECT_NEAR(angleBetween(top.eye - top.target, Vec3::UnitY()), radians(1.0f), 1e-3f);
  Camera bottom = orbit(cam, 0.0f, -10.0f);
  EXPECT_NEAR(angleBetween(bottom.eye - bottom.target, Vec3::UnitY()), radians(179.0f), 1e-3f);
}

TEST(RenderCamera, PanMovesEyeAndTargetTogetherAndZoomScalesTheDistance) {
  Camera cam;
  cam.eye = Vec3(0, 1, 5);
  cam.target = Vec3(0, 1, 0);
  Camera moved = pan(cam, 0.5f, 0.0f);
  EXPECT_LT((moved.eye - moved.target - (cam.eye - cam.target)).norm(), 1e-5f);
  // Half the image height to the right at distance 5 with a 40° field of view.
  EXPECT_NEAR(moved.target.x(), 0.5f * 2.0f * 5.0f * std::tan(0.5f * cam.fovY), 1e-4f);
  Camera closer = zoom(cam, 0.5f);
  EXPECT_NEAR(closer.distance(), 2.5f, 1e-5f);
  EXPECT_NEAR(closer.near, 0.5f * cam.near, 1e-6f);
  EXPECT_EQ(closer.target, cam.target);
}

TEST(RenderCamera, BadCamerasAreErrors) {
  Camera cam;
  cam.target = cam.eye;
  EXPECT_THROW(validateCamera(cam, "test"), Error);
  cam = Camera{};
  cam.fovY = 0.0f;
  EXPECT_THROW(validateCamera(cam, "test"), Error);
  cam = Camera{};
  cam.near = 2.0f;
  cam.far = 1.0f;
  EXPECT_THROW(validateCamera(cam, "test"), Error);
  cam = Camera{};
  cam.up = cam.forward();
  EXPECT_THROW(validateCamera(cam, "test"), Error);
}

}  // namespace
}  // namespace tendril::render
