#include "tendril/plant/plant_model.h"

#include "tendril/core/error.h"

#include <gtest/gtest.h>

namespace tendril::plant {
namespace {

PlantModel chain(int n) {
  PlantModel p;
  p.name = "test";
  int32_t prev = -1;
  for (int i = 0; i < n; ++i) {
    PlantModel::NodeDef d;
    d.position = Vec3(0, 0.1f * i, 0);
    d.length = 0.1f;
    d.radius = 0.01f;
    d.parent = prev;
    prev = p.addNode(d);
  }
  return p;
}

TEST(PlantModel, StatsOfAChain) {
  PlantModel p = chain(10);
  PlantModel::LeafDef l;
  l.node = 3;
  l.size = 0.05f;
  p.addLeaf(l);
  PlantStats s = computeStats(p);
  EXPECT_EQ(s.nodes, 10u);
  EXPECT_EQ(s.leaves, 1u);
  EXPECT_EQ(s.roots, 1u);
  EXPECT_EQ(s.tips, 1u);
  EXPECT_NEAR(s.totalLength, 1.0, 1e-5);
  EXPECT_NEAR(s.bounds.max.y(), 1.0f, 1e-5f);
  EXPECT_NO_THROW(validate(p, "t"));
}

TEST(PlantModel, KeepLeavesKeepsTheChosenOnesInOrder) {
  PlantModel p = chain(3);
  for (int j = 0; j < 6; ++j) {
    PlantModel::LeafDef l;
    l.node = j % 3;
    l.size = 0.01f * float(j + 1);
    l.petiole = 0.002f * float(j);
    l.shape = uint16_t(j);
    p.addLeaf(l);
    p.leafMotion.back() = Vec3(float(j), 0, 0);
  }
  p.keepLeaves({0, 1, 2, 3, 4, 5});
  ASSERT_EQ(p.leafCount(), 6u);
  p.keepLeaves({1, 4, 5});
  ASSERT_EQ(p.leafCount(), 3u);
  ASSERT_EQ(p.leafMotion.size(), 3u);
  const int was[3] = {1, 4, 5};
  for (size_t o = 0; o < 3; ++o) {
    EXPECT_EQ(p.leafNode[o], was[o] % 3);
    EXPECT_FLOAT_EQ(p.leafSize[o], 0.01f * float(was[o] + 1));
    EXPECT_FLOAT_EQ(p.leafPetiole[o], 0.002f * float(was[o]));
    EXPECT_EQ(p.leafShape[o], uint16_t(was[o]));
    EXPECT_EQ(p.leafMotion[o].x(), float(was[o]));
  }
  p.keepLeaves({});
  EXPECT_EQ(p.leafCount(), 0u);
  EXPECT_NO_THROW(validate(p, "test"));
}

TEST(PlantModel, ValidateRejectsBadData) {
  PlantModel p = chain(3);
  p.radius[1] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(validate(p, "t"), Error);
  p = chain(3);
  p.parent[1] = 2;  // child before parent
  EXPECT_THROW(validate(p, "t"), Error);
  p = chain(3);
  p.length.pop_back();
  EXPECT_THROW(validate(p, "t"), Error);
  p = chain(3);
  PlantModel::LeafDef l;
  l.node = 5;
  l.size = 0.1f;
  p.addLeaf(l);
  try {
    validate(p, "t");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "t:leaf 0: plant \"test\": is attached to a missing node");
  }
}

TEST(PlantModel, ContentHashChangesWithAnyBit) {
  PlantModel a = chain(5), b = chain(5);
  EXPECT_EQ(contentHash(a), contentHash(b));
  b.position[2].x() = std::nextafter(b.position[2].x(), 1.0f);
  EXPECT_NE(contentHash(a), contentHash(b));
}

TEST(PlantModel, ChildrenCsr) {
  PlantModel p = chain(3);
  PlantModel::NodeDef d;
  d.parent = 0;
  d.length = 0.1f;
  d.radius = 0.01f;
  p.addNode(d);
  std::vector<int32_t> start, idx;
  p.children(start, idx);
  ASSERT_EQ(start[1] - start[0], 2);
  EXPECT_EQ(idx[start[0]], 1);
  EXPECT_EQ(idx[start[0] + 1], 3);
}

}  // namespace
}  // namespace tendril::plant
