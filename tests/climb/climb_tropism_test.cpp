// The tip rotation of seed 003's tropisms (eq. 3–4) in the climbing model, one tropism at a time.
//
// Eq. 3 gives the axis of rotation a = d × v (world space) between the tip's direction d and the
// tropism vector v; eq. 4 turns the tip's frame about it. The angle is the strength-weighted
// sine |d × v| (ABOP §2.4's torque), never past v (docs/species.md). Each test grows a single
// tip from a known state with only one strength set: the first segment grows along d, the
// Tropism rule then turns the tip, and the second segment grows along the turned direction d'.
// The test computes v from the scene it built (for attraction, from the field's value it asks
// the environment for) and d' by Rodrigues' formula, and checks that d' lies in the plane of d
// and v, on v's side (the rotation axis is d × v, not its opposite), by the angle above, within
// kAngleTol; and that with the strength 0 the tip does not turn. No test seam is needed: a
// plant seeded in free air or beside a wall is a single tip in a known state.
#include "tendril/climb/climb_system.h"
#include "tendril/env/environment.h"
#include "tendril/env/primitives.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tendril::climb {
namespace {

// Float arithmetic on unit vectors: the directions agree to a few ulps of 1 after two frame
// constructions; 2e-5 rad (about 1e-3 degrees) is far below any turn tested here.
constexpr float kAngleTol = 2e-5f;

// A species that grows straight: every tropism strength 0, only the tropism rule, no
// branching, leaves, crowding or decrease.
ClimbSpecies straightSpecies() {
  ClimbSpecies s;
  s.gravity = s.light = s.randomness = s.adhesion = s.up = 0.0f;
  s.userDirectionStrength = s.windStrength = s.attraction = 0.0f;
  s.rules = {{RuleKind::Tropism, 1, 1.0f}};
  s.crowdingRadius = 0.0f;
  s.maxUnsupported = 0;
  return s;
}

// A wall whose front face is the plane z = 0 (outward normal +z), 4 m wide and high.
uint32_t addWall(env::Environment& env) {
  env::ObstacleDef d;
  d.name = "wall";
  d.kind = env::ObstacleKind::Box;
  d.mesh = env::makeBox(Vec3(4, 4, 0.2f));
  d.worldFromLocal.translation = Vec3(0, 2, -0.1f);
  return env.addObstacle(std::move(d));
}

struct Turn {
  Vec3 d, turned;  // the first and second segments' directions
  bool climbing;   // the first segment was grown climbing
  Vec3 firstEnd;   // where the tropism was evaluated
};

// Grows two segments of one plant seeded at p with direction d.
Turn growTwo(const ClimbSpecies& s, const env::Environment& env, const Vec3& p, const Vec3& d, uint64_t seed = 1) {
  ClimbSystem system(7);
  system.addPlant({"tip", s, p, d, seed}, env);
  system.step(env);
  system.step(env);
  plant::PlantModel m = system.snapshot(0);
  EXPECT_EQ(m.nodeCount(), 2u);
  if (m.nodeCount() < 2) return {d, d, false, p};
  EXPECT_EQ(m.parent[1], 0);
  return {m.direction(0), m.direction(1), (m.flags[0] & plant::kNodeClimbing) != 0, m.tip(0)};
}

// Eq. 3–4, written out independently of the model: the rotation of d about d × v by
// min(|d × v|, angle(d, v)), by Rodrigues' formula.
Vec3 expectedTurn(const Vec3& d, const Vec3& v) {
  const Vec3 axis = d.cross(v);
  const double s = axis.norm();
  if (s == 0.0) return d;
  const double angleToV = std::atan2(s, double(d.dot(v)));
  const double phi = std::min(s, angleToV);
  const Eigen::Vector3d k = axis.cast<double>() / s, dd = d.cast<double>();
  const Eigen::Vector3d r = dd * std::cos(phi) + k.cross(dd) * std::sin(phi) + k * k.dot(dd) * (1.0 - std::cos(phi));
  return r.normalized().cast<float>();
}

double angle(const Vec3& a, const Vec3& b) {
  const Eigen::Vector3d x = a.cast<double>(), y = b.cast<double>();
  return std::atan2(x.cross(y).norm(), x.dot(y));
}

// The turn grown matches eq. 3–4 for tropism vector v, and is a real turn toward v.
void expectTurnToward(const Turn& t, const Vec3& v) {
  const Vec3 axis = t.d.cross(v);
  ASSERT_GT(axis.norm(), 1e-3f) << "the test's tropism vector must not be parallel to the tip";
  const Vec3 k = axis.normalized();
  const double phi = std::min(double(axis.norm()), angle(t.d, v));
  // About d × v: d' stays in the plane of d and v, and turns the way d × v says (toward v).
  EXPECT_NEAR(t.turned.dot(k), 0.0, kAngleTol) << "turned out of the plane of d and v";
  EXPECT_GT(t.d.cross(t.turned).dot(k), 0.0f) << "turned about -(d × v), away from v";
  // By the angle eq. 3–4 give, and closer to v than before.
  EXPECT_NEAR(angle(t.d, t.turned), phi, kAngleTol);
  EXPECT_LT(angle(t.turned, v), angle(t.d, v));
  const Vec3 want = expectedTurn(t.d, v);
  EXPECT_NEAR(angle(t.turned, want), 0.0, kAngleTol) << "got " << t.turned.transpose() << ", eq. 3-4 give "
                                                     << want.transpose();
}

void expectNoTurn(const Turn& t) { EXPECT_NEAR(angle(t.d, t.turned), 0.0, kAngleTol); }

const Vec3 kSideways = Vec3(1, 0, 0);
const Vec3 kFreeAir = Vec3(0, 1, 0.5f);   // 0.5 m in front of the wall (when there is one)
const Vec3 kOnWall = Vec3(0, 1, 0.05f);   // within the 0.08 m adhesion distance of the wall

TEST(ClimbTropism, GravityTurnsAFreeTipDown) {
  env::Environment env;
  env.commit();
  ClimbSpecies s = straightSpecies();
  s.gravity = 0.2f;
  Turn t = growTwo(s, env, kFreeAir, kSideways);
  EXPECT_FALSE(t.climbing);
  expectTurnToward(t, s.gravity * Vec3(0, -1, 0));
  EXPECT_NEAR(angle(t.d, t.turned), 0.2, kAngleTol);  // |d × v| for d ⟂ v
  s.gravity = 0.0f;
  expectNoTurn(growTwo(s, env, kFreeAir, kSideways));
}

TEST(ClimbTropism, GravityDoesNotActOnAClimbingTip) {
  env::Environment env;
  addWall(env);
  env.commit();
  ClimbSpecies s = straightSpecies();
  s.gravity = 0.2f;
  Turn t = growTwo(s, env, kOnWall, kSideways);
  EXPECT_TRUE(t.climbing);
  expectNoTurn(t);  // eq. 7: adhesion and v_up replace gravity
}

TEST(ClimbTropism, AdhesionTurnsAClimbingTipTowardItsSupport) {
  env::Environment env;
  addWall(env);
  env.commit();
  ClimbSpecies s = straightSpecies();
  s.adhesion = 0.3f;
  Turn t = growTwo(s, env, kOnWall, kSideways);
  EXPECT_TRUE(t.climbing);
  expectTurnToward(t, s.adhesion * Vec3(0, 0, -1));  // toward the wall's face z = 0
  // Not climbing (the same tip 0.5 m from the wall): no adhesion.
  Turn free = growTwo(s, env, kFreeAir, kSideways);
  EXPECT_FALSE(free.climbing);
  expectNoTurn(free);
  s.adhesion = 0.0f;
  expectNoTurn(growTwo(s, env, kOnWall, kSideways));
}

TEST(ClimbTropism, UpTurnsAClimbingTipUpwardOnly) {
  env::Environment env;
  addWall(env);
  env.commit();
  ClimbSpecies s = straightSpecies();
  s.up = 0.25f;
  // A tip growing sideways and slightly down the wall turns up, in the wall's plane.
  const Vec3 d = Vec3(1, -0.3f, 0).normalized();
  Turn t = growTwo(s, env, kOnWall, d);
  EXPECT_TRUE(t.climbing);
  expectTurnToward(t, s.up * Vec3(0, 1, 0));
  EXPECT_NEAR(t.turned.z(), 0.0f, kAngleTol);
  // Eq. 6: a tip that is not climbing feels no v_up.
  Turn free = growTwo(s, env, kFreeAir, d);
  EXPECT_FALSE(free.climbing);
  expectNoTurn(free);
  s.up = 0.0f;
  expectNoTurn(growTwo(s, env, kOnWall, d));
}

TEST(ClimbTropism, UpAndAdhesionAddUpWhileClimbing) {
  // Eq. 7's weighted sum: v = s_adhesion · (toward the support) + s_up · up.
  env::Environment env;
  addWall(env);
  env.commit();
  ClimbSpecies s = straightSpecies();
  s.adhesion = 0.3f;
  s.up = 0.2f;
  Turn t = growTwo(s, env, kOnWall, kSideways);
  expectTurnToward(t, Vec3(0, 0.2f, -0.3f));
}

TEST(ClimbTropism, LightTurnsAnExposedTipTowardTheLight) {
  env::Environment env;
  env::Light sun;
  sun.direction = Vec3(0, -1, -1).normalized();  // travels down and back: toward it is (0, 1, 1)/√2
  env.addLight(sun);
  env.commit();
  ClimbSpecies s = straightSpecies();
  s.light = 0.3f;
  Turn t = growTwo(s, env, kFreeAir, kSideways);
  expectTurnToward(t, s.light * Vec3(0, 1, 1).normalized());
  s.light = 0.0f;
  expectNoTurn(growTwo(s, env, kFreeAir, kSideways));
}

TEST(ClimbTropism, LightInShadeTurnsByTheAmbientFraction) {
  // A roof over the tip: fully shaded, the pull toward the light is light · light_ambient.
  env::Environment env;
  env::ObstacleDef roof;
  roof.name = "roof";
  roof.kind = env::ObstacleKind::Box;
  roof.mesh = env::makeBox(Vec3(6, 0.1f, 6));
  roof.worldFromLocal.translation = Vec3(0, 2, 0);
  env.addObstacle(std::move(roof));
  env::Light sun;
  sun.direction = Vec3(0, -1, 0);
  env.addLight(sun);
  env.commit();
  ClimbSpecies s = straightSpecies();
  s.light = 0.5f;
  s.lightAmbient = 0.4f;
  Turn t = growTwo(s, env, kFreeAir, kSideways);
  ASSERT_EQ(env.light(t.firstEnd).exposure, 0.0f);
  expectTurnToward(t, s.light * s.lightAmbient * Vec3(0, 1, 0));
  EXPECT_NEAR(angle(t.d, t.turned), 0.2, kAngleTol);
}

TEST(ClimbTropism, UserDirectionTurnsTheTipTowardIt) {
  env::Environment env;
  env.commit();
  ClimbSpecies s = straightSpecies();
  s.userDirection = Vec3(0, 0.6f, 0.8f);
  s.userDirectionStrength = 0.4f;
  Turn t = growTwo(s, env, kFreeAir, kSideways);
  expectTurnToward(t, s.userDirectionStrength * s.userDirection);
  s.userDirectionStrength = 0.0f;
  expectNoTurn(growTwo(s, env, kFreeAir, kSideways));
}

TEST(ClimbTropism, AStrongPullNeverTurnsPastItsDirection) {
  // |d × v| = 3 · sin 30° = 1.5 rad, more than the 30° (0.52 rad) to v: the tip ends on v.
  env::Environment env;
  env.commit();
  ClimbSpecies s = straightSpecies();
  const Vec3 d = Vec3(0, 1, 0);
  s.userDirection = Vec3(std::sin(radians(30.0f)), std::cos(radians(30.0f)), 0);
  s.userDirectionStrength = 3.0f;
  Turn t = growTwo(s, env, kFreeAir, d);
  expectTurnToward(t, s.userDirectionStrength * s.userDirection);
  EXPECT_NEAR(angle(t.turned, s.userDirection), 0.0, kAngleTol);
}

TEST(ClimbTropism, WindTurnsTheTipDownwind) {
  // 2.5 m/s: below Growth-Flow's w_min (4 m/s), so only the pseudo-tropism acts.
  env::Environment env;
  const Vec3 wind(1.5f, 0, 2);
  env.setWind(wind);
  env.commit();
  ClimbSpecies s = straightSpecies();
  ASSERT_LT(wind.norm(), s.growthFlow.windMin);
  s.windStrength = 0.1f;  // per m/s
  const Vec3 d = Vec3(0, 1, 0);
  Turn t = growTwo(s, env, kFreeAir, d);
  expectTurnToward(t, s.windStrength * wind);
  EXPECT_NEAR(angle(t.d, t.turned), 0.25, kAngleTol);  // 0.1 per m/s · 2.5 m/s, d ⟂ wind
  s.windStrength = 0.0f;
  expectNoTurn(growTwo(s, env, kFreeAir, d));
}

TEST(ClimbTropism, AttractionTurnsTheTipTowardAStroke) {
  env::Environment env;
  env::Stroke stroke;
  stroke.radius = 0.6f;
  stroke.points = {Vec3(0.2f, 1.15f, 0.5f)};
  env.addStroke(stroke);
  env.commit();
  ClimbSpecies s = straightSpecies();
  s.attraction = 0.8f;
  Turn t = growTwo(s, env, kFreeAir, kSideways);
  // The field's own value where the tropism acts (the end of the first segment); the stroke
  // lies up and ahead of it.
  const Vec3 pull = env.attraction(t.firstEnd);
  ASSERT_GT(pull.norm(), 0.1f);
  ASSERT_GT(pull.y(), 0.0f);
  expectTurnToward(t, s.attraction * pull);
  s.attraction = 0.0f;
  expectNoTurn(growTwo(s, env, kFreeAir, kSideways));
}

TEST(ClimbTropism, RandomTurnsFollowAUniformDirection) {
  // The random tropism is a unit vector u drawn afresh per tip and segment, uniformly on the
  // sphere: eq. 3–4 turn the tip by s·|d × u| = s·sin θ, θ the angle from d to u. Over many
  // tips the turns never exceed s, average s·E[sin θ] = s·π/4, and point every way around d.
  env::Environment env;
  env.commit();
  ClimbSpecies s = straightSpecies();
  s.randomness = 0.3f;
  ClimbSystem system(11);
  const int n = 600;
  const Vec3 d = Vec3(0, 1, 0);
  for (int i = 0; i < n; ++i) system.addPlant({"tip", s, Vec3(float(i % 30), 1, float(i / 30)), d, uint64_t(i)}, env);
  system.step(env);
  system.step(env);
  double sum = 0.0;
  Vec3 sideSum = Vec3::Zero();
  for (uint32_t i = 0; i < uint32_t(n); ++i) {
    plant::PlantModel m = system.snapshot(i);
    ASSERT_EQ(m.nodeCount(), 2u);
    const double phi = angle(m.direction(0), m.direction(1));
    EXPECT_LE(phi, s.randomness + kAngleTol);
    sum += phi;
    Vec3 side = m.direction(1) - d * d.dot(m.direction(1));
    if (side.norm() > 1e-6f) sideSum += side.normalized();
  }
  // sin θ has standard deviation 0.22 for uniform u: the mean of 600 turns is within 4σ
  // (0.036 s) of s·π/4; the mean of 600 unit side directions has |·| about 0.03.
  EXPECT_NEAR(sum / n, s.randomness * kPi / 4, 0.036 * s.randomness);
  EXPECT_LT(sideSum.norm() / n, 0.12f);
  s.randomness = 0.0f;
  expectNoTurn(growTwo(s, env, kFreeAir, d));
}

}  // namespace
}  // namespace tendril::climb
