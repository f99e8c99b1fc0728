// GPU instancing of graph plants' repeated primitives (io/instancing.h, issue 26 part 6): the
// instanced .glb, its instances expanded, has the baked file's triangles; it is smaller for the
// sunflower and the rhododendron (the chestnut, whose leaves are all bent, is unchanged); it
// validates, composes with LOD chains, leaf atlases, wind data and several plants, both writers
// agree and the bytes do not depend on the thread count.
#include "tendril/io/instancing.h"

#include "support/determinism.h"
#include "support/gltf_read.h"
#include "support/gltf_validator.h"
#include "support/run_command.h"
#include "support/test_paths.h"
#include "tendril/core/error.h"
#include "tendril/graph/build_plant.h"
#include "tendril/graph/graph.h"
#include "tendril/io/atomic_file.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/image.h"
#include "tendril/scene/scene.h"
#include "tendril/session/plant_export.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <tuple>

namespace tendril::io {
namespace {

namespace fs = std::filesystem;
using plant::PlantModel;

// Not kept between tests: the test process's peak memory is checked (Soak).
PlantModel graphPlant(const char* name) {
  auto g = graph::loadGraph(test::sourceDir() / "examples/graphs" / (std::string(name) + ".json"));
  PlantModel p = graph::generatePlant(g, {g->seed, {}});
  p.name = name;
  return p;
}

ExportScene sceneOf(std::initializer_list<const char*> names) {
  ExportScene s;
  for (const char* n : names) s.plants.push_back(graphPlant(n));
  return s;
}

ExportOptions options(bool instancing, int levels = 1, bool atlas = false) {
  ExportOptions o;
  o.instancing = instancing;
  o.lods.levels = levels;
  o.leafAtlas = atlas;
  return o;
}

tinygltf::Model load(const fs::path& file) { return test::loadGlb(file); }

template <class T>
std::vector<T> accessorData(const tinygltf::Model& m, int accessor) {
  const tinygltf::Accessor& a = m.accessors.at(size_t(accessor));
  const tinygltf::BufferView& v = m.bufferViews.at(size_t(a.bufferView));
  const size_t width = size_t(tinygltf::GetNumComponentsInType(uint32_t(a.type)));
  std::vector<T> out(a.count * width);
  std::memcpy(out.data(), m.buffers[size_t(v.buffer)].data.data() + v.byteOffset + a.byteOffset, out.size() * sizeof(T));
  return out;
}

std::vector<uint32_t> indicesOf(const tinygltf::Model& m, const tinygltf::Primitive& p) {
  const tinygltf::Accessor& a = m.accessors.at(size_t(p.indices));
  std::vector<uint32_t> out;
  if (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)
    for (uint16_t i : accessorData<uint16_t>(m, p.indices)) out.push_back(i);
  else
    out = accessorData<uint32_t>(m, p.indices);
  return out;
}

using Triangle = std::array<Vec3, 3>;

// Every triangle of node `n` and its children (LOD0 of a plant: the node MSFT_lod lists others
// from, with its instanced shapes as children), instances expanded by T·R·S. Nodes carry no
// transforms of their own.
void collect(const tinygltf::Model& m, int n, std::vector<Triangle>& out, size_t* instancedNodes = nullptr) {
  const tinygltf::Node& node = m.nodes.at(size_t(n));
  EXPECT_TRUE(node.matrix.empty() && node.translation.empty() && node.rotation.empty() && node.scale.empty());
  if (node.mesh >= 0) {
    std::vector<Mat4> transforms{Mat4::Identity()};
    auto ext = node.extensions.find("EXT_mesh_gpu_instancing");
    if (ext != node.extensions.end()) {
      if (instancedNodes) ++*instancedNodes;
      const tinygltf::Value& attr = ext->second.Get("attributes");
      const std::vector<float> t = accessorData<float>(m, attr.Get("TRANSLATION").GetNumberAsInt());
      const std::vector<float> r = accessorData<float>(m, attr.Get("ROTATION").GetNumberAsInt());
      const std::vector<float> s = accessorData<float>(m, attr.Get("SCALE").GetNumberAsInt());
      transforms.clear();
      for (size_t i = 0; i < t.size() / 3; ++i) {
        Mat4 x = Mat4::Identity();
        const Quat q(r[4 * i + 3], r[4 * i], r[4 * i + 1], r[4 * i + 2]);
        EXPECT_NEAR(q.norm(), 1.0f, 1e-5f);
        x.topLeftCorner<3, 3>() = q.toRotationMatrix() * Vec3(s[3 * i], s[3 * i + 1], s[3 * i + 2]).asDiagonal();
        x.topRightCorner<3, 1>() = Vec3(t[3 * i], t[3 * i + 1], t[3 * i + 2]);
        transforms.push_back(x);
      }
    }
    for (const tinygltf::Primitive& p : m.meshes.at(size_t(node.mesh)).primitives) {
      const std::vector<float> pos = accessorData<float>(m, p.attributes.at("POSITION"));
      const std::vector<uint32_t> idx = indicesOf(m, p);
      for (const Mat4& x : transforms)
        for (size_t k = 0; k + 2 < idx.size(); k += 3) {
          Triangle tri;
          for (int c = 0; c < 3; ++c) {
            const size_t v = idx[k + size_t(c)];
            tri[size_t(c)] = (x * Vec4(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2], 1.0f)).head<3>();
          }
          out.push_back(tri);
        }
    }
  }
  for (int c : node.children) collect(m, c, out, instancedNodes);
}

// Whether two triangle soups are the same triangles (same winding, any order, any first
// vertex) with positions within `tolerance`.
::testing::AssertionResult sameTriangles(const std::vector<Triangle>& a, const std::vector<Triangle>& b,
                                         float tolerance) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << a.size() << " triangles vs " << b.size();
  const float cell = 1e-3f;
  auto key = [&](const Vec3& c, int dx, int dy, int dz) {
    return std::make_tuple(int64_t(std::floor(c.x() / cell)) + dx, int64_t(std::floor(c.y() / cell)) + dy,
                           int64_t(std::floor(c.z() / cell)) + dz);
  };
  auto centre = [](const Triangle& t) { return Vec3((t[0] + t[1] + t[2]) / 3.0f); };
  std::map<std::tuple<int64_t, int64_t, int64_t>, std::vector<size_t>> grid;
  for (size_t i = 0; i < b.size(); ++i) grid[key(centre(b[i]), 0, 0, 0)].push_back(i);
  std::vector<uint8_t> used(b.size(), 0);
  for (size_t i = 0; i < a.size(); ++i) {
    const Vec3 c = centre(a[i]);
    bool found = false;
    for (int dx = -1; dx <= 1 && !found; ++dx)
      for (int dy = -1; dy <= 1 && !found; ++dy)
        for (int dz = -1; dz <= 1 && !found; ++dz) {
          auto it = grid.find(key(c, dx, dy, dz));
          if (it == grid.end()) continue;
          for (size_t j : it->second) {
            if (used[j]) continue;
            for (int r = 0; r < 3 && !found; ++r)
              if ((a[i][0] - b[j][size_t(r)]).cwiseAbs().maxCoeff() <= tolerance &&
                  (a[i][1] - b[j][size_t((r + 1) % 3)]).cwiseAbs().maxCoeff() <= tolerance &&
                  (a[i][2] - b[j][size_t((r + 2) % 3)]).cwiseAbs().maxCoeff() <= tolerance)
                found = true;
            if (found) {
              used[j] = 1;
              break;
            }
          }
        }
    if (!found)
      return ::testing::AssertionFailure() << "triangle " << i << " at (" << c.transpose() << ") has no match";
  }
  return ::testing::AssertionSuccess();
}

// LOD0 of every plant in the file (the scene's nodes), instances expanded.
std::vector<Triangle> sceneTriangles(const tinygltf::Model& m, size_t* instancedNodes = nullptr) {
  std::vector<Triangle> out;
  for (int n : m.scenes.at(0).nodes) collect(m, n, out, instancedNodes);
  return out;
}

void expectValid(const fs::path& file) {
  const meshtest::GltfValidation v = meshtest::validateGltf(file);
  EXPECT_EQ(v.exitCode, 0) << v.output;
  EXPECT_EQ(v.errors, 0) << v.output;
  EXPECT_EQ(v.warnings, 0) << v.output;
}

TEST(Instancing, DecomposesRotationTimesScaleOnly) {
  Mat4 m = Mat4::Identity();
  const Quat q = Quat(Eigen::AngleAxisf(0.7f, Vec3(1, 2, 3).normalized()));
  m.topLeftCorner<3, 3>() = q.toRotationMatrix() * Vec3(0.5f, 2.0f, 1.5f).asDiagonal();
  m.topRightCorner<3, 1>() = Vec3(1, -2, 3);
  Vec3 t, s;
  Vec4 r;
  ASSERT_TRUE(decomposeTrs(m, t, r, s));
  EXPECT_TRUE(t.isApprox(Vec3(1, -2, 3)));
  EXPECT_TRUE(s.isApprox(Vec3(0.5f, 2.0f, 1.5f), 1e-5f));
  EXPECT_GE(r.w(), 0.0f);
  InstancedShape shape;
  shape.translation = {t};
  shape.rotation = {r};
  shape.scale = {s};
  EXPECT_TRUE(shape.transform(0).isApprox(m, 1e-5f));
  // Sheared, mirrored or flat: not a glTF instance transform.
  Mat4 shear = m;
  shear(0, 1) += 0.3f;
  EXPECT_FALSE(decomposeTrs(shear, t, r, s));
  Mat4 mirror = m;
  mirror.col(0) *= -1.0f;
  EXPECT_FALSE(decomposeTrs(mirror, t, r, s));
  Mat4 flat = m;
  flat.col(2).head<3>().setZero();
  EXPECT_FALSE(decomposeTrs(flat, t, r, s));
}

// The instanced file has the baked file's triangles, is smaller and validates, for the
// sunflower and the rhododendron, on both writer paths.
TEST(Instancing, ExpandedInstancesAreTheBakedTrianglesInASmallerFile) {
  const fs::path dir = meshtest::exportTestDir();
  for (const char* name : {"sunflower", "rhododendron"}) {
    SCOPED_TRACE(name);
    const ExportScene scene = sceneOf({name});
    const fs::path baked = dir / (std::string(name) + "-baked.glb"), inst = dir / (std::string(name) + "-inst.glb"),
                   whole = dir / (std::string(name) + "-whole.glb");
    writeGlb(scene, baked, options(false));
    writeGlb(scene, inst, options(true));
    writeGlb(buildExportModel(scene, options(true)), whole);
    const tinygltf::Model bm = load(baked), im = load(inst);
    size_t instancedNodes = 0;
    const std::vector<Triangle> bt = sceneTriangles(bm), it = sceneTriangles(im, &instancedNodes);
    EXPECT_GT(instancedNodes, 0u);
    EXPECT_TRUE(sameTriangles(it, bt, 1e-5f));
    EXPECT_LT(fs::file_size(inst), fs::file_size(baked));
    std::printf("%s: baked %zu bytes, instanced %zu bytes (%zu instanced shapes)\n", name, size_t(fs::file_size(baked)),
                size_t(fs::file_size(inst)), instancedNodes);
    // Required: no fallback.
    EXPECT_EQ(im.extensionsRequired, std::vector<std::string>{"EXT_mesh_gpu_instancing"});
    EXPECT_TRUE(bm.extensionsUsed.empty());
    // Every copy carries its node id, a node of the plant.
    for (const tinygltf::Node& node : im.nodes) {
      auto ext = node.extensions.find("EXT_mesh_gpu_instancing");
      if (ext == node.extensions.end()) continue;
      const std::vector<float> ids = accessorData<float>(im, ext->second.Get("attributes").Get("_NODE_ID").GetNumberAsInt());
      for (float id : ids) EXPECT_LT(size_t(id), scene.plants[0].nodeCount());
    }
    expectValid(inst);
    // The streamed writer's bytes are the whole model's (only the JSON chunk's padding differs).
    const std::vector<uint8_t> s = readFileBytes(inst), w = readFileBytes(whole);
    uint32_t sj = 0, wj = 0;
    std::memcpy(&sj, s.data() + 12, 4);
    std::memcpy(&wj, w.data() + 12, 4);
    EXPECT_TRUE(std::equal(s.begin() + 20 + sj, s.end(), w.begin() + 20 + wj, w.end()));
    EXPECT_GT(sj, wj + 3);  // streamed, not written again the simple way
  }
  // The chestnut's leaves are each bent by the graph's deformation into a mesh of its own:
  // nothing repeats, nothing is instanced, and the file is the baked one, byte for byte.
  const ExportScene chestnut = sceneOf({"chestnut"});
  writeGlb(chestnut, dir / "chestnut-baked.glb", options(false));
  writeGlb(chestnut, dir / "chestnut-inst.glb", options(true));
  EXPECT_TRUE(readFileBytes(dir / "chestnut-baked.glb") == readFileBytes(dir / "chestnut-inst.glb"));
}

// With LOD chains, a leaf atlas, wind data and several plants: LOD0 as the baked file's, the
// lower levels baked as they were, valid, both writers alike, the same bytes at 1-8 threads.
TEST(Instancing, ComposesWithLodsAtlasWindAndPlants) {
  const fs::path dir = meshtest::exportTestDir();
  const ExportScene scene = [] {
    ExportScene s = sceneOf({"sunflower", "agave", "fig2"});
    // Wind tables (io only writes them): a distinct record per node.
    for (const PlantModel& p : s.plants) {
      std::vector<WindVertexNode>& table = s.wind.emplace_back(p.nodeCount());
      for (size_t n = 0; n < table.size(); ++n)
        table[n] = {Vec3(float(n), 1.0f, 2.0f), Vec3(0.0f, float(n) * 0.01f, 1.0f), float(n % 7) / 7.0f,
                    float(n % 11) / 11.0f, 0.5f};
    }
    return s;
  }();
  const ExportOptions inst = options(true, 3, true), plain = options(false, 3, true);
  writeGlb(scene, dir / "baked.glb", plain);
  writeGlb(scene, dir / "inst.glb", inst);
  writeGlb(buildExportModel(scene, inst), dir / "whole.glb", &scene.wind);
  expectValid(dir / "inst.glb");
  const tinygltf::Model bm = load(dir / "baked.glb"), im = load(dir / "inst.glb");
  size_t instancedNodes = 0;
  EXPECT_TRUE(sameTriangles(sceneTriangles(im, &instancedNodes), sceneTriangles(bm), 1e-5f));
  EXPECT_GT(instancedNodes, 1u);
  // Lower levels: the same meshes, baked.
  std::map<std::string, std::vector<Triangle>> lower;
  for (size_t n = 0; n < bm.nodes.size(); ++n)
    if (bm.nodes[n].name.find("_LOD0") == std::string::npos && bm.nodes[n].mesh >= 0)
      collect(bm, int(n), lower[bm.nodes[n].name]);
  size_t compared = 0;
  for (size_t n = 0; n < im.nodes.size(); ++n) {
    const tinygltf::Node& node = im.nodes[n];
    if (node.name.find("_LOD0") != std::string::npos || !lower.count(node.name)) continue;
    std::vector<Triangle> t;
    collect(im, int(n), t);
    EXPECT_TRUE(sameTriangles(t, lower[node.name], 0.0f)) << node.name;
    ++compared;
  }
  EXPECT_EQ(compared, 6u);  // three plants × LOD1, LOD2
  // Per copy, the wind record of its node, as a baked vertex of that node has it.
  size_t copies = 0;
  for (const tinygltf::Node& node : im.nodes) {
    auto ext = node.extensions.find("EXT_mesh_gpu_instancing");
    if (ext == node.extensions.end()) continue;
    size_t plant = 0;
    while (plant < scene.plants.size() && node.name.rfind(scene.plants[plant].name + "_LOD0-", 0) != 0) ++plant;
    ASSERT_LT(plant, scene.plants.size()) << node.name;
    const tinygltf::Value& attr = ext->second.Get("attributes");
    if (!attr.Has("_NODE_ID")) {  // a plant without skeleton nodes (the agave): no node ids, no wind
      EXPECT_EQ(scene.plants[plant].nodeCount(), 0u) << node.name;
      EXPECT_FALSE(attr.Has("_WIND_PIVOT")) << node.name;
      continue;
    }
    const std::vector<float> ids = accessorData<float>(im, attr.Get("_NODE_ID").GetNumberAsInt());
    const std::vector<float> colour = accessorData<float>(im, attr.Get("_WIND_COLOR").GetNumberAsInt());
    const std::vector<float> pivot = accessorData<float>(im, attr.Get("_WIND_PIVOT").GetNumberAsInt());
    const std::vector<float> axis = accessorData<float>(im, attr.Get("_WIND_AXIS").GetNumberAsInt());
    ASSERT_EQ(colour.size(), 4 * ids.size());
    for (size_t i = 0; i < ids.size(); ++i, ++copies) {
      const WindVertexNode& w = scene.wind[plant].at(size_t(ids[i]));
      EXPECT_EQ(Vec3(pivot[3 * i], pivot[3 * i + 1], pivot[3 * i + 2]), w.pivot);
      EXPECT_EQ(Vec3(axis[3 * i], axis[3 * i + 1], axis[3 * i + 2]), w.lever);
      EXPECT_EQ(Vec4(colour[4 * i], colour[4 * i + 1], colour[4 * i + 2], colour[4 * i + 3]),
                Vec4(w.level, w.phase, w.period, 0.0f));
    }
  }
  EXPECT_GT(copies, 50u);  // the sunflower's and the fig's
  const std::vector<uint8_t> s = readFileBytes(dir / "inst.glb"), w = readFileBytes(dir / "whole.glb");
  uint32_t sj = 0, wj = 0;
  std::memcpy(&sj, s.data() + 12, 4);
  std::memcpy(&wj, w.data() + 12, 4);
  EXPECT_TRUE(std::equal(s.begin() + 20 + sj, s.end(), w.begin() + 20 + wj, w.end()));
  test::sameAtEveryThreadCount([&] {
    writeGlb(scene, dir / "threads.glb", inst);
    return readFileBytes(dir / "threads.glb");
  });
}

// A shape is instanced only where that is smaller: one copy of a shape stays baked.
TEST(Instancing, SingleCopiesStayBaked) {
  const PlantModel p = graphPlant("sunflower");
  std::vector<size_t> uses(p.meshes.size(), 0);
  for (const plant::Primitive& pr : p.primitives) ++uses[pr.mesh];
  mesh::PlantMesh pm;
  mesh::buildPlantMesh(p, {}, pm);
  const PlantInstancing inst = instancePrimitives(p, pm.primitives, {});
  ASSERT_FALSE(inst.empty());
  size_t instancedCopies = 0;
  for (const InstancedShape& s : inst.shapes) {
    EXPECT_GT(uses[s.mesh], 1u) << s.name;
    instancedCopies += s.instances();
  }
  // Every primitive is an instance or in the rest.
  size_t restTriangles = 0, instancedTriangles = 0, bakedTriangles = 0;
  for (const TriangleMesh& r : inst.rest) restTriangles += r.triangleCount();
  for (const InstancedShape& s : inst.shapes) instancedTriangles += s.instances() * s.shape.triangleCount();
  for (size_t g = 0; g < pm.primitives.size(); ++g)
    if (inst.instanced[g]) bakedTriangles += pm.primitives[g].mesh.triangleCount();
  EXPECT_EQ(restTriangles + instancedTriangles, bakedTriangles);
  EXPECT_GT(instancedCopies, 10u);
}

TEST(Instancing, SceneSettingAndCommandLine) {
  const fs::path dir = test::scratchDir();
  const fs::path file = dir / "inst.json";
  test::writeText(file, R"({"tendril": 1, "plants": [], "output": {"instancing": true}})");
  EXPECT_TRUE(session::exportOptions(scene::loadScene(file).output).instancing);
  test::writeText(file, R"({"tendril": 1, "plants": []})");
  EXPECT_FALSE(session::exportOptions(scene::loadScene(file).output).instancing);
  // A bad value: one line naming the file and the key.
  test::writeText(file, R"({"tendril": 1, "plants": [], "output": {"instancing": "yes"}})");
  try {
    scene::loadScene(file);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(file.string() + ":/output/instancing:", 0), 0u) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  test::CommandResult r = test::runTendril("model " + test::quoted(test::sourceDir() / "examples/graphs/sunflower.json") +
                                               " -o " + test::quoted(dir / "sunflower.glb") + " --instancing=maybe",
                                           dir);
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.err.find("--instancing"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  r = test::runTendril("model " + test::quoted(test::sourceDir() / "examples/graphs/sunflower.json") + " -o " +
                           test::quoted(dir / "sunflower.glb") + " --instancing -q",
                       dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const tinygltf::Model m = load(dir / "sunflower.glb");
  EXPECT_EQ(m.extensionsRequired, std::vector<std::string>{"EXT_mesh_gpu_instancing"});
}

}  // namespace
}  // namespace tendril::io
