// Expansion of p-graphs into i-trees (seed 004, "Modeling with components", Fig. 2 and 3).
#include "graph_test_util.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace tendril {
namespace {

using graphtest::instancesOf;
using graphtest::parse;

// seed 004, Fig. 2: A (the root) → B (a stem) → C (a multiplier, n = 3) → D (a twig part with
// recursion depth 3, linked to itself).
const char* kFig2 = R"({"tendril_graph": 1, "name": "fig2",
  "root": {"links": ["B"]},
  "components": [
    {"name": "B", "type": "horn", "params": {"length": 1, "segments": 4}, "links": ["C"]},
    {"name": "C", "type": "hydra", "params": {"count": 3, "angle": 40}, "links": ["D"]},
    {"name": "D", "type": "horn", "depth": 3, "params": {"length": 0.3, "segments": 2, "rotate": [15, 0, 0]},
     "links": ["D"]}]})";

TEST(GraphExpand, Fig2GivesNineInstancesOfDInThreeChainsOfThree) {
  graph::ITree t = graph::expand(parse(kFig2));
  ASSERT_EQ(t.instances.size(), 12u);  // A1, B1, C1 and nine D
  EXPECT_EQ(t.countOf(-1), 1u);
  EXPECT_EQ(t.countOf("B"), 1u);
  EXPECT_EQ(t.countOf("C"), 1u);
  EXPECT_EQ(t.countOf("D"), 9u);

  // The tree's shape: A1 → B1 → C1 → {D11, D21, D31}, Di1 → Di2 → Di3.
  int32_t b = t.graph->find("B"), c = t.graph->find("C"), d = t.graph->find("D");
  std::vector<int32_t> rootChildren = t.childrenOf(0);
  ASSERT_EQ(rootChildren.size(), 1u);
  EXPECT_EQ(t.instances[size_t(rootChildren[0])].component, b);
  std::vector<int32_t> bChildren = t.childrenOf(rootChildren[0]);
  ASSERT_EQ(bChildren.size(), 1u);
  EXPECT_EQ(t.instances[size_t(bChildren[0])].component, c);
  std::vector<int32_t> chains = t.childrenOf(bChildren[0]);
  ASSERT_EQ(chains.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    int32_t at = chains[size_t(i)];
    for (int level = 1; level <= 3; ++level) {
      const graph::Instance& inst = t.instances[size_t(at)];
      EXPECT_EQ(inst.component, d);
      EXPECT_EQ(inst.depth, level);
      EXPECT_EQ(inst.iteration, i);  // the multiplier's iteration number reaches the whole chain
      EXPECT_EQ(inst.count, 3);
      std::vector<int32_t> next = t.childrenOf(at);
      if (level < 3) {
        ASSERT_EQ(next.size(), 1u);
        at = next[0];
      } else {
        EXPECT_TRUE(next.empty());  // the recursion ends at depth 3
      }
    }
  }

  // Geometry: ten stems; each D continues the previous D's chain, the first D of each chain
  // branches off B's tip.
  ASSERT_EQ(t.stems.size(), 10u);
  plant::PlantModel p = graph::buildPlant(t);
  EXPECT_EQ(p.nodeCount(), 4u + 9u * 2u);
  plant::PlantStats s = plant::computeStats(p);
  EXPECT_EQ(s.roots, 1u);
  EXPECT_EQ(s.tips, 3u);
}

TEST(GraphExpand, MultiplierRangesFollowTheRangeFormula) {
  // v_i = v0 + i (v1 − v0) / (n − 1), then the user function (seed 004).
  auto g = parse(R"({"tendril_graph": 1, "root": {"links": ["star"]},
    "components": [
      {"name": "star", "type": "hydra",
       "params": {"count": 5, "child_scale": [0.5, 1.5], "angle": {"range": [10, 30], "f": "v * 2 + i"}},
       "links": ["leaf"]},
      {"name": "leaf", "type": "leaf", "params": {"size": [0.1, 0.3]}}]})");
  graph::ITree t = graph::expand(g);
  std::vector<const graph::Instance*> leaves = instancesOf(t, "leaf");
  ASSERT_EQ(leaves.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    const graph::Instance& l = *leaves[size_t(i)];
    EXPECT_EQ(l.iteration, i);
    float v = 0.5f + float(i) * (1.5f - 0.5f) / 4.0f;
    EXPECT_NEAR(l.frame.scale, v, 1e-6f);
    float angle = 2.0f * (10.0f + float(i) * (30.0f - 10.0f) / 4.0f) + float(i);
    EXPECT_NEAR(degrees(angleBetween(l.frame.rotation * Vec3::UnitY(), Vec3::UnitY())), angle, 1e-3f);
    // The leaf's own range uses the iteration number it received from the multiplier.
    float size = 0.1f + float(i) * 0.2f / 4.0f;
    EXPECT_NEAR(t.leaves[size_t(i)].size, size * v, 1e-6f);
  }
}

TEST(GraphExpand, FlagListsExcludeExactlyTheListedIterations) {
  // seed 004, Fig. 5c: a twig that branches in leaves everywhere except at iterations 2 and 13,
  // where it branches in tiny twigs.
  auto g = parse(R"({"tendril_graph": 1, "root": {"links": ["twig"]},
    "components": [
      {"name": "twig", "type": "tree", "params": {"branches": 16, "branch_start": 0.1},
       "links": [{"to": "leaf", "type": "branch"}, {"to": "tiny", "type": "branch"}]},
      {"name": "leaf", "type": "leaf", "exclude": [2, 13]},
      {"name": "tiny", "type": "tree", "only": [2, 13], "params": {"length": 0.2}}]})");
  graph::ITree t = graph::expand(g);
  std::set<int> leaves, tiny;
  for (const graph::Instance* i : instancesOf(t, "leaf")) leaves.insert(i->iteration);
  for (const graph::Instance* i : instancesOf(t, "tiny")) tiny.insert(i->iteration);
  std::set<int> expectedLeaves;
  for (int i = 0; i < 16; ++i)
    if (i != 2 && i != 13) expectedLeaves.insert(i);
  EXPECT_EQ(leaves, expectedLeaves);
  EXPECT_EQ(tiny, (std::set<int>{2, 13}));
  EXPECT_EQ(instancesOf(t, "leaf").size(), 14u);
  EXPECT_EQ(instancesOf(t, "tiny").size(), 2u);
}

TEST(GraphExpand, LeafLinksAreFollowedOnceTheRecursionEnds) {
  auto g = parse(R"({"tendril_graph": 1, "root": {"links": ["star"]},
    "components": [
      {"name": "star", "type": "hydra", "params": {"count": 2}, "links": ["D", {"to": "bud", "type": "leaf"}]},
      {"name": "D", "type": "horn", "depth": 4, "params": {"length": 0.2, "segments": 1},
       "links": ["D", {"to": "bud", "type": "leaf"}]},
      {"name": "bud", "type": "simple", "params": {"shape": "sphere"}}]})");
  graph::ITree t = graph::expand(g);
  EXPECT_EQ(t.countOf("D"), 8u);
  // Two buds at the ends of the two recursions, and two under the (non-recursive) star, where
  // a leaf link is an ordinary child link.
  std::vector<const graph::Instance*> buds = instancesOf(t, "bud");
  ASSERT_EQ(buds.size(), 4u);
  int afterRecursion = 0;
  for (const graph::Instance* b : buds) {
    const graph::Instance& parent = t.instances[size_t(b->parent)];
    if (parent.component == t.graph->find("D")) {
      EXPECT_EQ(parent.depth, 4);
      ++afterRecursion;
    }
  }
  EXPECT_EQ(afterRecursion, 2);
}

TEST(GraphExpand, RecursionThroughSeveralComponentsIsBoundedByTheOneWithADepth) {
  auto g = parse(R"({"tendril_graph": 1, "root": {"links": ["a"]},
    "components": [
      {"name": "a", "type": "horn", "depth": 3, "params": {"length": 0.1, "segments": 1}, "links": ["b"]},
      {"name": "b", "type": "hydra", "params": {"count": 2, "child_scale": 0.7}, "links": ["a"]}]})");
  graph::ITree t = graph::expand(g);
  EXPECT_EQ(t.countOf("a"), 1u + 2u + 4u);
  EXPECT_EQ(t.countOf("b"), 1u + 2u + 4u);
  for (const graph::Instance* i : instancesOf(t, "a")) EXPECT_LE(i->depth, 3);
}

TEST(GraphExpand, BranchLinksMultiplyChildrenAlongTheStem) {
  auto g = parse(R"({"tendril_graph": 1, "root": {"links": ["stem"]},
    "components": [
      {"name": "stem", "type": "tree",
       "params": {"length": 2, "segments": 10, "branches": 7, "branch_start": 0.2, "branch_end": 0.8,
                  "branch_angle": 60, "phyllotaxis": 90, "branch_scale": 1},
       "links": [{"to": "leaf", "type": "branch"}, "cap"]},
      {"name": "leaf", "type": "leaf"},
      {"name": "cap", "type": "hydra", "params": {"count": 2}, "links": [{"to": "bud", "type": "branch"}]},
      {"name": "bud", "type": "simple"}]})");
  graph::ITree t = graph::expand(g);
  std::vector<const graph::Instance*> leaves = instancesOf(t, "leaf");
  ASSERT_EQ(leaves.size(), 7u);
  for (int i = 0; i < 7; ++i) {
    const graph::Instance& l = *leaves[size_t(i)];
    // Evenly from 20 % to 80 % of the straight stem, each 90° around from the last, 60° out.
    EXPECT_NEAR(l.frame.position.y(), 2.0f * (0.2f + 0.6f * float(i) / 6.0f), 1e-5f);
    EXPECT_NEAR(std::hypot(l.frame.position.x(), l.frame.position.z()), 0.0f, 1e-5f);
    Vec3 dir = l.frame.rotation * Vec3::UnitY();
    EXPECT_NEAR(degrees(angleBetween(dir, Vec3::UnitY())), 60.0f, 1e-3f);
    float azimuth = degrees(std::atan2(-dir.x(), -dir.z()));
    float expected = std::fmod(90.0f * float(i) + 540.0f, 360.0f) - 180.0f;
    EXPECT_NEAR(std::remainder(azimuth - expected, 360.0f), 0.0f, 1e-3f) << i;
    // The leaf hangs from the stem node it sits on.
    EXPECT_EQ(l.anchor, std::min(9, int(std::floor((0.2f + 0.6f * float(i) / 6.0f) * 10.0f + 1e-4f))));
  }
  // The child link places one "cap" at the stem's tip; a branch link from a component that is
  // not a Tree is a child link: the cap's two children.
  std::vector<const graph::Instance*> caps = instancesOf(t, "cap");
  ASSERT_EQ(caps.size(), 1u);
  EXPECT_NEAR((caps[0]->frame.position - Vec3(0, 2, 0)).norm(), 0.0f, 1e-5f);
  EXPECT_EQ(caps[0]->anchor, 9);
  EXPECT_EQ(instancesOf(t, "bud").size(), 2u);
}

TEST(GraphExpand, TooManyInstancesIsAnErrorNamingTheLimit) {
  auto g = parse(R"({"tendril_graph": 1, "max_instances": 100, "root": {"links": ["many"]},
    "components": [{"name": "many", "type": "hydra", "params": {"count": 200}, "links": ["x"]},
                   {"name": "x", "type": "simple"}]})");
  try {
    graph::expand(g);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.location(), "/max_instances");
    EXPECT_NE(e.message().find("raise \"max_instances\""), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tendril
