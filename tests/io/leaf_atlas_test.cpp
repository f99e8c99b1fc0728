// Leaf atlases (io/leaf_atlas.h, issue 26 part 2): a plant's leaf textures in one image, its
// leaves one material and one part on every level of detail, UVs remapped so that every leaf
// shows the texels it showed before.
#include "tendril/io/leaf_atlas.h"

#include "support/determinism.h"
#include "support/gltf_validator.h"
#include "support/run_command.h"
#include "support/synthetic_plants.h"
#include "support/test_paths.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/image.h"
#include "tendril/io/obj_writer.h"
#include "tendril/scene/scene.h"
#include "tendril/session/plant_export.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>

namespace tendril::io {
namespace {

namespace fs = std::filesystem;
using plant::PlantModel;

// Two ivies of the same species (three shapes, ivy-0/1/2, white tints: one shared atlas) and a
// tree with three differently tinted shapes (its tints baked into its own atlas).
ExportScene atlasScene() {
  ExportScene scene;
  PlantModel ivy = meshtest::syntheticIvy(600);
  scene.plants.push_back(ivy);
  PlantModel tree = meshtest::branchingTree();
  meshtest::addLeaves(tree, 3);
  tree.name = "tree";
  scene.plants.push_back(tree);
  PlantModel ivy2 = meshtest::syntheticIvy(300, 7);
  ivy2.name = "ivy 2";
  scene.plants.push_back(ivy2);
  return scene;
}

ExportOptions atlasOptions(int levels = 1) {
  ExportOptions o;
  o.leafAtlas = true;
  o.lods.levels = levels;
  return o;
}

const ExportPart* leafPart(const std::vector<ExportPart>& parts) {
  const ExportPart* found = nullptr;
  for (const ExportPart& p : parts)
    if (p.source == PartSource::Leaves) {
      EXPECT_EQ(found, nullptr) << "more than one leaf part";
      found = &p;
    }
  return found;
}

// The texel (RGBA) under a mesh-convention UV (v up) with nearest sampling, and whether the
// point is clear of texel borders (so that float rounding cannot pick a neighbour).
struct Texel {
  std::array<uint8_t, 4> rgba{};
  bool clear = false;
};
Texel sample(const Image& img, const Vec2& uv) {
  const double x = double(uv.x()) * img.width, y = (1.0 - double(uv.y())) * img.height;
  const double fx = x - std::floor(x), fy = y - std::floor(y);
  Texel t;
  t.clear = fx > 0.01 && fx < 0.99 && fy > 0.01 && fy < 0.99;
  const int ix = std::clamp(int(std::floor(x)), 0, img.width - 1), iy = std::clamp(int(std::floor(y)), 0, img.height - 1);
  std::memcpy(t.rgba.data(), img.pixel(ix, iy), 4);
  return t;
}

TEST(LeafAtlas, EachPlantHasOneLeafMaterialAndTextureOnEveryLevel) {
  const ExportScene scene = atlasScene();
  const ExportModel plain = buildExportModel(scene, ExportOptions{});
  const ExportModel model = buildExportModel(scene, atlasOptions(3));
  ASSERT_EQ(model.objects.size(), 3u);
  std::set<int> leafMaterials;
  for (size_t i = 0; i < scene.plants.size(); ++i) {
    SCOPED_TRACE(scene.plants[i].name);
    const ExportObject& o = model.objects[i];
    const ExportPart* leaves = leafPart(o.parts);
    ASSERT_NE(leaves, nullptr);
    EXPECT_EQ(leaves->name, "leaves");
    const ExportMaterial& m = model.materials[size_t(leaves->material)];
    EXPECT_EQ(m.kind, ExportMaterial::Kind::Leaf);
    EXPECT_TRUE(m.alphaMask);
    ASSERT_GE(m.texture, 0);
    EXPECT_EQ(model.images[size_t(model.textures[size_t(m.texture)].image)].spec.rfind("leaf-atlas-", 0), 0u);
    leafMaterials.insert(leaves->material);
    // Every leaf triangle is in it.
    size_t before = 0;
    for (const TriangleMesh& l : plain.plantMeshes[i].leaves) before += l.triangleCount();
    EXPECT_EQ(leaves->mesh->triangleCount(), before);
    // The lower levels use the same material, in one part.
    ASSERT_EQ(o.lods.size(), 2u);
    for (const std::vector<ExportPart>& level : o.lods) {
      const ExportPart* l = leafPart(level);
      ASSERT_NE(l, nullptr);
      EXPECT_EQ(l->material, leaves->material);
      EXPECT_EQ(l->index, leaves->index);
    }
  }
  // The two ivies share one atlas and material; the tree (other textures, baked tints) has its own.
  EXPECT_EQ(leafMaterials.size(), 2u);
  EXPECT_EQ(model.leafAtlases.atlases.size(), 2u);
  EXPECT_EQ(model.leafAtlases.plants[0].atlas, model.leafAtlases.plants[2].atlas);
  EXPECT_FALSE(model.leafAtlases.atlases[0].bakedTints);
  EXPECT_TRUE(model.leafAtlases.atlases[1].bakedTints);
  // Only atlases and the bark are images: no single leaf texture is written.
  std::set<std::string> specs;
  for (const ExportImage& img : model.images) specs.insert(img.spec);
  EXPECT_EQ(specs.size(), 3u);
  EXPECT_TRUE(specs.count("builtin:bark"));
  // Without the option, a part per shape as before.
  size_t plainLeafParts = 0;
  for (const ExportPart& p : plain.objects[0].parts) plainLeafParts += p.source == PartSource::Leaves;
  EXPECT_EQ(plainLeafParts, 3u);
}

TEST(LeafAtlas, RectanglesFitWithGuttersAndDoNotOverlap) {
  const ExportModel model = buildExportModel(atlasScene(), atlasOptions());
  for (const LeafAtlas& a : model.leafAtlases.atlases) {
    SCOPED_TRACE(a.spec);
    ASSERT_EQ(a.rects.size(), 3u);
    EXPECT_EQ(a.width % 4, 0);
    EXPECT_EQ(a.height % 4, 0);
    const int g = kLeafAtlasGutter;
    for (size_t k = 0; k < a.rects.size(); ++k) {
      const LeafAtlasRect& r = a.rects[k];
      EXPECT_EQ(r.width, kBuiltinTextureSize);
      EXPECT_GE(r.x - g, 0);
      EXPECT_GE(r.y - g, 0);
      EXPECT_LE(r.x + r.width + g, a.width);
      EXPECT_LE(r.y + r.height + g, a.height);
      for (size_t j = 0; j < k; ++j) {
        const LeafAtlasRect& o = a.rects[j];
        const bool apart = r.x + r.width + g <= o.x - g || o.x + o.width + g <= r.x - g ||
                           r.y + r.height + g <= o.y - g || o.y + o.height + g <= r.y - g;
        EXPECT_TRUE(apart) << k << " overlaps " << j << " (gutters included)";
      }
    }
    // Tightly packed: under twice the textures' own area.
    EXPECT_LT(double(a.width) * a.height, 2.0 * 3 * kBuiltinTextureSize * kBuiltinTextureSize);
  }
}

// Every leaf vertex of shape s lies in s's rectangle, at the place its own UV maps to; sampling
// the atlas there gives the texel the shape's texture gives at the original UV.
TEST(LeafAtlas, UvsMapIntoTheirShapesRectangleAndSampleTheSameTexels) {
  const ExportScene scene = atlasScene();
  const ExportModel model = buildExportModel(scene, atlasOptions());
  for (size_t i : {size_t(0), size_t(1)}) {
    const PlantModel& p = scene.plants[i];
    SCOPED_TRACE(p.name);
    const mesh::PlantMesh original = mesh::buildPlantMesh(p, {});
    const PlantLeafAtlas& pa = model.leafAtlases.plants[i];
    const LeafAtlas& atlas = model.leafAtlases.atlases[size_t(pa.atlas)];
    const ExportPart* part = leafPart(model.objects[i].parts);
    ASSERT_NE(part, nullptr);
    const TriangleMesh& merged = *part->mesh;
    const ExportMaterial& m = model.materials[size_t(part->material)];
    const Image atlasImage =
        decodeImage(model.images[size_t(model.textures[size_t(m.texture)].image)].image.bytes, "atlas");
    ASSERT_EQ(atlasImage.width, atlas.width);
    ASSERT_EQ(atlasImage.height, atlas.height);
    size_t v = 0, probes = 0, tri = 0;
    for (size_t s = 0; s < original.leaves.size(); ++s) {
      const TriangleMesh& o = original.leaves[s];
      if (o.empty()) continue;
      ASSERT_GE(pa.shapeRect[s], 0);
      const LeafAtlasRect& r = atlas.rects[size_t(pa.shapeRect[s])];
      const plant::LeafShape shape = mesh::leafShapeFor(p, s);
      EXPECT_EQ(r.texture, shape.texture);
      const Image texture = loadTexture(shape.texture);
      ASSERT_LE(v + o.vertexCount(), merged.vertexCount());
      for (size_t k = 0; k < o.vertexCount(); ++k, ++v) {
        const Vec2 uv = merged.uvs[v];
        EXPECT_EQ(merged.positions[v], o.positions[k]);
        const float px = uv.x() * float(atlas.width), py = (1.0f - uv.y()) * float(atlas.height);
        EXPECT_GE(px, float(r.x) - 1e-3f);
        EXPECT_LE(px, float(r.x + r.width) + 1e-3f);
        EXPECT_GE(py, float(r.y) - 1e-3f);
        EXPECT_LE(py, float(r.y + r.height) + 1e-3f);
        EXPECT_LT((uv - atlasUv(atlas, r, o.uvs[k])).norm(), 1e-6f);
      }
      // Probes inside triangles (the same barycentric points of the original and merged
      // triangle) and at a few texel centres.
      for (size_t t = 0; t < o.triangleCount() && t < 600; t += 7, ++tri) {
        const uint32_t base = uint32_t(v - o.vertexCount());
        for (const Vec3& b : {Vec3(1.0f / 3, 1.0f / 3, 1.0f / 3), Vec3(0.6f, 0.3f, 0.1f), Vec3(0.15f, 0.25f, 0.6f)}) {
          Vec2 a = Vec2::Zero(), q = Vec2::Zero();
          for (int c = 0; c < 3; ++c) {
            a += b[c] * o.uvs[o.indices[3 * t + c]];
            q += b[c] * merged.uvs[base + o.indices[3 * t + c]];
          }
          const Texel want = sample(texture, a), got = sample(atlasImage, q);
          if (!want.clear || !got.clear) continue;
          ++probes;
          if (atlas.bakedTints) {
            EXPECT_EQ(got.rgba[3], want.rgba[3]);
            for (int c = 0; c < 3; ++c) EXPECT_LE(int(got.rgba[c]), int(want.rgba[c]));  // tints darken
          } else {
            EXPECT_EQ(got.rgba, want.rgba) << "at uv " << a.transpose() << " -> " << q.transpose();
          }
        }
      }
      for (const Vec2 uv : {Vec2(0.5f, 0.5f), Vec2(0.3f, 0.7f), Vec2(0.62f, 0.2f)}) {
        const Vec2 c((std::floor(uv.x() * r.width) + 0.5f) / r.width, (std::floor(uv.y() * r.height) + 0.5f) / r.height);
        const Texel want = sample(texture, c), got = sample(atlasImage, atlasUv(atlas, r, c));
        ASSERT_TRUE(want.clear && got.clear);
        if (!atlas.bakedTints) EXPECT_EQ(got.rgba, want.rgba);
        ++probes;
      }
    }
    EXPECT_EQ(v, merged.vertexCount());
    EXPECT_GT(probes, i == 0 ? 50u : 12u);  // the tree has few leaves
  }
}

// The gutter repeats each texture's edge texels, as clamp-to-edge sampling of the texture alone
// would: a mip level or a bilinear tap that reaches over the edge sees the same colours.
TEST(LeafAtlas, GuttersExtendTheEdges) {
  const ExportModel model = buildExportModel(atlasScene(), atlasOptions());
  const LeafAtlas& atlas = model.leafAtlases.atlases[0];
  const Image img = decodeImage(model.images[1].image.bytes, "atlas");
  ASSERT_EQ(model.images[1].spec, atlas.spec);
  const Image ivy0 = loadTexture(atlas.rects[0].texture);
  for (const LeafAtlasRect& r : atlas.rects) {
    for (int k = 0; k < r.height; k += 5)
      for (int d = 1; d <= kLeafAtlasGutter; ++d) {
        EXPECT_EQ(std::memcmp(img.pixel(r.x - d, r.y + k), img.pixel(r.x, r.y + k), 4), 0);
        EXPECT_EQ(std::memcmp(img.pixel(r.x + r.width - 1 + d, r.y + k), img.pixel(r.x + r.width - 1, r.y + k), 4), 0);
      }
    for (int k = 0; k < r.width; k += 5)
      for (int d = 1; d <= kLeafAtlasGutter; ++d) {
        EXPECT_EQ(std::memcmp(img.pixel(r.x + k, r.y - d), img.pixel(r.x + k, r.y), 4), 0);
        EXPECT_EQ(std::memcmp(img.pixel(r.x + k, r.y + r.height - 1 + d), img.pixel(r.x + k, r.y + r.height - 1), 4), 0);
      }
  }
  // And the texture itself is there unchanged.
  const LeafAtlasRect& r = atlas.rects[0];
  for (int y = 0; y < r.height; y += 3)
    EXPECT_EQ(std::memcmp(img.pixel(r.x, r.y + y), ivy0.pixel(0, y), size_t(r.width) * 4), 0) << "row " << y;
}

// A .glb with atlases: Khronos validator clean, one leaf material and texture per plant on every
// level, the streamed file's bytes those of the whole model's, at any thread count.
TEST(LeafAtlas, GlbIsValidStreamedAndDeterministic) {
  const fs::path dir = meshtest::exportTestDir();
  const ExportScene scene = atlasScene();
  const ExportOptions options = atlasOptions(3);
  writeGlb(scene, dir / "atlas.glb", options);
  writeGlb(buildExportModel(scene, options), dir / "atlas-whole.glb");
  const meshtest::GltfValidation v = meshtest::validateGltf(dir / "atlas.glb");
  EXPECT_EQ(v.exitCode, 0) << v.output;
  EXPECT_EQ(v.errors, 0) << v.output;
  EXPECT_EQ(v.warnings, 0) << v.output;
  const std::vector<uint8_t> streamed = readFileBytes(dir / "atlas.glb"), whole = readFileBytes(dir / "atlas-whole.glb");
  uint32_t sj = 0, wj = 0;
  std::memcpy(&sj, streamed.data() + 12, 4);
  std::memcpy(&wj, whole.data() + 12, 4);
  EXPECT_TRUE(std::equal(streamed.begin() + 20 + sj, streamed.end(), whole.begin() + 20 + wj, whole.end()));
  EXPECT_GT(sj, wj + 3);  // streamed, not written again the simple way

  tinygltf::TinyGLTF loader;
  tinygltf::Model m;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, (dir / "atlas.glb").string())) << err;
  EXPECT_EQ(m.images.size(), 3u);  // bark and two atlases
  size_t leafPrims = 0;
  for (const tinygltf::Node& node : m.nodes) {
    std::set<int> leafMaterials;
    for (const tinygltf::Primitive& p : m.meshes.at(size_t(node.mesh)).primitives)
      if (m.materials.at(size_t(p.material)).alphaMode == "MASK") {
        leafMaterials.insert(p.material);
        ++leafPrims;
      }
    EXPECT_EQ(leafMaterials.size(), 1u) << node.name;
  }
  EXPECT_EQ(leafPrims, 9u);  // 3 plants × 3 levels, one leaf primitive each
  // Leaves let light through (KHR_materials_diffuse_transmission), coloured by the atlas.
  const std::string transmission = "KHR_materials_diffuse_transmission";
  EXPECT_NE(std::find(m.extensionsUsed.begin(), m.extensionsUsed.end(), transmission), m.extensionsUsed.end());
  for (const tinygltf::Material& mat : m.materials) {
    SCOPED_TRACE(mat.name);
    const bool leaf = mat.alphaMode == "MASK";
    ASSERT_EQ(mat.extensions.count(transmission), leaf ? 1u : 0u);
    if (!leaf) continue;
    const tinygltf::Value& t = mat.extensions.at(transmission);
    EXPECT_DOUBLE_EQ(t.Get("diffuseTransmissionFactor").GetNumberAsDouble(), double(kLeafDiffuseTransmission));
    EXPECT_EQ(t.Get("diffuseTransmissionColorTexture").Get("index").GetNumberAsInt(),
              mat.pbrMetallicRoughness.baseColorTexture.index);
  }
  // Without the atlas, neither.
  writeGlb(scene, dir / "plain.glb", ExportOptions{});
  tinygltf::Model plainModel;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&plainModel, &err, &warn, (dir / "plain.glb").string())) << err;
  EXPECT_TRUE(plainModel.extensionsUsed.empty());
  for (const tinygltf::Material& mat : plainModel.materials) EXPECT_TRUE(mat.extensions.empty()) << mat.name;

  const ExportScene bigger = [&] {
    ExportScene s = scene;
    s.plants.push_back(meshtest::syntheticIvy(3000, 3));
    return s;
  }();
  test::sameAtEveryThreadCount([&] {
    writeGlb(bigger, dir / "atlas-threads.glb", options);
    return readFileBytes(dir / "atlas-threads.glb");
  });
}

TEST(LeafAtlas, ObjWritesOneLeafMaterialAndImage) {
  const fs::path dir = meshtest::exportTestDir() / "atlas-obj";
  fs::create_directories(dir);
  ExportScene scene;
  scene.plants.push_back(meshtest::syntheticIvy(400));
  writeObj(scene, dir / "ivy.obj", atlasOptions());
  EXPECT_TRUE(fs::exists(dir / "ivy_leaf0.png"));
  EXPECT_FALSE(fs::exists(dir / "ivy_leaf1.png"));
  const std::string mtl = test::readText(dir / "ivy.mtl");
  EXPECT_NE(mtl.find("newmtl leaf-atlas\n"), std::string::npos) << mtl;
  const std::string obj = test::readText(dir / "ivy.obj");
  size_t uses = 0;
  for (size_t at = obj.find("usemtl"); at != std::string::npos; at = obj.find("usemtl", at + 1)) ++uses;
  EXPECT_EQ(uses, 2u);  // bark and leaves
  const Image atlas = readImage(dir / "ivy_leaf0.png");
  EXPECT_GT(atlas.width, kBuiltinTextureSize);
}

TEST(LeafAtlas, SceneSettingAndCommandLine) {
  const fs::path dir = test::scratchDir();
  const fs::path file = dir / "atlas.json";
  test::writeText(file, R"({"tendril": 1, "plants": [], "output": {"leaf_atlas": true}})");
  EXPECT_TRUE(session::exportOptions(scene::loadScene(file).output).leafAtlas);
  test::writeText(file, R"({"tendril": 1, "plants": []})");
  EXPECT_FALSE(session::exportOptions(scene::loadScene(file).output).leafAtlas);

  const std::string scene = test::quoted(test::sourceDir() / "examples/scenes/default.json");
  const test::CommandResult r = test::runTendril(
      "grow " + scene + " -o " + test::quoted(dir / "grow") + " --steps 60 --lods 2 --leaf-atlas -q", dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  tinygltf::TinyGLTF loader;
  tinygltf::Model m;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, (dir / "grow/plant.glb").string())) << err;
  size_t leafMaterials = 0;
  for (const tinygltf::Material& mat : m.materials) leafMaterials += mat.alphaMode == "MASK";
  EXPECT_EQ(leafMaterials, 1u);
  bool atlasImage = false;
  for (const tinygltf::Image& img : m.images) atlasImage |= img.name.rfind("leaf-atlas-", 0) == 0;
  EXPECT_TRUE(atlasImage);
}

}  // namespace
}  // namespace tendril::io
