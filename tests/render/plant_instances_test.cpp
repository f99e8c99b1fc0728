#include "tendril/render/plant_instances.h"

#include "support/determinism.h"
#include "support/synthetic_plants.h"
#include "tendril/render/texture_layers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace tendril::render {
namespace {

Vec3 xyz(const GpuVec4& v) { return Vec3(v.x, v.y, v.z); }

std::vector<BranchInstance> branches(const plant::PlantModel& p, std::span<const float> stress = {}) {
  std::vector<BranchInstance> out;
  PlantView view;
  view.model = &p;
  view.stress = stress;
  appendBranchInstances(view, 0.0f, Vec3::Ones(), out);
  return out;
}

TEST(RenderInstances, ConsecutiveSegmentsShareTheirJointRingBitForBit) {
  plant::PlantModel arc = meshtest::arcChain(24, 0.5f, 2.0f, 0.01f);
  std::vector<BranchInstance> b = branches(arc);
  ASSERT_EQ(b.size(), arc.nodeCount());
  for (size_t i = 1; i < b.size(); ++i) {
    // Same centre and radius, same ring plane, same angle-0 direction: no gap, no crack.
    EXPECT_EQ(std::memcmp(&b[i].start, &b[i - 1].end, sizeof(GpuVec4)), 0) << i;
    EXPECT_EQ(xyz(b[i].startAxis), xyz(b[i - 1].endAxis)) << i;
    EXPECT_EQ(xyz(b[i].startRef), xyz(b[i - 1].endRef)) << i;
    // The ring plane bisects the two segment directions (a mitre).
    Vec3 bisector = (arc.direction(i - 1) + arc.direction(i)).normalized();
    EXPECT_LT((xyz(b[i].startAxis) - bisector).norm(), 1e-5f);
    EXPECT_NEAR(xyz(b[i].startRef).dot(xyz(b[i].startAxis)), 0.0f, 1e-5f);
    // Bark v runs on along the chain.
    EXPECT_EQ(b[i].startAxis.w, b[i - 1].startRef.w);
  }
  EXPECT_EQ(uint32_t(b.front().endAxis.w), kCapStart);
  EXPECT_EQ(uint32_t(b.back().endAxis.w), kCapEnd);
  for (size_t i = 1; i + 1 < b.size(); ++i) EXPECT_EQ(b[i].endAxis.w, 0.0f) << i;
}

TEST(RenderInstances, SpinningNodeFramesDoNotTwistTheCylinders) {
  // Every node's frame turns 90° about its axis relative to the previous one; the angular
  // reference is transported along the chain instead, so rings stay aligned.
  plant::PlantModel p = meshtest::straightChain(6);
  for (size_t i = 0; i < p.nodeCount(); ++i) p.orientation[i] = axisAngle(Vec3::UnitY(), 0.5f * kPi * float(i));
  std::vector<BranchInstance> b = branches(p);
  for (size_t i = 0; i < b.size(); ++i) {
    EXPECT_LT((xyz(b[i].startRef) - xyz(b[0].startRef)).norm(), 1e-5f) << i;
    EXPECT_LT((xyz(b[i].endRef) - xyz(b[0].startRef)).norm(), 1e-5f) << i;
  }
}

TEST(RenderInstances, LateralBranchesStartWithTheirOwnCappedRing) {
  plant::PlantModel tree = meshtest::branchingTree();
  std::vector<BranchInstance> b = branches(tree);
  // Chains [0 1 2 3 4 5], [6 7 8], [9 10], [11]: each chain start is capped and starts on its
  // own node; each chain end is capped.
  for (int start : {0, 6, 9, 11}) {
    EXPECT_TRUE(uint32_t(b[size_t(start)].endAxis.w) & kCapStart) << start;
    EXPECT_EQ(xyz(b[size_t(start)].start), tree.position[size_t(start)]) << start;
    EXPECT_EQ(xyz(b[size_t(start)].startAxis), tree.direction(size_t(start))) << start;
  }
  for (int end : {5, 8, 10, 11}) EXPECT_TRUE(uint32_t(b[size_t(end)].endAxis.w) & kCapEnd) << end;
  for (int inner : {1, 2, 3, 4, 7}) EXPECT_EQ(b[size_t(inner)].endAxis.w, 0.0f) << inner;
  // Segments taper from their own radius to their continuing child's.
  EXPECT_EQ(b[0].start.w, tree.radius[0]);
  EXPECT_EQ(b[0].end.w, tree.radius[1]);
  EXPECT_EQ(b[5].end.w, tree.radius[5]);
}

TEST(RenderInstances, StressRunsFromBlueToRedAndSelectionIsMarked) {
  plant::PlantModel p = meshtest::straightChain(5);
  std::vector<float> stress = {0.0f, 0.25f, 0.5f, 0.75f, 1.0f};
  PlantView view;
  view.model = &p;
  view.stress = stress;
  view.selected = {1, 2};
  std::vector<BranchInstance> b;
  appendBranchInstances(view, 0.0f, Vec3::Ones(), b);
  EXPECT_GT(b[0].color.z, 3.0f * b[0].color.x);  // blue
  EXPECT_GT(b[4].color.x, 3.0f * b[4].color.z);  // red
  for (size_t i = 1; i < 5; ++i) EXPECT_GT(b[i].color.x, b[i - 1].color.x);
  EXPECT_EQ(b[0].color.w, 0.0f);
  EXPECT_EQ(b[1].color.w, 1.0f);
  EXPECT_EQ(b[2].color.w, 1.0f);
  EXPECT_EQ(b[3].color.w, 0.0f);
}

TEST(RenderInstances, LeafBladesFollowThePlantModelFrame) {
  plant::PlantModel p = meshtest::straightChain(4);
  meshtest::addLeaves(p, 2, 0.1f);
  std::vector<float> layer = {3.0f, 5.0f}, aspect = {0.8f, 1.2f};
  std::vector<Vec3> tint = {Vec3(1, 0.9f, 0.8f), Vec3(0.5f, 1, 0.5f)};
  PlantView view;
  view.model = &p;
  std::vector<LeafInstance> out;
  appendLeafInstances(view, layer, aspect, tint, out);
  ASSERT_EQ(out.size(), p.leafCount());
  for (size_t i = 0; i < out.size(); ++i) {
    Mat3 r = p.leafWorldRotation(i).toRotationMatrix();
    uint16_t s = p.leafShape[i];
    Vec3 base = p.leafWorldPosition(i) + p.leafPetiole[i] * r.col(1);
    EXPECT_LT((xyz(out[i].base) - base).norm(), 1e-6f);
    EXPECT_NEAR(xyz(out[i].halfWidth).norm(), 0.5f * p.leafSize[i] * aspect[s], 1e-6f);
    EXPECT_LT((xyz(out[i].along) - p.leafSize[i] * r.col(1)).norm(), 1e-6f);
    EXPECT_EQ(out[i].halfWidth.w, layer[s]);
    EXPECT_EQ(xyz(out[i].tint), tint[s]);
  }
}

TEST(RenderInstances, AllPlantsAtOnceEqualPlantAfterPlantForAnyThreadCount) {
  // Plants of different sizes and materials, one view without a model, one with stress and a
  // selection: the parallel build gives the sequential appends' bytes.
  std::vector<plant::PlantModel> plants;
  for (int i = 0; i < 9; ++i) {
    plants.push_back(i % 3 == 0 ? meshtest::syntheticIvy(200 + 150 * size_t(i), uint64_t(i) + 1)
                                : meshtest::arcChain(10 + i, 0.3f + 0.05f * float(i)));
    if (plants.back().leafCount() == 0) meshtest::addLeaves(plants.back(), 2, 0.05f);
  }
  std::vector<float> stress(plants[4].nodeCount());
  for (size_t i = 0; i < stress.size(); ++i) stress[i] = float(i) / float(stress.size());
  std::vector<PlantView> views(plants.size() + 1);
  std::vector<PlantMaterial> materials(views.size());
  for (size_t i = 0; i < plants.size(); ++i) {
    views[i + 1].model = &plants[i];
    PlantMaterial& m = materials[i + 1];
    m.barkLayer = float(i % 2);
    m.barkMean = Vec3(0.4f, 0.5f, 0.3f + 0.01f * float(i));
    size_t shapes = 0;
    for (uint16_t s : plants[i].leafShape) shapes = std::max(shapes, size_t(s) + 1);
    for (size_t s = 0; s < shapes; ++s) {
      m.shapeLayer.push_back(float(s + i));
      m.shapeAspect.push_back(0.5f + 0.1f * float(s));
      m.shapeTint.push_back(Vec3(1.0f, 0.9f, 0.1f * float(i)));
    }
  }
  views[5].stress = stress;
  views[3].selected = {2, 5};
  std::vector<BranchInstance> wantBranches;
  std::vector<LeafInstance> wantLeaves;
  for (size_t i = 1; i < views.size(); ++i) {
    const PlantMaterial& m = materials[i];
    appendBranchInstances(views[i], m.barkLayer, m.barkMean, wantBranches);
    appendLeafInstances(views[i], m.shapeLayer, m.shapeAspect, m.shapeTint, wantLeaves);
  }
  // The instances as bytes: the same at every thread count, and those of the plants one by one.
  const std::string got = tendril::test::sameAtEveryThreadCount([&] {
    std::vector<BranchInstance> gotBranches(3);  // replaced, not appended to
    std::vector<LeafInstance> gotLeaves(5);
    buildPlantInstances(views, materials, gotBranches, gotLeaves);
    return std::string(reinterpret_cast<const char*>(gotBranches.data()), gotBranches.size() * sizeof(BranchInstance)) +
           "|" + std::string(reinterpret_cast<const char*>(gotLeaves.data()), gotLeaves.size() * sizeof(LeafInstance));
  });
  EXPECT_TRUE(got == std::string(reinterpret_cast<const char*>(wantBranches.data()),
                                 wantBranches.size() * sizeof(BranchInstance)) +
                         "|" +
                         std::string(reinterpret_cast<const char*>(wantLeaves.data()),
                                     wantLeaves.size() * sizeof(LeafInstance)));
}

TEST(RenderInstances, PrimitivesArePlacedByTheirNodeAndGroupedByMesh) {
  plant::PlantModel p = meshtest::branchingTree();
  p.meshes.resize(2);
  p.meshes[0].color = Vec3(1, 0, 0);
  p.meshes[1].color = Vec3(0, 0, 1);
  Mat4 offset = Eigen::Affine3f(Eigen::Translation3f(0.0f, 0.1f, 0.0f)).matrix();
  p.primitives.push_back({3, 1, offset});
  p.primitives.push_back({-1, 1, offset});  // node −1: already in world space
  p.primitives.push_back({7, 0, Mat4::Identity()});
  PlantView view;
  view.model = &p;
  view.selected = {7, 1};
  std::vector<std::vector<PrimitiveInstance>> perMesh;
  appendPrimitiveInstances(view, perMesh);
  ASSERT_EQ(perMesh.size(), 2u);
  ASSERT_EQ(perMesh[0].size(), 1u);
  ASSERT_EQ(perMesh[1].size(), 2u);
  auto origin = [](const PrimitiveInstance& i) { return xyz(i.worldFromPrimitive[3]); };
  // 0.1 m along node 3's +Y from its start.
  EXPECT_LT((origin(perMesh[1][0]) - (p.position[3] + 0.1f * p.direction(3))).norm(), 1e-6f);
  EXPECT_LT((origin(perMesh[1][1]) - Vec3(0.0f, 0.1f, 0.0f)).norm(), 1e-6f);
  EXPECT_LT((origin(perMesh[0][0]) - p.position[7]).norm(), 1e-6f);
  EXPECT_EQ(xyz(perMesh[1][0].color), Vec3(0, 0, 1));
  EXPECT_EQ(perMesh[0][0].color.w, 1.0f) << "on a selected node";
  EXPECT_EQ(perMesh[1][0].color.w, 0.0f);
}

TEST(RenderTextures, AlphaMipmapsKeepThinLeavesFromVanishing) {
  // Eight spokes 3 texels wide, like the leaflets of a compound leaf, on a transparent field.
  // Box-filtered mipmaps fade such thin parts below the alpha test at 0.5, so the leaf
  // disappears in the distance; the rescaled chain keeps its area.
  io::Image fern = io::makeImage(128, 128, 0, 0, 0, 0);
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) {
      float dx = float(x) + 0.5f - 64.0f, dy = float(y) + 0.5f - 64.0f;
      float r = std::sqrt(dx * dx + dy * dy), a = std::atan2(dy, dx);
      float toSpoke = r * std::sin(a - std::round(a / (0.25f * kPi)) * 0.25f * kPi);
      if (r < 60.0f && std::abs(toSpoke) < 1.5f) {
        uint8_t* p = fern.pixel(x, y);
        p[0] = 40;
        p[1] = 120;
        p[2] = 40;
        p[3] = 255;
      }
    }
  const double base = alphaCoverage(fern);
  ASSERT_GT(base, 0.05);
  std::vector<io::Image> chain = buildMipChain(fern, true), plain = buildMipChain(fern, false);
  ASSERT_EQ(chain.size(), 8u);
  EXPECT_EQ(chain.back().width, 1);
  for (size_t level = 1; level <= 3; ++level)  // 64², 32², 16²
    EXPECT_NEAR(alphaCoverage(chain[level]), base, 0.02) << "level " << level;
  EXPECT_NEAR(alphaCoverage(chain[4]), base, 1.0 / 16.0) << "8²: coverage comes in steps of 1/64";
  EXPECT_EQ(alphaCoverage(plain[4]), 0.0) << "plain box filtering loses the leaf at 8²";
  // Colour is averaged over opaque texels only: the black transparent field does not darken it.
  for (size_t level = 1; level <= 4; ++level) {
    const io::Image& img = chain[level];
    for (size_t i = 0; i < img.rgba.size(); i += 4) {
      if (img.rgba[i + 3] >= 128) {
        ASSERT_EQ(img.rgba[i + 1], 120) << "level " << level;
      }
    }
  }
}

}  // namespace
}  // namespace tendril::render
