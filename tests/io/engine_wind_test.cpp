// Engine wind data (issue 26 part 4, docs/engine-wind.md): the .glb's COLOR_0, _WIND_PIVOT and
// _WIND_AXIS read back from a grown plant, fed through the doc's shader
// (wind::engineWindDisplacement, the same formula as the GLSL), move each vertex as WindMotion's
// own settled sway moves it in a small steady wind; a wrong pivot does not. Both writer paths,
// the validator, thread counts and the scene/CLI switch.
#include "tendril/wind/engine_wind.h"

#include "support/determinism.h"
#include "support/example_plants.h"
#include "support/gltf_read.h"
#include "support/gltf_validator.h"
#include "support/run_command.h"
#include "support/test_paths.h"
#include "tendril/core/json_reader.h"
#include "tendril/env/wind_field.h"
#include "tendril/graph/build_plant.h"
#include "tendril/graph/graph.h"
#include "tendril/io/atomic_file.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/image.h"
#include "tendril/scene/scene.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session.h"
#include "tendril/wind/motion.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <set>

namespace tendril {
namespace {

namespace fs = std::filesystem;
using plant::PlantModel;

// Honda's monopodial tree (ABOP fig. 2.6a) grown by the L-system model for its 10 steps.
const PlantModel& grownTree() {
  static const PlantModel p = [] {
    session::Session s(scene::parseScene(parseJson(R"({"tendril": 1, "steps": 10, "plants": [
        {"name": "tree", "model": "lsystem", "grammar": "../grammars/abop-2.6-monopodial.ls", "position": [0, 0, 0]}]})",
                                                   "test scene"),
                                         "test scene", test::sourceDir() / "examples/scenes"));
    s.run(10);
    return s.plants().at(0);
  }();
  return p;
}

// Seed 004's chestnut (a component graph with leaves).
const PlantModel& chestnut() { return test::exampleChestnut(); }

std::vector<float> floats(const tinygltf::Model& m, const tinygltf::Primitive& prim, const std::string& name, int width) {
  return test::floatAttribute(m, prim, name, width);
}

tinygltf::Model load(const fs::path& file) { return test::loadGlb(file); }

// A plant vertex as the .glb has it.
struct WindVertex {
  Vec3 position, pivot, lever;
  Vec4 color;
  uint32_t node;
};

// Every vertex of LOD0 (glTF node 0) with wind data.
std::vector<WindVertex> windVertices(const tinygltf::Model& m) {
  std::vector<WindVertex> out;
  const tinygltf::Mesh& mesh = m.meshes[size_t(m.nodes[0].mesh)];
  for (const tinygltf::Primitive& prim : mesh.primitives) {
    const std::vector<float> p = floats(m, prim, "POSITION", 3), id = floats(m, prim, "_NODE_ID", 1),
                             c = floats(m, prim, "COLOR_0", 4), pv = floats(m, prim, "_WIND_PIVOT", 3),
                             ax = floats(m, prim, "_WIND_AXIS", 3);
    EXPECT_FALSE(c.empty() || pv.empty() || ax.empty() || id.empty()) << "a plant part without wind data";
    if (c.empty() || pv.empty() || ax.empty() || id.empty()) continue;
    for (size_t k = 0; k < id.size(); ++k)
      out.push_back({Vec3(p[3 * k], p[3 * k + 1], p[3 * k + 2]), Vec3(pv[3 * k], pv[3 * k + 1], pv[3 * k + 2]),
                     Vec3(ax[3 * k], ax[3 * k + 1], ax[3 * k + 2]),
                     Vec4(c[4 * k], c[4 * k + 1], c[4 * k + 2], c[4 * k + 3]), uint32_t(id[k])});
  }
  return out;
}

io::ExportScene windScene(const PlantModel& p) {
  io::ExportScene s;
  s.plants.push_back(p);
  s.wind = wind::engineWindTables(s.plants, {plant::GrowthFlowSpecies{}});
  return s;
}

// WindMotion's settled pose in the steady wind w: the periodic solution of eq. 1 in a constant
// wind is its static deflection θ* = τ / k.
struct Settled {
  std::vector<Quat> rotation;
  std::vector<Vec3> translation;
  float largestAngle = 0.0f;
};
Settled settledSway(const PlantModel& p, const Vec3& w) {
  wind::MotionSettings ms;
  ms.loopSeconds = 4.0f;
  wind::WindMotion motion(p, plant::GrowthFlowSpecies{}, ms);
  env::WindSettings ws;
  ws.velocity = w;
  PlantModel posed;
  motion.step(0.0f, 1.0f / 30.0f, env::WindField(ws), posed);
  Settled s;
  s.translation = motion.nodeTranslation();
  for (size_t i = 0; i < p.nodeCount(); ++i) {
    s.rotation.push_back(motion.nodeRotation(i));
    s.largestAngle = std::max(s.largestAngle, float(Eigen::AngleAxisf(motion.nodeRotation(i)).angle()));
  }
  return s;
}

// Σ |d_shader − d_tendril|² / Σ |d_tendril|² over the vertices (the shader's pivot taken from
// `pivotOf`), and the largest Tendril displacement.
struct Mismatch {
  double relative = 0, largest = 0;
};
template <class PivotOf>
Mismatch mismatch(const std::vector<WindVertex>& vs, const Settled& s, const Vec3& w, PivotOf&& pivotOf) {
  wind::EngineWindUniforms u;
  u.wind = w;
  double err = 0, norm = 0, largest = 0;
  for (const WindVertex& v : vs) {
    const Vec3d tendril = (s.rotation[v.node] * v.position + s.translation[v.node] - v.position).cast<double>();
    const Vec3 pivot = pivotOf(v);
    const Vec3d shader = wind::engineWindDisplacement(v.position, pivot, v.lever, v.color, u).cast<double>();
    err += (shader - tendril).squaredNorm();
    norm += tendril.squaredNorm();
    largest = std::max(largest, tendril.norm());
  }
  return {std::sqrt(err / std::max(norm, 1e-300)), largest};
}

// The stated tolerance: the shader's displacement is within 15 % (RMS over the vertices) of
// WindMotion's in winds that bend no node more than 2° (the single rotation is exact for
// parallel levers along a path; the rest is the tree's curvature and eq. 1's twist rule).
constexpr double kTolerance = 0.15;

TEST(EngineWind, ShaderDisplacementMatchesTendrilsSway) {
  const fs::path dir = test::scratchDir();
  struct Case {
    const char* name;
    const PlantModel& plant;
  } cases[] = {{"grown monopodial tree", grownTree()}, {"chestnut", chestnut()}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    ASSERT_GT(c.plant.nodeCount(), 20u);
    const io::ExportScene scene = windScene(c.plant);
    io::writeGlb(scene, dir / "wind.glb");
    const std::vector<WindVertex> vs = windVertices(load(dir / "wind.glb"));
    ASSERT_GT(vs.size(), 1000u);
    // A wind whose settled sway stays small: at most about 2° at any node.
    float largestLever = 0;
    for (const io::WindVertexNode& n : scene.wind[0]) largestLever = std::max(largestLever, n.lever.norm());
    ASSERT_GT(largestLever, 0.0f);
    const float speed = std::sqrt(radians(1.0f) / largestLever);
    for (const Vec3& direction : {Vec3(1, 0, 0), Vec3(0.6f, 0, -0.8f)}) {
      const Vec3 w = speed * direction;
      SCOPED_TRACE(fmt::format("wind ({}, {}, {}) m/s", w.x(), w.y(), w.z()));
      const Settled s = settledSway(c.plant, w);
      ASSERT_GT(s.largestAngle, radians(0.1f));
      ASSERT_LT(s.largestAngle, radians(3.0f));
      const Mismatch good = mismatch(vs, s, w, [](const WindVertex& v) { return v.pivot; });
      ASSERT_GT(good.largest, 1e-4);
      EXPECT_LT(good.relative, kTolerance) << "largest displacement " << good.largest << " m";
      // A wrong pivot — the vertex's own node (where its segment starts), or the plant's root —
      // is far off.
      const Mismatch ownNode = mismatch(vs, s, w, [&](const WindVertex& v) { return c.plant.position[v.node]; });
      const Mismatch root = mismatch(vs, s, w, [&](const WindVertex&) { return c.plant.position[0]; });
      EXPECT_GT(ownNode.relative, 2 * kTolerance);
      EXPECT_GT(root.relative, 2 * kTolerance);
      fmt::print("{}: relative RMS error {:.4f} (own-node pivot {:.3f}, root pivot {:.3f}), largest {:.4g} m\n", c.name,
                 good.relative, ownNode.relative, root.relative, good.largest);
    }
    // COLOR_0: levels and phases in [0, 1], periods in [0, 1], the leaf flag exactly 0 or 1.
    for (const WindVertex& v : vs) {
      ASSERT_TRUE(v.color.x() >= 0 && v.color.x() <= 1 && v.color.y() >= 0 && v.color.y() < 1 && v.color.z() >= 0 &&
                  v.color.z() <= 1 && (v.color.w() == 0 || v.color.w() == 1));
      const io::WindVertexNode& n = scene.wind[0][v.node];
      ASSERT_EQ(v.pivot, n.pivot);
      ASSERT_EQ(v.lever, n.lever);
    }
  }
}

TEST(EngineWind, BothWritersSameBytesAtAnyThreadCountAndValid) {
  const fs::path dir = test::scratchDir();
  io::ExportScene scene = windScene(chestnut());
  io::ExportOptions lods;
  lods.lods.levels = 3;
  const std::vector<uint8_t> one = [&] {
    test::ScopedThreadCount t(1);
    io::ExportScene s = windScene(chestnut());
    io::writeGlb(s, dir / "one.glb", lods);
    return io::readFileBytes(dir / "one.glb");
  }();
  const std::vector<uint8_t> two = [&] {
    test::ScopedThreadCount t(2);
    io::ExportScene s = windScene(chestnut());
    io::writeGlb(s, dir / "two.glb", lods);
    return io::readFileBytes(dir / "two.glb");
  }();
  EXPECT_EQ(one, two);
  const meshtest::GltfValidation v = meshtest::validateGltf(dir / "one.glb");
  EXPECT_EQ(v.errors, 0) << v.output;
  EXPECT_EQ(v.warnings, 0) << v.output;
  // The whole-model path writes the same binary chunk (the JSON differs in padding only).
  io::ExportModel model = io::buildExportModel(scene, lods);
  io::writeGlb(model, dir / "whole.glb", &scene.wind);
  const std::vector<uint8_t> whole = io::readFileBytes(dir / "whole.glb");
  uint32_t sj = 0, wj = 0;
  std::memcpy(&sj, one.data() + 12, 4);
  std::memcpy(&wj, whole.data() + 12, 4);
  EXPECT_TRUE(std::equal(one.begin() + 20 + sj, one.end(), whole.begin() + 20 + wj, whole.end()));
  // Every level's plant parts carry the attributes; leaves have the leaf flag, bark not.
  const tinygltf::Model m = load(dir / "whole.glb");
  size_t leafParts = 0, barkParts = 0;
  for (const tinygltf::Mesh& mesh : m.meshes)
    for (const tinygltf::Primitive& prim : mesh.primitives) {
      const std::vector<float> c = floats(m, prim, "COLOR_0", 4);
      ASSERT_FALSE(c.empty());
      ASSERT_TRUE(prim.attributes.count("_WIND_PIVOT") && prim.attributes.count("_WIND_AXIS"));
      const bool leaf = m.materials[size_t(prim.material)].alphaMode == "MASK";
      (leaf ? leafParts : barkParts) += 1;
      for (size_t k = 0; k < c.size(); k += 4) ASSERT_EQ(c[k + 3], leaf ? 1.0f : 0.0f);
    }
  EXPECT_GE(leafParts, 3u);
  EXPECT_GE(barkParts, 3u);
  // Without wind tables nothing changes.
  io::ExportScene plainScene;
  plainScene.plants = scene.plants;
  io::writeGlb(plainScene, dir / "plain.glb");
  const tinygltf::Model plain = load(dir / "plain.glb");
  for (const tinygltf::Primitive& prim : plain.meshes[0].primitives) EXPECT_EQ(prim.attributes.count("COLOR_0"), 0u);
}

TEST(EngineWind, SceneOutputSwitchesItOn) {
  const fs::path dir = test::scratchDir();
  for (bool on : {false, true}) {
    session::Session s(scene::parseScene(
        parseJson(fmt::format(R"({{"tendril": 1, "steps": 10, "output": {{"wind_data": {}}}, "plants": [
        {{"name": "tree", "model": "lsystem", "grammar": "../grammars/abop-2.6-monopodial.ls", "position": [0, 0, 0]}}]}})",
                              on),
                  "test scene"),
        "test scene", test::sourceDir() / "examples/scenes"));
    s.run(10);
    io::ExportScene exported;
    for (const char* formats : {"glb", "glb,obj"}) {
      SCOPED_TRACE(fmt::format("wind_data {}, {}", on, formats));
      const std::set<std::string> f = std::string(formats) == "glb" ? std::set<std::string>{"glb"}
                                                                     : std::set<std::string>{"glb", "obj"};
      session::writePlantFiles(s, dir, "plant", f, "test", exported, nullptr);
      const tinygltf::Model m = load(dir / "plant.glb");
      for (const tinygltf::Primitive& prim : m.meshes[0].primitives) {
        EXPECT_EQ(prim.attributes.count("COLOR_0"), on ? 1u : 0u);
        EXPECT_EQ(prim.attributes.count("_WIND_PIVOT"), on ? 1u : 0u);
      }
    }
  }
}

TEST(EngineWind, CliWindDataOnModelAndLsysAtOneAndTwoThreads) {
  const fs::path dir = test::scratchDir();
  const std::string chestnutGraph = test::quoted(test::sourceDir() / "examples/graphs/chestnut.json");
  const std::string tree = test::quoted(test::sourceDir() / "examples/grammars/abop-2.6-monopodial.ls");
  for (const std::string& command : {"model " + chestnutGraph, "lsys " + tree + " -n 8"}) {
    SCOPED_TRACE(command);
    std::vector<uint8_t> bytes[2];
    for (int threads : {1, 2}) {
      const fs::path file = dir / fmt::format("t{}.glb", threads);
      const test::CommandResult r =
          test::runTendril(fmt::format("{} --wind-data -q --threads {} -o {}", command, threads, test::quoted(file)), dir);
      ASSERT_EQ(r.exitCode, 0) << r.err;
      bytes[threads - 1] = io::readFileBytes(file);
    }
    EXPECT_EQ(bytes[0], bytes[1]);
    const meshtest::GltfValidation v = meshtest::validateGltf(dir / "t1.glb");
    EXPECT_EQ(v.errors, 0) << v.output;
    EXPECT_EQ(v.warnings, 0) << v.output;
    const tinygltf::Model m = load(dir / "t1.glb");
    for (const tinygltf::Primitive& prim : m.meshes[0].primitives) {
      EXPECT_EQ(prim.attributes.count("COLOR_0"), 1u);
      EXPECT_EQ(prim.attributes.count("_WIND_PIVOT"), 1u);
      EXPECT_EQ(prim.attributes.count("_WIND_AXIS"), 1u);
    }
  }
}

}  // namespace
}  // namespace tendril
