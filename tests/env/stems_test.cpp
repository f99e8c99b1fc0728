// Plants as supports: host stems as round cones answering the Environment's queries.
#include "tendril/env/environment.h"

#include "tendril/core/random.h"
#include "tendril/env/primitives.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tendril::env {
namespace {

StemTube tube(Vec3 a, Vec3 b, float ra, float rb, uint32_t plant = 0, uint32_t node = 0) {
  StemTube t;
  t.a = a, t.b = b, t.ra = ra, t.rb = rb, t.plant = plant, t.node = node;
  return t;
}

// Signed distance to the union of balls along the axis, by dense sampling.
float sampledDistance(const StemTube& t, const Vec3& p) {
  float best = 1e30f;
  for (int i = 0; i <= 20000; ++i) {
    const float s = float(i) / 20000.0f;
    best = std::min(best, (p - (t.a + s * (t.b - t.a))).norm() - (t.ra + s * (t.rb - t.ra)));
  }
  return best;
}

TEST(Stems, ClosestOnTubeMatchesTheUnionOfBallsItSweeps) {
  Rng rng(7);
  for (int i = 0; i < 300; ++i) {
    const Vec3 a(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const Vec3 b = a + Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const StemTube t = tube(a, b, rng.uniform(0.01f, 0.3f), rng.uniform(0.01f, 0.3f));
    const Vec3 p(rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-2, 2));
    const TubePoint tp = closestOnTube(t, p);
    EXPECT_NEAR(tp.distance, sampledDistance(t, p), 2e-4f) << i;
    if (tp.distance > 0.0f) {
      // The surface point is on the surface, and p lies along its normal.
      EXPECT_NEAR(sampledDistance(t, tp.point), 0.0f, 2e-4f) << i;
      EXPECT_NEAR((tp.point + tp.distance * tp.normal - p).norm(), 0.0f, 1e-4f) << i;
    }
  }
}

Environment& withTrunk(Environment& env, uint32_t owner = 1) {
  // A vertical trunk of radius 0.2 from y = 0 to y = 4, host plant 3, nodes 0..3.
  std::vector<StemTube> tubes;
  for (uint32_t n = 0; n < 4; ++n) tubes.push_back(tube(Vec3(0, float(n), 0), Vec3(0, float(n + 1), 0), 0.2f, 0.2f, 3, n));
  env.setStems(owner, std::move(tubes));
  env.commit();
  return env;
}

TEST(Stems, RaysHitTheTubeSurfaceWithAnOutwardNormalAndSayWhichNode) {
  Environment env;
  withTrunk(env);
  auto hit = env.rayCast(Vec3(2, 2.5f, 0), Vec3(-1, 0, 0), 10.0f);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->t, 1.8f, 1e-4f);
  EXPECT_NEAR(hit->normal.x(), 1.0f, 1e-4f);
  EXPECT_EQ(hit->obstacle, kOnStem);
  EXPECT_EQ(env.stem(hit->stem()).node, 2u);
  EXPECT_EQ(env.stem(hit->stem()).plant, 3u);
  EXPECT_TRUE(env.occluded(Vec3(2, 2.5f, 0), Vec3(-1, 0, 0), 10.0f));
  EXPECT_FALSE(env.occluded(Vec3(2, 2.5f, 0), Vec3(-1, 0, 0), 1.7f));
  EXPECT_FALSE(env.rayCast(Vec3(2, 2.5f, 0), Vec3(0, 0, 1), 10.0f));
  EXPECT_EQ(env.countSegmentHits(Vec3(2, 2.5f, 0), Vec3(-2, 2.5f, 0)), 2u);
  const Vec3 from[] = {Vec3(1, 1, 1), Vec3(1, 1.5f, 0)};
  const Vec3 to[] = {Vec3(1, 2, 1), Vec3(-1, 1.5f, 0)};
  EXPECT_FALSE(env.anySegmentBlocked(from, to, 1));
  EXPECT_TRUE(env.anySegmentBlocked(from, to, 2));
}

TEST(Stems, ClosestPointAndSignedDistanceSeeTheTube) {
  Environment env;
  withTrunk(env);
  auto sp = env.closestPoint(Vec3(0.5f, 1.5f, 0), 1.0f);
  ASSERT_TRUE(sp);
  EXPECT_TRUE(sp->onStem());
  EXPECT_NEAR(sp->distance, 0.3f, 1e-5f);
  EXPECT_NEAR((sp->point - Vec3(0.2f, 1.5f, 0)).norm(), 0.0f, 1e-5f);
  EXPECT_NEAR(sp->away.x(), 1.0f, 1e-5f);
  EXPECT_EQ(env.stem(sp->stem()).node, 1u);
  EXPECT_FALSE(env.closestPoint(Vec3(0.5f, 1.5f, 0), 0.29f));
  EXPECT_NEAR(env.signedDistance(Vec3(0.5f, 1.5f, 0)), 0.3f, 1e-5f);
  Vec3 g;
  EXPECT_NEAR(env.signedDistance(Vec3(0.1f, 1.5f, 0), &g), -0.1f, 1e-5f);
  EXPECT_NEAR(g.x(), 1.0f, 1e-5f);
  EXPECT_NEAR(env.exactSignedDistance(Vec3(0, 2.0f, 0.15f), 1.0f), -0.05f, 1e-5f);
  // A surface facing the growth direction does not hold a tip growing away from it.
  EXPECT_FALSE(env.closestPointFacing(Vec3(0.5f, 1.5f, 0), 1.0f, Vec3(1, 0, 0), 0.5f));
  EXPECT_TRUE(env.closestPointFacing(Vec3(0.5f, 1.5f, 0), 1.0f, Vec3(0, 1, 0), 0.5f));
}

TEST(Stems, TheNearerOfObstacleAndStemAnswers) {
  Environment env;
  env.addObstacle({"ground", ObstacleKind::Plane, "", makePlane(Vec2(10, 10), 0.1f), {}});
  withTrunk(env);
  auto sp = env.closestPoint(Vec3(0.5f, 0.2f, 0), 1.0f);
  ASSERT_TRUE(sp);
  EXPECT_FALSE(sp->onStem());
  EXPECT_NEAR(sp->distance, 0.2f, 1e-5f);
  sp = env.closestPoint(Vec3(0.5f, 0.4f, 0), 1.0f);
  ASSERT_TRUE(sp);
  EXPECT_TRUE(sp->onStem());
  auto hit = env.rayCast(Vec3(1, 3, 0), Vec3(-1, -1, 0).normalized(), 10.0f);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->obstacle, kOnStem);
  hit = env.rayCast(Vec3(3, 1, 0), Vec3(-1, -1, 0).normalized(), 10.0f);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->obstacle, 0u);
  EXPECT_NEAR(env.signedDistance(Vec3(0.5f, 0.4f, 0)), 0.3f, 1e-3f);
}

TEST(Stems, AViewerDoesNotSeeItsOwnStems) {
  Environment env;
  withTrunk(env, 2);
  const Vec3 p(0.5f, 1.5f, 0);
  env.setStemViewer(2);
  EXPECT_FALSE(env.closestPoint(p, 1.0f));
  EXPECT_FALSE(env.rayCast(Vec3(2, 2.5f, 0), Vec3(-1, 0, 0), 10.0f));
  EXPECT_FALSE(env.occluded(Vec3(2, 2.5f, 0), Vec3(-1, 0, 0), 10.0f));
  EXPECT_EQ(env.signedDistance(p), std::numeric_limits<float>::infinity());
  env.setStemViewer(0);
  EXPECT_TRUE(env.closestPoint(p, 1.0f));
  env.setStemViewer(Environment::kNoStems);
  EXPECT_FALSE(env.closestPoint(p, 1.0f));
  env.setStemViewer(Environment::kEveryStem);
  EXPECT_TRUE(env.closestPoint(p, 1.0f));
  // Replacing an owner's stems with none removes them.
  env.setStems(2, {});
  env.commit();
  EXPECT_EQ(env.stemCount(), 0u);
  EXPECT_FALSE(env.closestPoint(p, 1.0f));
}

TEST(Stems, HostLeavesShadeTheLightAndBlockNothingElse) {
  Environment env;
  env.addLight({});  // straight down
  env.commit();
  const Vec3 p(0, 0, 0);
  ASSERT_FLOAT_EQ(env.light(p).exposure, 1.0f);
  // A leaf 1 m above p.
  env.setStems(1, {}, {{Vec3(-0.5f, 1, -0.5f), Vec3(0.5f, 1, -0.5f), Vec3(0, 1, 0.5f)}});
  env.commit();
  EXPECT_FLOAT_EQ(env.light(p).exposure, 0.0f);
  EXPECT_FALSE(env.rayCast(p, Vec3(0, 1, 0), 10.0f));
  EXPECT_FALSE(env.occluded(p, Vec3(0, 1, 0), 10.0f));
  env.setStemViewer(1);
  EXPECT_FLOAT_EQ(env.light(p).exposure, 1.0f);
  // A trunk shades too.
  env.setStemViewer(Environment::kEveryStem);
  env.setStems(1, {tube(Vec3(-1, 2, 0), Vec3(1, 2, 0), 0.1f, 0.1f)});
  env.commit();
  EXPECT_FLOAT_EQ(env.light(p).exposure, 0.0f);
}

TEST(Stems, BrokenTubesAreDropped) {
  Environment env;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  env.setStems(0, {tube(Vec3(nan, 0, 0), Vec3(0, 1, 0), 0.1f, 0.1f), tube(Vec3(0, 0, 0), Vec3(0, 1, 0), -1, 0.1f),
                   tube(Vec3(0, 0, 0), Vec3(0, 1, 0), 0, 0), tube(Vec3(0, 0, 0), Vec3(0, 1, 0), 0.1f, 0.05f)});
  env.commit();
  EXPECT_EQ(env.stemCount(), 1u);
  EXPECT_TRUE(env.closestPoint(Vec3(0.5f, 0.5f, 0), 1.0f));
}

}  // namespace
}  // namespace tendril::env
