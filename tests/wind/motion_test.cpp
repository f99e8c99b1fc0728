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

TEST(WindMotion, BranchesSwayTowardTheWindAndBack) {
  plant::PlantModel rest = leafyTree();
  plant::GrowthFlowSpecies species;
  species.youngModulus = 2e6f;  // soft enough to reach the sway limit in this wind
  WindMotion motion(rest, species);
  env::WindField wind = constantWind(Vec3(10, 0, 0));
  plant::PlantModel posed;
  double maxLean = 0, minLean = 1e9;
  for (int f = 0; f < 400; ++f) {
    motion.step(0.025f * float(f), 0.025f, wind, posed);
    plant::validate(posed, "posed");
    // Node 5 (top of the stem): how far its tip moved downwind.
    float lean = posed.tip(5).x() - rest.tip(5).x();
    maxLean = std::max(maxLean, double(lean));
    minLean = std::min(minLean, double(lean));
    for (size_t i = 0; i < posed.nodeCount(); ++i) {
      ASSERT_LE(motion.swayAngle(i), species.maxSwayAngle + 1e-6f);
      ASSERT_NEAR(posed.length[i], rest.length[i], 0.0f);
    }
    // The stem stays connected: each chain node starts where its parent ends.
    for (int i = 1; i < 6; ++i) ASSERT_LT((posed.position[size_t(i)] - posed.tip(size_t(i - 1))).norm(), 1e-5f);
  }
  EXPECT_GT(maxLean, 0.05);   // the top leans downwind...
  EXPECT_LT(minLean, 0.005);  // ...and comes back (sinusoidal ease-in / ease-out)
  EXPECT_GE(minLean, -1e-4);  // never upwind
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
