// Growth-Flow's growth and leaf-motion equations (seed 001 eq. 6–17) against values worked out
// by hand and an independent long-double evaluation.
#include "tendril/plant/growth_flow.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tendril::plant {
namespace {

GrowthFlowSpecies paperSpecies() {
  GrowthFlowSpecies s;
  s.windMin = 4.0f;
  s.windMax = 12.0f;
  s.radiusRate = 0.02f;
  s.radiusSensitivity = 0.5f;
  s.lengthSensitivity = 0.25f;
  s.maxLength = 0.0f;
  s.angle0 = 0.1f;
  s.angleConversion = 0.05f;
  s.angleSensitivity = 0.4f;
  s.leafThicknessRate = 0.01f;
  s.leafThicknessSensitivity = 0.6f;
  s.leafRadiusSensitivity = 0.2f;
  return s;
}

TEST(GrowthFlowEquations, WindGrowthFactorIsEquationSix) {
  // f(w) = min(1, max(0, (w − w_min) / (w_max − w_min))), w_min = 4, w_max = 12.
  struct Row { float w, f; };
  const Row rows[] = {{0.0f, 0.0f}, {3.99f, 0.0f}, {4.0f, 0.0f}, {5.0f, 0.125f}, {8.0f, 0.5f},
                      {10.0f, 0.75f}, {12.0f, 1.0f}, {30.0f, 1.0f}, {-5.0f, 0.0f}};
  for (const Row& r : rows) EXPECT_NEAR(windGrowthFactor(r.w, 4.0f, 12.0f), r.f, 1e-6) << "w = " << r.w;
}

TEST(GrowthFlowEquations, ClosedFormsMatchTheTableToOneMillionth) {
  const GrowthFlowSpecies s = paperSpecies();
  // Hand-worked rows: w = 8 m/s gives f = 0.5.
  //  eq. 7: r = 0.01 (1 + 0.02 (1 + 0.5·0.5))^10 = 0.01 · 1.025^10 = 0.0128008454...
  EXPECT_NEAR(radiusAt(0.01, 10, 8.0, s), 0.012800845441963, 1e-9);
  //  eq. 8: l = 0.04 (0.97 (1 − 0.25·0.5))^3 = 0.04 · 0.84875^3 = 0.0244573...
  EXPECT_NEAR(lengthAt(0.04, 3, 8.0, 0.97, s), 0.04 * 0.84875 * 0.84875 * 0.84875, 1e-9);
  //  eq. 9: α = 0.1 (1 + 0.05·0.4·0.5)^20 = 0.1 · 1.01^20 = 0.12201900399...
  EXPECT_NEAR(angleAt(20, 8.0, s), 0.122019003995, 1e-7);  // the species' constants are floats
  //  eq. 16: h = 0.0003 (1 + 0.01 (1 + 0.6·0.5))^5 = 0.0003 · 1.013^5
  EXPECT_NEAR(leafThicknessAt(0.0003, 5, 8.0, s), 0.0003 * std::pow(1.013, 5), 1e-12);
  //  eq. 17: d = 0.1 (0.94 (1 − 0.2·0.5))^4 = 0.1 · 0.846^4
  EXPECT_NEAR(leafRadiusAt(0.1, 4, 8.0, 0.94, s), 0.1 * std::pow(0.846, 4), 1e-9);

  // A table of winds and times against an independent long-double evaluation.
  const double winds[] = {0.0, 2.0, 4.0, 4.5, 7.0, 9.5, 12.0, 20.0};
  const double times[] = {0.0, 1.0, 2.5, 10.0, 37.0, 100.0};
  for (double w : winds) {
    long double f = std::min(1.0L, std::max(0.0L, (w - 4.0L) / 8.0L));
    for (double t : times) {
      long double r = 0.005L * std::pow(1.0L + 0.02L * (1.0L + 0.5L * f), (long double)t);
      long double l = 0.05L * std::pow(0.99L * (1.0L - 0.25L * f), (long double)t);
      long double a = 0.1L * std::pow(1.0L + 0.05L * 0.4L * f, (long double)t);
      long double h = 0.0004L * std::pow(1.0L + 0.01L * (1.0L + 0.6L * f), (long double)t);
      long double d = 0.08L * std::pow(0.97L * (1.0L - 0.2L * f), (long double)t);
      // Species constants are floats: compare relative to the value, to 1e-6.
      auto rel = [](double got, long double want) { return std::fabs(got - double(want)) / std::max(1e-12, double(want)); };
      EXPECT_LT(rel(radiusAt(0.005, t, w, s), r), 1e-6) << "eq. 7, w " << w << " t " << t;
      EXPECT_LT(rel(lengthAt(0.05, t, w, 0.99, s), l), 1e-6) << "eq. 8, w " << w << " t " << t;
      EXPECT_LT(rel(angleAt(t, w, s), a), 1e-6) << "eq. 9, w " << w << " t " << t;
      EXPECT_LT(rel(leafThicknessAt(0.0004, t, w, s), h), 1e-6) << "eq. 16, w " << w << " t " << t;
      EXPECT_LT(rel(leafRadiusAt(0.08, t, w, 0.97, s), d), 1e-6) << "eq. 17, w " << w << " t " << t;
    }
  }
}

TEST(GrowthFlowEquations, LengthStopsAtTheSpeciesMaximum) {
  GrowthFlowSpecies s = paperSpecies();
  s.maxLength = 0.3f;
  EXPECT_NEAR(lengthAt(0.1, 50, 0.0, 1.05, s), 0.3, 1e-7);        // would be 1.15 m
  EXPECT_NEAR(lengthAt(0.1, 2, 0.0, 1.05, s), 0.1 * 1.1025, 1e-9);  // below the cap
}

TEST(GrowthFlowEquations, StepFactorsCompoundToTheClosedForms) {
  // A model that multiplies the per-step factors into its still-air growth t times ends up
  // exactly eq. 7/8/16/17 times its still-air size.
  const GrowthFlowSpecies s = paperSpecies();
  for (float w : {5.0f, 8.0f, 15.0f}) {
    GrowthFlowStep g = growthStep(w, s);
    double r = 1, l = 1, h = 1, d = 1;
    for (int t = 0; t < 40; ++t) {
      r *= g.radius;
      l *= g.length;
      h *= g.leafThickness;
      d *= g.leafRadius;
    }
    EXPECT_NEAR(r, radiusAt(1, 40, w, s) / radiusAt(1, 40, 0, s), 1e-5) << w;
    EXPECT_NEAR(l, lengthAt(1, 40, w, 1.0, s) / lengthAt(1, 40, 0, 1.0, s), 1e-5) << w;
    EXPECT_NEAR(h, leafThicknessAt(1, 40, w, s) / leafThicknessAt(1, 40, 0, s), 1e-5) << w;
    EXPECT_NEAR(d, leafRadiusAt(1, 40, w, 1.0, s) / leafRadiusAt(1, 40, 0, 1.0, s), 1e-5) << w;
    EXPECT_GT(g.radius, 1.0f);
    EXPECT_LT(g.length, 1.0f);
  }
}

TEST(GrowthFlowEquations, CalmWindIsExactlyStillAir) {
  const GrowthFlowSpecies s = paperSpecies();
  for (float w : {0.0f, 1.0f, 3.9f, 4.0f}) {
    GrowthFlowStep g = growthStep(w, s);
    EXPECT_FALSE(g.active());
    EXPECT_EQ(g.radius, 1.0f);
    EXPECT_EQ(g.length, 1.0f);
    EXPECT_EQ(g.leafThickness, 1.0f);
    EXPECT_EQ(g.leafRadius, 1.0f);
    EXPECT_EQ(nextGrowthAngle(s.angle0, g), s.angle0);
  }
}

TEST(GrowthFlowEquations, GrowthAngleBendsTheShootTowardTheWindByEquationNine) {
  const GrowthFlowSpecies s = paperSpecies();
  GrowthFlowStep g = growthStep(20.0f, s);  // f = 1, Δα = 0.02
  float angle = s.angle0;
  const Vec3 wind(20, 0, 0);
  for (int t = 1; t <= 30; ++t) {
    angle = nextGrowthAngle(angle, g);
    EXPECT_NEAR(angle, angleAt(t, 20.0, s), 1e-5 * angleAt(t, 20.0, s));
  }
  // Algorithm 1: the still-air direction turned by α_30 about u = b × w, toward +X.
  Vec3 d = windGrowthDirection(Vec3::UnitY(), wind, angle);
  EXPECT_NEAR(std::atan2(double(d.x()), double(d.y())), angleAt(30, 20.0, s), 1e-5);
  EXPECT_NEAR(d.z(), 0.0f, 1e-6f);
  // Never past the wind, whatever the angle; along or against the wind nothing turns.
  EXPECT_NEAR(windGrowthDirection(Vec3::UnitY(), wind, 2.5f).x(), 1.0f, 1e-6f);
  EXPECT_EQ(windGrowthDirection(Vec3::UnitX(), wind, 0.3f), Vec3::UnitX());
  float big = s.angle0;
  for (int t = 0; t < 5000; ++t) big = nextGrowthAngle(big, g);
  EXPECT_EQ(big, kPi);
}

TEST(GrowthFlowLeaves, AnglesBounceAndNeverLeaveTheirLimits) {
  GrowthFlowSpecies s;
  LeafMotionState leaf;
  s.petioleStrength = s.bladeStrength = 1e3f;  // never detach here
  double maxTheta = 0, maxPsi = 0, maxPhi = 0;
  int flips = 0;
  int8_t last = leaf.sTwist;
  for (int frame = 0; frame < 20000; ++frame) {
    float w = 0.5f + 30.0f * float((frame * 7919) % 1000) / 1000.0f;  // 0.5 … 30.5 m/s
    updateLeafMotion(leaf, frame % 3, w, 1.0f, 0.04f, s);
    maxTheta = std::max(maxTheta, double(std::fabs(leaf.petioleBend)));
    maxPsi = std::max(maxPsi, double(std::fabs(leaf.twist)));
    maxPhi = std::max(maxPhi, double(std::fabs(leaf.vibrate)));
    ASSERT_LE(std::fabs(leaf.petioleBend), s.petioleBendLimit + 1e-6f);
    ASSERT_LE(std::fabs(leaf.bladeBend), s.bladeBendLimit + 1e-6f);
    ASSERT_LE(std::fabs(leaf.twist), s.twistLimit + 1e-6f);
    ASSERT_LE(std::fabs(leaf.vibrate), s.vibrateLimit + 1e-6f);
    if (leaf.sTwist != last) ++flips;
    last = leaf.sTwist;
  }
  // The angles use their whole range and keep reversing (eq. 10, 12, 14).
  EXPECT_GT(maxTheta, 0.9 * s.petioleBendLimit);
  EXPECT_GT(maxPsi, 0.9 * s.twistLimit);
  EXPECT_GT(maxPhi, 0.9 * s.vibrateLimit);
  EXPECT_GT(flips, 10);
  // t_p > t_b: the blade bends instead of the petiole (Algorithm 2).
  GrowthFlowSpecies stiffPetiole = s;
  stiffPetiole.petioleStrength = 2e3f;
  LeafMotionState other;
  for (int frame = 0; frame < 100; ++frame) updateLeafMotion(other, 0, 10.0f, 1.0f, 0.04f, stiffPetiole);
  EXPECT_EQ(other.petioleBend, 0.0f);
  EXPECT_GT(std::fabs(other.bladeBend), 0.0f);
}

TEST(GrowthFlowLeaves, EquationElevenStepsBySignWindRateAndTime) {
  int8_t sign = 1;
  // θ = 0.01 + 1 · 5 · 0.02 · 0.1 = 0.02
  EXPECT_NEAR(bounceAngle(0.01f, sign, 5.0f, 0.02f, 0.1f, 0.05f), 0.02f, 1e-7f);
  EXPECT_EQ(sign, 1);
  // 0.045 + 0.01 > 0.05: the sign flips first (eq. 10), then θ = 0.045 − 0.01.
  EXPECT_NEAR(bounceAngle(0.045f, sign, 5.0f, 0.02f, 0.1f, 0.05f), 0.035f, 1e-7f);
  EXPECT_EQ(sign, -1);
}

TEST(GrowthFlowLeaves, LeavesDetachAboveTheirStrength) {
  GrowthFlowSpecies s;
  s.petioleStrength = 0.5f;
  s.bladeStrength = 1.0f;
  s.strengthToWind = 20.0f;  // the petiole holds up to 10 m/s
  LeafMotionState leaf;
  updateLeafMotion(leaf, 0, 9.9f, 1.0f, 0.04f, s);
  EXPECT_FALSE(leaf.detached);
  updateLeafMotion(leaf, 1, 10.1f, 1.0f, 0.04f, s);
  EXPECT_TRUE(leaf.detached);
  EXPECT_FALSE(leafDetaches(10.0f, s));
  EXPECT_TRUE(leafDetaches(10.01f, s));
}

}  // namespace
}  // namespace tendril::plant
