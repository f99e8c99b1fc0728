// Levels of detail (mesh/lod.h, issue 26 part 1): budgets met and falling, the silhouette kept,
// MSFT_lod in the .glb, one .obj per level, vertex cache order, determinism and the settings'
// errors — for a climbing ivy, an L-system plant and a graph plant grown from the examples.
#include "tendril/mesh/lod.h"

#include "support/determinism.h"
#include "support/eight_views.h"
#include "support/example_plants.h"
#include "support/gltf_validator.h"
#include "support/run_command.h"
#include "support/silhouette.h"
#include "support/synthetic_plants.h"
#include "support/test_paths.h"
#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"
#include "tendril/core/log.h"
#include "tendril/io/atomic_file.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/image.h"
#include "tendril/io/obj_writer.h"
#include "tendril/scene/scene.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <meshoptimizer.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>

namespace tendril {
namespace {

namespace fs = std::filesystem;
using plant::PlantModel;

// The first plant of `sceneJson` (a scene document; relative paths from examples/scenes) after
// `steps` steps.
PlantModel grown(const std::string& sceneJson, uint32_t steps, size_t which = 0) {
  const fs::path dir = test::sourceDir() / "examples/scenes";
  session::Session s(scene::parseScene(parseJson(sceneJson, "test scene"), "test scene", dir));
  s.run(steps);
  return s.plants().at(which);
}

// A climbing ivy (seed 003) on the default scene's wall.
const PlantModel& climbingIvy() { return test::exampleClimbingIvy(); }

// The L-system ivy of examples/scenes/ivy-lsystem.json.
const PlantModel& lsystemPlant() {
  static const PlantModel p = [] {
    std::unique_ptr<session::Session> s = session::Session::open(test::sourceDir() / "examples/scenes/ivy-lsystem.json");
    s->run(200);
    return s->plants().at(1);
  }();
  return p;
}

// The sunflower component graph (seed 004): primitives on a stem.
const PlantModel& graphPlant() {
  static const PlantModel p = grown(R"({"tendril": 1, "steps": 0, "plants": [
      {"name": "sunflower", "model": "graph", "graph": "../graphs/sunflower.json", "position": [0, 0, 0]}]})",
                                    0);
  return p;
}

struct Named {
  const char* name;
  const PlantModel& (*plant)();
};
const Named kPlants[] = {{"climbing ivy", climbingIvy}, {"L-system ivy", lsystemPlant}, {"graph sunflower", graphPlant}};

io::ExportOptions lodOptions(int levels = 4, float ratio = 0.5f) {
  io::ExportOptions o;
  o.lods.levels = levels;
  o.lods.ratio = ratio;
  return o;
}

io::ExportScene sceneOf(const PlantModel& p) {
  io::ExportScene s;
  s.plants.push_back(p);
  return s;
}

// Every part's triangles of a plant mesh, as one mesh (positions only).
TriangleMesh whole(const mesh::PlantMesh& m) {
  TriangleMesh out;
  auto add = [&](const TriangleMesh& part) {
    const uint32_t base = uint32_t(out.positions.size());
    out.positions.insert(out.positions.end(), part.positions.begin(), part.positions.end());
    for (uint32_t i : part.indices) out.indices.push_back(base + i);
  };
  add(m.bark);
  for (const TriangleMesh& l : m.leaves) add(l);
  for (const mesh::PrimitiveGroup& g : m.primitives) add(g.mesh);
  return out;
}

Bounds3 boundsOf(const TriangleMesh& m) {
  Bounds3 b;
  for (uint32_t i : m.indices) b.extend(m.positions[i]);
  return b;
}

// Silhouettes (support/silhouette.h) of whole meshes, untextured.
using test::ViewFrame;
ViewFrame viewFrame(const TriangleMesh& m, const Vec3& view) { return test::viewFrame({{&m}}, view, 0.55f); }
size_t silhouette(const TriangleMesh& m, const ViewFrame& f) { return test::silhouette({{&m}}, f); }

// A plant mesh's leaves alone, as one mesh.
TriangleMesh leavesOf(const mesh::PlantMesh& m) {
  TriangleMesh out;
  for (const TriangleMesh& part : m.leaves) {
    const uint32_t base = uint32_t(out.positions.size());
    out.positions.insert(out.positions.end(), part.positions.begin(), part.positions.end());
    for (uint32_t i : part.indices) out.indices.push_back(base + i);
  }
  return out;
}

// --- budgets ---

TEST(LodChain, TrianglesFallAndStayWithinBudget) {
  for (const Named& n : kPlants) {
    SCOPED_TRACE(n.name);
    const PlantModel& p = n.plant();
    const io::ExportOptions options = lodOptions();
    io::ExportModel model = io::buildExportModel(sceneOf(p), options);
    ASSERT_EQ(model.plantLods.size(), 1u);
    const std::vector<mesh::LodLevel>& lods = model.plantLods[0];
    ASSERT_EQ(lods.size(), 3u);
    const size_t n0 = model.plantMeshes[0].triangleCount();
    EXPECT_EQ(n0, mesh::buildPlantMesh(p, options.mesh).triangleCount());  // LOD0 as without levels
    size_t previous = n0;
    for (size_t k = 0; k < lods.size(); ++k) {
      const mesh::LodLevel& l = lods[k];
      SCOPED_TRACE(fmt::format("LOD{}: {} triangles (bark {}), budget {}; {} of {} leaves, scale {}; {} of {} "
                               "primitives, scale {}; {} radial, {} subdivisions, twigs < {} m ({} nodes) pruned, "
                               "simplified {}, sloppy {}",
                               k + 1, l.triangles, l.mesh.bark.triangleCount(), l.budget, l.leaves, p.leafCount(),
                               l.leafScale, l.primitives, p.primitives.size(), l.primitiveScale,
                               l.options.radialSegments, l.options.subdivisions, l.twigLength, l.prunedNodes,
                               l.simplified, l.sloppy));
      EXPECT_EQ(lods[k].triangles, lods[k].mesh.triangleCount());
      EXPECT_EQ(lods[k].budget, std::min<uint64_t>(mesh::lodBudget(options.lods, n0, int(k + 1)), previous));
      EXPECT_LE(lods[k].triangles, lods[k].budget);
      EXPECT_LE(lods[k].triangles, previous);
      EXPECT_FALSE(lods[k].overBudget());
      // The budget is used, not thrown away: at least a third of it.
      EXPECT_GE(3 * lods[k].triangles, lods[k].budget);
      previous = lods[k].triangles;
    }
    EXPECT_LE(lods.back().triangles, n0 / 8);
    // Every step of the chain took part somewhere: tessellation and leaves fell, twigs went.
    EXPECT_LT(lods.back().options.radialSegments, options.mesh.radialSegments);
    if (p.leafCount() > 0) {
      EXPECT_LT(lods.back().leaves, p.leafCount());
      EXPECT_GT(lods.back().leafScale, 1.0f);
    }
    if (&p == &climbingIvy()) {
      EXPECT_GT(lods.back().prunedNodes, 0u);  // its short side shoots
    }
    if (!p.primitives.empty()) {
      EXPECT_LT(lods.back().primitives, p.primitives.size());
      EXPECT_GT(lods.back().primitiveScale, 1.0f);
    }
  }
}

TEST(LodChain, ExplicitBudgetsAreMet) {
  const PlantModel& p = climbingIvy();
  io::ExportOptions options;
  const size_t n0 = mesh::buildPlantMesh(p, options.mesh).triangleCount();
  options.lods.levels = 3;
  options.lods.triangles = {n0 / 3, n0 / 20};
  io::ExportModel model = io::buildExportModel(sceneOf(p), options);
  const std::vector<mesh::LodLevel>& lods = model.plantLods[0];
  ASSERT_EQ(lods.size(), 2u);
  EXPECT_EQ(lods[0].budget, n0 / 3);
  EXPECT_LE(lods[0].triangles, n0 / 3);
  EXPECT_GT(lods[0].triangles, n0 / 6);
  EXPECT_LE(lods[1].triangles, n0 / 20);
}

// A budget below what one leaf per shape and the roughest bark need cannot be met: the level
// is written with the fewest triangles reached, and a warning says so for every such level.
TEST(LodChain, UnreachableBudgetsAreWarnedAbout) {
  const PlantModel& p = climbingIvy();
  io::ExportOptions options;
  options.lods.levels = 3;
  options.lods.triangles = {200, 1};
  std::vector<std::string> messages;
  io::ExportModel model;
  {
    log::ThreadCapture capture(&messages);
    model = io::buildExportModel(sceneOf(p), options);
  }
  const std::vector<mesh::LodLevel>& lods = model.plantLods[0];
  size_t over = 0;
  for (const mesh::LodLevel& l : lods) over += l.overBudget() ? 1 : 0;
  EXPECT_EQ(lods[1].triangles > 1, lods[1].overBudget());
  EXPECT_GE(over, 1u);
  ASSERT_EQ(messages.size(), over);
  for (const std::string& m : messages) EXPECT_NE(m.find("over its budget"), std::string::npos) << m;
  EXPECT_NE(messages.back().find("LOD2"), std::string::npos) << messages.back();
  // Still falling, and still far below LOD0.
  EXPECT_LE(lods[1].triangles, lods[0].triangles);
  EXPECT_LT(lods[0].triangles, model.plantMeshes[0].triangleCount() / 10);
}

// --- shape ---

TEST(LodChain, TheDefaultRatioPutsTheDefaultIvysLod3UnderATenth) {
  // The default scene's ivy with four levels and the default lod_ratio (the scene's, the CLI's
  // and the library's default agree).
  io::ExportOptions o;
  o.lods.levels = 4;
  EXPECT_EQ(o.lods.ratio, scene::OutputSettings{}.lodRatio);
  io::ExportModel model = io::buildExportModel(sceneOf(climbingIvy()), o);
  const size_t lod0 = model.plantMeshes[0].triangleCount();
  ASSERT_EQ(model.plantLods[0].size(), 3u);
  EXPECT_LE(model.plantLods[0][2].triangles * 10, lod0) << model.plantLods[0][2].triangles << " of " << lod0;
}

TEST(LodChain, BoundsAndSilhouetteStayCloseToLod0) {
  for (const Named& n : kPlants) {
    SCOPED_TRACE(n.name);
    io::ExportModel model = io::buildExportModel(sceneOf(n.plant()), lodOptions());
    const TriangleMesh lod0 = whole(model.plantMeshes[0]), leaves0 = leavesOf(model.plantMeshes[0]);
    const Bounds3 b0 = boundsOf(lod0);
    const float diagonal = b0.size().norm();
    const std::vector<Vec3> views = test::eightViews();
    // 10 % (issue 26), for every plant: the sunflower's few large leaves and its head stay whole
    // (simplified, they lost 11-14 % of the side views) and coarser bark rings are widened.
    const double silhouetteTolerance = 0.10;
    std::vector<ViewFrame> frames;
    std::vector<size_t> area0, leafArea0;
    double worst = 0.0;  // signed
    std::string worstAt;
    for (const Vec3& view : views) {
      frames.push_back(viewFrame(lod0, view));
      area0.push_back(silhouette(lod0, frames.back()));
      leafArea0.push_back(leaves0.indices.empty() ? 0 : silhouette(leaves0, frames.back()));
    }
    for (size_t k = 0; k < model.plantLods[0].size(); ++k) {
      SCOPED_TRACE(fmt::format("LOD{}", k + 1));
      const TriangleMesh lod = whole(model.plantLods[0][k].mesh), leaves = leavesOf(model.plantLods[0][k].mesh);
      const Bounds3 b = boundsOf(lod);
      // Box corners within 5 % of LOD0's diagonal.
      EXPECT_LE((b.min - b0.min).cwiseAbs().maxCoeff(), 0.05f * diagonal);
      EXPECT_LE((b.max - b0.max).cwiseAbs().maxCoeff(), 0.05f * diagonal);
      for (size_t v = 0; v < views.size(); ++v) {
        // Silhouette area from each of the eight views within 10 % of LOD0's, and the leaves'
        // projected area (their coverage) within 15 %.
        const size_t area = silhouette(lod, frames[v]);
        SCOPED_TRACE(fmt::format("view {}: {} cells, LOD0 {}", v, area, area0[v]));
        EXPECT_GT(area0[v], 1000u);
        EXPECT_LE(std::abs(double(area) - double(area0[v])), silhouetteTolerance * double(area0[v]));
        const double difference = (double(area) - double(area0[v])) / double(area0[v]);
        if (std::abs(difference) > std::abs(worst)) {
          worst = difference;
          worstAt = fmt::format("LOD{}, view {}", k + 1, v);
        }
        if (leafArea0[v] > 0) {
          const size_t leafArea = silhouette(leaves, frames[v]);
          SCOPED_TRACE(fmt::format("leaves: {} cells, LOD0 {}", leafArea, leafArea0[v]));
          EXPECT_LE(std::abs(double(leafArea) - double(leafArea0[v])), 0.15 * double(leafArea0[v]));
        }
      }
    }
    fmt::print("[ lod ] {}: worst silhouette difference {:+.1f} % ({})\n", n.name, 100.0 * worst, worstAt);
  }
}

TEST(LodSteps, PrunedTwigsLeaveTheirLeavesAndPrimitivesWhereTheyWere) {
  PlantModel tree = meshtest::branchingTree();
  meshtest::addLeaves(tree, 2);
  TriangleMesh bud;
  bud.positions = {Vec3(0, 0, 0), Vec3(0.02f, 0, 0), Vec3(0, 0.02f, 0)};
  bud.indices = {0, 1, 2};
  tree.meshes.push_back({"bud", bud, Vec3(0.9f, 0.2f, 0.3f), ""});
  for (int32_t node = 0; node < int32_t(tree.nodeCount()); ++node) {
    plant::Primitive pr;
    pr.node = node;
    pr.nodeFromPrimitive(0, 3) = 0.01f;
    tree.primitives.push_back(pr);
  }
  const std::vector<mesh::PrimitiveGroup> before = mesh::buildPrimitiveMeshes(tree);
  double total = 0.0;
  for (float l : tree.length) total += l;
  std::vector<uint32_t> kept;
  const PlantModel pruned = mesh::pruneTwigs(tree, float(total), &kept);  // every side branch goes
  plant::validate(pruned, "pruned");
  ASSERT_LT(pruned.nodeCount(), tree.nodeCount());
  ASSERT_EQ(kept.size(), pruned.nodeCount());
  for (size_t i = 0; i < kept.size(); ++i) EXPECT_EQ(pruned.position[i], tree.position[kept[i]]);
  for (size_t i = 0; i < pruned.nodeCount(); ++i) EXPECT_EQ(pruned.flags[i] & plant::kNodeBranchStart, 0u);
  ASSERT_EQ(pruned.leafCount(), tree.leafCount());
  for (size_t l = 0; l < tree.leafCount(); ++l) {
    EXPECT_LT((pruned.leafWorldPosition(l) - tree.leafWorldPosition(l)).norm(), 1e-5f);
    EXPECT_LT(pruned.leafWorldRotation(l).angularDistance(tree.leafWorldRotation(l)), 1e-4f);
  }
  const std::vector<mesh::PrimitiveGroup> after = mesh::buildPrimitiveMeshes(pruned);
  ASSERT_EQ(after.size(), before.size());
  ASSERT_EQ(after[0].mesh.positions.size(), before[0].mesh.positions.size());
  for (size_t i = 0; i < before[0].mesh.positions.size(); ++i)
    EXPECT_LT((after[0].mesh.positions[i] - before[0].mesh.positions[i]).norm(), 1e-5f);
  // Nothing below the length goes: the tree stays whole.
  EXPECT_EQ(mesh::pruneTwigs(tree, 0.0f).nodeCount(), tree.nodeCount());
}

TEST(LodSteps, ThinnedLeavesKeepEachShapesAreaAndNest) {
  PlantModel ivy = meshtest::syntheticIvy(3000);
  meshtest::addLeaves(ivy, 3);
  ASSERT_GT(ivy.leafCount(), 300u);
  auto areas = [](const PlantModel& p) {
    std::map<uint16_t, double> a;
    for (size_t l = 0; l < p.leafCount(); ++l) a[p.leafShape[l]] += double(p.leafSize[l]) * p.leafSize[l];
    return a;
  };
  auto centres = [](const PlantModel& p) {
    std::vector<Vec3> c;
    for (size_t l = 0; l < p.leafCount(); ++l)
      c.push_back(p.leafWorldPosition(l) + (p.leafPetiole[l] + 0.5f * p.leafSize[l]) * (p.leafWorldRotation(l) * Vec3::UnitY()));
    return c;
  };
  const std::vector<Vec3> all = centres(ivy);
  PlantModel half = ivy, quarter = ivy;
  const float s2 = mesh::thinLeaves(half, ivy.leafCount() / 2);
  const float s4 = mesh::thinLeaves(quarter, ivy.leafCount() / 4);
  EXPECT_NEAR(double(half.leafCount()), ivy.leafCount() / 2.0, 3.0);
  EXPECT_NEAR(double(quarter.leafCount()), ivy.leafCount() / 4.0, 3.0);
  EXPECT_GT(s4, s2);
  EXPECT_GT(s2, 1.2f);
  for (const PlantModel* p : {&half, &quarter}) {
    plant::validate(*p, "thinned");
    for (const auto& [shape, area] : areas(ivy)) EXPECT_NEAR(areas(*p).at(shape), area, 1e-4 * area);
  }
  // Centres stay; the quarter is a subset of the half.
  const std::vector<Vec3> h = centres(half), q = centres(quarter);
  auto contains = [](const std::vector<Vec3>& set, const Vec3& c) {
    return std::any_of(set.begin(), set.end(), [&](const Vec3& x) { return (x - c).norm() < 1e-5f; });
  };
  for (const Vec3& c : h) EXPECT_TRUE(contains(all, c));
  for (const Vec3& c : q) EXPECT_TRUE(contains(h, c));
}

// --- vertex order ---

meshopt_VertexCacheStatistics cacheStats(const TriangleMesh& m) {
  return meshopt_analyzeVertexCache(m.indices.data(), m.indices.size(), m.vertexCount(), 16, 0, 0);
}

// The same triangles, as sorted position triples.
std::vector<std::array<float, 9>> triangleSet(const TriangleMesh& m) {
  std::vector<std::array<float, 9>> t;
  for (size_t i = 0; i + 2 < m.indices.size(); i += 3) {
    std::array<std::array<float, 3>, 3> c;
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = m.positions[m.indices[i + k]];
      c[size_t(k)] = {p.x(), p.y(), p.z()};
    }
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());  // keep the winding
    t.push_back({c[0][0], c[0][1], c[0][2], c[1][0], c[1][1], c[1][2], c[2][0], c[2][1], c[2][2]});
  }
  std::sort(t.begin(), t.end());
  return t;
}

TEST(LodChain, VertexCacheOrderLowersAcmrAndKeepsTheSurface) {
  for (const Named& n : kPlants) {
    SCOPED_TRACE(n.name);
    const PlantModel& p = n.plant();
    const mesh::PlantMesh plain = mesh::buildPlantMesh(p, {});
    io::ExportModel model = io::buildExportModel(sceneOf(p), lodOptions());
    const mesh::PlantMesh& ordered = model.plantMeshes[0];
    // The bark: tubes whose vertices the triangles share (leaf quads and small primitives are
    // already about as good as they get).
    const TriangleMesh& before = plain.bark;
    const TriangleMesh& after = ordered.bark;
    ASSERT_GT(before.triangleCount(), 1000u);
    const meshopt_VertexCacheStatistics a = cacheStats(before), b = cacheStats(after);
    SCOPED_TRACE(fmt::format("ACMR {} -> {}", a.acmr, b.acmr));
    EXPECT_LT(b.acmr, 0.9f * a.acmr);
    EXPECT_EQ(triangleSet(before), triangleSet(after));
    EXPECT_EQ(after.vertexCount(), before.vertexCount());  // every vertex is used, none lost
    // Vertices in the order the triangles first use them (meshopt_optimizeVertexFetch).
    uint32_t next = 0;
    bool inOrder = true;
    for (uint32_t i : after.indices) {
      if (i > next) inOrder = false;
      if (i == next) ++next;
    }
    EXPECT_TRUE(inOrder);
    // And every lower level too.
    for (const mesh::LodLevel& l : model.plantLods[0]) {
      std::vector<uint32_t> fresh(l.mesh.bark.indices.size());
      if (l.mesh.bark.triangleCount() < 100) continue;
      meshopt_optimizeVertexCache(fresh.data(), l.mesh.bark.indices.data(), fresh.size(), l.mesh.bark.vertexCount());
      EXPECT_LE(cacheStats(l.mesh.bark).acmr,
                1.001f * meshopt_analyzeVertexCache(fresh.data(), fresh.size(), l.mesh.bark.vertexCount(), 16, 0, 0).acmr);
    }
  }
  // Without a chain LOD0 is written as it always was.
  io::ExportModel single = io::buildExportModel(sceneOf(climbingIvy()), {});
  EXPECT_EQ(single.plantMeshes[0].bark.indices, mesh::buildPlantMesh(climbingIvy(), {}).bark.indices);
  EXPECT_TRUE(single.plantLods[0].empty());
}

// A mesh of more than 2 × 2^16 triangles is ordered in runs that share no vertices, in
// parallel: the same result at every thread count, as good for the cache as ordering it whole,
// the same triangles, every vertex kept and numbered in the order the triangles first use it.
TEST(LodChain, LargeMeshesAreOrderedInRunsTheSameAtEveryThreadCount) {
  const TriangleMesh bark = mesh::buildPlantMesh(meshtest::syntheticIvy(6000), {}).bark;
  ASSERT_GT(bark.triangleCount(), 4u << 16);  // at least four runs
  auto order = [&] {
    TriangleMesh m = bark;
    mesh::optimizeMeshOrder(m);
    return m;
  };
  test::sameAtEveryThreadCount([&] {
    const TriangleMesh m = order();
    std::vector<uint32_t> words(m.indices);
    for (const Vec3& p : m.positions)
      for (int k = 0; k < 3; ++k) words.push_back(std::bit_cast<uint32_t>(p[k]));
    for (const Vec3& n : m.normals)
      for (int k = 0; k < 3; ++k) words.push_back(std::bit_cast<uint32_t>(n[k]));
    words.insert(words.end(), m.nodeIds.begin(), m.nodeIds.end());
    return words;
  });
  const TriangleMesh ordered = order();
  std::vector<uint32_t> whole(bark.indices.size());
  meshopt_optimizeVertexCache(whole.data(), bark.indices.data(), whole.size(), bark.vertexCount());
  const float acmrWhole = meshopt_analyzeVertexCache(whole.data(), whole.size(), bark.vertexCount(), 16, 0, 0).acmr;
  SCOPED_TRACE(fmt::format("ACMR {} -> {} (ordered whole: {})", cacheStats(bark).acmr, cacheStats(ordered).acmr,
                           acmrWhole));
  EXPECT_LE(cacheStats(ordered).acmr, 1.01f * acmrWhole);
  EXPECT_EQ(triangleSet(bark), triangleSet(ordered));
  EXPECT_EQ(ordered.vertexCount(), bark.vertexCount());
  uint32_t next = 0;
  bool inOrder = true;
  for (uint32_t i : ordered.indices) {
    if (i > next) inOrder = false;
    if (i == next) ++next;
  }
  EXPECT_TRUE(inOrder);
  EXPECT_EQ(next, ordered.vertexCount());
}

// --- files ---

std::vector<uint8_t> bytesOf(const fs::path& p) { return io::readFileBytes(p); }

io::ExportScene threePlants() {
  io::ExportScene s;
  s.plants = {climbingIvy(), lsystemPlant(), graphPlant()};
  s.plants[1].name = "lsystem";
  return s;
}

size_t primitiveTriangles(const tinygltf::Model& m, int node) {
  size_t n = 0;
  for (const tinygltf::Primitive& p : m.meshes.at(size_t(m.nodes.at(size_t(node)).mesh)).primitives)
    n += m.accessors.at(size_t(p.indices)).count / 3;
  return n;
}

TEST(LodChain, GlbHasMsftLodAndLevelNodes) {
  const fs::path dir = test::scratchDir();
  const io::ExportScene scene = threePlants();
  const io::ExportOptions options = lodOptions();
  io::writeGlb(scene, dir / "streamed.glb", options);
  io::ExportModel model = io::buildExportModel(scene, options);
  io::writeGlb(model, dir / "whole.glb");
  const meshtest::GltfValidation v = meshtest::validateGltf(dir / "streamed.glb");
  EXPECT_EQ(v.errors, 0) << v.output;
  EXPECT_EQ(v.warnings, 0) << v.output;
  // The streamed file has the whole model's binary chunk (their JSON differs in padding only).
  const std::vector<uint8_t> streamed = bytesOf(dir / "streamed.glb"), wholeBytes = bytesOf(dir / "whole.glb");
  uint32_t sj = 0, wj = 0;
  std::memcpy(&sj, streamed.data() + 12, 4);
  std::memcpy(&wj, wholeBytes.data() + 12, 4);
  EXPECT_TRUE(std::equal(streamed.begin() + 20 + sj, streamed.end(), wholeBytes.begin() + 20 + wj, wholeBytes.end()));
  EXPECT_GT(sj, wj + 3);  // streamed into its reserved room, not written again the simple way

  for (const char* file : {"streamed.glb", "whole.glb"}) {
    SCOPED_TRACE(file);
    tinygltf::TinyGLTF loader;
    tinygltf::Model m;
    std::string err, warn;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, (dir / file).string())) << err;
    EXPECT_NE(std::find(m.extensionsUsed.begin(), m.extensionsUsed.end(), "MSFT_lod"), m.extensionsUsed.end());
    ASSERT_EQ(m.scenes.size(), 1u);
    ASSERT_EQ(m.scenes[0].nodes.size(), scene.plants.size());  // LOD0s only
    ASSERT_EQ(m.nodes.size(), 4 * scene.plants.size());
    for (size_t i = 0; i < scene.plants.size(); ++i) {
      const std::string name = scene.plants[i].name;
      SCOPED_TRACE(name);
      const int root = m.scenes[0].nodes[i];
      const tinygltf::Node& lod0 = m.nodes.at(size_t(root));
      EXPECT_EQ(lod0.name, name + "_LOD0");
      ASSERT_TRUE(lod0.extensions.count("MSFT_lod"));
      const tinygltf::Value& ids = lod0.extensions.at("MSFT_lod").Get("ids");
      ASSERT_TRUE(ids.IsArray());
      ASSERT_EQ(ids.ArrayLen(), 3u);
      const tinygltf::Value& coverage = lod0.extras.Get("MSFT_screencoverage");
      ASSERT_TRUE(coverage.IsArray());
      ASSERT_EQ(coverage.ArrayLen(), 4u);
      size_t previous = primitiveTriangles(m, root);
      EXPECT_EQ(previous, model.plantMeshes[i].triangleCount());
      for (size_t k = 0; k < 3; ++k) {
        const int id = ids.Get(int(k)).GetNumberAsInt();
        const tinygltf::Node& node = m.nodes.at(size_t(id));
        EXPECT_EQ(node.name, fmt::format("{}_LOD{}", name, k + 1));
        EXPECT_EQ(m.meshes.at(size_t(node.mesh)).name, node.name);
        const size_t triangles = primitiveTriangles(m, id);
        EXPECT_EQ(triangles, model.plantLods[i][k].triangles);
        EXPECT_LE(triangles, previous);
        previous = triangles;
        EXPECT_GE(coverage.Get(int(k)).GetNumberAsDouble(), coverage.Get(int(k + 1)).GetNumberAsDouble());
      }
      EXPECT_GT(coverage.Get(0).GetNumberAsDouble(), 0.0);
      EXPECT_LE(coverage.Get(0).GetNumberAsDouble(), 1.0);
    }
  }

  // Without levels of detail: plain names, no extension.
  io::writeGlb(scene, dir / "plain.glb", io::ExportOptions{});
  tinygltf::TinyGLTF loader;
  tinygltf::Model plain;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&plain, &err, &warn, (dir / "plain.glb").string())) << err;
  EXPECT_TRUE(plain.extensionsUsed.empty());
  ASSERT_EQ(plain.nodes.size(), scene.plants.size());
  EXPECT_EQ(plain.nodes[0].name, scene.plants[0].name);
}

TEST(LodChain, ObjWritesOneFilePerLevel) {
  const fs::path dir = test::scratchDir();
  const io::ExportScene scene = threePlants();
  io::ExportModel model = io::buildExportModel(scene, lodOptions());
  io::writeObj(model, dir / "plant.obj");
  for (size_t level = 0; level < 4; ++level) {
    SCOPED_TRACE(level);
    const fs::path file = level == 0 ? dir / "plant.obj" : io::objLodPath(dir / "plant.obj", level);
    EXPECT_EQ(file.filename().string(), level == 0 ? "plant.obj" : fmt::format("plant_LOD{}.obj", level));
    std::istringstream in(test::readText(file));
    std::string line;
    std::vector<std::string> objects;
    size_t faces = 0;
    bool mtl = false;
    while (std::getline(in, line)) {
      if (line.rfind("o ", 0) == 0) objects.push_back(line.substr(2));
      if (line.rfind("f ", 0) == 0) ++faces;
      if (line == "mtllib plant.mtl") mtl = true;
    }
    EXPECT_TRUE(mtl);
    ASSERT_EQ(objects.size(), scene.plants.size());
    size_t expected = 0;
    for (size_t i = 0; i < scene.plants.size(); ++i) {
      EXPECT_EQ(objects[i], fmt::format("{}_LOD{}", scene.plants[i].name, level));
      expected += level == 0 ? model.plantMeshes[i].triangleCount() : model.plantLods[i][level - 1].triangles;
    }
    EXPECT_EQ(faces, expected);
  }
  EXPECT_FALSE(fs::exists(dir / "plant_LOD4.obj"));
}

TEST(LodChain, BytesDoNotDependOnThreadCount) {
  const fs::path dir = test::scratchDir();
  const io::ExportScene scene = threePlants();
  test::sameAtEveryThreadCount([&] {
    io::writeGlb(scene, dir / "streamed.glb", lodOptions());
    io::ExportModel model = io::buildExportModel(scene, lodOptions(3, 0.3f));
    io::writeObj(model, dir / "plant.obj");
    std::vector<uint8_t> bytes = bytesOf(dir / "streamed.glb");
    for (const char* f : {"plant.obj", "plant_LOD1.obj", "plant_LOD2.obj"}) {
      const std::vector<uint8_t> b = bytesOf(dir / f);
      bytes.insert(bytes.end(), b.begin(), b.end());
    }
    return bytes;
  });
}

// --- settings ---

// The error a scene with this "output" object gives, as the CLI prints it.
std::string outputError(const std::string& output, const fs::path& dir) {
  const fs::path file = dir / "scene.json";
  test::writeText(file, R"({"tendril": 1, "plants": [], "output": )" + output + "}");
  try {
    scene::loadScene(file);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(LodSettings, BadValuesGiveOneLineNamingFileAndKey) {
  const fs::path dir = test::scratchDir();
  const std::string file = (dir / "scene.json").string();
  const std::pair<const char*, const char*> cases[] = {
      {R"({"lods": 0})", "/output/lods"},
      {R"({"lods": 9})", "/output/lods"},
      {R"({"lods": 2.5})", "/output/lods"},
      {R"({"lods": 3, "lod_ratio": 0})", "/output/lod_ratio"},
      {R"({"lods": 3, "lod_ratio": 1.5})", "/output/lod_ratio"},
      {R"({"lod_triangles": [1000, 2000]})", "/output/lod_triangles/1"},
      {R"({"lod_triangles": [1000, 0]})", "/output/lod_triangles/1"},
      {R"({"lod_triangles": [1000, 10.5]})", "/output/lod_triangles/1"},
      {R"({"lods": 4, "lod_triangles": [1000, 100]})", "/output/lod_triangles"},
      {R"({"lod_triangles": [1000], "lod_ratio": 0.5})", "/output/lod_triangles"},
      {R"({"lod_triangles": []})", "/output/lod_triangles"},
      {R"({"lod_triangles": 1000})", "/output/lod_triangles"},
      {R"({"lod_triangles": [9, 8, 7, 6, 5, 4, 3, 2]})", "/output/lod_triangles"},
      {R"({"lod_count": 3})", "/output/lod_count"},
  };
  for (const auto& [output, key] : cases) {
    SCOPED_TRACE(output);
    const std::string e = outputError(output, dir);
    EXPECT_EQ(e.rfind(file + ":" + key + ":", 0), 0u) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  }
  // Good ones read.
  const fs::path good = dir / "good.json";
  test::writeText(good, R"({"tendril": 1, "plants": [], "output": {"lod_triangles": [5000, 1000, 200]}})");
  const scene::Scene s = scene::loadScene(good);
  EXPECT_EQ(s.output.lods, 4);
  EXPECT_EQ(s.output.lodTriangles, (std::vector<uint64_t>{5000, 1000, 200}));
  const io::ExportOptions o = session::exportOptions(s.output);
  EXPECT_EQ(o.lods.levels, 4);
  EXPECT_EQ(o.lods.triangles, s.output.lodTriangles);
  // Options made in code are checked where they enter the exporters.
  io::ExportOptions bad;
  bad.lods.levels = 3;
  bad.lods.triangles = {10};
  try {
    io::writeGlb(threePlants(), dir / "x.glb", bad);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("export options:lod_triangles:", 0), 0u) << e.what();
  }
}

TEST(LodSettings, CommandLine) {
  const fs::path dir = test::scratchDir();
  const std::string scene = test::quoted(test::sourceDir() / "examples/scenes/default.json");
  // Bad options: one line naming the option.
  test::CommandResult r = test::runTendril("grow " + scene + " -o " + test::quoted(dir / "a") + " --lods 9", dir);
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.err.find("--lods"), std::string::npos) << r.err;
  r = test::runTendril("grow " + scene + " -o " + test::quoted(dir / "a") + " --steps 5 --lod-ratio 0.3", dir);
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("command line:--lod-ratio:"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  // A scene's bad key: the file and the key.
  const fs::path bad = dir / "bad.json";
  test::writeText(bad, R"({"tendril": 1, "plants": [], "output": {"lods": 3, "lod_ratio": 2}})");
  r = test::runTendril("grow " + test::quoted(bad) + " -o " + test::quoted(dir / "b"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.err.find(bad.string() + ":/output/lod_ratio:"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;

  // grow, lsys and model write the levels.
  r = test::runTendril("grow " + scene + " -o " + test::quoted(dir / "grow") + " --steps 60 --lods 3 --lod-ratio 0.4 -q",
                       dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "grow/plant_LOD2.obj"));
  EXPECT_FALSE(fs::exists(dir / "grow/plant_LOD3.obj"));
  r = test::runTendril("lsys abop-1.24a -o " + test::quoted(dir / "bush.glb") + " --lods 3 -q", dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  r = test::runTendril("model " + test::quoted(test::sourceDir() / "examples/graphs/sunflower.json") + " -o " +
                           test::quoted(dir / "sunflower.glb") + " --lods 2 --lod-ratio 0.25 -q",
                       dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  for (const auto& [file, levels] : {std::pair<const char*, size_t>{"grow/plant.glb", 3}, {"bush.glb", 3}, {"sunflower.glb", 2}}) {
    SCOPED_TRACE(file);
    tinygltf::TinyGLTF loader;
    tinygltf::Model m;
    std::string err, warn;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, (dir / file).string())) << err;
    const tinygltf::Node& lod0 = m.nodes.at(size_t(m.scenes.at(0).nodes.at(0)));
    ASSERT_TRUE(lod0.extensions.count("MSFT_lod"));
    EXPECT_EQ(lod0.extensions.at("MSFT_lod").Get("ids").ArrayLen(), levels - 1);
    EXPECT_EQ(lod0.name.substr(lod0.name.size() - 5), "_LOD0");
  }
}

}  // namespace
}  // namespace tendril

