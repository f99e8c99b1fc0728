// Pivot Painter 2-style textures (issue 26 part 4; docs/export.md "Pivot Painter textures"):
// read back with OpenEXR and the PNG reader, every vertex's TEXCOORD_1 names the pixel that
// holds its own _WIND_PIVOT and _WIND_AXIS (in Unreal's frame, to half-float / 8-bit
// precision), the parent indices make a tree of the skeleton, the extent is the branch's length;
// on every level of detail, for a graph plant and a climbing ivy, with several plants, at one and
// two threads, from both writers and from the CLI; the option's errors.
#include "tendril/io/pivot_painter.h"

#include "support/determinism.h"
#include "support/example_plants.h"
#include "support/gltf_read.h"
#include "support/gltf_validator.h"
#include "support/run_command.h"
#include "support/test_paths.h"
#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"
#include "tendril/graph/build_plant.h"
#include "tendril/graph/graph.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/image.h"
#include "tendril/scene/scene.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session.h"
#include "tendril/wind/engine_wind.h"

#include <ImfRgbaFile.h>
#include <Imath/half.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <map>
#include <set>

namespace tendril {
namespace {

namespace fs = std::filesystem;
using plant::PlantModel;

// Seed 004's chestnut (a component graph with leaves).
const PlantModel& chestnut() { return test::exampleChestnut(); }

// The default scene (seed 003) after 160 steps: its plants, a climbing ivy among them.
session::Session& defaultScene() {
  static std::unique_ptr<session::Session> s = [] {
    std::unique_ptr<session::Session> s = session::Session::open(test::sourceDir() / "examples/scenes/default.json");
    s->run(160);
    return s;
  }();
  return *s;
}

// The climbing ivy of the default scene.
const PlantModel& climbingIvy() {
  static const PlantModel p = defaultScene().plants().at(1);
  return p;
}

std::vector<float> floats(const tinygltf::Model& m, const tinygltf::Primitive& prim, const std::string& name, int width) {
  return test::floatAttribute(m, prim, name, width);
}

tinygltf::Model load(const fs::path& file) { return test::loadGlb(file); }

// The pivot texture as OpenEXR reads it.
struct Exr {
  int width = 0, height = 0;
  std::vector<Imf::Rgba> pixels;
};
Exr readExr(const fs::path& file) {
  Imf::RgbaInputFile in(file.c_str());
  const Imath::Box2i dw = in.dataWindow();
  Exr e;
  e.width = dw.max.x - dw.min.x + 1;
  e.height = dw.max.y - dw.min.y + 1;
  e.pixels.resize(size_t(e.width) * size_t(e.height));
  in.setFrameBuffer(e.pixels.data() - dw.min.x - size_t(dw.min.y) * e.width, 1, size_t(e.width));
  in.readPixels(dw.min.y, dw.max.y);
  EXPECT_EQ(in.channels(), Imf::WRITE_RGBA);
  return e;
}

// The length of node i's branch counted here independently: from the start of its axis (up
// while the parent has its order) over every node whose axis starts there.
std::vector<double> branchLengthsByWalking(const PlantModel& p) {
  const size_t n = p.nodeCount();
  std::vector<size_t> start(n);
  for (size_t i = 0; i < n; ++i) {
    size_t k = i;
    while (p.parent[k] >= 0 && p.order[size_t(p.parent[k])] == p.order[k]) k = size_t(p.parent[k]);
    start[i] = k;
  }
  std::map<size_t, double> total;
  for (size_t i = 0; i < n; ++i) total[start[i]] += p.length[i];
  std::vector<double> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = total[start[i]];
  return out;
}

// What one plant's check found.
struct Checked {
  size_t vertices = 0;
  std::set<uint32_t> elements;  // the elements vertices index
  size_t levels = 0;            // glTF meshes checked (levels of detail)
};

// Checks the textures of `plant` (exr, png) against every vertex of the glTF meshes `meshes`
// of `m`, and the parents and extents against the plant; what it saw goes to `c`.
void checkPlant(const PlantModel& plant, const tinygltf::Model& m, const std::vector<int>& meshes, const fs::path& exr,
                const fs::path& png, Checked& c) {
  const Exr pivot = readExr(exr);
  const io::Image axis = io::readImage(png);
  const size_t n = plant.nodeCount();
  EXPECT_EQ(pivot.width, axis.width);
  EXPECT_EQ(pivot.height, axis.height);
  EXPECT_GE(size_t(pivot.width) * size_t(pivot.height), n);
  EXPECT_LT(size_t(pivot.width) * size_t(pivot.height - 1), n) << "a pixel row left empty";
  // Parents: a root's parent is itself, every other element's its node's parent; following
  // parents from any element ends at a root, in fewer steps than there are elements.
  for (size_t i = 0; i < n; ++i) {
    const uint32_t parent = io::unpackPivotPainterIndex(pivot.pixels[i].a.bits());
    EXPECT_EQ(parent, plant.parent[i] >= 0 ? uint32_t(plant.parent[i]) : uint32_t(i)) << "element " << i;
    if (parent != i) {
      EXPECT_LT(parent, i);
    }
  }
  for (size_t i = 0; i < n; ++i) {
    uint32_t k = uint32_t(i);
    size_t steps = 0;
    while (io::unpackPivotPainterIndex(pivot.pixels[k].a.bits()) != k && steps <= n) {
      k = io::unpackPivotPainterIndex(pivot.pixels[k].a.bits());
      ASSERT_LT(k, n);
      ++steps;
    }
    ASSERT_LE(steps, n) << "element " << i << "'s parents do not end at a root";
    EXPECT_LT(plant.parent[k], 0) << "element " << i << "'s chain ends at node " << k << ", not a root";
  }
  // X-Extent: the branch's length, clamped to Pivot Painter 2's 8 cm – 20.48 m, to its 8 cm steps.
  const std::vector<double> lengths = branchLengthsByWalking(plant);
  for (size_t i = 0; i < n; ++i) {
    const double expected = std::clamp(lengths[i], 0.08, 20.48);
    EXPECT_NEAR(io::decodePivotPainterExtent(axis.pixel(int(i % size_t(axis.width)), int(i / size_t(axis.width)))[3]),
                expected, 0.041)
        << "element " << i;
  }
  // Every vertex of every level: its TEXCOORD_1 is its node's pixel centre, and that pixel holds
  // its pivot and its axis's direction.
  for (int meshIndex : meshes) {
    ++c.levels;
    for (const tinygltf::Primitive& prim : m.meshes[size_t(meshIndex)].primitives) {
      const std::vector<float> uv = floats(m, prim, "TEXCOORD_1", 2), id = floats(m, prim, "_NODE_ID", 1),
                               pv = floats(m, prim, "_WIND_PIVOT", 3), ax = floats(m, prim, "_WIND_AXIS", 3);
      EXPECT_TRUE(prim.attributes.count("TEXCOORD_0"));
      if (id.empty()) continue;  // an impostor's quads (no nodes)
      EXPECT_EQ(uv.size(), 2 * id.size());
      EXPECT_EQ(pv.size(), 3 * id.size());
      EXPECT_EQ(ax.size(), 3 * id.size());
      if (uv.size() != 2 * id.size() || pv.size() != 3 * id.size() || ax.size() != 3 * id.size()) continue;
      for (size_t k = 0; k < id.size(); ++k) {
        // The pixel the UV falls in, as Pivot Painter 2's element index is worked out.
        const int col = int(std::floor(uv[2 * k] * float(pivot.width)));
        const int row = int(std::floor(uv[2 * k + 1] * float(pivot.height)));
        ASSERT_TRUE(col >= 0 && col < pivot.width && row >= 0 && row < pivot.height);
        const uint32_t e = uint32_t(row * pivot.width + col);
        ASSERT_EQ(e, uint32_t(id[k])) << "vertex " << k << " indexes another element than its node";
        c.elements.insert(e);
        ++c.vertices;
        const Imf::Rgba& px = pivot.pixels[e];
        const Vec3 cm(float(px.r), float(px.g), float(px.b));
        const Vec3 expected = io::unrealPoint(Vec3(pv[3 * k], pv[3 * k + 1], pv[3 * k + 2]));
        for (int a = 0; a < 3; ++a)
          ASSERT_NEAR(cm[a], expected[a], std::abs(expected[a]) / 2048.0f + 1e-4f)
              << "element " << e << " axis " << a << ": the pivot texture disagrees with _WIND_PIVOT";
        // Back in the glTF frame too (what docs/engine-wind.md's shader does).
        ASSERT_LT((io::gltfPoint(cm) - Vec3(pv[3 * k], pv[3 * k + 1], pv[3 * k + 2])).norm(),
                  Vec3(pv[3 * k], pv[3 * k + 1], pv[3 * k + 2]).norm() / 1000.0f + 1e-6f);
        const Vec3 lever(ax[3 * k], ax[3 * k + 1], ax[3 * k + 2]);
        if (lever.norm() == 0.0f) continue;
        const uint8_t* a8 = axis.pixel(col, row);
        const Vec3 unreal(a8[0] / 255.0f * 2.0f - 1.0f, a8[1] / 255.0f * 2.0f - 1.0f, a8[2] / 255.0f * 2.0f - 1.0f);
        const Vec3 direction = io::gltfDirection(unreal), want = lever.normalized();
        for (int a = 0; a < 3; ++a)
          ASSERT_NEAR(direction[a], want[a], 1.01f / 255.0f)
              << "element " << e << " axis " << a << ": the axis texture disagrees with _WIND_AXIS";
      }
    }
  }
}

// The glTF meshes of node `name` and its lower levels (MSFT_lod).
std::vector<int> levelMeshes(const tinygltf::Model& m, const std::string& name) {
  std::vector<int> out;
  for (const tinygltf::Node& node : m.nodes)
    if (node.mesh >= 0 && (node.name == name || node.name.rfind(name + "_LOD", 0) == 0)) out.push_back(node.mesh);
  return out;
}

TEST(PivotPainter, TexturesHoldEveryVertexsWindDataOnEveryLevel) {
  const fs::path dir = test::scratchDir();
  struct Case {
    const char* name;
    const PlantModel& plant;
  } cases[] = {{"chestnut", chestnut()}, {"climbing ivy", climbingIvy()}};
  for (const Case& cs : cases) {
    SCOPED_TRACE(cs.name);
    ASSERT_GT(cs.plant.nodeCount(), 50u);
    io::ExportScene scene;
    scene.plants.push_back(cs.plant);
    scene.plants.back().name = cs.name;
    scene.wind = wind::engineWindTables(scene.plants, {plant::GrowthFlowSpecies{}});
    const io::PivotPainterTextures t = io::pivotPainterTextures(scene.plants[0], scene.wind[0], "test");
    const fs::path exr = io::pivotPainterPivotPath(dir, "plant", cs.name), png = io::pivotPainterXAxisPath(dir, "plant", cs.name);
    EXPECT_EQ(exr.filename().string(), fmt::format("plant-{}-pp-pivot.exr", cs.name == std::string("chestnut") ? "chestnut" : "climbing_ivy"));
    io::writePivotPainterTextures(t, exr, png);
    scene.pivotPainter = {t.grid};
    io::ExportOptions options;
    options.lods.levels = 3;
    io::writeGlb(scene, dir / "plant.glb", options);
    const tinygltf::Model m = load(dir / "plant.glb");
    Checked c;
    checkPlant(scene.plants[0], m, levelMeshes(m, cs.name), exr, png, c);
    EXPECT_EQ(c.levels, 3u);
    EXPECT_GT(c.vertices, 1000u);
    // Many elements are indexed, and the pixel of each holds that element's own pivot: at least
    // two elements with different pivots (so a UV off by one element would have failed above).
    EXPECT_GT(c.elements.size(), cs.plant.nodeCount() / 2);
    std::set<std::tuple<float, float, float>> pivots;
    for (uint32_t e : c.elements) pivots.insert({scene.wind[0][e].pivot.x(), scene.wind[0][e].pivot.y(), scene.wind[0][e].pivot.z()});
    EXPECT_GT(pivots.size(), 10u);
    fmt::print("{}: {} nodes, {}x{} texture, {} vertices on {} levels, {} elements indexed\n", cs.name,
               cs.plant.nodeCount(), t.grid.width, t.grid.height, c.vertices, c.levels, c.elements.size());
  }
}

TEST(PivotPainter, ElementIndexAndLayoutConventions) {
  // ⌈√n⌉ wide, no row left empty; pixel centres; the parent index's half bits.
  const io::PivotPainterGrid g = io::pivotPainterGrid(10);
  EXPECT_EQ(g.width, 4u);
  EXPECT_EQ(g.height, 3u);
  EXPECT_EQ(io::pivotPainterGrid(16).width, 4u);
  EXPECT_EQ(io::pivotPainterGrid(16).height, 4u);
  EXPECT_EQ(io::pivotPainterGrid(17).width, 5u);
  EXPECT_EQ(io::pivotPainterGrid(17).height, 4u);
  EXPECT_EQ(io::pivotPainterGrid(1).width, 1u);
  const Vec2 uv = io::pivotPainterUv(6, g);  // column 2, row 1
  EXPECT_FLOAT_EQ(uv.x(), 2.5f / 4.0f);
  EXPECT_FLOAT_EQ(uv.y(), 1.5f / 3.0f);
  for (uint32_t i : {0u, 1u, 1000u, io::kPivotPainterMaxElements - 1}) {
    half h;
    h.setBits(io::packPivotPainterIndex(i));
    EXPECT_TRUE(h.isFinite() && !h.isDenormalized()) << i;  // survives any half-float texture path
    EXPECT_EQ(io::unpackPivotPainterIndex(h.bits()), i);
  }
  EXPECT_NO_THROW(io::pivotPainterGrid(io::kPivotPainterMaxElements));
  try {
    io::pivotPainterGrid(io::kPivotPainterMaxElements + 1, "scene.json", "ivy");
    FAIL() << "too many elements accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_NE(what.find("scene.json"), std::string::npos) << what;
    EXPECT_NE(what.find("ivy"), std::string::npos) << what;
  }
  // Unreal's frame: Z up, left-handed, cm (what its glTF importer gives the mesh).
  EXPECT_EQ(io::unrealPoint(Vec3(1, 2, 3)), Vec3(100, 300, 200));
  EXPECT_EQ(io::gltfPoint(io::unrealPoint(Vec3(1, 2, 3))), Vec3(1, 2, 3));
  // X-Extent: 8 cm steps from 8 cm to 20.48 m.
  EXPECT_NEAR(io::decodePivotPainterExtent(io::encodePivotPainterExtent(1.0f)), 1.0f, 0.041f);
  EXPECT_NEAR(io::decodePivotPainterExtent(io::encodePivotPainterExtent(0.01f)), 0.08f, 0.001f);
  EXPECT_NEAR(io::decodePivotPainterExtent(io::encodePivotPainterExtent(100.0f)), 20.48f, 0.001f);
}

// A session's files with pivot_painter (and wind data, levels of detail, a leaf atlas) as
// writePlantFiles writes them; returns every file's bytes by name.
std::map<std::string, std::vector<uint8_t>> writeSession(session::Session& s, const fs::path& dir,
                                                         const std::set<std::string>& formats, int threads) {
  test::ScopedThreadCount t(threads);
  scene::OutputSettings output = s.scene().output;
  output.pivotPainter = true;
  output.windData = true;
  output.lods = 2;
  output.leafAtlas = true;
  io::ExportScene exported;
  std::map<std::string, std::vector<uint8_t>> out;
  for (const std::string& f : session::writePlantFiles(s, dir, "scene", formats, "test", exported, &output))
    out[fs::path(f).filename().string()] = io::readFileBytes(f);
  return out;
}

TEST(PivotPainter, SeveralPlantsSameBytesAtAnyThreadCountFromBothWritersAndValid) {
  const fs::path dir = test::scratchDir();
  session::Session& s = defaultScene();
  ASSERT_GE(s.plants().size(), 2u);
  const auto one = writeSession(s, dir, {"glb"}, 1);
  const auto two = writeSession(s, dir, {"glb"}, 2);
  EXPECT_EQ(one, two);
  // One .glb and two textures per plant with nodes.
  size_t withNodes = 0;
  for (const PlantModel& p : s.plants()) withNodes += p.nodeCount() > 0 ? 1 : 0;
  ASSERT_GE(withNodes, 2u);
  EXPECT_EQ(one.size(), 1 + 2 * withNodes);
  const meshtest::GltfValidation v = meshtest::validateGltf(dir / "scene.glb");
  EXPECT_EQ(v.errors, 0) << v.output;
  EXPECT_EQ(v.warnings, 0) << v.output;
  // Every plant's textures agree with its vertices on both levels.
  const tinygltf::Model m = load(dir / "scene.glb");
  for (const PlantModel& p : s.plants()) {
    if (p.nodeCount() == 0) continue;
    SCOPED_TRACE(p.name);
    Checked c;
    checkPlant(p, m, levelMeshes(m, p.name), io::pivotPainterPivotPath(dir, "scene", p.name),
               io::pivotPainterXAxisPath(dir, "scene", p.name), c);
    EXPECT_EQ(c.levels, 2u);
    EXPECT_GT(c.elements.size(), 1u);
  }
  // With the .obj too the .glb is written from one model: the same binary chunk and textures;
  // the .obj has no Pivot Painter data.
  const auto both = writeSession(s, dir, {"glb", "obj"}, 2);
  for (const auto& [name, bytes] : one)
    if (name != "scene.glb") {
      EXPECT_EQ(both.at(name), bytes) << name;
    }
  const std::vector<uint8_t>& streamed = one.at("scene.glb");
  const std::vector<uint8_t>& whole = both.at("scene.glb");
  uint32_t sj = 0, wj = 0;
  std::memcpy(&sj, streamed.data() + 12, 4);
  std::memcpy(&wj, whole.data() + 12, 4);
  EXPECT_TRUE(std::equal(streamed.begin() + 20 + sj, streamed.end(), whole.begin() + 20 + wj, whole.end()));
  // The .obj alone: no textures (nothing in it could index them).
  const auto objOnly = writeSession(s, dir, {"obj"}, 2);
  for (const auto& [name, bytes] : objOnly) EXPECT_EQ(name.find("-pp-"), std::string::npos) << name;
}

TEST(PivotPainter, WithoutTheOptionNothingChanges) {
  const fs::path dir = test::scratchDir();
  io::ExportScene scene;
  scene.plants.push_back(chestnut());
  io::writeGlb(scene, dir / "plain.glb");
  const tinygltf::Model m = load(dir / "plain.glb");
  for (const tinygltf::Primitive& prim : m.meshes[0].primitives) EXPECT_EQ(prim.attributes.count("TEXCOORD_1"), 0u);
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(PivotPainter, OptionErrorsAreOneLine) {
  const fs::path dir = test::scratchDir();
  // Bad values of output.pivot_painter.
  for (const char* value : {"3", "\"yes\"", "null", "[true]"}) {
    SCOPED_TRACE(value);
    const std::string e = errorOf([&] {
      scene::parseScene(parseJson(fmt::format(R"({{"tendril": 1, "output": {{"pivot_painter": {}}}, "plants": []}})", value),
                                  "bad.json"),
                        "bad.json", dir);
    });
    ASSERT_FALSE(e.empty());
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    EXPECT_NE(e.find("bad.json"), std::string::npos) << e;
    EXPECT_NE(e.find("pivot_painter"), std::string::npos) << e;
  }
  // With GPU instancing: refused, before anything is written.
  session::Session s(scene::parseScene(parseJson(R"({"tendril": 1, "steps": 0,
      "output": {"pivot_painter": true, "instancing": true}, "plants": [
      {"name": "sunflower", "model": "graph", "graph": "../graphs/sunflower.json", "position": [0, 0, 0]}]})",
                                                 "inst.json"),
                                       "inst.json", test::sourceDir() / "examples/scenes"));
  s.run(0);
  io::ExportScene exported;
  fs::remove(dir / "inst.glb");
  const std::string e = errorOf([&] { session::writePlantFiles(s, dir, "inst", {"glb"}, "inst.json", exported); });
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  EXPECT_NE(e.find("inst.json"), std::string::npos) << e;
  EXPECT_NE(e.find("output.pivot_painter"), std::string::npos) << e;
  EXPECT_NE(e.find("instancing"), std::string::npos) << e;
  EXPECT_FALSE(fs::exists(dir / "inst.glb"));
  EXPECT_FALSE(fs::exists(io::pivotPainterPivotPath(dir, "inst", "sunflower")));
  // The .glb writer refuses it too.
  io::ExportScene scene;
  scene.plants.push_back(s.plants().at(0));
  scene.pivotPainter = {io::pivotPainterGrid(scene.plants[0].nodeCount())};
  io::ExportOptions options;
  options.instancing = true;
  const std::string w = errorOf([&] { io::writeGlb(scene, dir / "inst.glb", options); });
  EXPECT_NE(w.find("instancing"), std::string::npos) << w;
  EXPECT_FALSE(fs::exists(dir / "inst.glb"));
}

TEST(PivotPainter, CliModelAtOneAndTwoThreads) {
  const fs::path dir = test::scratchDir();
  const std::string graphFile = test::quoted(test::sourceDir() / "examples/graphs/sunflower.json");
  std::map<std::string, std::vector<uint8_t>> files[2];
  for (int threads : {1, 2}) {
    const fs::path sub = dir / fmt::format("t{}", threads);
    fs::create_directories(sub);
    const test::CommandResult r = test::runTendril(
        fmt::format("model {} --pivot-painter --wind-data --lods 2 -q --threads {} -o {}", graphFile, threads,
                    test::quoted(sub / "flower.glb")),
        dir);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const auto& entry : fs::directory_iterator(sub))
      files[threads - 1][entry.path().filename().string()] = io::readFileBytes(entry.path());
  }
  EXPECT_EQ(files[0], files[1]);
  ASSERT_EQ(files[0].size(), 3u);
  EXPECT_TRUE(files[0].count("flower-sunflower-pp-pivot.exr"));
  EXPECT_TRUE(files[0].count("flower-sunflower-pp-xaxis.png"));
  const meshtest::GltfValidation v = meshtest::validateGltf(dir / "t1/flower.glb");
  EXPECT_EQ(v.errors, 0) << v.output;
  EXPECT_EQ(v.warnings, 0) << v.output;
  // With --instancing: a one-line error, exit code not 0.
  const test::CommandResult r = test::runTendril(
      fmt::format("model {} --pivot-painter --instancing -q -o {}", graphFile, test::quoted(dir / "inst.glb")), dir);
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.err.find("output.pivot_painter"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "inst.glb"));
}

}  // namespace
}  // namespace tendril
