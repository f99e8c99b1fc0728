// Headless rendering through EGL (Mesa's llvmpipe in CI). These tests need an OpenGL context:
// when none can be made they fail with the error naming what was tried; they never skip.
#include "tendril/render/offscreen.h"

#include "support/synthetic_plants.h"
#include "support/test_paths.h"
#include "tendril/core/error.h"
#include "tendril/env/primitives.h"
#include "tendril/io/image.h"
#include "tendril/render/plant_instances.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>

namespace tendril::render {
namespace {

const Vec3 kWallColor(0.6f, 0.12f, 0.05f);    // brick red: red over green over blue
const Vec3 kGroundColor(0.2f, 0.3f, 0.6f);    // blue: blue over green over red
const Vec3 kBackground(0.62f, 0.72f, 0.84f);  // RenderScene's default
const Vec3 kLightDirection = Vec3(0.6f, -0.5f, -0.6f).normalized();
constexpr int kWidth = 320, kHeight = 240;

ObstacleView obstacle(const TriangleMesh& mesh, const RigidTransform& worldFromLocal, const Vec3& color) {
  ObstacleView o;
  o.mesh = &mesh;
  o.worldFromLocal = worldFromLocal;
  o.color = color;
  return o;
}

// A ground slab, a wall whose front face is the plane z = 0, and a 1 m vertical chain with
// leaves standing 35 cm in front of it; a sun from the front left above, so the plant's shadow
// falls on the wall to its lower right. Not copyable: the RenderScene points into it.
struct TestScene {
  TriangleMesh ground = env::makeBox(Vec3(3.0f, 0.1f, 3.0f));
  TriangleMesh wall = env::makeBox(Vec3(2.0f, 1.6f, 0.1f));
  plant::PlantModel plant;
  RenderScene scene;
  Camera camera;

  TestScene(bool obstacles, bool withPlant) {
    plant = meshtest::straightChain(10, 0.1f, 0.012f, 0.006f, Vec3(0.0f, 0.0f, 0.35f));
    meshtest::addLeaves(plant, 2, 0.12f);
    if (obstacles) {
      RigidTransform groundFrame, wallFrame;
      groundFrame.translation = Vec3(0.0f, -0.05f, 0.5f);
      wallFrame.translation = Vec3(0.0f, 0.8f, -0.05f);
      scene.obstacles.push_back(obstacle(ground, groundFrame, kGroundColor));
      scene.obstacles.push_back(obstacle(wall, wallFrame, kWallColor));
    }
    if (withPlant) {
      PlantView view;
      view.model = &plant;
      scene.plants.push_back(view);
    }
    env::Light sun;
    sun.direction = kLightDirection;
    scene.lights.push_back(sun);
    scene.background = kBackground;
    camera.eye = Vec3(0.0f, 0.6f, 3.0f);
    camera.target = Vec3(0.0f, 0.6f, 0.0f);
    camera.fovY = radians(40.0f);
    camera.near = 0.05f;
    camera.far = 50.0f;
  }
  TestScene(const TestScene&) = delete;
  TestScene& operator=(const TestScene&) = delete;
};

RenderSettings testSettings(bool shadows = true) {
  RenderSettings s;
  s.width = kWidth;
  s.height = kHeight;
  s.shadows = shadows;
  return s;
}

// Fails the test (not skips) with the reason when no OpenGL context can be made.
std::unique_ptr<OffscreenRenderer> makeRenderer() {
  try {
    return std::make_unique<OffscreenRenderer>();
  } catch (const Error& e) {
    ADD_FAILURE() << "headless OpenGL is required for the render tests: " << e.what();
    return nullptr;
  }
}

struct PixelBox {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // inclusive
  int area() const { return (x1 - x0 + 1) * (y1 - y0 + 1); }
};

// The pixels covered by the plant's segments and leaf blades as projected by `camera`.
PixelBox projectedBox(const plant::PlantModel& p, const Camera& camera) {
  Vec2 lo = Vec2::Constant(1e9f), hi = Vec2::Constant(-1e9f);
  auto add = [&](const Vec3& w) {
    Vec2 px = projectToPixel(camera, kWidth, kHeight, w).pixel;
    lo = lo.cwiseMin(px);
    hi = hi.cwiseMax(px);
  };
  for (size_t i = 0; i < p.nodeCount(); ++i) {
    add(p.position[i]);
    add(p.tip(i));
  }
  std::vector<LeafInstance> leaves;
  PlantView view;
  view.model = &p;
  std::vector<float> layer(p.leafShapes.size(), 0.0f), aspect;
  std::vector<Vec3> tint(p.leafShapes.size(), Vec3::Ones());
  for (const plant::LeafShape& s : p.leafShapes) aspect.push_back(s.aspect);
  appendLeafInstances(view, layer, aspect, tint, leaves);
  for (const LeafInstance& l : leaves) {
    Vec3 base(l.base.x, l.base.y, l.base.z), w(l.halfWidth.x, l.halfWidth.y, l.halfWidth.z);
    Vec3 along(l.along.x, l.along.y, l.along.z);
    for (Vec3 c : {Vec3(base - w), Vec3(base + w), Vec3(base + along - w), Vec3(base + along + w)}) add(c);
  }
  PixelBox b;
  b.x0 = std::max(0, int(std::floor(lo.x())));
  b.y0 = std::max(0, int(std::floor(lo.y())));
  b.x1 = std::min(kWidth - 1, int(std::ceil(hi.x())));
  b.y1 = std::min(kHeight - 1, int(std::ceil(hi.y())));
  return b;
}

uint8_t srgbByte(float linear) {
  float c = std::clamp(linear, 0.0f, 1.0f);
  float e = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
  return uint8_t(std::lround(e * 255.0f));
}

bool differs(const uint8_t* a, const uint8_t* b, int tolerance) {
  for (int k = 0; k < 3; ++k)
    if (std::abs(int(a[k]) - int(b[k])) > tolerance) return true;
  return false;
}

bool isBackground(const uint8_t* px) {
  uint8_t bg[3] = {srgbByte(kBackground.x()), srgbByte(kBackground.y()), srgbByte(kBackground.z())};
  return !differs(px, bg, 3);
}

bool isGreen(const uint8_t* px) { return px[1] > px[0] && px[1] > px[2]; }

// Mean luminance of the 3×3 pixels around (x, y).
double luminance(const io::Image& img, int x, int y) {
  double sum = 0.0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const uint8_t* p = img.pixel(std::clamp(x + dx, 0, img.width - 1), std::clamp(y + dy, 0, img.height - 1));
      sum += 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    }
  return sum / 9.0;
}

std::pair<int, int> pixelOf(const Camera& camera, const Vec3& world) {
  Vec2 p = projectToPixel(camera, kWidth, kHeight, world).pixel;
  return {int(p.x()), int(p.y())};
}

TEST(RenderOffscreen, ImagesHaveTheRequestedSize) {
  auto r = makeRenderer();
  ASSERT_TRUE(r);
  TestScene t(true, true);
  for (auto [w, h] : {std::pair{203, 157}, {64, 480}}) {
    RenderSettings s = testSettings();
    s.width = w;
    s.height = h;
    io::Image img = r->render(t.scene, t.camera, s);
    EXPECT_EQ(img.width, w);
    EXPECT_EQ(img.height, h);
    EXPECT_EQ(img.rgba.size(), size_t(w) * size_t(h) * 4);
    // A PNG of that size decodes back.
    io::Image back = io::decodeImage(io::encodePng(img), "test");
    EXPECT_EQ(back.width, w);
    EXPECT_EQ(back.height, h);
  }
}

TEST(RenderOffscreen, ThePlantFillsItsProjectedBoxWithGreenLeaves) {
  auto r = makeRenderer();
  ASSERT_TRUE(r);
  TestScene t(false, true);  // the plant alone on the background, filling the view
  t.camera = frameBounds(sceneBounds(t.scene), Vec3(0.0f, 0.0f, -1.0f), float(kWidth) / float(kHeight));
  io::Image img = r->render(t.scene, t.camera, testSettings());
  PixelBox box = projectedBox(t.plant, t.camera);
  ASSERT_GT(box.area(), 10000) << "the plant should span a good part of the image";
  // The stem is vertical: its column is the projected x of its axis ± its radius and a pixel.
  float stemX = projectToPixel(t.camera, kWidth, kHeight, t.plant.position[0]).pixel.x();
  float stemHalfWidth = projectToPixel(t.camera, kWidth, kHeight, t.plant.position[0] + Vec3(0.012f, 0, 0)).pixel.x() -
                        stemX + 1.5f;
  int covered = 0, leafPixels = 0, green = 0, outside = 0;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const uint8_t* px = img.pixel(x, y);
      bool inBox = x >= box.x0 && x <= box.x1 && y >= box.y0 && y <= box.y1;
      if (isBackground(px)) continue;
      if (!inBox) {
        ++outside;
        continue;
      }
      ++covered;
      if (std::abs(float(x) + 0.5f - stemX) <= stemHalfWidth) continue;
      ++leafPixels;
      green += isGreen(px);
    }
  // Five leaves on alternate sides of a bare stem: about a fifth of the box is plant
  // (measured 0.19 with llvmpipe).
  EXPECT_GT(double(covered) / double(box.area()), 0.12) << covered << " plant pixels in a box of " << box.area();
  // Away from the stem every plant pixel is leaf, and leaves are green (anti-aliased edges
  // against the blue sky are the exception).
  EXPECT_GT(double(green) / double(leafPixels), 0.85) << green << " green of " << leafPixels;
  // Nothing is drawn outside the plant's projection (up to anti-aliased edges).
  EXPECT_LT(outside, 20);
}

TEST(RenderOffscreen, ObstaclesShowTheirColour) {
  auto r = makeRenderer();
  ASSERT_TRUE(r);
  TestScene t(true, true);
  io::Image img = r->render(t.scene, t.camera, testSettings());
  // Far from the plant and its shadow: the wall's upper left and the ground's front left.
  auto [wx, wy] = pixelOf(t.camera, Vec3(-0.7f, 1.3f, 0.0f));
  const uint8_t* wall = img.pixel(wx, wy);
  EXPECT_GT(wall[0], wall[1]) << "wall r > g";
  EXPECT_GT(wall[1], wall[2]) << "wall g > b";
  EXPECT_GT(wall[0], 1.4 * wall[1]) << "red, not grey";
  EXPECT_GT(wall[0], 100) << "lit, not black";
  auto [gx, gy] = pixelOf(t.camera, Vec3(-0.8f, 0.0f, 1.2f));
  const uint8_t* ground = img.pixel(gx, gy);
  EXPECT_GT(ground[2], ground[1]) << "ground b > g";
  EXPECT_GT(ground[1], ground[0]) << "ground g > r";
  EXPECT_GT(ground[2], 1.4 * ground[0]);
  EXPECT_LT(ground[2], 250) << "not blown out";
}

TEST(RenderOffscreen, ThePlantShadowsTheWall) {
  auto r = makeRenderer();
  ASSERT_TRUE(r);
  TestScene withPlant(true, true), bare(true, false);
  io::Image lit = r->render(withPlant.scene, withPlant.camera, testSettings(false));
  io::Image shadowed = r->render(withPlant.scene, withPlant.camera, testSettings(true));
  io::Image wallOnly = r->render(bare.scene, bare.camera, testSettings(true));
  // The centre of each leaf blade, moved along the light onto the wall plane z = 0. Take the
  // leaves whose shadow lands on the wall where the camera sees the wall itself (the render
  // without shadows equals the one without the plant there).
  const plant::PlantModel& p = withPlant.plant;
  int tested = 0;
  for (size_t i = 0; i < p.leafCount(); ++i) {
    Vec3 y = p.leafWorldRotation(i) * Vec3::UnitY();
    Vec3 centre = p.leafWorldPosition(i) + (p.leafPetiole[i] + 0.5f * p.leafSize[i]) * y;
    Vec3 onWall = centre + (centre.z() / -kLightDirection.z()) * kLightDirection;
    if (onWall.y() < 0.1f || onWall.y() > 1.5f) continue;
    auto [x, yPx] = pixelOf(withPlant.camera, onWall);
    bool seesWall = true;
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx)
        seesWall = seesWall && !differs(lit.pixel(x + dx, yPx + dy), wallOnly.pixel(x + dx, yPx + dy), 40);
    if (!seesWall) continue;
    ++tested;
    double dark = luminance(shadowed, x, yPx);
    double unshadowed = luminance(wallOnly, x, yPx);
    // The same wall pixel without the plant, and a wall pixel far from any shadow, are both
    // much brighter (the shadow measured 28% of the lit wall with llvmpipe).
    auto [fx, fy] = pixelOf(withPlant.camera, Vec3(-0.7f, onWall.y(), 0.0f));
    EXPECT_LT(dark, 0.7 * unshadowed) << "leaf " << i << " at pixel " << x << "," << yPx;
    EXPECT_LT(dark, 0.7 * luminance(shadowed, fx, fy)) << "leaf " << i;
  }
  EXPECT_GE(tested, 2) << "some leaf shadows should fall on visible wall";
}

TEST(RenderOffscreen, RenderingIsDeterministic) {
  TestScene t(true, true);
  io::Image first, second;
  {
    auto r = makeRenderer();
    ASSERT_TRUE(r);
    first = r->render(t.scene, t.camera, testSettings());
    second = r->render(t.scene, t.camera, testSettings());
  }
  EXPECT_TRUE(first.rgba == second.rgba) << "the same renderer twice";
  // A new context with a single llvmpipe thread (the default uses every core): llvmpipe
  // rasterises tiles independently with the same arithmetic, so the pixels are bit-identical.
  const char* previous = std::getenv("LP_NUM_THREADS");
  std::string saved = previous ? previous : "";
  setenv("LP_NUM_THREADS", "1", 1);
  io::Image third;
  {
    auto r = makeRenderer();
    ASSERT_TRUE(r);
    third = r->render(t.scene, t.camera, testSettings());
  }
  if (previous)
    setenv("LP_NUM_THREADS", saved.c_str(), 1);
  else
    unsetenv("LP_NUM_THREADS");
  EXPECT_TRUE(first.rgba == third.rgba) << "one rasteriser thread against the default";
}

TEST(RenderOffscreen, StressColoursBranchesFromBlueToRed) {
  auto r = makeRenderer();
  ASSERT_TRUE(r);
  TestScene t(false, false);
  plant::PlantModel stem = meshtest::straightChain(10, 0.1f, 0.03f, 0.03f, Vec3(0.0f, 0.1f, 0.35f));
  std::vector<float> stress(stem.nodeCount());
  for (size_t i = 0; i < stress.size(); ++i) stress[i] = float(i) / float(stress.size() - 1);
  PlantView view;
  view.model = &stem;
  view.stress = stress;
  t.scene.plants.push_back(view);
  io::Image img = r->render(t.scene, t.camera, testSettings());
  auto [bx, by] = pixelOf(t.camera, stem.position[0] + Vec3(0.0f, 0.05f, 0.03f));
  auto [tx, ty] = pixelOf(t.camera, stem.position[9] + Vec3(0.0f, 0.05f, 0.03f));
  const uint8_t* low = img.pixel(bx, by);
  const uint8_t* high = img.pixel(tx, ty);
  EXPECT_GT(low[2], low[0] + 40) << "unstressed: blue";
  EXPECT_GT(high[0], high[2] + 40) << "stressed: red";
}

TEST(RenderOffscreen, SelectedObstaclesAreHighlighted) {
  auto r = makeRenderer();
  ASSERT_TRUE(r);
  TestScene t(true, false);
  io::Image plain = r->render(t.scene, t.camera, testSettings());
  t.scene.obstacles[0].selected = true;  // the (blue) ground
  io::Image selected = r->render(t.scene, t.camera, testSettings());
  auto [gx, gy] = pixelOf(t.camera, Vec3(-0.8f, 0.0f, 1.2f));
  const uint8_t* a = plain.pixel(gx, gy);
  const uint8_t* b = selected.pixel(gx, gy);
  EXPECT_GT(int(b[0]), int(a[0]) + 30) << "warmer";
  EXPECT_LT(int(b[2]) - int(b[0]), int(a[2]) - int(a[0])) << "less blue than red";
  // The wall, not selected, is unchanged.
  auto [wx, wy] = pixelOf(t.camera, Vec3(-0.7f, 1.3f, 0.0f));
  EXPECT_FALSE(differs(plain.pixel(wx, wy), selected.pixel(wx, wy), 0));
}

TEST(RenderOffscreen, PlantPrimitivesAreDrawnInTheirColourAndCastShadows) {
  auto r = makeRenderer();
  ASSERT_TRUE(r);
  TestScene t(true, false);
  // A one-node plant carrying a 30 cm yellow cube 40 cm above the node, turned 45° about y;
  // the same mesh twice (one draw), the second cube beside the first.
  plant::PlantModel p = meshtest::straightChain(1, 0.2f, 0.01f, 0.01f, Vec3(-0.3f, 0.3f, 0.4f));
  plant::PrimitiveMesh cube;
  cube.mesh = env::makeBox(Vec3::Constant(0.3f));
  cube.color = Vec3(0.8f, 0.65f, 0.05f);
  p.meshes.push_back(cube);
  for (float dx : {0.0f, 0.6f}) {
    plant::Primitive prim;
    prim.node = 0;
    Eigen::Affine3f nodeFromPrimitive = Eigen::Translation3f(dx, 0.4f, 0.0f) * axisAngle(Vec3::UnitY(), 0.25f * kPi);
    prim.nodeFromPrimitive = nodeFromPrimitive.matrix();
    p.primitives.push_back(prim);
  }
  PlantView view;
  view.model = &p;
  t.scene.plants.push_back(view);
  io::Image img = r->render(t.scene, t.camera, testSettings());
  EXPECT_EQ(r->renderer().lastFrame().primitiveInstances, 2u);
  for (float dx : {0.0f, 0.6f}) {
    auto [x, y] = pixelOf(t.camera, Vec3(-0.3f + dx, 0.7f, 0.4f));
    const uint8_t* px = img.pixel(x, y);
    EXPECT_GT(px[0], px[2] + 60) << "yellow cube " << dx;
    EXPECT_GT(px[1], px[2] + 60) << "yellow cube " << dx;
  }
  // The cubes cast shadows onto the wall like everything else: the wall behind and to the
  // lower right of the first cube is darker than the wall far to the left.
  Vec3 centre(-0.3f, 0.7f, 0.4f);
  Vec3 onWall = centre + (centre.z() / -kLightDirection.z()) * kLightDirection;
  auto [sx, sy] = pixelOf(t.camera, onWall);
  auto [fx, fy] = pixelOf(t.camera, Vec3(-0.9f, onWall.y(), 0.0f));
  EXPECT_LT(luminance(img, sx, sy), 0.7 * luminance(img, fx, fy));
}

TEST(RenderOffscreen, StrokesAndGizmosAreDrawn) {
  auto r = makeRenderer();
  ASSERT_TRUE(r);
  TestScene t(false, false);
  env::Stroke attract, repel;
  attract.radius = 0.3f;
  attract.points = {Vec3(-0.6f, 0.8f, 0.0f)};
  repel.attract = false;
  repel.radius = 0.3f;
  repel.points = {Vec3(0.6f, 0.8f, 0.0f)};
  t.scene.strokes = {attract, repel};
  GizmoLine arrow;
  arrow.start = Vec3(-0.5f, 0.2f, 0.0f);
  arrow.end = Vec3(0.5f, 0.2f, 0.0f);
  arrow.color = Vec3(1.0f, 1.0f, 0.0f);
  arrow.arrow = true;
  t.scene.gizmos.push_back(arrow);
  RenderSettings s = testSettings();
  s.lineWidth = 3.0f;
  io::Image img = r->render(t.scene, t.camera, s);
  auto [ax, ay] = pixelOf(t.camera, attract.points[0]);
  auto [rx, ry] = pixelOf(t.camera, repel.points[0]);
  EXPECT_TRUE(isGreen(img.pixel(ax, ay)));
  const uint8_t* red = img.pixel(rx, ry);
  EXPECT_GT(red[0], red[1]);
  EXPECT_GT(red[0], red[2]);
  auto [lx, ly] = pixelOf(t.camera, Vec3(0.0f, 0.2f, 0.0f));
  const uint8_t* line = img.pixel(lx, ly);
  EXPECT_GT(line[0], 200);
  EXPECT_GT(line[1], 200);
  EXPECT_LT(line[2], 120) << "yellow line";
}

TEST(RenderOffscreen, AirStreaksShowTheirSpeedAlongTheirVelocity) {
  // Three rows of air particles in front of the background: still, at half the scale's top
  // and at its top, moving along +x. Streaks are blue, green and red, and lie along x only.
  auto r = makeRenderer();
  ASSERT_TRUE(r);
  TestScene t(false, false);
  const float speeds[3] = {0.0f, 2.0f, 4.0f}, heights[3] = {0.3f, 0.8f, 1.3f};
  for (int row = 0; row < 3; ++row)
    for (int k = 0; k < 9; ++k) {
      t.scene.air.positions.push_back(Vec3(-0.4f + 0.1f * float(k), heights[row], 0.0f));
      t.scene.air.velocities.push_back(Vec3(speeds[row], 0.0f, 0.0f));
    }
  t.scene.air.maxSpeed = 4.0f;
  t.scene.air.streakSeconds = 0.025f;  // 10 cm at the top speed: the row is one line
  t.scene.air.minLength = 0.02f;
  RenderSettings s = testSettings();
  s.lineWidth = 4.0f;
  io::Image img = r->render(t.scene, t.camera, s);
  auto dominant = [&](const Vec3& p) {
    auto [x, y] = pixelOf(t.camera, p);
    const uint8_t* c = img.pixel(x, y);
    return c[0] > c[1] + 40 && c[0] > c[2] + 40 ? 0 : c[1] > c[0] + 40 && c[1] > c[2] + 40 ? 1
                                                      : c[2] > c[0] + 40 && c[2] > c[1] + 40 ? 2 : -1;
  };
  EXPECT_EQ(dominant(Vec3(0.0f, 0.3f, 0.0f)), 2) << "still air is blue";
  EXPECT_EQ(dominant(Vec3(0.0f, 0.8f, 0.0f)), 1) << "half the top speed is green";
  EXPECT_EQ(dominant(Vec3(0.0f, 1.3f, 0.0f)), 0) << "the top speed is red";
  EXPECT_EQ(dominant(Vec3(0.04f, 1.3f, 0.0f)), 0) << "and 10 cm long";
  EXPECT_EQ(dominant(Vec3(0.05f, 0.8f, 0.0f)), -1) << "half as long at half the speed";
  EXPECT_EQ(dominant(Vec3(0.05f, 1.4f, 0.0f)), -1) << "streaks run along the velocity only";
  EXPECT_EQ(dominant(Vec3(0.05f, 0.3f, 0.0f)), -1) << "still air is a short tick";
}

}  // namespace
}  // namespace tendril::render
