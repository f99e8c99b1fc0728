// The leaves' periodic motion in a looping clip (wind/motion.h, LeafLoop) and its glTF form:
// morph targets whose weighted sum poses the leaves as the motion does.
#include "tendril/env/wind_field.h"
#include "tendril/mesh/leaf_mesh.h"
#include "tendril/wind/gltf_animation.h"
#include "tendril/wind/motion.h"

#include "support/gltf_validator.h"
#include "support/synthetic_plants.h"
#include "support/test_paths.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>

namespace tendril::wind {
namespace {

env::WindField windOf(env::WindMode mode, Vec3 v) {
  env::WindSettings s;
  s.mode = mode;
  s.velocity = v;
  return env::WindField(s);
}

// Ivy clinging to its wall: every node held by the support, so only the leaves can move.
plant::PlantModel clingingIvy() {
  plant::PlantModel ivy = meshtest::syntheticIvy(600, 3);
  for (uint32_t& f : ivy.flags) f |= plant::kNodeClimbing;
  for (uint16_t& shape : ivy.leafShape) shape = 0;  // one leaf mesh: one primitive to check
  ivy.name = "ivy";
  return ivy;
}

TEST(LeafLoop, TriangleWave) {
  EXPECT_FLOAT_EQ(triangleWave(0.0f), 0.0f);
  EXPECT_FLOAT_EQ(triangleWave(0.25f), 1.0f);
  EXPECT_FLOAT_EQ(triangleWave(0.5f), 0.0f);
  EXPECT_FLOAT_EQ(triangleWave(0.75f), -1.0f);
  EXPECT_FLOAT_EQ(triangleWave(1.125f), 0.5f);
  EXPECT_FLOAT_EQ(triangleWave(-0.125f), -0.5f);
}

TEST(LeafLoop, LeavesMoveWithinTheirLimitsAndRepeatAfterTheLoop) {
  plant::PlantModel ivy = clingingIvy();
  ASSERT_GT(ivy.leafCount(), 50u);
  plant::GrowthFlowSpecies species;
  MotionSettings ms;
  ms.loopSeconds = 2.0f;
  // Oblique to the wall the leaves lie on: every leaf bends, twists and vibrates (§3.2.1).
  const env::WindField wind = windOf(env::WindMode::Gusty, Vec3(8, 0, -5));
  WindMotion motion(ivy, species, ms);
  plant::PlantModel first, later, last;
  motion.step(0.0f, 1.0f / 24, wind, first);
  motion.step(0.6f, 1.0f / 24, wind, later);
  motion.step(2.0f, 1.0f / 24, wind, last);
  ASSERT_EQ(first.leafCount(), ivy.leafCount());
  EXPECT_EQ(first.leafMotion, last.leafMotion);
  EXPECT_EQ(first.leafRotation, last.leafRotation);
  EXPECT_NE(first.leafMotion, later.leafMotion);
  // Nothing else moves: the support holds every node.
  EXPECT_EQ(first.position, ivy.position);
  const LeafLoop& loop = motion.leafLoop();
  ASSERT_EQ(loop.leaves.size(), ivy.leafCount());
  const float limits[3] = {loop.bendsBlade ? species.bladeBendLimit : species.petioleBendLimit, species.twistLimit,
                           species.vibrateLimit};
  size_t phases[LeafLoop::kPhases] = {};
  for (const LeafLoop::Leaf& f : loop.leaves) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_GT(f.amplitude[k], 0.0f);
      EXPECT_LE(f.amplitude[k], limits[k]);
    }
    ++phases[f.phase[0]];
  }
  for (size_t g : phases) EXPECT_GT(g, loop.leaves.size() / 8) << "phases are spread over the groups";
  for (size_t j = 0; j < later.leafCount(); ++j) {
    EXPECT_LE(std::fabs(later.leafMotion[j].y()), species.twistLimit + 1e-6f);
    EXPECT_LE(std::fabs(later.leafMotion[j].z()), species.vibrateLimit + 1e-6f);
  }
}

TEST(LeafLoop, CalmerAirMovesLeavesLessAndStillAirNotAtAll) {
  plant::PlantModel ivy = clingingIvy();
  plant::GrowthFlowSpecies species;
  MotionSettings ms;
  ms.loopSeconds = 4.0f;
  auto meanAmplitude = [&](float speed, int kind) {
    WindMotion motion(ivy, species, ms);
    // At 45° to the blades, where they twist the most (§3.2.1).
    const LeafLoop& loop = motion.prepareLeafLoop(windOf(env::WindMode::Constant, Vec3(speed, 0, -speed) / std::sqrt(2.0f)));
    double sum = 0;
    for (const LeafLoop::Leaf& f : loop.leaves) sum += f.amplitude[kind];
    return sum / double(loop.leaves.size());
  };
  EXPECT_EQ(meanAmplitude(0.0f, 1), 0.0);
  // At 0.5 m/s a twist covers far less than its limit in a quarter period; at 2 m/s more.
  const double slow = meanAmplitude(0.5f, 1), faster = meanAmplitude(2.0f, 1);
  EXPECT_GT(slow, 0.0);
  EXPECT_LT(slow, 0.5 * species.twistLimit);
  EXPECT_GT(faster, slow);
  // Above the leaves' strength every leaf is torn off from the first frame.
  WindMotion storm(ivy, species, ms);
  plant::PlantModel posed;
  storm.step(0.0f, 0.04f, windOf(env::WindMode::Constant, Vec3(2.0f * species.strengthToWind * species.bladeStrength, 0, 0)), posed);
  EXPECT_EQ(posed.leafCount(), 0u);
}

TEST(LeafLoop, LeavesBendFacingTheWindTwistObliqueToItAndVibrateAlongIt) {
  // §3.2.1: one held node with one leaf lying in the XY plane (normal +Z), in a wind along +Z
  // (facing), along +X (parallel) and at 45°. Frame by frame (Algorithm 2's random draw with
  // the orientation's chances) and in a loop.
  plant::PlantModel p = meshtest::straightChain(1, 0.2f, 0.01f, 0.01f);
  p.flags[0] |= plant::kNodeClimbing;
  plant::PlantModel::LeafDef leaf;
  leaf.node = 0;
  leaf.offset = Vec3(0, 0.1f, 0);
  leaf.size = 0.06f;
  p.addLeaf(leaf);
  plant::GrowthFlowSpecies species;
  const Vec3 winds[3] = {Vec3(0, 0, 6), Vec3(6, 0, 0), Vec3(6, 0, 6) / std::sqrt(2.0f)};
  for (int which = 0; which < 3; ++which) {
    SCOPED_TRACE(which == 0 ? "facing" : which == 1 ? "parallel" : "oblique");
    const env::WindField wind = windOf(env::WindMode::Constant, winds[which]);
    WindMotion motion(p, species);
    plant::PlantModel posed;
    int moved[3] = {0, 0, 0};  // frames in which the bend, the twist, the vibration changed
    plant::LeafMotionState last;
    const int frames = 600;
    for (int f = 0; f < frames; ++f) {
      motion.step(0.04f * float(f), 0.04f, wind, posed);
      const plant::LeafMotionState& L = motion.leaves()[0];
      moved[0] += L.petioleBend != last.petioleBend || L.bladeBend != last.bladeBend;
      moved[1] += L.twist != last.twist;
      moved[2] += L.vibrate != last.vibrate;
      last = L;
    }
    MotionSettings ms;
    ms.loopSeconds = 4.0f;
    WindMotion looped(p, species, ms);
    const LeafLoop::Leaf& a = looped.prepareLeafLoop(wind).leaves[0];
    if (which == 0) {
      EXPECT_GT(moved[0], frames / 2);
      EXPECT_EQ(moved[1], 0);
      EXPECT_EQ(moved[2], 0);
      EXPECT_GT(a.amplitude[0], 0.0f);
      EXPECT_EQ(a.amplitude[1], 0.0f);
      EXPECT_EQ(a.amplitude[2], 0.0f);
    } else if (which == 1) {
      EXPECT_EQ(moved[0], 0);
      EXPECT_EQ(moved[1], 0);
      EXPECT_GT(moved[2], frames / 2);
      EXPECT_EQ(a.amplitude[0], 0.0f);
      EXPECT_EQ(a.amplitude[1], 0.0f);
      EXPECT_GT(a.amplitude[2], 0.0f);
    } else {
      // c = cos 45°: bend 0.5, twist 0.41, vibrate 0.09 of the frames.
      EXPECT_NEAR(double(moved[0]) / frames, 0.5, 0.08);
      EXPECT_NEAR(double(moved[1]) / frames, 2 * 0.7071 * (1 - 0.7071), 0.08);
      EXPECT_NEAR(double(moved[2]) / frames, (1 - 0.7071) * (1 - 0.7071), 0.05);
      for (float amplitude : a.amplitude) EXPECT_GT(amplitude, 0.0f);
    }
  }
}

// Reads a float accessor's elements (dense or sparse, or all zeros without a buffer).
std::vector<float> readFloats(const tinygltf::Model& m, int index, int components) {
  const tinygltf::Accessor& a = m.accessors[size_t(index)];
  std::vector<float> out(a.count * size_t(components), 0.0f);
  auto bytesOf = [&](int view) {
    const tinygltf::BufferView& v = m.bufferViews[size_t(view)];
    return m.buffers[size_t(v.buffer)].data.data() + v.byteOffset;
  };
  if (a.bufferView >= 0) std::memcpy(out.data(), bytesOf(a.bufferView) + a.byteOffset, out.size() * sizeof(float));
  if (a.sparse.isSparse) {
    std::vector<uint32_t> at(size_t(a.sparse.count));
    std::memcpy(at.data(), bytesOf(a.sparse.indices.bufferView) + a.sparse.indices.byteOffset, at.size() * 4);
    const uint8_t* values = bytesOf(a.sparse.values.bufferView) + a.sparse.values.byteOffset;
    for (size_t e = 0; e < at.size(); ++e)
      std::memcpy(&out[at[e] * size_t(components)], values + e * size_t(components) * 4, size_t(components) * 4);
  }
  return out;
}

TEST(LeafLoop, TheClipsMorphTargetsPoseTheLeavesAsTheMotionDoes) {
  plant::PlantModel ivy = clingingIvy();
  plant::GrowthFlowSpecies species;
  // Mostly along the wall, a little into it: the leaves vibrate and twist more than they bend.
  const env::WindField wind = windOf(env::WindMode::Gusty, Vec3(8, 0, -3));
  WindAnimationOptions o;
  o.seconds = 2.0f;
  o.fps = 12;
  const std::filesystem::path file = meshtest::exportTestDir() / "ivy-leaves-wind.glb";
  const WindAnimationStats stats = writeWindAnimationGlb({{&ivy, species}}, wind, o, file);
  EXPECT_EQ(stats.morphTargets, size_t(3 * LeafLoop::kPhases));
  meshtest::GltfValidation v = meshtest::validateGltf(file);
  EXPECT_EQ(v.exitCode, 0) << v.output;
  EXPECT_EQ(v.errors, 0) << v.output;

  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, file.string())) << err;
  ASSERT_EQ(m.animations.size(), 1u);
  // Clinging ivy: its support holds every node, so the leaves' weights are what moves.
  const tinygltf::AnimationChannel* weights = nullptr;
  for (const tinygltf::AnimationChannel& c : m.animations[0].channels)
    if (c.target_path == "weights") weights = &c;
  ASSERT_NE(weights, nullptr);
  const int targets = 3 * LeafLoop::kPhases;
  const int frames = int(stats.keyframes);
  const std::vector<float> w = readFloats(m, m.animations[0].samplers[size_t(weights->sampler)].output, 1);
  ASSERT_EQ(w.size(), size_t(frames * targets));
  for (int t = 0; t < targets; ++t) EXPECT_EQ(w[size_t(t)], w[size_t((frames - 1) * targets + t)]) << "the loop closes";
  bool differ = false;
  for (int t = 0; t < targets; ++t) differ = differ || w[size_t(t)] != w[size_t(5 * targets + t)];
  EXPECT_TRUE(differ);

  // The leaf primitive: rest positions plus the weighted targets at keyframe k against the
  // leaves the motion poses at that time.
  const tinygltf::Mesh& mesh = m.meshes[size_t(m.nodes[size_t(weights->target_node)].mesh)];
  const tinygltf::Primitive* leafPrim = nullptr;
  for (const tinygltf::Primitive& p : mesh.primitives)
    if (p.targets.size() == size_t(targets) && m.accessors[size_t(p.targets[0].at("POSITION"))].sparse.isSparse)
      leafPrim = &p;
  ASSERT_NE(leafPrim, nullptr);
  const std::vector<float> rest = readFloats(m, leafPrim->attributes.at("POSITION"), 3);
  std::vector<std::vector<float>> target;
  for (const auto& t : leafPrim->targets) target.push_back(readFloats(m, t.at("POSITION"), 3));
  ASSERT_EQ(rest.size(), ivy.leafCount() * mesh::leafVertexCount(o.mesh) * 3) << "one leaf shape: all leaves here";

  MotionSettings ms;
  ms.loopSeconds = o.seconds;
  ms.seed = o.seed;
  WindMotion motion(ivy, species, ms);
  plant::PlantModel posed;
  const float dt = o.seconds / float(frames - 1);
  double worst = 0, largest = 0;
  for (int k = 0; k < frames; ++k) {
    motion.step(float(k) * dt, dt, wind, posed);
    if (k % 4 != 3) continue;
    const TriangleMesh truth = mesh::buildLeafQuads(posed, o.mesh)[0];
    ASSERT_EQ(truth.positions.size() * 3, rest.size());
    for (size_t vtx = 0; vtx < truth.positions.size(); ++vtx) {
      Vec3 p(rest[3 * vtx], rest[3 * vtx + 1], rest[3 * vtx + 2]);
      for (int t = 0; t < targets; ++t)
        p += w[size_t(k * targets + t)] * Vec3(target[size_t(t)][3 * vtx], target[size_t(t)][3 * vtx + 1], target[size_t(t)][3 * vtx + 2]);
      const Vec3 restP(rest[3 * vtx], rest[3 * vtx + 1], rest[3 * vtx + 2]);
      worst = std::max(worst, double((p - truth.positions[vtx]).norm()));
      largest = std::max(largest, double((truth.positions[vtx] - restP).norm()));
    }
  }
  EXPECT_GT(largest, 1e-3) << "the leaves move by millimetres at least";
  // Linearised rotations: the error is of second order, about half the angle times the
  // displacement, for the largest sum of a leaf's three amplitudes (here about 20°).
  double angle = 0;
  for (const LeafLoop::Leaf& f : motion.leafLoop().leaves)
    angle = std::max(angle, double(f.amplitude[0] + f.amplitude[1] + f.amplitude[2]));
  ASSERT_GT(angle, 0.1);
  EXPECT_LT(worst, 0.5 * angle * largest) << "worst " << worst << " of " << largest << ", angles up to " << angle;
}

TEST(LeafLoop, StillAirWritesNoLeafTargets) {
  plant::PlantModel ivy = clingingIvy();
  WindAnimationOptions o;
  o.seconds = 1.0f;
  o.fps = 8;
  const std::filesystem::path file = meshtest::exportTestDir() / "ivy-still.glb";
  const WindAnimationStats stats =
      writeWindAnimationGlb({{&ivy, plant::GrowthFlowSpecies{}}}, env::WindField{}, o, file);
  EXPECT_EQ(stats.morphTargets, 0u);
  meshtest::GltfValidation v = meshtest::validateGltf(file);
  EXPECT_EQ(v.errors, 0) << v.output;
}

}  // namespace
}  // namespace tendril::wind
