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

TEST(Stems, AHintChangesHowFastNotWhatTheClosestStemIs) {
  // A tangle of 400 random tubes in two owners: the answer with any hint (the true nearest stem,
  // a wrong one, one of another owner, a stale index past the end, an obstacle) is the one
  // without, to the bit, for plain and facing searches alike.
  Rng rng(11);
  std::vector<StemTube> tubes[2];
  for (int i = 0; i < 400; ++i) {
    const Vec3 a(rng.uniform(-1, 1), rng.uniform(0, 2), rng.uniform(-1, 1));
    const Vec3 b = a + 0.3f * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    tubes[i % 2].push_back(tube(a, b, rng.uniform(0.002f, 0.05f), rng.uniform(0.002f, 0.05f), i % 2, uint32_t(i)));
  }
  Environment env;
  env.setStems(1, tubes[0]);
  env.setStems(2, tubes[1]);
  env.commit();
  auto same = [](const std::optional<SurfacePoint>& x, const std::optional<SurfacePoint>& y) {
    if (!x || !y) return !x && !y;
    return x->point == y->point && x->away == y->away && x->distance == y->distance && x->triangle == y->triangle;
  };
  int found = 0, differentHint = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p(rng.uniform(-1.2f, 1.2f), rng.uniform(-0.2f, 2.2f), rng.uniform(-1.2f, 1.2f));
    const float radius = rng.uniform(0.01f, 0.4f);
    const Vec3 dir = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)).normalized();
    const auto plain = env.closestPoint(p, radius);
    const auto facing = env.closestPointFacing(p, radius, dir, 0.3f);
    found += plain.has_value();
    SurfacePoint hint;
    hint.obstacle = kOnStem;
    for (uint32_t h : {plain ? plain->triangle : 0u, uint32_t(rng.below(400)), 399u, 400u, 100000u}) {
      hint.triangle = h;
      differentHint += plain && h != plain->triangle;
      EXPECT_TRUE(same(env.closestPoint(p, radius, &hint), plain)) << i << " hint " << h;
      EXPECT_TRUE(same(env.closestPointFacing(p, radius, dir, 0.3f, &hint), facing)) << i << " hint " << h;
    }
    hint.obstacle = 0;  // not a stem: ignored
    EXPECT_TRUE(same(env.closestPoint(p, radius, &hint), plain)) << i;
  }
  EXPECT_GT(found, 500);
  EXPECT_GT(differentHint, 1000);
}

// The least signed distance from the segment p-q to any of the tubes, by dense sampling.
float sampledSegmentDistance(const std::vector<StemTube>& tubes, const Vec3& p, const Vec3& q) {
  float best = 1e30f;
  for (int i = 0; i <= 400; ++i) {
    const Vec3 x = p + (float(i) / 400.0f) * (q - p);
    for (const StemTube& t : tubes) best = std::min(best, closestOnTube(t, x).distance);
  }
  return best;
}

TEST(Stems, LeafOutlinesAreBlockedExactlyWhereTheyTouchAStem) {
  // Tapering and even tubes, some crossing; short segments (leaf edges) thrown among them in
  // groups of five, as a leaf's outline is tested, and alone. Blocked when a segment passes
  // within 0.1 mm of the inside of a tube, clear when it keeps 0.1 mm outside every one; the
  // group's answer is that of its segments together.
  Rng rng(5);
  std::vector<StemTube> tubes;
  for (int i = 0; i < 60; ++i) {
    const Vec3 a(rng.uniform(-0.5f, 0.5f), rng.uniform(0, 1), rng.uniform(-0.5f, 0.5f));
    const Vec3 b = a + 0.4f * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    tubes.push_back(tube(a, b, rng.uniform(0.005f, 0.08f), rng.uniform(0.005f, 0.08f)));
  }
  Environment env;
  env.setStems(1, tubes);
  env.commit();
  int blocked = 0, clear = 0, groupsBlocked = 0;
  for (int g = 0; g < 600; ++g) {
    const Vec3 centre(rng.uniform(-0.6f, 0.6f), rng.uniform(-0.1f, 1.1f), rng.uniform(-0.6f, 0.6f));
    Vec3 from[5], to[5];
    bool any = false, sure = true;
    for (int i = 0; i < 5; ++i) {
      from[i] = centre + 0.05f * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
      to[i] = centre + 0.05f * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
      const float d = sampledSegmentDistance(tubes, from[i], to[i]);
      if (std::fabs(d) < 1e-4f) {
        sure = false;  // grazing: either answer is right
        continue;
      }
      any |= d < 0.0f;
      EXPECT_EQ(env.anySegmentBlocked(&from[i], &to[i], 1), d < 0.0f) << g << " " << i << " " << d;
      (d < 0.0f ? blocked : clear) += 1;
    }
    if (sure) {
      EXPECT_EQ(env.anySegmentBlocked(from, to, 5), any) << g;
      groupsBlocked += any;
    }
  }
  EXPECT_GT(blocked, 300);
  EXPECT_GT(clear, 300);
  EXPECT_GT(groupsBlocked, 50);
}

TEST(Stems, LeafOutlinesAmongManyStemsFallBackToRays) {
  // 200 parallel twigs 2 mm apart: more tubes near a leaf than the gathered test takes. A leaf
  // edge across them is blocked, one beside them is not, as rays say.
  std::vector<StemTube> tubes;
  for (int i = 0; i < 200; ++i)
    tubes.push_back(tube(Vec3(0.002f * float(i), 0, 0), Vec3(0.002f * float(i), 0.2f, 0), 0.0005f, 0.0005f));
  Environment env;
  env.setStems(1, tubes);
  env.commit();
  const Vec3 from[2] = {Vec3(-0.01f, 0.1f, 0.0f), Vec3(-0.01f, 0.1f, 0.01f)};
  const Vec3 to[2] = {Vec3(0.41f, 0.1f, 0.0f), Vec3(0.41f, 0.1f, 0.01f)};
  EXPECT_TRUE(env.anySegmentBlocked(from, to, 2));
  EXPECT_FALSE(env.anySegmentBlocked(from + 1, to + 1, 1));
  EXPECT_TRUE(env.occluded(from[0], (to[0] - from[0]).normalized(), (to[0] - from[0]).norm()));
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
