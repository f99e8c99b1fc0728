// The impostor (io/impostor.h, render/impostor_baker.h; issue 26 part 3): a slab billboard
// cloud baked with the renderer as each plant's last level of detail. Quads and their bounds,
// texels empty where a slab has nothing, the alpha-tested silhouette from eight views close to
// LOD0's, the .glb (MSFT_lod, validator, thread-count independence), the .obj and the errors.
#include "tendril/io/impostor.h"

#include "support/determinism.h"
#include "support/eight_views.h"
#include "support/example_plants.h"
#include "support/gltf_read.h"
#include "support/gltf_validator.h"
#include "support/silhouette.h"
#include "support/test_paths.h"
#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"
#include "tendril/graph/build_plant.h"
#include "tendril/graph/graph.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/atomic_file.h"
#include "tendril/io/image.h"
#include "tendril/io/obj_writer.h"
#include "tendril/render/impostor_baker.h"
#include "tendril/scene/scene.h"
#include "tendril/session/session.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

namespace tendril {
namespace {

namespace fs = std::filesystem;
using plant::PlantModel;

// Seed 004's chestnut (a component graph with leaves).
const PlantModel& chestnut() { return test::exampleChestnut(); }

// A climbing ivy (seed 003) on the default scene's wall.
const PlantModel& climbingIvy() { return test::exampleClimbingIvy(); }

// The sunflower component graph (seed 004): primitives on a stem.
const PlantModel& sunflower() {
  static const PlantModel p = [] {
    auto g = graph::loadGraph(test::sourceDir() / "examples/graphs/sunflower.json");
    PlantModel m = graph::generatePlant(g, {g->seed, {}});
    m.name = "sunflower";
    return m;
  }();
  return p;
}

struct Named {
  const char* name;
  const PlantModel& (*plant)();
};
const Named kPlants[] = {
    {"chestnut", chestnut}, {"climbing ivy", climbingIvy}, {"sunflower", sunflower}};

io::ExportScene sceneOf(const PlantModel& p) {
  io::ExportScene s;
  s.plants.push_back(p);
  return s;
}

io::ExportOptions impostorOptions(int lods = 1) {
  io::ExportOptions o;
  o.lods.levels = lods;
  o.impostor.enabled = true;
  return o;
}

// Every test here bakes with the renderer's baker, as the CLI, studio and Python module do.
class Impostor : public ::testing::Test {
 protected:
  void SetUp() override { render::installRendererImpostorBaker(); }
};

using Drawn = test::DrawnPart;
using test::silhouette;
using test::ViewFrame;
ViewFrame viewFrame(const std::vector<Drawn>& parts, const Vec3& view) { return test::viewFrame(parts, view, 0.6f); }

// A model's images, decoded, by texture index.
struct Decoded {
  std::map<int, io::Image> images;
  const io::Image* of(const io::ExportModel& model, int texture) {
    if (texture < 0) return nullptr;
    const int image = model.textures[size_t(texture)].image;
    if (!images.count(image))
      images[image] = io::decodeImage(model.images[size_t(image)].image.bytes, model.images[size_t(image)].spec);
    return &images[image];
  }
};

std::vector<Drawn> drawnLevel(const io::ExportModel& model, size_t level, Decoded& decoded) {
  std::vector<Drawn> out;
  for (const io::ExportPart& part : model.objects[0].partsOf(level)) {
    const io::ExportMaterial& m = model.materials[size_t(part.material)];
    out.push_back({part.mesh, decoded.of(model, m.texture), m.alphaMask});
  }
  return out;
}

// --- layout ---

TEST_F(Impostor, QuadsCoverThePlantInThreeFamiliesOfSlabs) {
  for (const Named& n : kPlants) {
    SCOPED_TRACE(n.name);
    const io::ExportOptions options = impostorOptions();
    io::ExportModel model = io::buildExportModel(sceneOf(n.plant()), options);
    ASSERT_EQ(model.impostors.size(), 1u);
    const io::Impostor& imp = model.impostors[0];
    const io::ExportObject& object = model.objects[0];
    // The impostor is the last level: LOD1 here, one part, its own material.
    ASSERT_EQ(object.levels(), 2u);
    ASSERT_EQ(object.partsOf(1).size(), 1u);
    EXPECT_EQ(object.partsOf(1)[0].mesh, &imp.mesh);
    EXPECT_EQ(io::levelName(object, 1), object.name + "_LOD1");
    ASSERT_EQ(object.screenCoverage.size(), 2u);
    EXPECT_GT(object.screenCoverage[0], object.screenCoverage[1]);
    const io::ExportMaterial& mat = model.materials[size_t(object.partsOf(1)[0].material)];
    EXPECT_EQ(mat.kind, io::ExportMaterial::Kind::Impostor);
    EXPECT_TRUE(mat.alphaMask);
    EXPECT_TRUE(mat.doubleSided);
    EXPECT_GE(mat.texture, 0);
    EXPECT_GE(mat.normalTexture, 0);

    // Per family at most `slabs` quads and at least one, and at most kImpostorFlatQuads flat
    // parts on quads of their own (the sunflower's head); four vertices and two triangles each.
    std::array<int, 4> perAxis{};
    for (const io::ImpostorQuad& q : imp.quads) ++perAxis[size_t(q.axis)];
    EXPECT_LE(perAxis[3], io::kImpostorFlatQuads);
    EXPECT_EQ(perAxis[3] > 0, std::string(n.name) == "sunflower");
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(perAxis[size_t(a)], 1) << "axis " << a;
      EXPECT_LE(perAxis[size_t(a)], options.impostor.slabs) << "axis " << a;
    }
    EXPECT_EQ(imp.mesh.positions.size(), 4 * imp.quads.size());
    EXPECT_EQ(imp.mesh.triangleCount(), 2 * imp.quads.size());
    EXPECT_EQ(imp.tangents.size(), imp.mesh.positions.size());

    // Bounds: the quads stay within LOD0's bounds grown by two texels, and reach them on every
    // side (each family spans the plant across its axis).
    Bounds3 lod0;
    for (const io::ExportPart& part : object.parts)
      for (uint32_t i : part.mesh->indices) lod0.extend(part.mesh->positions[i]);
    const float texel = lod0.size().maxCoeff() / float(options.impostor.resolution);
    Bounds3 quads;
    for (const Vec3& p : imp.mesh.positions) quads.extend(p);
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(quads.min[a], lod0.min[a] - 2.5f * texel) << "axis " << a;
      EXPECT_LE(quads.max[a], lod0.max[a] + 2.5f * texel) << "axis " << a;
      EXPECT_LE(quads.min[a], lod0.min[a] + 0.5f * lod0.size()[a] / float(options.impostor.slabs) + texel);
      EXPECT_GE(quads.max[a], lod0.max[a] - 0.5f * lod0.size()[a] / float(options.impostor.slabs) - texel);
    }
    // A family's quad lies within its slab (at the mean depth of what it shows), facing along
    // its axis, and the slabs are equally thick; a flat part's quad faces along its unit normal
    // and shows that part alone.
    const float thickness = lod0.size().maxCoeff() / float(options.impostor.slabs);
    for (const io::ImpostorQuad& q : imp.quads) {
      if (q.axis == 3) {
        EXPECT_NEAR(q.view.normal.norm(), 1.0f, 1e-5f);
        EXPECT_GE(q.view.surface, 0);
        continue;
      }
      EXPECT_EQ(q.view.surface, -1);
      EXPECT_EQ(q.view.normal, Vec3::Unit(q.axis));
      EXPECT_LE(q.view.lo, 0.0f);
      EXPECT_GE(q.view.hi, 0.0f);
      EXPECT_LE(q.view.hi - q.view.lo, 1.01f * thickness);
    }
    // Quads at the mean depth of their slab's content, not its middle: somewhere a quad is off
    // its slab's middle by more than a tenth of the slab (a stem in a slab lies on its quad).
    EXPECT_TRUE(std::any_of(imp.quads.begin(), imp.quads.end(), [](const io::ImpostorQuad& q) {
      return q.axis < 3 && std::abs(q.view.lo + q.view.hi) > 0.2f * (q.view.hi - q.view.lo);
    }));
  }
}

// Clips polygon `poly` to lo <= (p − origin) · normal <= hi; the polygon that remains (maybe empty).
std::vector<Vec3> clipToSlab(std::vector<Vec3> poly, const Vec3& origin, const Vec3& normal, float lo, float hi) {
  auto depth = [&](const Vec3& q) { return (q - origin).dot(normal); };
  for (int side = 0; side < 2; ++side) {
    std::vector<Vec3> out;
    auto inside = [&](const Vec3& q) { return side == 0 ? depth(q) >= lo : depth(q) <= hi; };
    const float plane = side == 0 ? lo : hi;
    for (size_t i = 0; i < poly.size(); ++i) {
      const Vec3& c = poly[i];
      const Vec3& n = poly[(i + 1) % poly.size()];
      if (inside(c)) out.push_back(c);
      if (inside(c) != inside(n)) out.push_back(c + (plane - depth(c)) / (depth(n) - depth(c)) * (n - c));
    }
    poly = std::move(out);
  }
  return poly;
}

// Texels: a quad's colour is transparent wherever nothing of the plant lies in its slab. The
// reference: LOD0's triangles clipped to the slab, marked conservatively (their bounding boxes
// in texels, grown by one) in the quad's texel grid. Without the slab clipping every quad would
// show the whole plant, and its texels would be opaque where its slab is empty.
TEST_F(Impostor, TexelsAreTransparentWhereTheSlabIsEmpty) {
  for (const Named& n : kPlants) {
    SCOPED_TRACE(n.name);
    io::ExportModel model = io::buildExportModel(sceneOf(n.plant()), impostorOptions());
    const io::Impostor& imp = model.impostors[0];
    size_t opaqueTotal = 0, strayTotal = 0;
    for (const io::ImpostorQuad& q : imp.quads) {
      const io::ImpostorView& v = q.view;
      const Vec3 du = v.u / v.u.squaredNorm(), dv = v.v / v.v.squaredNorm();
      std::vector<uint8_t> occupied(size_t(v.width) * size_t(v.height), 0);
      for (const io::ExportPart& part : model.objects[0].parts) {
        const TriangleMesh& m = *part.mesh;
        for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
          const std::vector<Vec3> poly = clipToSlab(
              {m.positions[m.indices[t]], m.positions[m.indices[t + 1]], m.positions[m.indices[t + 2]]}, v.corner,
              v.normal, v.lo, v.hi);
          if (poly.empty()) continue;
          Vec2 lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
          for (const Vec3& p : poly) {
            const Vec2 texel((p - v.corner).dot(du) * float(v.width), (p - v.corner).dot(dv) * float(v.height));
            lo = lo.cwiseMin(texel);
            hi = hi.cwiseMax(texel);
          }
          for (int y = std::max(0, int(std::floor(lo.y())) - 1); y <= std::min(v.height - 1, int(hi.y()) + 1); ++y)
            for (int x = std::max(0, int(std::floor(lo.x())) - 1); x <= std::min(v.width - 1, int(hi.x()) + 1); ++x)
              occupied[size_t(y) * size_t(v.width) + size_t(x)] = 1;
        }
      }
      size_t opaque = 0, stray = 0;
      for (int y = 0; y < v.height; ++y)
        for (int x = 0; x < v.width; ++x) {
          if (imp.color.pixel(q.atlasX + x, q.atlasY + y)[3] == 0) continue;
          ++opaque;
          if (!occupied[size_t(y) * size_t(v.width) + size_t(x)]) ++stray;
        }
      EXPECT_GT(opaque, 0u) << "axis " << q.axis << " slab " << q.slab;
      opaqueTotal += opaque;
      strayTotal += stray;
    }
    EXPECT_EQ(strayTotal, 0u) << "of " << opaqueTotal << " opaque texels";
    // Outside every quad's cell the atlas is transparent.
    size_t inCells = 0, opaqueAll = 0;
    for (const io::ImpostorQuad& q : imp.quads) inCells += size_t(q.view.width) * size_t(q.view.height);
    for (int y = 0; y < imp.color.height; ++y)
      for (int x = 0; x < imp.color.width; ++x) opaqueAll += imp.color.pixel(x, y)[3] > 0;
    EXPECT_EQ(opaqueAll, opaqueTotal);
    EXPECT_LT(opaqueTotal, inCells);  // alpha-tested: not every texel is covered
  }
}

// The normal texture holds unit normals facing the viewer of their slab (blue >= 0.5).
TEST_F(Impostor, NormalTexelsAreUnitAndFaceTheQuadsSide) {
  io::ExportModel model = io::buildExportModel(sceneOf(chestnut()), impostorOptions());
  const io::Impostor& imp = model.impostors[0];
  size_t checked = 0;
  for (int y = 0; y < imp.normal.height; ++y)
    for (int x = 0; x < imp.normal.width; ++x) {
      if (imp.color.pixel(x, y)[3] == 0) continue;
      const uint8_t* n = imp.normal.pixel(x, y);
      const Vec3 v(float(n[0]) / 127.5f - 1.0f, float(n[1]) / 127.5f - 1.0f, float(n[2]) / 127.5f - 1.0f);
      ASSERT_NEAR(v.norm(), 1.0f, 0.03f) << x << ", " << y;
      ASSERT_GE(v.z(), -0.01f) << x << ", " << y;
      ++checked;
    }
  EXPECT_GT(checked, 1000u);
}

// --- silhouette ---

// From the eight views of the LOD test, the alpha-tested silhouette of the impostor (its quads
// rasterised with the atlas's alpha) stays within 10 % of LOD0's (leaves alpha-tested with their
// textures), for a tree, an ivy on a wall and a graph plant of large flat primitives; and the
// leaves' coverage — the impostor's texels its normal texture marks as leaf
// (alpha 255) against LOD0's alpha-tested leaves alone — within 15 %.
TEST_F(Impostor, SilhouetteAndLeafCoverageFromEightViewsStayCloseToLod0) {
  for (const Named& n : kPlants) {
    SCOPED_TRACE(n.name);
    io::ExportModel model = io::buildExportModel(sceneOf(n.plant()), impostorOptions());
    Decoded decoded;
    const std::vector<Drawn> lod0 = drawnLevel(model, 0, decoded);
    const std::vector<Drawn> impostor = drawnLevel(model, 1, decoded);
    ASSERT_EQ(impostor.size(), 1u);
    ASSERT_TRUE(impostor[0].alphaMask && impostor[0].texture);
    // The leaves alone: LOD0's alpha-tested parts; the impostor's quads cut by the leaf mask.
    std::vector<Drawn> leaves0;
    for (const Drawn& d : lod0)
      if (d.alphaMask) leaves0.push_back(d);
    const io::ExportMaterial& mat = model.materials[size_t(model.objects[0].partsOf(1)[0].material)];
    const std::vector<Drawn> impostorLeaves{{impostor[0].mesh, decoded.of(model, mat.normalTexture), true, 192}};
    double worst = 0.0, worstLeaves = 0.0;
    for (const Vec3& view : test::eightViews()) {
      const ViewFrame f = viewFrame(lod0, view);
      const size_t a0 = silhouette(lod0, f), a1 = silhouette(impostor, f);
      SCOPED_TRACE(fmt::format("view ({:.2f}, {:.2f}, {:.2f}): LOD0 {} cells, impostor {}", view.x(), view.y(),
                               view.z(), a0, a1));
      ASSERT_GT(a0, 1000u);
      const double error = std::abs(double(a1) - double(a0)) / double(a0);
      worst = std::max(worst, error);
      EXPECT_LE(error, 0.10);
      const size_t l0 = silhouette(leaves0, f), l1 = silhouette(impostorLeaves, f);
      if (leaves0.empty()) {
        EXPECT_EQ(l1, 0u) << "no leaves, no leaf texels";
        continue;
      }
      SCOPED_TRACE(fmt::format("leaves: LOD0 {} cells, impostor {}", l0, l1));
      ASSERT_GT(l0, 500u);
      const double leafError = std::abs(double(l1) - double(l0)) / double(l0);
      worstLeaves = std::max(worstLeaves, leafError);
      EXPECT_LE(leafError, 0.15);
    }
    std::printf("[ impostor ] %s: worst silhouette difference %.1f %%, leaf coverage %.1f %%\n", n.name, 100.0 * worst,
                100.0 * worstLeaves);
  }
}

// --- files ---

size_t countOf(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST_F(Impostor, GlbHasTheImpostorAsLastMsftLodLevelAndValidates) {
  const fs::path dir = meshtest::exportTestDir();
  io::ExportScene scene = sceneOf(chestnut());
  scene.plants.push_back(sunflower());
  io::ExportOptions options = impostorOptions(3);
  options.leafAtlas = true;
  io::writeGlb(scene, dir / "plants.glb", options);
  const meshtest::GltfValidation v = meshtest::validateGltf(dir / "plants.glb");
  EXPECT_EQ(v.errors, 0) << v.output;
  EXPECT_EQ(v.warnings, 0) << v.output;

  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, (dir / "plants.glb").string())) << err;
  for (const char* name : {"chestnut", "sunflower"}) {
    SCOPED_TRACE(name);
    int lod0 = -1;
    for (size_t i = 0; i < m.nodes.size(); ++i)
      if (m.nodes[i].name == std::string(name) + "_LOD0") lod0 = int(i);
    ASSERT_GE(lod0, 0);
    const tinygltf::Value& ids = m.nodes[size_t(lod0)].extensions.at("MSFT_lod").Get("ids");
    ASSERT_EQ(ids.ArrayLen(), 3u);  // LOD1, LOD2 and the impostor, LOD3
    const tinygltf::Node& last = m.nodes.at(size_t(ids.Get(2).GetNumberAsInt()));
    EXPECT_EQ(last.name, std::string(name) + "_LOD3");
    EXPECT_EQ(m.nodes[size_t(lod0)].extras.Get("MSFT_screencoverage").ArrayLen(), 4u);
    const tinygltf::Mesh& mesh = m.meshes.at(size_t(last.mesh));
    ASSERT_EQ(mesh.primitives.size(), 1u);
    const tinygltf::Primitive& prim = mesh.primitives[0];
    EXPECT_TRUE(prim.attributes.count("TANGENT"));
    EXPECT_TRUE(prim.attributes.count("NORMAL"));
    EXPECT_TRUE(prim.attributes.count("TEXCOORD_0"));
    const tinygltf::Material& mat = m.materials.at(size_t(prim.material));
    EXPECT_EQ(mat.alphaMode, "MASK");
    EXPECT_EQ(mat.alphaCutoff, 0.5);
    EXPECT_TRUE(mat.doubleSided);
    EXPECT_GE(mat.pbrMetallicRoughness.baseColorTexture.index, 0);
    EXPECT_GE(mat.normalTexture.index, 0);
  }
}

TEST_F(Impostor, BytesDoNotDependOnThreadCountAndWindDataSwaysFromTheRoot) {
  const fs::path dir = meshtest::exportTestDir();
  io::ExportScene scene = sceneOf(chestnut());
  scene.plants[0].name = "chestnut";
  // Engine wind data: a table for the plant (the impostor's vertices take the root's record).
  scene.wind.resize(1);
  scene.wind[0].resize(scene.plants[0].nodeCount());
  for (size_t i = 0; i < scene.wind[0].size(); ++i) {
    scene.wind[0][i].pivot = scene.plants[0].position[i];
    scene.wind[0][i].level = float(i == 0 ? 0 : 1);
  }
  int run = 0;
  test::sameAtEveryThreadCount([&] {
    const fs::path file = dir / fmt::format("run{}.glb", run++);
    io::writeGlb(scene, file, impostorOptions(2));
    return io::readFileBytes(file);
  });
  const meshtest::GltfValidation v = meshtest::validateGltf(dir / "run0.glb");
  EXPECT_EQ(v.errors, 0) << v.output;
  EXPECT_EQ(v.warnings, 0) << v.output;
  const tinygltf::Model m = test::loadGlb(dir / "run0.glb");
  const tinygltf::Node& impostorNode = m.nodes.back();
  ASSERT_EQ(impostorNode.name, "chestnut_LOD2");
  const tinygltf::Primitive& prim = m.meshes.at(size_t(impostorNode.mesh)).primitives.at(0);
  ASSERT_TRUE(prim.attributes.count("_WIND_PIVOT"));
  const tinygltf::Accessor& a = m.accessors.at(size_t(prim.attributes.at("_WIND_PIVOT")));
  const tinygltf::BufferView& bv = m.bufferViews.at(size_t(a.bufferView));
  const float* pivots = reinterpret_cast<const float*>(m.buffers[0].data.data() + bv.byteOffset + a.byteOffset);
  for (size_t i = 0; i < a.count; ++i)
    for (int k = 0; k < 3; ++k) ASSERT_EQ(pivots[3 * i + size_t(k)], scene.plants[0].position[0][k]);
  // The sunflower's flat pieces on quads of their own, too.
  const io::ExportScene flat = sceneOf(sunflower());
  test::sameAtEveryThreadCount([&] {
    const fs::path file = dir / fmt::format("run{}.glb", run++);
    io::writeGlb(flat, file, impostorOptions(2));
    return io::readFileBytes(file);
  });
}

TEST_F(Impostor, ObjWritesTheImpostorLevelWithItsTextures) {
  const fs::path dir = meshtest::exportTestDir();
  io::writeObj(sceneOf(sunflower()), dir / "plant.obj", impostorOptions(2));
  ASSERT_TRUE(fs::exists(dir / "plant_LOD1.obj"));
  ASSERT_TRUE(fs::exists(dir / "plant_LOD2.obj"));
  EXPECT_FALSE(fs::exists(dir / "plant_LOD3.obj"));
  std::ifstream objIn(dir / "plant_LOD2.obj"), mtlIn(dir / "plant.mtl");
  std::stringstream obj, mtl;
  obj << objIn.rdbuf();
  mtl << mtlIn.rdbuf();
  EXPECT_NE(obj.str().find("usemtl impostor"), std::string::npos);
  EXPECT_EQ(countOf(obj.str(), "\nf "), 2 * (countOf(obj.str(), "\nv ") / 4));
  EXPECT_NE(mtl.str().find("map_Kd plant_impostor0.png"), std::string::npos) << mtl.str();
  EXPECT_NE(mtl.str().find("map_d plant_impostor0.png"), std::string::npos) << mtl.str();
  EXPECT_NE(mtl.str().find("norm plant_impostor0_normal.png"), std::string::npos) << mtl.str();
  EXPECT_TRUE(fs::exists(dir / "plant_impostor0.png"));
  EXPECT_TRUE(fs::exists(dir / "plant_impostor0_normal.png"));
}

// --- errors ---

TEST_F(Impostor, BadSettingsAndAMissingBakerAreOneLineErrors) {
  auto message = [](auto&& f) -> std::string {
    try {
      f();
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  io::ExportOptions o = impostorOptions();
  o.impostor.slabs = 0;
  std::string m = message([&] { io::buildExportModel(sceneOf(sunflower()), o); });
  EXPECT_NE(m.find("slabs must be between 1 and 16, got 0"), std::string::npos) << m;
  o = impostorOptions();
  o.impostor.resolution = 4096;
  m = message([&] { io::buildExportModel(sceneOf(sunflower()), o); });
  EXPECT_NE(m.find("resolution must be between 16 and 2048"), std::string::npos) << m;

  io::installImpostorBaker(nullptr);
  for (bool stream : {false, true}) {
    const fs::path file = meshtest::exportTestDir() / "none.glb";
    m = message([&] {
      if (stream)
        io::writeGlb(sceneOf(sunflower()), file, impostorOptions());
      else
        io::buildExportModel(sceneOf(sunflower()), impostorOptions());
    });
    EXPECT_NE(m.find("no impostor baker is installed"), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    EXPECT_FALSE(fs::exists(file));
  }
  render::installRendererImpostorBaker();

  // The scene's output.impostor: strict.
  auto parse = [&](const std::string& output) {
    return message([&] {
      scene::parseScene(parseJson(fmt::format(R"({{"tendril": 1, "output": {{"impostor": {}}}}})", output), "s.json"),
                        "s.json", test::sourceDir());
    });
  };
  EXPECT_EQ(parse("true"), "");
  EXPECT_EQ(parse(R"({"slabs": 6, "resolution": 128})"), "");
  m = parse("3");
  EXPECT_NE(m.find("s.json"), std::string::npos) << m;
  EXPECT_NE(m.find("impostor"), std::string::npos) << m;
  m = parse(R"({"slabs": 0})");
  EXPECT_NE(m.find("/output/impostor/slabs"), std::string::npos) << m;
  m = parse(R"({"slab": 4})");
  EXPECT_NE(m.find("slab"), std::string::npos) << m;
  EXPECT_NE(parse(R"({"resolution": 8})"), "");
  const scene::Scene s = scene::parseScene(
      parseJson(R"({"tendril": 1, "output": {"impostor": {"slabs": 6, "resolution": 128}}})", "s.json"), "s.json",
      test::sourceDir());
  EXPECT_TRUE(s.output.impostor);
  EXPECT_EQ(s.output.impostorSlabs, 6);
  EXPECT_EQ(s.output.impostorResolution, 128);
}

}  // namespace
}  // namespace tendril
