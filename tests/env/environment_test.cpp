#include "tendril/env/environment.h"

#include "tendril/core/random.h"
#include "tendril/env/primitives.h"
#include "tendril/env/topology.h"

#include <gtest/gtest.h>

#include <limits>

namespace tendril::env {
namespace {

ObstacleDef def(const char* name, TriangleMesh mesh, RigidTransform t = {}) {
  ObstacleDef d;
  d.name = name;
  d.mesh = std::move(mesh);
  d.worldFromLocal = t;
  return d;
}

// Brute-force closest distance over every triangle, for checking the BVH query.
float bruteDistance(const Environment& env, const Vec3& p) {
  float best = 1e30f;
  for (uint32_t id = 0; id < env.obstacleCount(); ++id) {
    TriangleMesh m = env.obstacleMesh(id);
    const RigidTransform& t = env.obstacle(id).worldFromLocal;
    for (size_t i = 0; i < m.indices.size(); i += 3) {
      auto c = closestPointOnTriangle(p, t.applyPoint(m.positions[m.indices[i]]),
                                      t.applyPoint(m.positions[m.indices[i + 1]]),
                                      t.applyPoint(m.positions[m.indices[i + 2]]));
      best = std::min(best, (c.point - p).norm());
    }
  }
  return best;
}

TEST(Environment, RayCastHitsBoxFaceWithOutwardNormal) {
  Environment env;
  env.addObstacle(def("box", makeBox(Vec3(1, 1, 1)), {Quat::Identity(), Vec3(0, 0, 5)}));
  env.commit();
  auto hit = env.rayCast(Vec3(0, 0, 0), Vec3(0, 0, 1), 100.0f);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->t, 4.5f, 1e-5f);
  EXPECT_TRUE(hit->normal.isApprox(Vec3(0, 0, -1), 1e-5f));
  EXPECT_FALSE(env.rayCast(Vec3(0, 0, 0), Vec3(0, 0, -1), 100.0f));
  EXPECT_FALSE(env.rayCast(Vec3(0, 0, 0), Vec3(0, 0, 1), 4.0f));
  EXPECT_EQ(env.countSegmentHits(Vec3(0, 0, 0), Vec3(0, 0, 10)), 2u);
  EXPECT_EQ(env.countSegmentHits(Vec3(0, 0, 0), Vec3(0, 0, 5)), 1u);
  EXPECT_EQ(env.countSegmentHits(Vec3(0, 0, 0), Vec3(0, 0, 4)), 0u);
}

TEST(Environment, RaysEmbreeCannotTakeHitNothing) {
  // A plant gone wrong (a turtle or particle far out or NaN) asks about rays Embree refuses
  // (its assertion would abort the process): they hit nothing, and the ray beside them still hits.
  Environment env;
  env.addObstacle(def("box", makeBox(Vec3(1, 1, 1)), {Quat::Identity(), Vec3(0, 0, 5)}));
  env.commit();
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const Vec3 z = Vec3::UnitZ();
  for (const Vec3& origin : {Vec3(nan, 0, 0), Vec3(0, 0, -1e30f), Vec3(0, inf, 0)}) {
    EXPECT_FALSE(env.rayCast(origin, z, 100.0f));
    EXPECT_FALSE(env.occluded(origin, z, 100.0f));
    const Vec3 to = origin + Vec3(0, 0, 10);
    EXPECT_FALSE(env.anySegmentBlocked(&origin, &to, 1));
  }
  EXPECT_FALSE(env.rayCast(Vec3::Zero(), Vec3(0, nan, 1), 100.0f));
  EXPECT_FALSE(env.rayCast(Vec3::Zero(), Vec3(0, 0, 3e18f), 100.0f));
  EXPECT_FALSE(env.rayCast(Vec3::Zero(), z, nan));
  EXPECT_FALSE(env.occluded(Vec3::Zero(), z, 100.0f, nan));
  EXPECT_TRUE(env.rayCast(Vec3::Zero(), z, inf));
  EXPECT_TRUE(env.occluded(Vec3::Zero(), z, 100.0f));
}

// Rays (of any length) and segment tests skip the obstacles whose boxes their span misses. Segments that only
// just reach a surface (0.2 or 1 mm past it) must still be blocked, and those beside
// an obstacle's box must not: checked against the analytic answer for a box turned about y,
// alone (its box is tested) and among nine spheres far away (too many obstacles to test).
TEST(Environment, SegmentsThatJustReachAnObstacleAreBlockedAndOthersAreNot) {
  const RigidTransform boxAt{axisAngle(Vec3::UnitY(), 0.5f), Vec3(0, 1, 0)};
  const Vec3 half(0.5f, 0.5f, 0.5f);
  auto insideBox = [&](const Vec3& p) {
    const Vec3 l = boxAt.rotation.conjugate() * (p - boxAt.translation);
    return (l.cwiseAbs() - half).maxCoeff() < 0.0f;
  };
  for (bool many : {false, true}) {
    Environment env;
    env.addObstacle(def("box", makeBox(Vec3(1, 1, 1)), boxAt));
    for (int k = 0; many && k < 9; ++k)
      env.addObstacle(def("sphere", makeSphere(0.5f, 2), {Quat::Identity(), Vec3(20, float(k), 0)}));
    env.commit();
    Rng rng(RandomKey{17, 0, 0, 0, 1});
    int hits = 0, checked = 0;
    for (int i = 0; i < 4000; ++i) {
      // A point on the box's surface, and a segment from outside to just past it.
      Vec3 l(rng.uniform(-0.5f, 0.5f), rng.uniform(-0.5f, 0.5f), rng.uniform(-0.5f, 0.5f));
      const int axis = int(rng.below(3));
      l[axis] = rng.bernoulli(0.5f) ? 0.5f : -0.5f;
      const Vec3 onSurface = boxAt.applyPoint(l);
      const Vec3 outward = boxAt.rotation * (Vec3::Unit(axis) * (l[axis] > 0.0f ? 1.0f : -1.0f));
      const Vec3 start = onSurface + outward * rng.uniform(0.001f, 0.3f) + 0.1f * rng.unitVector();
      if (insideBox(start)) continue;
      const float past = i % 4 == 0 ? 0.0002f : 0.001f;  // ending 0.2 or 1 mm inside
      const Vec3 end = onSurface + (onSurface - start).normalized() * past;
      const Vec3 d = (end - start).normalized();
      const float len = (end - start).norm();
      EXPECT_TRUE(env.anySegmentBlocked(&start, &end, 1)) << many << " " << i;
      EXPECT_TRUE(env.rayCast(start, d, len)) << many << " " << i;
      EXPECT_TRUE(env.occluded(start, d, len)) << many << " " << i;
      EXPECT_TRUE(env.occluded(start - 5.0f * d, d, std::numeric_limits<float>::infinity())) << many << " " << i;
      ++hits;
      // The same segment moved 2 mm off the surface beside the box: clear.
      const Vec3 shift = outward * (0.002f + (len + 0.01f));
      const Vec3 a = start + shift, b = end + shift;
      if (insideBox(a) || insideBox(b)) continue;
      EXPECT_FALSE(env.anySegmentBlocked(&a, &b, 1)) << many << " " << i;
      EXPECT_FALSE(env.rayCast(a, d, len)) << many << " " << i;
      EXPECT_FALSE(env.occluded(a, d, len)) << many << " " << i;
      ++checked;
    }
    EXPECT_GT(hits, 3000);
    EXPECT_GT(checked, 2000);
  }
}

TEST(Environment, ClosestPointMatchesBruteForce) {
  Environment env;
  env.addObstacle(def("sphere", makeSphere(0.7f, 3), {axisAngle(Vec3(1, 2, 3), 0.4f), Vec3(1, 0.5f, 0)}));
  env.addObstacle(def("wall", makeWall(Vec3(3, 2, 0.2f), {{Vec2(0, 1), Vec2(0.8f, 0.6f)}}),
                      {Quat::Identity(), Vec3(0, 0, -1)}));
  env.commit();
  Rng rng(RandomKey{11});
  for (int i = 0; i < 500; ++i) {
    Vec3 p(rng.uniform(-2, 2), rng.uniform(-0.5f, 2.5f), rng.uniform(-2, 2));
    float brute = bruteDistance(env, p);
    auto sp = env.closestPoint(p, 10.0f);
    ASSERT_TRUE(sp);
    ASSERT_NEAR(sp->distance, brute, 1e-4f) << "at " << p.transpose();
    ASSERT_NEAR((sp->point - p).norm(), sp->distance, 1e-4f);
    ASSERT_NEAR(sp->away.norm(), 1.0f, 1e-4f);
    // Within a smaller radius the answer exists exactly when the surface is that close.
    EXPECT_EQ(env.closestPoint(p, 0.3f).has_value(), brute <= 0.3f);
  }
}

TEST(Environment, ConvexObstaclesAreToldApartAndLieBehindTheirClosestPointsPlane) {
  Environment env;
  const RigidTransform turned{axisAngle(Vec3(1, 1, 0).normalized(), 0.7f), Vec3(0.3f, 1.0f, -0.2f)};
  env.addObstacle(def("box", makeBox(Vec3(1, 0.5f, 0.3f)), turned));
  env.addObstacle(def("ball", makeSphere(0.4f, 2), {Quat::Identity(), Vec3(3, 0, 0)}));
  env.addObstacle(def("post", makeCylinder(0.2f, 1.0f, 24), {Quat::Identity(), Vec3(-3, 0, 0)}));
  env.addObstacle(def("slab", makePlane(Vec2(2, 2), 0.1f), {Quat::Identity(), Vec3(0, -3, 0)}));
  WallOpening window;
  window.center = Vec2(0, 1);
  window.size = Vec2(0.6f, 0.6f);
  env.addObstacle(def("wall with a window", makeWall(Vec3(3, 2, 0.2f), {window}), {Quat::Identity(), Vec3(0, 0, 4)}));
  env.addObstacle(def("sheet", makePlane(Vec2(2, 2), 0.0f), {Quat::Identity(), Vec3(0, 0, -4)}));
  env.addObstacle(def("fine ball", makeSphere(0.4f, 5), {Quat::Identity(), Vec3(0, 3, 0)}));
  env.commit();
  const bool expected[] = {true, true, true, true, false, false, false};  // the last: too many triangles to check
  for (uint32_t o = 0; o < env.obstacleCount(); ++o) EXPECT_EQ(env.obstacle(o).convex, expected[o]) << env.obstacle(o).name;
  // The bound the stand-off pass uses (models/stand_off.cpp): the plane through a convex
  // obstacle's closest point, facing the query, has the whole obstacle behind it.
  Rng rng(RandomKey{41});
  for (uint32_t o : {0u, 1u, 2u}) {
    const Bounds3& box = env.obstacle(o).worldBounds;
    for (int k = 0; k < 300; ++k) {
      const Vec3 p = box.center() + Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
      const std::optional<SurfacePoint> s = env.closestPoint(p, 10.0f);
      ASSERT_TRUE(s.has_value());
      if (s->obstacle != o || env.exactSignedDistance(p, 10.0f) <= 0.0f) continue;
      for (int t = 0; t < 20; ++t) {
        const Vec3 y = box.center() + 1.5f * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
        const std::optional<SurfacePoint> sy = env.closestPoint(y, 10.0f);
        const float dy = env.exactSignedDistance(y, 10.0f);
        if (!sy || sy->obstacle != o) continue;
        EXPECT_GE(dy, s->away.dot(y - s->point) - 1e-5f) << env.obstacle(o).name << " at " << y.transpose();
      }
    }
  }
}

TEST(Environment, AFewTrianglesGiveTheTraversalsClosestPoints) {
  // A box wall and a ground plane (24 triangles: the queries test each triangle's box) against
  // the same with a fine sphere far away (over the limit: Embree's traversal): every closest
  // point, with and without a facing filter and a hint, is the same point at the same distance.
  // Where the wall stands on the ground two triangles can be as near to the last bit of float;
  // there the traversal may have skipped the nearer one, so only which one is named may differ.
  auto fill = [](Environment& env, bool farSphere) {
    env.addObstacle(def("ground", makePlane(Vec2(10, 10), 0.0f)));
    env.addObstacle(def("wall", makeBox(Vec3(4, 2.5f, 0.2f)), {axisAngle(Vec3(0, 1, 0), 0.3f), Vec3(0, 1.25f, -0.1f)}));
    if (farSphere) env.addObstacle(def("far", makeSphere(1.0f, 4), {Quat::Identity(), Vec3(0, 0, 500)}));
    env.commit();
  };
  Environment few, many;
  fill(few, false);
  fill(many, true);
  Rng rng(RandomKey{12});
  int ties = 0;
  for (int i = 0; i < 4000; ++i) {
    const Vec3 p(rng.uniform(-2.5f, 2.5f), rng.uniform(-0.2f, 2.8f), rng.uniform(-0.6f, 0.6f));
    const float radius = i % 2 ? 0.05f : 5.0f;
    const Vec3 facing = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)).normalized();
    const std::optional<SurfacePoint> a = few.closestPoint(p, radius), b = many.closestPoint(p, radius);
    const std::optional<SurfacePoint> fa = few.closestPointFacing(p, radius, facing, 0.2f),
                                      fb = many.closestPointFacing(p, radius, facing, 0.2f);
    for (const auto& [x, y] : {std::pair{&a, &b}, std::pair{&fa, &fb}}) {
      ASSERT_EQ(x->has_value(), y->has_value()) << "at " << p.transpose();
      if (!x->has_value()) continue;
      ASSERT_LE((*x)->distance, (*y)->distance) << "at " << p.transpose();  // never farther
      ASSERT_NEAR((*x)->distance, (*y)->distance, 1e-6f) << "at " << p.transpose();
      ASSERT_LT(((*x)->point - (*y)->point).norm(), 1e-5f);
      if ((*x)->obstacle == (*y)->obstacle && (*x)->triangle == (*y)->triangle) {
        ASSERT_EQ((*x)->point, (*y)->point) << "at " << p.transpose();
        ASSERT_EQ((*x)->normal, (*y)->normal);
        ASSERT_EQ((*x)->away, (*y)->away);
        ASSERT_EQ((*x)->distance, (*y)->distance);
      } else {
        ++ties;
      }
    }
    if (a) {
      const std::optional<SurfacePoint> ha = few.closestPoint(p, radius, &*a), hb = many.closestPoint(p, radius, &*b);
      ASSERT_TRUE(ha && hb);
      ASSERT_NEAR(ha->distance, a->distance, 1e-6f);
      ASSERT_NEAR(hb->distance, b->distance, 1e-6f);
    }
  }
  EXPECT_LT(ties, 40) << "ties are rare: points near the wall's foot";
}

TEST(Environment, ExactSignedDistanceIsNegativeInsideOnly) {
  Environment env;
  env.addObstacle(def("box", makeBox(Vec3(1, 1, 1))));
  env.commit();
  EXPECT_NEAR(env.exactSignedDistance(Vec3(0, 0, 0), 5), -0.5f, 1e-5f);
  EXPECT_NEAR(env.exactSignedDistance(Vec3(0.4f, 0.45f, 0.1f), 5), -0.05f, 1e-5f);
  EXPECT_NEAR(env.exactSignedDistance(Vec3(1, 0, 0), 5), 0.5f, 1e-5f);
  // Near a corner the closest feature is a vertex or edge: pseudonormals still give the sign.
  EXPECT_GT(env.exactSignedDistance(Vec3(0.6f, 0.6f, 0.6f), 5), 0.0f);
  EXPECT_LT(env.exactSignedDistance(Vec3(0.49f, 0.49f, 0.49f), 5), 0.0f);
}

TEST(Environment, SdfGridAgreesWithExactDistance) {
  Environment env;
  ObstacleDef d = def("sphere", makeSphere(0.5f, 4), {Quat::Identity(), Vec3(0, 1, 0)});
  d.sdfCell = 0.02f;
  env.addObstacle(std::move(d));
  env.addObstacle(def("wall", makeWall(Vec3(2, 2, 0.25f), {{Vec2(0, 1), Vec2(0.6f, 0.6f)}}),
                      {Quat::Identity(), Vec3(0, 0, -1.5f)}));
  env.commit();
  Rng rng(RandomKey{5});
  for (int i = 0; i < 400; ++i) {
    Vec3 p(rng.uniform(-1.2f, 1.2f), rng.uniform(-0.2f, 2.2f), rng.uniform(-2, 1));
    float exact = env.exactSignedDistance(p, 10.0f);
    Vec3 g;
    float grid = env.signedDistance(p, &g);
    // Near surfaces (where collisions happen) the trilinear error is below a couple of cells;
    // farther out, beyond the grids, the value is an upper bound that keeps the right sign.
    if (std::abs(exact) < 0.3f) {
      ASSERT_NEAR(grid, exact, 0.05f) << p.transpose();
    } else {
      ASSERT_GE(grid, exact - 0.05f) << p.transpose();
    }
    if (std::abs(exact) > 0.1f) {
      ASSERT_EQ(grid < 0, exact < 0) << p.transpose();
    }
  }
  // Inside the sphere the distance is negative and the gradient points outward.
  Vec3 g;
  EXPECT_LT(env.signedDistance(Vec3(0.2f, 1, 0), &g), -0.2f);
  EXPECT_GT(g.x(), 0.9f);
}

TEST(Environment, MovingAnObstacleMovesEveryQuery) {
  Environment env;
  uint32_t id = env.addObstacle(def("box", makeBox(Vec3(1, 1, 1))));
  env.commit();
  EXPECT_LT(env.signedDistance(Vec3(0, 0, 0)), 0.0f);
  env.setObstacleTransform(id, {axisAngle(Vec3::UnitY(), 0.3f), Vec3(3, 0, 0)});
  env.commit();
  EXPECT_GT(env.signedDistance(Vec3(0, 0, 0)), 2.0f);
  EXPECT_LT(env.signedDistance(Vec3(3, 0, 0)), -0.4f);
  auto hit = env.rayCast(Vec3(0, 0, 0), Vec3(1, 0, 0), 10);
  ASSERT_TRUE(hit);
  EXPECT_GT(hit->t, 2.3f);
  EXPECT_NEAR(env.closestPoint(Vec3(3, 2, 0), 5)->distance, 1.5f, 1e-4f);
}

TEST(Environment, OpenMeshGivesUnsignedDistance) {
  Environment env;
  TriangleMesh m = makeBox(Vec3(1, 1, 1));
  m.indices.resize(m.indices.size() - 6);
  env.addObstacle(def("open", m));
  env.commit();
  EXPECT_FALSE(env.obstacle(0).closed);
  EXPECT_GT(env.exactSignedDistance(Vec3(0, 0, 0), 5), 0.0f);
  EXPECT_GT(env.signedDistance(Vec3(0, 0, 0)), 0.0f);
}

TEST(Environment, LightExposureFollowsShadows) {
  Environment env;
  env.addObstacle(def("roof", makeBox(Vec3(2, 0.1f, 2)), {Quat::Identity(), Vec3(0, 2, 0)}));
  Light sun;
  sun.direction = Vec3(0, -1, 0);
  env.addLight(sun);
  env.commit();
  LightSample under = env.light(Vec3(0, 0, 0));
  LightSample open = env.light(Vec3(5, 0, 0));
  EXPECT_EQ(under.exposure, 0.0f);
  EXPECT_EQ(under.direction, Vec3::Zero());
  EXPECT_EQ(open.exposure, 1.0f);
  EXPECT_TRUE(open.direction.isApprox(Vec3(0, 1, 0)));
  // A second, unblocked point light of equal intensity gives half exposure under the roof.
  Light lamp;
  lamp.type = Light::Type::Point;
  lamp.position = Vec3(5, 0.5f, 0);
  env.addLight(lamp);
  LightSample both = env.light(Vec3(0, 0, 0));
  EXPECT_NEAR(both.exposure, 0.5f, 1e-6f);
  EXPECT_GT(both.direction.x(), 0.9f);
}

TEST(Environment, SoftShadowsGiveFractionalExposure) {
  Environment env;
  env.addObstacle(def("edge", makeBox(Vec3(2, 0.1f, 4)), {Quat::Identity(), Vec3(-1, 2, 0)}));
  Light sun;
  sun.direction = Vec3(0, -1, 0);
  sun.angularRadius = radians(10);
  sun.samples = 64;
  env.addLight(sun);
  env.commit();
  float e = env.light(Vec3(0, 0, 0)).exposure;  // right under the roof's edge
  EXPECT_GT(e, 0.3f);
  EXPECT_LT(e, 0.7f);
}

TEST(Environment, StrokesAttractAndRepel) {
  Environment env;
  Stroke s;
  s.radius = 0.5f;
  s.strength = 2.0f;
  s.points = {Vec3(1, 0, 0), Vec3(1, 0.1f, 0)};
  env.addStroke(s);
  Stroke r;
  r.attract = false;
  r.radius = 0.3f;
  r.points = {Vec3(-1, 0, 0)};
  env.addStroke(r);
  env.commit();
  Vec3 a = env.attraction(Vec3(0.8f, 0, 0));
  EXPECT_GT(a.x(), 0.0f);
  EXPECT_LE(a.norm(), 2.0f);
  Vec3 b = env.attraction(Vec3(-0.9f, 0, 0));
  EXPECT_GT(b.x(), 0.0f);  // pushed away from the repulsor at x = -1
  EXPECT_EQ(env.attraction(Vec3(0, 0, 0)), Vec3::Zero());
  // Closer means stronger.
  EXPECT_GT(env.attraction(Vec3(0.9f, 0, 0)).norm(), env.attraction(Vec3(0.6f, 0, 0)).norm());
  // The repelling stroke keeps growth out where its weight (1 − d/r)², times its strength,
  // reaches ½: within 0.3 · 0.293 = 0.088 m at strength 1. Attracting strokes keep out nothing.
  EXPECT_TRUE(env.repelled(Vec3(-1, 0.08f, 0)));
  EXPECT_FALSE(env.repelled(Vec3(-1, 0.095f, 0)));
  EXPECT_FALSE(env.repelled(Vec3(1, 0, 0)));
  r.strength = 2.0f;  // (1 − d/r)² ≥ ¼: within 0.15 m
  Environment strong;
  strong.addStroke(r);
  strong.commit();
  EXPECT_TRUE(strong.repelled(Vec3(-1, 0.14f, 0)));
  EXPECT_FALSE(strong.repelled(Vec3(-1, 0.16f, 0)));
}

}  // namespace
}  // namespace tendril::env
