// Growth-Flow motion on PlantModels, the wind field and the looping glTF wind animation.
#include "tendril/core/error.h"
#include "tendril/core/random.h"
#include "tendril/env/wind_field.h"
#include "tendril/graph/build_plant.h"
#include "tendril/graph/graph.h"
#include "tendril/wind/gltf_animation.h"
#include "tendril/wind/motion.h"

#include "support/determinism.h"
#include "support/gltf_validator.h"
#include "support/synthetic_plants.h"
#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <iterator>

namespace tendril::wind {
namespace {

plant::PlantModel leafyTree() {
  plant::PlantModel p = meshtest::branchingTree();
  meshtest::addLeaves(p, 2);
  return p;
}

env::WindField constantWind(Vec3 v) {
  env::WindSettings s;
  s.velocity = v;
  return env::WindField(s);
}

TEST(WindField, ConstantGustyAndEmitterWinds) {
  env::WindField calm;
  EXPECT_EQ(calm.sample(Vec3(1, 2, 3), 5.0f), Vec3::Zero());
  EXPECT_TRUE(calm.settings().calm());

  env::WindField steady = constantWind(Vec3(6, 0, 0));
  EXPECT_EQ(steady.sample(Vec3(-40, 3, 9), 123.0f), Vec3(6, 0, 0));

  env::WindSettings g;
  g.mode = env::WindMode::Gusty;
  g.velocity = Vec3(8, 0, 0);
  g.gustStrength = 0.5f;
  g.seed = 7;
  env::WindField gusty(g);
  double mean = 0, lo = 1e9, hi = 0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    Vec3 w = gusty.sample(Vec3(0, 1, 0), 0.05f * float(i));
    ASSERT_TRUE(std::isfinite(w.x()));
    double s = w.norm();
    mean += s / n;
    lo = std::min(lo, s);
    hi = std::max(hi, s);
    EXPECT_GT(w.x(), 0.0f);  // wanders by at most gustTurn about +Y
  }
  EXPECT_NEAR(mean, 8.0, 1.2);       // gusts vary about the prevailing speed
  EXPECT_GT(hi - lo, 4.0);           // ±50 % is a range of 8 m/s
  EXPECT_LE(hi, 8.0 * 1.5 + 1e-3);
  // Smooth in time, and gusts travel downwind: what blows at x = 0 at t blows at x = 8 at t + 1.
  EXPECT_LT((gusty.sample(Vec3(0, 1, 0), 10.0f) - gusty.sample(Vec3(0, 1, 0), 10.01f)).norm(), 0.2f);
  EXPECT_NEAR((gusty.sample(Vec3(0, 1, 0), 10.0f) - gusty.sample(Vec3(8, 1, 0), 11.0f)).norm(), 0.0f, 1e-4f);

  env::WindSettings e;
  env::WindEmitter jet;
  jet.position = Vec3(0, 1, 0);
  jet.direction = Vec3::UnitZ();
  jet.speed = 10.0f;
  jet.radius = 0.5f;
  jet.reach = 5.0f;
  e.emitters.push_back(jet);
  env::WindField emitter(e);
  EXPECT_NEAR(emitter.sample(Vec3(0, 1, 0.01f), 0).z(), 10.0f, 0.1f);   // at the nozzle
  Vec3 far = emitter.sample(Vec3(0, 1, 3), 0);
  EXPECT_GT(far.z(), 0.0f);
  EXPECT_LT(far.z(), 10.0f);                                            // widened and slowed
  EXPECT_EQ(emitter.sample(Vec3(0, 1, -1), 0), Vec3::Zero());           // behind it
  EXPECT_EQ(emitter.sample(Vec3(3, 1, 1), 0), Vec3::Zero());            // beside it
  EXPECT_EQ(emitter.sample(Vec3(0, 1, 6), 0), Vec3::Zero());            // past its reach
}

TEST(WindField, GustSamplerGivesTheAmbientWindBitForBit) {
  // Points spread over a plant-sized box, a field-sized one and (with tiny gusts) one too wide
  // for the lattice table; winds along, across and straight up; times before zero and late.
  struct Case {
    Vec3 velocity;
    float span, gustScale, gustPeriod;
    bool tabled;
  };
  const Case cases[] = {{Vec3(9, 0, 3), 6.0f, 6.0f, 3.0f, true},    {Vec3(-2, 0.5f, -7), 300.0f, 6.0f, 3.0f, true},
                        {Vec3(0, 7, 0), 6.0f, 0.5f, 0.2f, true},    {Vec3(4, 0, 0), 80.0f, 1e-3f, 3.0f, false},
                        {Vec3(0, 0, 0), 6.0f, 6.0f, 3.0f, false}};
  Rng rng(RandomKey{3, 0, 0, 0, purposeId("test.gust-sampler")});
  for (const Case& c : cases) {
    env::WindSettings s;
    s.mode = env::WindMode::Gusty;
    s.velocity = c.velocity;
    s.gustScale = c.gustScale;
    s.gustPeriod = c.gustPeriod;
    s.seed = 11;
    const env::WindField field(s);
    std::vector<Vec3> points(2000);
    for (Vec3& p : points) p = Vec3(rng.uniform(-c.span, c.span), rng.uniform(0, c.span), rng.uniform(-c.span, c.span) + 40.0f);
    env::GustSampler sampler;
    EXPECT_FALSE(sampler.preparedFor(field, points.size()));
    sampler.prepare(field, points.data(), points.size());
    EXPECT_TRUE(sampler.preparedFor(field, points.size()));
    for (float t : {-37.3f, 0.0f, 0.04f, 2.5f, 1234.56f}) {
      sampler.beginFrame(t);
      EXPECT_EQ(sampler.tabled(), c.tabled) << "span " << c.span << " t " << t;
      for (size_t k = 0; k < points.size(); ++k) {
        const Vec3 a = sampler.ambient(k), b = field.ambient(points[k], t);
        ASSERT_TRUE(a.x() == b.x() && a.y() == b.y() && a.z() == b.z())
            << "span " << c.span << " t " << t << " point " << k << ": " << a.transpose() << " vs " << b.transpose();
      }
      // Four at a time.
      for (size_t k = 0; k + 4 <= points.size(); k += 4) {
        float x[4], y[4], z[4];
        sampler.ambient4(k, x, y, z);
        for (size_t l = 0; l < 4; ++l) {
          const Vec3 b = field.ambient(points[k + l], t);
          ASSERT_TRUE(x[l] == b.x() && y[l] == b.y() && z[l] == b.z())
              << "span " << c.span << " t " << t << " point " << k + l << ": " << Vec3(x[l], y[l], z[l]).transpose()
              << " vs " << b.transpose();
        }
      }
    }
    // Other gusts, or other points, need preparing again.
    env::WindSettings other = s;
    other.seed = 12;
    EXPECT_FALSE(sampler.preparedFor(env::WindField(other), points.size()));
    other = s;
    other.gustStrength = 0.1f;
    EXPECT_FALSE(sampler.preparedFor(env::WindField(other), points.size()));
    EXPECT_FALSE(sampler.preparedFor(field, points.size() + 1));
  }
}

// Eq. 1 for one straight segment across a steady wind, solved independently of WindMotion:
// I θ'' + c θ' + k θ = τ with k = E π r⁴ / (4 l), I = m l² / 3 (m = ρ π r² l), c = 2 ζ √(k I) and
// τ = ½ ρ_air C_d (2 r l) w² · l / 2 (the drag at the segment's centre of gravity).
struct Eq1 {
  double k, I, c, tau;
};
Eq1 eq1ForOneSegment(float length, float radius, float wind, const plant::GrowthFlowSpecies& s) {
  Eq1 e;
  const double l = length, r = radius;
  e.k = double(s.youngModulus) * kPi * r * r * r * r / (4.0 * l);
  const double m = double(s.woodDensity) * kPi * r * r * l;
  e.I = m * l * l / 3.0;
  e.c = 2.0 * double(s.swayDamping) * std::sqrt(e.k * e.I);
  e.tau = 0.5 * 1.25 * double(s.dragCoefficient) * (2.0 * r * l) * double(wind) * double(wind) * 0.5 * l;
  return e;
}

// θ(t) of eq. 1 from rest under a constant τ by RK4 with a step of 1e-5 s, at the times given.
std::vector<double> rk4StepResponse(const Eq1& e, double dt, int frames) {
  std::vector<double> out;
  double th = 0, v = 0, t = 0;
  const double h = 1e-5;
  auto acc = [&](double x, double y) { return (e.tau - e.c * y - e.k * x) / e.I; };
  for (int f = 1; f <= frames; ++f) {
    const double until = dt * f;
    while (t < until - 1e-12) {
      const double step = std::min(h, until - t);
      const double k1x = v, k1v = acc(th, v);
      const double k2x = v + 0.5 * step * k1v, k2v = acc(th + 0.5 * step * k1x, v + 0.5 * step * k1v);
      const double k3x = v + 0.5 * step * k2v, k3v = acc(th + 0.5 * step * k2x, v + 0.5 * step * k2v);
      const double k4x = v + step * k3v, k4v = acc(th + step * k3x, v + step * k3v);
      th += step / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x);
      v += step / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
      t += step;
    }
    out.push_back(th);
  }
  return out;
}

TEST(WindMotion, AStepInWindGivesTheDampedResponseOfEq1) {
  // A 1 m stem of radius 1 cm, straight up, in a wind of 5 m/s along +X from t = 0: it swings
  // downwind past its static deflection θ* = τ / k and settles there, with the overshoot and
  // period of the damped oscillator — at the studio's frame rate, at 25 ms and at 100 ms frames.
  const plant::PlantModel rest = meshtest::straightChain(1, 1.0f, 0.01f, 0.01f);
  const plant::GrowthFlowSpecies species;
  const Eq1 e = eq1ForOneSegment(1.0f, 0.01f, 5.0f, species);
  const double staticAngle = e.tau / e.k;
  const double wn = std::sqrt(e.k / e.I), zeta = e.c / (2.0 * std::sqrt(e.k * e.I));
  const double wd = wn * std::sqrt(1.0 - zeta * zeta);
  ASSERT_GT(kTwoPi / wn, kMinSwayPeriod);  // the period limits do not apply to this stem
  ASSERT_LT(kTwoPi / wn, kMaxSwayPeriod);
  const env::WindField wind = constantWind(Vec3(5, 0, 0));
  for (float dt : {1.0f / 60.0f, 0.025f, 0.1f}) {
    SCOPED_TRACE(::testing::Message() << "frames of " << dt << " s");
    WindMotion motion(rest, species);
    const int frames = int(std::lround(8.0 / dt));
    const std::vector<double> reference = rk4StepResponse(e, dt, frames);
    std::vector<double> theta;
    plant::PlantModel posed;
    for (int f = 0; f < frames; ++f) {
      motion.step(dt * float(f), dt, wind, posed);
      // The rotation turns the stem about −Z, toward +X.
      const Vec3 v = motion.swayVector(0);
      ASSERT_NEAR(v.x(), 0.0, 1e-7);
      ASSERT_NEAR(v.y(), 0.0, 1e-7);
      theta.push_back(-double(v.z()));
      ASSERT_NEAR(posed.tip(0).x(), std::sin(theta.back()), 1e-5);
    }
    EXPECT_NEAR(motion.stiffness(0), e.k, 1e-4 * e.k);
    EXPECT_NEAR(motion.inertia(0), e.I, 1e-4 * e.I);
    EXPECT_NEAR(motion.damping(0), e.c, 1e-4 * e.c);
    EXPECT_NEAR(motion.torque(0).norm(), e.tau, 1e-4 * e.tau);
    double worst = 0, peak = 0;
    for (size_t f = 0; f < theta.size(); ++f) {
      worst = std::max(worst, std::fabs(theta[f] - reference[f]));
      peak = std::max(peak, theta[f]);
      ASSERT_GE(theta[f], 0.0);  // from rest it never swings upwind
    }
    EXPECT_LT(worst, 1e-3 * staticAngle);
    // The first peak: 1 + exp(−π ζ / √(1 − ζ²)) times θ*, sampled within a frame of its time π / ω_d.
    const double overshoot = std::exp(-kPi * zeta / std::sqrt(1.0 - zeta * zeta));
    // A peak sampled up to half a frame off: the cosine's drop and the decay over that time.
    const double sampled = (1.0 - 0.5 * std::pow(wd * dt / 2.0, 2)) * std::exp(-zeta * wn * dt / 2.0);
    EXPECT_LE(peak, (1.0 + overshoot) * staticAngle * 1.0001);
    EXPECT_GE(peak, (1.0 + overshoot * sampled) * staticAngle * 0.999);
    // Period: the first two maxima of θ − θ* (three-point parabolas through the samples).
    std::vector<double> maxima;
    for (size_t f = 1; f + 1 < theta.size() && maxima.size() < 2; ++f)
      if (theta[f] > theta[f - 1] && theta[f] >= theta[f + 1]) {
        const double a = theta[f - 1], b = theta[f], c = theta[f + 1];
        maxima.push_back(dt * (double(f) + 1.0 + 0.5 * (a - c) / (a - 2 * b + c)));
      }
    ASSERT_EQ(maxima.size(), 2u);
    EXPECT_NEAR(maxima[1] - maxima[0], kTwoPi / wd, 0.02 * kTwoPi / wd);
    // ... and it settles at θ*.
    for (int f = 0; f < int(60.0f / dt); ++f) motion.step(8.0f + dt * float(f), dt, wind, posed);
    EXPECT_NEAR(-motion.swayVector(0).z(), staticAngle, 1e-4 * staticAngle);
    EXPECT_NEAR(motion.swayVelocity(0).norm(), 0.0, 1e-4 * staticAngle * wn);
  }
}

TEST(WindMotion, ThickerBranchesSwayLess) {
  // Drag grows with r, the spring with r⁴: a stem twice as thick bends an eighth as far, and it
  // swings less all the way there.
  const plant::GrowthFlowSpecies species;
  const env::WindField wind = constantWind(Vec3(6, 0, 0));
  double peak[2] = {0, 0}, settled[2] = {0, 0};
  for (int thick = 0; thick < 2; ++thick) {
    const float r = thick ? 0.02f : 0.01f;
    WindMotion motion(meshtest::straightChain(1, 1.0f, r, r), species);
    plant::PlantModel posed;
    for (int f = 0; f < 2000; ++f) {
      motion.step(0.025f * float(f), 0.025f, wind, posed);
      peak[thick] = std::max(peak[thick], double(motion.swayAngle(0)));
    }
    settled[thick] = motion.swayAngle(0);
  }
  EXPECT_LT(peak[1], peak[0] / 4);
  EXPECT_NEAR(settled[1] / settled[0], 1.0 / 8.0, 0.002);
}

TEST(WindMotion, ChildrensForcePropagatesToTheParent) {
  // Two 0.5 m segments up a stem across the wind: the lower node carries the drag of both, its
  // own at 0.25 m and the upper one's at 0.75 m (T_r), four times the upper node's torque; a
  // lone lower segment carries only its own. Each node settles at its own τ / k.
  const plant::GrowthFlowSpecies species;
  const env::WindField wind = constantWind(Vec3(4, 0, 0));
  const Eq1 half = eq1ForOneSegment(0.5f, 0.01f, 4.0f, species);  // τ: one segment's drag × 0.25 m
  WindMotion pair(meshtest::straightChain(2, 0.5f, 0.01f, 0.01f), species);
  WindMotion lone(meshtest::straightChain(1, 0.5f, 0.01f, 0.01f), species);
  plant::PlantModel a, b;
  for (int f = 0; f < 4000; ++f) {
    pair.step(0.025f * float(f), 0.025f, wind, a);
    lone.step(0.025f * float(f), 0.025f, wind, b);
  }
  EXPECT_NEAR(lone.torque(0).norm(), half.tau, 1e-4 * half.tau);
  EXPECT_NEAR(pair.torque(1).norm(), half.tau, 1e-4 * half.tau);
  EXPECT_NEAR(pair.torque(0).norm(), 4.0 * half.tau, 4e-4 * half.tau);
  EXPECT_NEAR(pair.swayAngle(0), 4.0 * half.tau / half.k, 1e-3 * 4.0 * half.tau / half.k);
  EXPECT_NEAR(pair.swayAngle(1), half.tau / half.k, 1e-3 * half.tau / half.k);
  // The lower node of the pair carries the upper segment: more inertia than the lone one.
  EXPECT_GT(pair.inertia(0), 2.0f * lone.inertia(0));
}

TEST(WindMotion, BranchesSwayTowardTheWindAndBackInGusts) {
  // Gusts keep eq. 1 going: the top of a soft leafy stem leans downwind and comes back, again
  // and again, never upwind of its rest by more than the rebound, within its limits, connected.
  plant::PlantModel rest = leafyTree();
  plant::GrowthFlowSpecies species;
  species.youngModulus = 2e6f;
  WindMotion motion(rest, species);
  env::WindSettings g;
  g.mode = env::WindMode::Gusty;
  g.velocity = Vec3(6, 0, 0);
  g.gustStrength = 0.8f;
  g.gustPeriod = 1.5f;
  const env::WindField wind(g);
  plant::PlantModel posed;
  std::vector<double> lean;
  for (int f = 0; f < 1200; ++f) {
    motion.step(0.025f * float(f), 0.025f, wind, posed);
    plant::validate(posed, "posed");
    lean.push_back(posed.tip(5).x() - rest.tip(5).x());  // node 5: the top of the stem
    for (size_t i = 0; i < posed.nodeCount(); ++i) {
      ASSERT_LE(motion.swayAngle(i), species.maxSwayAngle + 1e-6f);
      ASSERT_NEAR(posed.length[i], rest.length[i], 0.0f);
    }
    for (int i = 1; i < 6; ++i) ASSERT_LT((posed.position[size_t(i)] - posed.tip(size_t(i - 1))).norm(), 1e-5f);
  }
  // After the first 5 s: swings of at least a fifth of the lean, more than once.
  double hi = 0, lo = 1e9;
  int reversals = 0;
  for (size_t f = 200; f < lean.size(); ++f) {
    hi = std::max(hi, lean[f]);
    lo = std::min(lo, lean[f]);
    if (f + 1 < lean.size() && (lean[f] - lean[f - 1]) * (lean[f + 1] - lean[f]) < 0) ++reversals;
  }
  EXPECT_GT(hi, 0.05);
  EXPECT_LT(lo, 0.8 * hi);
  EXPECT_GE(reversals, 4);
}

TEST(WindMotion, SwayInALoopIsThePeriodicSolutionOfEq1) {
  // With a loop the sway is eq. 1's periodic answer to the looped gusts: I θ'' + c θ' + k θ = τ(t)
  // holds (finite differences) to within what the series leaves out, and t = L poses as t = 0.
  const plant::PlantModel rest = meshtest::straightChain(3, 0.4f, 0.012f, 0.008f);
  plant::GrowthFlowSpecies species;
  env::WindSettings g;
  g.mode = env::WindMode::Gusty;
  g.velocity = Vec3(7, 0, 1);
  g.gustStrength = 0.6f;
  g.gustPeriod = 1.0f;
  MotionSettings ms;
  ms.loopSeconds = 4.0f;
  WindMotion motion(rest, species, ms);
  const env::WindField wind(g);
  plant::PlantModel posed;
  auto thetaAt = [&](float t) {
    motion.step(t, 0.04f, wind, posed);
    return motion.swayVector(0);
  };
  const Vec3 start = thetaAt(0.0f);
  double worst = 0, scale = 0, swing = 0;
  const float h = 0.01f;
  for (float t = 0.2f; t < 4.0f; t += 0.3f) {
    const Vec3 before = thetaAt(t - h), after = thetaAt(t + h), now = thetaAt(t);
    const Vec3 tau = motion.torque(0);
    const Vec3 acc = (after - 2.0f * now + before) / (h * h), vel = (after - before) / (2.0f * h);
    const Vec3 residual = motion.inertia(0) * acc + motion.damping(0) * vel + motion.stiffness(0) * now - tau;
    worst = std::max(worst, double(residual.norm()));
    scale = std::max(scale, double(tau.norm()));
    swing = std::max(swing, double((now - start).norm()));
  }
  EXPECT_GT(swing, 0.2 * start.norm());  // it does move
  EXPECT_LT(worst, 0.05 * scale);
  const Vec3 end = thetaAt(4.0f);
  EXPECT_EQ(end, start);
}

TEST(WindMotion, StillAirAndSupportedNodesDoNotMove) {
  plant::PlantModel rest = leafyTree();
  for (uint32_t& f : rest.flags) f |= plant::kNodeClimbing;  // all held by a wall
  WindMotion held(rest, plant::GrowthFlowSpecies{});
  plant::PlantModel posed;
  held.step(1.0f, 0.04f, constantWind(Vec3(15, 0, 0)), posed);
  for (size_t i = 0; i < rest.nodeCount(); ++i) EXPECT_EQ(posed.position[i], rest.position[i]);

  plant::PlantModel free = leafyTree();
  WindMotion still(free, plant::GrowthFlowSpecies{});
  still.step(1.0f, 0.04f, env::WindField{}, posed);
  for (size_t i = 0; i < free.nodeCount(); ++i) EXPECT_EQ(posed.position[i], free.position[i]);
  for (size_t j = 0; j < free.leafCount(); ++j) EXPECT_EQ(posed.leafMotion[j], Vec3::Zero());
}

TEST(WindMotion, LeafAnglesStayInTheirLimitsAndLeavesTearOffInAStorm) {
  plant::PlantModel rest = leafyTree();
  plant::GrowthFlowSpecies s;  // petiole holds up to c_p t_p = 20 m/s
  WindMotion motion(rest, s);
  plant::PlantModel posed;
  env::WindField breeze = constantWind(Vec3(12, 0, 0));
  for (int f = 0; f < 2000; ++f) {
    motion.step(0.04f * float(f), 0.04f, breeze, posed);
    ASSERT_EQ(posed.leafCount(), rest.leafCount());
    for (const plant::LeafMotionState& L : motion.leaves()) {
      ASSERT_LE(std::fabs(L.petioleBend), radians(5.0f) + 1e-6f);
      ASSERT_LE(std::fabs(L.bladeBend), radians(10.0f) + 1e-6f);
      ASSERT_LE(std::fabs(L.twist), radians(15.0f) + 1e-6f);
      ASSERT_LE(std::fabs(L.vibrate), radians(5.0f) + 1e-6f);
    }
  }
  size_t moving = 0;
  for (const plant::LeafMotionState& L : motion.leaves()) moving += (L.twist != 0.0f || L.vibrate != 0.0f);
  EXPECT_EQ(moving, rest.leafCount());
  motion.step(100.0f, 0.04f, constantWind(Vec3(25, 0, 0)), posed);
  EXPECT_EQ(posed.leafCount(), 0u);  // 25 m/s > 20 m/s: every leaf has detached
  motion.step(100.04f, 0.04f, breeze, posed);
  EXPECT_EQ(posed.leafCount(), 0u);  // and they stay gone
}

// Checks that 30 frames of a free-standing ivy pose it the same at every thread count;
// `wind(f)` is frame f's wind.
template <class WindOf>
void expectSamePoseAtEveryThreadCount(WindOf&& wind) {
  plant::PlantModel rest = meshtest::syntheticIvy(3000, 3);
  for (uint32_t& f : rest.flags) f &= ~uint32_t(plant::kNodeClimbing);
  tendril::test::sameAtEveryThreadCount([&] {
    WindMotion motion(rest, plant::GrowthFlowSpecies{});
    plant::PlantModel posed;
    for (int f = 0; f < 30; ++f) motion.step(0.04f * float(f), 0.04f, env::WindField(wind(f)), posed);
    return plant::contentHash(posed);
  });
}

TEST(WindMotion, SameForAnyThreadCount) {
  env::WindSettings g;
  g.mode = env::WindMode::Gusty;
  g.velocity = Vec3(9, 0, 2);
  expectSamePoseAtEveryThreadCount([&](int) { return g; });
}

TEST(WindMotion, SameForAnyThreadCountInASteadyWind) {
  // The constant wind keeps its torques from the first frame; leaves tear off in the last.
  env::WindSettings steady, storm;
  steady.velocity = Vec3(9, 0, 2);
  storm.velocity = Vec3(30, 0, 2);
  expectSamePoseAtEveryThreadCount([&](int f) { return f < 29 ? steady : storm; });
}

TEST(WindMotion, DragFourNodesAtATimeIsDragOneAtATime) {
  // The drag pass's four lanes against its one-node code, in gusts along, across and straight
  // up, with and without an emitter (the gusts then sampled per node), over 20 frames of an ivy
  // whose node count is not a multiple of four.
  plant::PlantModel rest = meshtest::syntheticIvy(2003, 7);
  for (uint32_t& f : rest.flags) f &= ~uint32_t(plant::kNodeClimbing);
  ASSERT_NE(rest.nodeCount() % 4, 0u);
  env::WindEmitter jet;
  jet.position = Vec3(-1, 0.5f, 0);
  jet.direction = Vec3::UnitX();
  jet.radius = 1.0f;
  for (const Vec3& velocity : {Vec3(9, 0, 3), Vec3(0, 7, 0.5f)})
    for (bool emitter : {false, true}) {
      env::WindSettings s;
      s.mode = env::WindMode::Gusty;
      s.velocity = velocity;
      if (emitter) s.emitters.push_back(jet);
      std::array<uint64_t, 2> hashes{};
      for (bool lanes : {true, false}) {
        detail::setDragLanes(lanes);
        WindMotion motion(rest, plant::GrowthFlowSpecies{});
        plant::PlantModel posed;
        for (int f = 0; f < 20; ++f) motion.step(0.3f * float(f), 0.04f, env::WindField(s), posed);
        hashes[lanes ? 0 : 1] = plant::contentHash(posed);
      }
      detail::setDragLanes(true);
      EXPECT_EQ(hashes[0], hashes[1]) << velocity.transpose() << (emitter ? " with an emitter" : "");
    }
}

TEST(WindMotion, SteadyWindIsReusedOnlyWhileItLasts) {
  // A constant wind's torques are kept from frame to frame. The same winds with a far emitter
  // that adds nothing are no longer uniform and are computed afresh every frame: both must pose
  // the plant identically, also when the wind turns, gusts and steadies again.
  plant::PlantModel rest = leafyTree();
  plant::GrowthFlowSpecies soft;
  soft.youngModulus = 2e6f;
  env::WindEmitter far;
  far.position = Vec3(1e4f, 0, 0);
  far.direction = Vec3::UnitX();
  far.speed = 1.0f;
  far.radius = 0.1f;
  far.reach = 1.0f;
  WindMotion kept(rest, soft), afresh(rest, soft);
  plant::PlantModel a, b;
  int frame = 0;
  double moved = 0;
  for (auto [velocity, gusty] : {std::pair{Vec3(8, 0, 0), false}, std::pair{Vec3(0, 0, 11), false},
                                 std::pair{Vec3(0, 0, 11), true}, std::pair{Vec3(0, 0, 11), false},
                                 std::pair{Vec3(-5, 0, 3), false}}) {
    env::WindSettings s;
    s.mode = gusty ? env::WindMode::Gusty : env::WindMode::Constant;
    s.velocity = velocity;
    env::WindSettings withEmitter = s;
    withEmitter.emitters.push_back(far);
    for (int f = 0; f < 4; ++f, ++frame) {
      const float t = 0.3f * float(frame);
      kept.step(t, 0.04f, env::WindField(s), a);
      afresh.step(t, 0.04f, env::WindField(withEmitter), b);
      ASSERT_EQ(plant::contentHash(a), plant::contentHash(b)) << "frame " << frame;
      for (size_t i = 0; i < rest.nodeCount(); ++i) moved = std::max(moved, double((a.tip(i) - rest.tip(i)).norm()));
    }
  }
  EXPECT_GT(moved, 0.01);  // the plant did sway
}

TEST(WindMotion, GraphTreesSwayDownwindAsRigidBranches) {
  // Seed 004's chestnut and willow (component graphs) in a gusty wind along +X: every branch
  // moves rigidly with its node (distances to the parent node kept), the crowns lean downwind,
  // the leaves keep their limits, and every thread count agrees; the looping clip validates.
  env::WindSettings g;
  g.mode = env::WindMode::Gusty;
  g.velocity = Vec3(12, 0, 0);
  g.seed = 4;
  const env::WindField wind(g);
  for (const char* name : {"chestnut", "willow"}) {
    SCOPED_TRACE(name);
    auto graphFile = graph::loadGraph(test::sourceDir() / "examples/graphs" / (std::string(name) + ".json"));
    const plant::PlantModel rest = graph::generatePlant(graphFile, {graphFile->seed, {}});
    ASSERT_GT(rest.nodeCount(), 200u);
    // Every frame of the first run: branches rigid, leaves within their limits.
    double downwind = 0, largest = 0;
    auto checkFrame = [&](const plant::PlantModel& posed, const WindMotion& motion, int f) {
      plant::validate(posed, name);
      for (size_t i = 0; i < rest.nodeCount(); ++i) {
        ASSERT_EQ(posed.length[i], rest.length[i]);
        const int32_t p = rest.parent[i];
        if (p >= 0) {
          const double before = (rest.position[i] - rest.position[size_t(p)]).norm();
          const double after = (posed.position[i] - posed.position[size_t(p)]).norm();
          ASSERT_NEAR(after, before, 1e-4 * (1.0 + before)) << "node " << i << ", frame " << f;
        }
        const Vec3 moved = posed.tip(i) - rest.tip(i);
        downwind += moved.x();
        largest = std::max(largest, double(moved.norm()));
      }
      for (const plant::LeafMotionState& L : motion.leaves()) {
        ASSERT_LE(std::fabs(L.petioleBend), radians(5.0f) + 1e-6f);
        ASSERT_LE(std::fabs(L.twist), radians(15.0f) + 1e-6f);
      }
    };
    bool first = true;
    tendril::test::sameAtEveryThreadCount([&] {
      WindMotion motion(rest, plant::GrowthFlowSpecies{});
      plant::PlantModel posed;
      for (int f = 0; f < 60; ++f) {
        motion.step(0.05f * float(f), 0.05f, wind, posed);
        if (first) checkFrame(posed, motion, f);
      }
      first = false;
      return plant::contentHash(posed);
    });
    EXPECT_GT(largest, 0.01);  // centimetres at least at the tips
    EXPECT_GT(downwind, 0.0);  // and on the whole downwind

    std::filesystem::path file = meshtest::exportTestDir() / (std::string(name) + "-wind.glb");
    wind::WindAnimationOptions o;
    o.seconds = 1.0f;
    o.fps = 12;
    o.maxJoints = 64;
    wind::writeWindAnimationGlb({{&rest, plant::GrowthFlowSpecies{}}}, wind, o, file);
    meshtest::GltfValidation v = meshtest::validateGltf(file);
    EXPECT_EQ(v.exitCode, 0) << v.output;
    EXPECT_EQ(v.errors, 0) << v.output;
  }
}

TEST(WindAnimation, JointsAreBoundedAndCoverTheRoots) {
  plant::PlantModel p = meshtest::syntheticIvy(5000, 2);
  for (int maxJoints : {8, 32, 128}) {
    std::vector<int32_t> joints = wind::chooseJoints(p, maxJoints);
    EXPECT_LE(joints.size(), size_t(maxJoints));
    EXPECT_EQ(joints.front(), 0);
    EXPECT_TRUE(std::is_sorted(joints.begin(), joints.end()));
  }
}

TEST(WindAnimation, LoopingClipPassesTheValidatorAndRepeats) {
  plant::PlantModel tree = leafyTree();
  plant::PlantModel ivy = meshtest::syntheticIvy(1500, 5);
  for (uint32_t& f : ivy.flags) f &= ~uint32_t(plant::kNodeClimbing);
  ivy.name = "ivy";
  plant::GrowthFlowSpecies soft;
  soft.youngModulus = 2e6f;
  env::WindSettings g;
  g.mode = env::WindMode::Gusty;
  g.velocity = Vec3(8, 0, 0);
  std::filesystem::path file = meshtest::exportTestDir() / "wind.glb";
  wind::WindAnimationOptions o;
  o.seconds = 2.0f;
  o.fps = 12;
  o.maxJoints = 24;
  wind::WindAnimationStats stats =
      wind::writeWindAnimationGlb({{&tree, soft}, {&ivy, soft}}, env::WindField(g), o, file);
  EXPECT_EQ(stats.keyframes, 25u);
  EXPECT_LE(stats.joints, 48u);
  EXPECT_GT(stats.bytes, 1000u);
  meshtest::GltfValidation v = meshtest::validateGltf(file);
  EXPECT_EQ(v.exitCode, 0) << v.output;
  EXPECT_EQ(v.errors, 0) << v.output;

  // The sway itself loops: frame 0 and frame 24 (t = 2 s) pose the plant identically.
  MotionSettings ms;
  ms.loopSeconds = 2.0f;
  WindMotion motion(tree, soft, ms);
  plant::PlantModel a, b;
  motion.step(0.0f, 0.1f, env::WindField(g), a);
  motion.step(2.0f, 0.1f, env::WindField(g), b);
  for (size_t i = 0; i < a.nodeCount(); ++i) EXPECT_LT((a.position[i] - b.position[i]).norm(), 1e-5f);
  plant::PlantModel c;
  motion.step(0.7f, 0.1f, env::WindField(g), c);
  double moved = 0;
  for (size_t i = 0; i < a.nodeCount(); ++i) moved = std::max(moved, double((a.tip(i) - c.tip(i)).norm()));
  EXPECT_GT(moved, 0.005);  // and it does move in between
}

TEST(WindAnimation, FrameSequenceCarriesTheLeavesOwnMotion) {
  plant::PlantModel tree = leafyTree();
  ASSERT_GT(tree.leafCount(), 0u);
  plant::GrowthFlowSpecies soft;
  soft.youngModulus = 2e6f;
  env::WindSettings g;
  g.velocity = Vec3(8, 0, 0);
  wind::WindAnimationOptions o;
  o.seconds = 0.5f;
  o.fps = 8;
  const std::filesystem::path dir = meshtest::exportTestDir() / "wind-frames";
  std::filesystem::create_directories(dir);
  std::vector<std::filesystem::path> files = wind::writeWindFrames({{&tree, soft}}, env::WindField(g), o, dir, "tree");
  ASSERT_EQ(files.size(), 4u);
  EXPECT_EQ(files[0].filename(), "tree_0000.glb");
  EXPECT_EQ(files[3].filename(), "tree_0003.glb");
  for (const auto& f : {files[0], files[3]}) {
    meshtest::GltfValidation v = meshtest::validateGltf(f);
    EXPECT_EQ(v.errors, 0) << f << "\n" << v.output;
  }
  // Frame k is the posed plant of the clip's k-th step, leaves moving on their own.
  MotionSettings ms;
  ms.loopSeconds = 0.5f;
  ms.seed = o.seed;
  WindMotion motion(tree, soft, ms);
  plant::PlantModel posed;
  std::vector<Vec3> leafMotion;
  for (int k = 0; k < 4; ++k) {
    motion.step(0.125f * float(k), 0.125f, env::WindField(g), posed);
    if (k == 0) leafMotion = posed.leafMotion;
  }
  EXPECT_NE(leafMotion, posed.leafMotion);
  auto bytes = [](const std::filesystem::path& f) {
    std::ifstream in(f, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_NE(bytes(files[0]), bytes(files[3])) << "the frames pose the plant differently";
  wind::WindAnimationOptions zeroLength;
  zeroLength.seconds = 0.0f;
  EXPECT_THROW(wind::writeWindFrames({{&tree, soft}}, env::WindField(g), zeroLength, dir, "x"), Error);
}

TEST(WindAnimation, BadOptionsAreAnError) {
  plant::PlantModel tree = leafyTree();
  wind::WindAnimationOptions o;
  o.seconds = 0.0f;
  std::vector<wind::AnimatedPlant> plants{{&tree, plant::GrowthFlowSpecies{}}};
  auto write = [&] { wind::writeWindAnimationGlb(plants, env::WindField{}, o, meshtest::exportTestDir() / "x.glb"); };
  EXPECT_THROW(write(), tendril::Error);
  o.seconds = 1.0f;
  o.fps = 0;
  EXPECT_THROW(write(), tendril::Error);
}

}  // namespace
}  // namespace tendril::wind
