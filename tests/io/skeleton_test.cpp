// Skeletons and labels (issue 26 part 5): the plant graph as <stem>.skeleton.json
// (io/skeleton_writer.h, docs/skeleton-format.md) and every plant vertex's node id, written to
// the .glb as _NODE_ID. Checked against the PlantModels a Session grows: a climbing ivy, an
// L-system plant and two component-graph plants (one of primitives on skeleton nodes, one of
// primitives alone).
#include "tendril/io/skeleton_writer.h"

#include "support/determinism.h"
#include "support/gltf_validator.h"
#include "support/synthetic_plants.h"
#include "support/test_paths.h"
#include "tendril/core/error.h"
#include "tendril/io/atomic_file.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/mesh/leaf_mesh.h"
#include "tendril/mesh/plant_mesh.h"
#include "tendril/mesh/primitive_mesh.h"
#include "tendril/scene/scene.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <memory>
#include <set>

namespace tendril::io {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using plant::PlantModel;

// A climbing ivy at the foot of a wall, an L-system ivy, a sunflower (primitives on a skeleton)
// and an agave (primitives alone, no skeleton nodes).
std::string threeModelScene() {
  const std::string examples = (test::sourceDir() / "examples").string();
  return R"({"tendril": 1, "seed": 5, "steps": 70,
    "environment": {"obstacles": [
      {"name": "ground", "type": "plane", "size": [8, 8]},
      {"name": "wall", "type": "wall", "size": [3, 2, 0.25]}],
      "lights": [{"type": "directional", "direction": [-0.1, -1, -0.5]}]},
    "plants": [
      {"name": "ivy", "species": "japanese-ivy", "position": [-0.6, 0, 0.15], "seed": 1},
      {"name": "lsystem-ivy", "model": "lsystem", "grammar": ")" + examples + R"(/grammars/japanese-ivy.ls",
       "position": [0.6, 0, 0.15], "seed": 2},
      {"name": "sunflower", "model": "graph", "graph": ")" + examples + R"(/graphs/sunflower.json",
       "position": [-1.5, 0, 1.5]},
      {"name": "agave", "model": "graph", "graph": ")" + examples + R"(/graphs/agave.json",
       "position": [1.5, 0, 1.5]}]})";
}

// The grown scene, once for the whole suite (growing is the slow part).
class Skeleton : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const fs::path dir = fs::path(TENDRIL_TEST_TMP) / "Skeleton.scene";
    fs::create_directories(dir);
    test::writeText(dir / "scene.json", threeModelScene());
    session_ = session::Session::open(dir / "scene.json");
    session_->run(uint32_t(session_->scene().steps));
  }
  static void TearDownTestSuite() { session_.reset(); }
  static const session::Session& session() { return *session_; }

 private:
  static std::unique_ptr<session::Session> session_;
};
std::unique_ptr<session::Session> Skeleton::session_;

json readJson(const fs::path& path) { return json::parse(test::readText(path)); }

// Reads a float the file wrote and checks it is bit for bit the model's.
::testing::AssertionResult sameFloat(const json& value, float expected) {
  if (!value.is_number()) return ::testing::AssertionFailure() << value.dump() << " is not a number";
  const float got = value.get<float>();
  if (std::memcmp(&got, &expected, sizeof(float)) != 0)
    return ::testing::AssertionFailure() << value.dump() << " reads back as " << got << ", not " << expected;
  return ::testing::AssertionSuccess();
}
::testing::AssertionResult sameVec(const json& value, std::initializer_list<float> expected) {
  if (!value.is_array() || value.size() != expected.size())
    return ::testing::AssertionFailure() << value.dump() << " has not " << expected.size() << " numbers";
  size_t k = 0;
  for (float e : expected)
    if (auto r = sameFloat(value[k++], e); !r) return r;
  return ::testing::AssertionSuccess();
}

TEST_F(Skeleton, JsonHoldsThePlantGraphOfEveryModel) {
  const fs::path dir = test::scratchDir();
  ExportScene exported;
  const std::vector<std::string> written =
      session::writePlantFiles(session(), dir, "plant", {"skeleton"}, "scene.json", exported);
  ASSERT_EQ(written, std::vector<std::string>{(dir / "plant.skeleton.json").string()});
  EXPECT_FALSE(fs::exists(dir / "plant.glb"));
  EXPECT_FALSE(fs::exists(dir / "plant.obj"));

  const json doc = readJson(dir / "plant.skeleton.json");
  EXPECT_EQ(doc.at("format"), "tendril-skeleton");
  EXPECT_EQ(doc.at("version"), 1);
  EXPECT_EQ(doc.at("units").at("length"), "m");
  const std::vector<PlantModel>& plants = exported.plants;
  ASSERT_EQ(doc.at("plants").size(), plants.size());
  bool climbing = false, primitivesOnNodes = false;
  for (size_t pi = 0; pi < plants.size(); ++pi) {
    const PlantModel& p = plants[pi];
    const json& jp = doc["plants"][pi];
    SCOPED_TRACE(p.name);
    EXPECT_EQ(jp.at("name"), p.name);
    EXPECT_EQ(jp.at("species"), p.species);

    // Nodes: every field, bit for bit.
    const json& nodes = jp.at("nodes");
    ASSERT_EQ(nodes.size(), p.nodeCount());
    std::vector<int> successors(p.nodeCount(), 0);
    for (size_t i = 0; i < p.nodeCount(); ++i) {
      const json& n = nodes[i];
      SCOPED_TRACE(i);
      ASSERT_EQ(n.at("id"), i);
      ASSERT_EQ(n.at("kind"), "internode");
      ASSERT_EQ(n.at("parent"), p.parent[i]);
      ASSERT_TRUE(sameVec(n.at("position"), {p.position[i].x(), p.position[i].y(), p.position[i].z()}));
      const Quat& q = p.orientation[i];
      ASSERT_TRUE(sameVec(n.at("orientation"), {q.x(), q.y(), q.z(), q.w()}));
      ASSERT_TRUE(sameFloat(n.at("length"), p.length[i]));
      ASSERT_TRUE(sameFloat(n.at("radius"), p.radius[i]));
      ASSERT_TRUE(sameFloat(n.at("age"), p.age[i]));
      ASSERT_EQ(n.at("order"), p.order[i]);
      uint32_t bits = n.value("other_flags", 0u);
      if (n.contains("tip_end")) {
        const std::string end = n.at("tip_end");
        const char* names[] = {"unknown", "no_support", "blocked", "crowded", "capped", "shortened", "rule"};
        auto it = std::find(std::begin(names), std::end(names), end);
        ASSERT_NE(it, std::end(names)) << end;
        bits |= uint32_t(it - std::begin(names)) << plant::kNodeTipEndShift;
        ASSERT_TRUE(p.flags[i] & plant::kNodeDead);
      }
      for (const json& name : n.at("flags")) {
        auto it = std::find(std::begin(kNodeFlagNames), std::end(kNodeFlagNames), name.get<std::string>());
        ASSERT_NE(it, std::end(kNodeFlagNames)) << name;
        bits |= 1u << (it - std::begin(kNodeFlagNames));
      }
      ASSERT_EQ(bits, p.flags[i]);
      climbing = climbing || (p.flags[i] & plant::kNodeClimbing);
      // Edges: none at a root; "+" at a branch start; at most one "<" (successor) per node.
      if (p.parent[i] < 0) {
        ASSERT_TRUE(n.at("edge").is_null());
      } else {
        ASSERT_TRUE(n.at("edge") == "<" || n.at("edge") == "+") << n.at("edge");
        if (p.flags[i] & plant::kNodeBranchStart) {
          ASSERT_EQ(n.at("edge"), "+");
        }
        if (n.at("edge") == "<") {
          ASSERT_LE(++successors[size_t(p.parent[i])], 1);
        }
      }
    }

    const json& leaves = jp.at("leaves");
    ASSERT_EQ(leaves.size(), p.leafCount());
    for (size_t l = 0; l < p.leafCount(); ++l) {
      const json& f = leaves[l];
      SCOPED_TRACE(l);
      ASSERT_EQ(f.at("kind"), "leaf");
      ASSERT_EQ(f.at("node"), p.leafNode[l]);
      const Vec3 at = p.leafWorldPosition(l);
      ASSERT_TRUE(sameVec(f.at("position"), {at.x(), at.y(), at.z()}));
      const Quat r = p.leafWorldRotation(l);
      ASSERT_TRUE(sameVec(f.at("rotation"), {r.x(), r.y(), r.z(), r.w()}));
      ASSERT_TRUE(sameFloat(f.at("size"), p.leafSize[l]));
      ASSERT_EQ(f.at("shape"), p.leafShape[l]);
    }

    const json& primitives = jp.at("primitives");
    ASSERT_EQ(primitives.size(), p.primitives.size());
    for (size_t k = 0; k < p.primitives.size(); ++k) {
      const json& r = primitives[k];
      ASSERT_EQ(r.at("kind"), "primitive");
      ASSERT_EQ(r.at("node"), p.primitives[k].node);
      ASSERT_EQ(r.at("mesh"), p.meshes[p.primitives[k].mesh].name);
      ASSERT_EQ(r.at("matrix").size(), 16u);
      primitivesOnNodes = primitivesOnNodes || p.primitives[k].node >= 0;
    }
  }
  // The scene has what the test is meant to see.
  EXPECT_TRUE(climbing);
  EXPECT_TRUE(primitivesOnNodes);
  EXPECT_GT(plants[0].nodeCount(), 50u);
  EXPECT_GT(plants[1].leafCount(), 10u);
  EXPECT_EQ(plants[3].nodeCount(), 0u);
  EXPECT_GT(plants[3].primitives.size(), 0u);
}

// A .glb's JSON and binary chunks.
struct Glb {
  json gltf;
  std::vector<uint8_t> bin;

  explicit Glb(const fs::path& path) {
    const std::vector<uint8_t> b = readFileBytes(path);
    uint32_t jsonBytes = 0;
    std::memcpy(&jsonBytes, b.data() + 12, 4);
    gltf = json::parse(std::string(b.begin() + 20, b.begin() + 20 + jsonBytes));
    if (20 + size_t(jsonBytes) < b.size()) bin.assign(b.begin() + 20 + jsonBytes + 8, b.end());
  }
  // The accessor's floats (tightly packed, as the writer lays them out).
  std::vector<float> floats(int accessor) const {
    const json& a = gltf["accessors"][size_t(accessor)];
    EXPECT_EQ(a.at("componentType"), 5126);  // FLOAT
    const json& view = gltf["bufferViews"][a.at("bufferView").get<size_t>()];
    const size_t components = a.at("type") == "VEC3" ? 3 : a.at("type") == "VEC2" ? 2 : 1;
    std::vector<float> out(a.at("count").get<size_t>() * components);
    std::memcpy(out.data(), bin.data() + view.value("byteOffset", size_t(0)) + a.value("byteOffset", size_t(0)),
                out.size() * sizeof(float));
    return out;
  }
};

float distanceToSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const float t = d.squaredNorm() > 0.0f ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0f, 1.0f) : 0.0f;
  return (p - (a + t * d)).norm();
}

// Checks every _NODE_ID of a .glb written from `plants` (objects in plant order): bark vertices
// lie on their node's segment (within its radius, or its children's where the sweep tapers
// toward them, plus a fifth of its length for the spline's bulge at bends: at most 8 % in the
// grown scene, while a ring labelled with the next or previous node lies a whole segment off
// it), each leaf's vertices carry its node and
// each primitive's vertices its node (node 0 for one on node −1). Plants without nodes have no
// _NODE_ID. Returns the node ids read, per plant.
std::vector<std::vector<float>> checkNodeIds(const fs::path& file, const std::vector<PlantModel>& plants,
                                            const mesh::MeshOptions& options) {
  const Glb glb(file);
  std::vector<std::vector<float>> all(plants.size());
  for (size_t pi = 0; pi < plants.size(); ++pi) {
    const PlantModel& p = plants[pi];
    SCOPED_TRACE(p.name);
    const json& node = glb.gltf["nodes"][pi];
    EXPECT_EQ(node.at("name"), p.name);
    const json& primitives = glb.gltf["meshes"][node.at("mesh").get<size_t>()]["primitives"];
    // Which part each glTF primitive is: the plant mesh's non-empty parts in order (only their
    // sizes are used, not their node ids).
    const mesh::PlantMesh pm = mesh::buildPlantMesh(p, options);
    size_t next = 0;
    auto part = [&](size_t vertices) -> std::vector<float> {
      EXPECT_LT(next, primitives.size());
      if (next >= primitives.size()) return {};
      const json& attributes = primitives[next++].at("attributes");
      EXPECT_EQ(glb.gltf["accessors"][attributes.at("POSITION").get<size_t>()]["count"], vertices);
      if (p.nodeCount() == 0) {
        EXPECT_FALSE(attributes.contains("_NODE_ID")) << "a plant without nodes";
        return {};
      }
      EXPECT_TRUE(attributes.contains("_NODE_ID"));
      if (!attributes.contains("_NODE_ID")) return {};
      std::vector<float> ids = glb.floats(attributes["_NODE_ID"].get<int>());
      EXPECT_EQ(ids.size(), vertices);
      for (float id : ids) {
        EXPECT_EQ(id, std::floor(id));
        EXPECT_GE(id, 0.0f);
        EXPECT_LT(id, float(p.nodeCount()));
        if (!(id >= 0.0f && id < float(p.nodeCount()))) return {};
      }
      all[pi].insert(all[pi].end(), ids.begin(), ids.end());
      return ids;
    };

    std::vector<int32_t> childStart, childIndex;
    p.children(childStart, childIndex);
    if (!pm.bark.empty()) {
      const std::vector<float> ids = part(pm.bark.vertexCount());
      const std::vector<float> positions = glb.floats(
          primitives[next - 1]["attributes"]["POSITION"].get<int>());
      size_t far = 0;
      float worst = 0.0f;
      for (size_t v = 0; v < ids.size(); ++v) {
        const size_t i = size_t(ids[v]);
        float radius = p.radius[i];
        for (int32_t k = childStart[i]; k < childStart[i + 1]; ++k) radius = std::max(radius, p.radius[childIndex[k]]);
        const Vec3 at(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
        const float excess = distanceToSegment(at, p.position[i], p.tip(i)) - radius;
        worst = std::max(worst, excess / std::max(p.length[i], 1e-6f));
        if (excess > 1e-5f + 0.2f * p.length[i]) ++far;
      }
      EXPECT_EQ(far, 0u) << "bark vertices off their node's segment; the worst by " << worst << " of its length";
    }
    for (size_t s = 0; s < pm.leaves.size(); ++s) {
      if (pm.leaves[s].empty()) continue;
      const std::vector<float> ids = part(pm.leaves[s].vertexCount());
      const size_t nv = mesh::leafVertexCount(options);
      size_t slot = 0, wrong = 0;
      for (size_t l = 0; l < p.leafCount(); ++l) {
        if (p.leafShape[l] != s) continue;
        for (size_t k = slot * nv; k < (slot + 1) * nv && k < ids.size(); ++k) wrong += ids[k] != float(p.leafNode[l]);
        ++slot;
      }
      EXPECT_EQ(slot * nv, ids.size());
      EXPECT_EQ(wrong, 0u) << "leaf vertices not labelled with their leaf's node (shape " << s << ")";
    }
    // Primitive groups: primitives of one colour and texture, in order of first use.
    std::vector<std::vector<size_t>> groups;
    std::vector<const plant::PrimitiveMesh*> looks;
    for (size_t k = 0; k < p.primitives.size(); ++k) {
      const plant::PrimitiveMesh& m = p.meshes[p.primitives[k].mesh];
      size_t g = 0;
      while (g < looks.size() && !(looks[g]->color == m.color && looks[g]->texture == m.texture)) ++g;
      if (g == looks.size()) {
        looks.push_back(&m);
        groups.emplace_back();
      }
      groups[g].push_back(k);
    }
    for (size_t g = 0; g < pm.primitives.size(); ++g) {
      if (pm.primitives[g].mesh.empty()) continue;
      const std::vector<float> ids = part(pm.primitives[g].mesh.vertexCount());
      if (ids.empty()) continue;
      size_t v = 0, wrong = 0;
      for (size_t k : groups[g]) {
        const TriangleMesh& m = p.meshes[p.primitives[k].mesh].mesh;
        const size_t count = m.empty() ? 0 : m.vertexCount();
        for (size_t e = v + count; v < e && v < ids.size(); ++v) wrong += ids[v] != float(std::max(p.primitives[k].node, 0));
      }
      EXPECT_EQ(v, ids.size());
      EXPECT_EQ(wrong, 0u) << "primitive vertices not labelled with their primitive's node (group " << g << ")";
    }
    EXPECT_EQ(next, primitives.size()) << "parts left unchecked";
  }
  // Extra meshes (obstacles) carry no node ids.
  for (size_t o = plants.size(); o < glb.gltf["nodes"].size(); ++o)
    for (const json& prim : glb.gltf["meshes"][glb.gltf["nodes"][o].at("mesh").get<size_t>()]["primitives"])
      EXPECT_FALSE(prim.at("attributes").contains("_NODE_ID"));
  return all;
}

TEST_F(Skeleton, GlbCarriesEveryVertexsNodeOnBothWriterPaths) {
  const fs::path dir = test::scratchDir();
  ExportScene exported;
  // The .glb alone streams plant by plant; with the .obj it is written from the whole model.
  session::writePlantFiles(session(), dir, "streamed", {"glb", "skeleton"}, "scene.json", exported);
  session::writePlantFiles(session(), dir, "whole", {"glb", "obj"}, "scene.json", exported);
  const mesh::MeshOptions options = session::exportOptions(session().scene().output).mesh;
  const auto streamed = checkNodeIds(dir / "streamed.glb", exported.plants, options);
  const auto whole = checkNodeIds(dir / "whole.glb", exported.plants, options);
  EXPECT_EQ(streamed, whole);
  // Every skeleton node with bark has vertices that say so.
  const std::set<float> used(streamed[0].begin(), streamed[0].end());
  EXPECT_GT(used.size(), exported.plants[0].nodeCount() / 2);
  for (const char* f : {"streamed.glb", "whole.glb"}) {
    SCOPED_TRACE(f);
    meshtest::GltfValidation v = meshtest::validateGltf(dir / f);
    EXPECT_EQ(v.exitCode, 0) << v.output;
    EXPECT_EQ(v.errors, 0) << v.output;
    EXPECT_EQ(v.warnings, 0) << v.output;
  }
}

TEST_F(Skeleton, FilesDoNotDependOnThreadCount) {
  const fs::path dir = test::scratchDir();
  tendril::test::sameAtEveryThreadCount([&] {
    ExportScene exported;
    session::writePlantFiles(session(), dir, "plant", {"glb", "skeleton"}, "scene.json", exported);
    session::writePlantFiles(session(), dir, "both", {"glb", "obj"}, "scene.json", exported);
    return std::vector<std::vector<uint8_t>>{readFileBytes(dir / "plant.skeleton.json"),
                                             readFileBytes(dir / "plant.glb"), readFileBytes(dir / "both.glb")};
  });
}

TEST(SkeletonWriter, PrimitivesOnThePlantFrameAreLabelledWithTheFirstRoot) {
  const fs::path dir = meshtest::exportTestDir();
  PlantModel p = meshtest::branchingTree();
  meshtest::addLeaves(p, 2);
  TriangleMesh bud;
  bud.positions = {Vec3(0, 0, 0), Vec3(0.02f, 0, 0), Vec3(0, 0.02f, 0), Vec3(0, 0, 0.02f)};
  bud.indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  p.meshes.push_back({"bud", bud, Vec3(0.9f, 0.2f, 0.3f), ""});
  p.meshes.push_back({"stone", bud, Vec3(0.5f, 0.5f, 0.5f), ""});
  for (auto [node, mesh] : {std::pair{7, 0u}, {-1, 1u}, {3, 0u}, {-1, 0u}}) {
    plant::Primitive pr;
    pr.node = node;
    pr.mesh = mesh;
    pr.nodeFromPrimitive(0, 3) = 0.05f;
    p.primitives.push_back(pr);
  }
  ExportScene scene;
  scene.plants = {p, meshtest::syntheticIvy(300)};
  writeGlb(scene, dir / "labels.glb");
  const auto ids = checkNodeIds(dir / "labels.glb", scene.plants, mesh::MeshOptions{});
  EXPECT_EQ(std::set<float>(ids[0].begin(), ids[0].end()).size(), p.nodeCount());
  writeSkeleton(scene.plants, dir / "labels.skeleton.json");
  const json primitives = readJson(dir / "labels.skeleton.json")["plants"][0]["primitives"];
  ASSERT_EQ(primitives.size(), 4u);
  EXPECT_EQ(primitives[1]["node"], -1);
  EXPECT_EQ(primitives[1]["mesh"], "stone");
  // World from primitive, column-major: node 7's frame, then 5 cm along its x.
  const Mat4 world = mesh::worldFromNode(p, 7) * p.primitives[0].nodeFromPrimitive;
  for (int k = 0; k < 16; ++k) EXPECT_TRUE(sameFloat(primitives[0]["matrix"][size_t(k)], world(k % 4, k / 4))) << k;
}

TEST(SkeletonWriter, LargePlantsAreTheSameAtEveryThreadCount) {
  // More nodes than one batch of records (64 × 1024), written in parallel batch by batch.
  const fs::path dir = meshtest::exportTestDir();
  const std::vector<PlantModel> plants = {meshtest::syntheticIvy(70000), meshtest::straightChain(3)};
  const std::vector<uint8_t> bytes = tendril::test::sameAtEveryThreadCount([&] {
    writeSkeleton(plants, dir / "ivy.skeleton.json");
    return readFileBytes(dir / "ivy.skeleton.json");
  });
  const json doc = json::parse(bytes.begin(), bytes.end());
  ASSERT_EQ(doc["plants"].size(), 2u);
  const json& nodes = doc["plants"][0]["nodes"];
  ASSERT_EQ(nodes.size(), plants[0].nodeCount());
  for (size_t i = 0; i < nodes.size(); i += 997) {
    EXPECT_EQ(nodes[i]["id"], i);
    EXPECT_EQ(nodes[i]["parent"], plants[0].parent[i]);
    EXPECT_TRUE(sameFloat(nodes[i]["position"][1], plants[0].position[i].y()));
  }
  EXPECT_EQ(doc["plants"][0]["leaves"].size(), plants[0].leafCount());
  EXPECT_EQ(doc["plants"][1]["nodes"].size(), 3u);
}

TEST(SkeletonWriter, ShortestFloatsNamedFlagsAndAnAtomicFile) {
  const fs::path dir = meshtest::exportTestDir();
  PlantModel p = meshtest::branchingTree();
  meshtest::addLeaves(p, 2);
  p.flags[0] |= plant::kNodeClimbing | plant::kNodeAnchored | (1u << 20);
  p.flags[5] |= plant::kNodeApex;
  p.flags[3] = plant::deadEnd(p.flags[3], plant::TipEnd::NoSupport);
  p.age[2] = 0.1f;
  writeSkeleton({p}, dir / "tree.skeleton.json");
  const std::string text = test::readText(dir / "tree.skeleton.json");
  // One record per line; floats as their own shortest form, not as doubles.
  const json doc = json::parse(text);
  const json& nodes = doc["plants"][0]["nodes"];
  EXPECT_EQ(nodes[0]["flags"], json({"climbing", "anchored"}));
  EXPECT_EQ(nodes[0]["other_flags"], 1u << 20);
  EXPECT_EQ(nodes[5]["flags"], json({"apex"}));
  EXPECT_FALSE(nodes[5].contains("other_flags"));
  EXPECT_EQ(nodes[3]["tip_end"], "no_support");
  EXPECT_FALSE(nodes[3].contains("other_flags"));
  EXPECT_FALSE(nodes[5].contains("tip_end"));
  EXPECT_EQ(nodes[6]["flags"], json({"branch_start"}));
  EXPECT_EQ(nodes[6]["edge"], "+");
  EXPECT_EQ(nodes[1]["edge"], "<");
  // Node 3's second unflagged child starts an axis of its own, as the bark sweep's chains.
  EXPECT_EQ(nodes[9]["parent"], 3);
  EXPECT_EQ(nodes[9]["edge"], "+");
  EXPECT_NE(text.find("\"age\":0.1,"), std::string::npos);
  EXPECT_EQ(text.find("0.10000000149011612"), std::string::npos);
  size_t nodeLines = 0, leafLines = 0;
  for (size_t at = 0, end; at < text.size(); at = end + 1) {
    end = text.find('\n', at);
    const std::string line = text.substr(at, end - at);
    nodeLines += line.starts_with("{\"id\":") && line.find("\"kind\":\"internode\"") != std::string::npos;
    leafLines += line.starts_with("{\"id\":") && line.find("\"kind\":\"leaf\"") != std::string::npos;
    if (end == std::string::npos) break;
  }
  EXPECT_EQ(nodeLines, p.nodeCount());
  EXPECT_EQ(leafLines, p.leafCount());

  // A bad plant is an Error naming it, and the file already there is kept.
  PlantModel bad = p;
  bad.name = "broken";
  bad.radius[4] = -1.0f;
  try {
    writeSkeleton({p, bad}, dir / "tree.skeleton.json");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.source(), "broken");
    EXPECT_EQ(e.location(), "node 4");
  }
  EXPECT_EQ(test::readText(dir / "tree.skeleton.json"), text);
}

}  // namespace
}  // namespace tendril::io
