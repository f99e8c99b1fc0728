// Normal and roughness maps made with the bark and leaf textures (io/material_maps.h, issue 26
// part 2): texels are unit normals that follow the height field's slopes, the bark's relief is
// the one that colours it, and the .glb / .obj carry them (validator clean, both writers alike).
#include "tendril/io/material_maps.h"

#include "support/gltf_validator.h"
#include "support/run_command.h"
#include "support/synthetic_plants.h"
#include "support/test_paths.h"
#include "tendril/core/error.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/obj_writer.h"
#include "tendril/io/texture.h"
#include "tendril/scene/scene.h"
#include "tendril/session/plant_export.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <utility>

namespace tendril::io {
namespace {

namespace fs = std::filesystem;

Vec3 decoded(const Image& img, int x, int y) {
  const uint8_t* p = img.pixel(x, y);
  return Vec3(p[0] / 255.0f * 2.0f - 1.0f, p[1] / 255.0f * 2.0f - 1.0f, p[2] / 255.0f * 2.0f - 1.0f);
}

// Texels are unit vectors pointing out of the surface, and their slopes are the height field's
// (central differences, in double, wrapping: the bark repeats).
TEST(MaterialMaps, BarkNormalsAreUnitAndFollowTheReliefGradient) {
  const int size = 128;
  const HeightField field = barkHeightField(size);
  const Image map = normalMap(field, kBarkReliefPixels, true);
  ASSERT_EQ(map.width, size);
  double worst = 0.0, slopes = 0.0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const Vec3 n = decoded(map, x, y);
      EXPECT_NEAR(n.norm(), 1.0f, 0.015f) << x << "," << y;  // 8-bit quantisation
      ASSERT_GT(n.z(), 0.0f);
      // The relief at the neighbouring pixel centres, straight from the texture's function.
      auto h = [&](int px, int py) {
        px = (px + size) % size, py = (py + size) % size;
        return double(builtinBarkHeight((float(px) + 0.5f) / size, (float(py) + 0.5f) / size));
      };
      const double dx = (h(x + 1, y) - h(x - 1, y)) / 2.0, dup = -(h(x, y + 1) - h(x, y - 1)) / 2.0;
      const double s = kBarkReliefPixels;
      const Vec3 expected = Vec3(float(-s * dx), float(-s * dup), 1.0f).normalized();
      worst = std::max(worst, double((n - expected).cwiseAbs().maxCoeff()));
      slopes += std::hypot(dx, dup);
    }
  EXPECT_LT(worst, 0.01);                   // within the 8-bit step (2/255)
  EXPECT_GT(slopes / (size * size), 0.01);  // and the relief is not flat
}

// The relief is the colour's: furrows (low) are dark in builtin:bark, plates (high) light.
TEST(MaterialMaps, BarkReliefMatchesTheColour) {
  const int size = 128;
  const Image colour = generateBuiltinTexture("bark", size);
  const HeightField field = barkHeightField(size);
  double sh = 0, sl = 0, shh = 0, sll = 0, shl = 0;
  const double n = double(size) * size;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const uint8_t* p = colour.pixel(x, y);
      const double l = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2], h = field.at(x, y);
      sh += h, sl += l, shh += h * h, sll += l * l, shl += h * l;
    }
  const double corr = (shl / n - sh / n * sl / n) /
                      std::sqrt((shh / n - sh / n * sh / n) * (sll / n - sl / n * sl / n));
  EXPECT_GT(corr, 0.8);
}

// A leaf's map: its veins (lighter lines) raised, flat where the blade is cut out, clamped at
// the edges (leaves do not repeat). The roughness map: G from smooth plates to rough furrows, B 0.
TEST(MaterialMaps, LeafNormalsAndRoughness) {
  const Image leaf = generateBuiltinTexture("ovate-0", 128);
  const HeightField field = luminanceHeightField(leaf);
  const Image map = normalMap(field, kLeafReliefPixels, false);
  size_t tilted = 0;
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) {
      const Vec3 n = decoded(map, x, y);
      EXPECT_NEAR(n.norm(), 1.0f, 0.015f);
      const Vec3 expected = heightFieldNormal(field, x, y, kLeafReliefPixels, false);
      EXPECT_LT((n - expected).cwiseAbs().maxCoeff(), 0.01f);
      tilted += leaf.pixel(x, y)[3] >= 128 && n.z() < 0.99f;
    }
  EXPECT_GT(tilted, 30u);  // veins and margins
  const Image rough = roughnessMap(barkHeightField(64));
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      EXPECT_EQ(rough.pixel(x, y)[2], 0);
      EXPECT_GE(rough.pixel(x, y)[1], uint8_t(0.7 * 255));
    }
}

// In the files: bark with normalTexture and metallicRoughnessTexture, leaves with normalTexture
// (also an atlas's, with its rectangles), validator clean — also with levels of detail, whose
// normal-mapped parts carry their own tangents; .obj with norm and map_Pr.
TEST(MaterialMaps, FilesCarryTheMaps) {
  const fs::path dir = meshtest::exportTestDir();
  ExportScene scene;
  scene.plants.push_back(meshtest::syntheticIvy(400));
  for (const auto& [atlas, levels] : {std::pair{false, 1}, std::pair{true, 1}, std::pair{false, 3}, std::pair{true, 3}}) {
    SCOPED_TRACE(fmt::format("{}, {} levels", atlas ? "atlas" : "no atlas", levels));
    ExportOptions o;
    o.maps = true;
    o.leafAtlas = atlas;
    o.lods.levels = levels;
    const fs::path file = dir / fmt::format("{}-{}.glb", atlas ? "atlas" : "maps", levels);
    writeGlb(scene, file, o);
    writeGlb(buildExportModel(scene, o), dir / "whole.glb");
    const std::vector<uint8_t> s = readFileBytes(file), w = readFileBytes(dir / "whole.glb");
    uint32_t sj = 0, wj = 0;
    std::memcpy(&sj, s.data() + 12, 4);
    std::memcpy(&wj, w.data() + 12, 4);
    EXPECT_TRUE(std::equal(s.begin() + 20 + sj, s.end(), w.begin() + 20 + wj, w.end()));
    const meshtest::GltfValidation v = meshtest::validateGltf(file);
    EXPECT_EQ(v.exitCode, 0) << v.output;
    EXPECT_EQ(v.errors, 0) << v.output;
    EXPECT_EQ(v.warnings, 0) << v.output;
    tinygltf::Model m;
    tinygltf::TinyGLTF loader;
    std::string err, warn;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, file.string())) << err;
    size_t barkMaps = 0, leafMaps = 0;
    for (const tinygltf::Material& mat : m.materials) {
      const bool leaf = mat.alphaMode == "MASK";
      EXPECT_GE(mat.normalTexture.index, 0) << mat.name;
      if (leaf) {
        ++leafMaps;
        EXPECT_LT(mat.pbrMetallicRoughness.metallicRoughnessTexture.index, 0);
      } else {
        ++barkMaps;
        EXPECT_GE(mat.pbrMetallicRoughness.metallicRoughnessTexture.index, 0);
      }
      // The normal map has its colour texture's size (an atlas's: the same rectangles).
      const int colour = m.textures.at(size_t(mat.pbrMetallicRoughness.baseColorTexture.index)).source;
      const int normal = m.textures.at(size_t(mat.normalTexture.index)).source;
      EXPECT_EQ(m.images.at(size_t(colour)).width, m.images.at(size_t(normal)).width);
      EXPECT_EQ(m.images.at(size_t(colour)).height, m.images.at(size_t(normal)).height);
    }
    // Normal-mapped primitives, on every level, carry their tangent space (unit xyz, w ±1: the
    // validator checks), as many as the primitive has vertices.
    EXPECT_EQ(m.meshes.size(), size_t(levels));
    for (const tinygltf::Mesh& mesh : m.meshes)
      for (const tinygltf::Primitive& p : mesh.primitives) {
        const bool mapped = m.materials.at(size_t(p.material)).normalTexture.index >= 0;
        ASSERT_EQ(p.attributes.count("TANGENT"), mapped ? 1u : 0u) << mesh.name;
        if (mapped)
          EXPECT_EQ(m.accessors.at(size_t(p.attributes.at("TANGENT"))).count,
                    m.accessors.at(size_t(p.attributes.at("POSITION"))).count) << mesh.name;
      }
    EXPECT_EQ(barkMaps, 1u);
    EXPECT_EQ(leafMaps, atlas ? 1u : 3u);
  }
  const fs::path objDir = dir / "obj";
  fs::create_directories(objDir);
  ExportOptions o;
  o.maps = true;
  writeObj(scene, objDir / "ivy.obj", o);
  const std::string mtl = test::readText(objDir / "ivy.mtl");
  EXPECT_NE(mtl.find("norm ivy_bark_normal.png"), std::string::npos) << mtl;
  EXPECT_NE(mtl.find("map_Pr -imfchan g ivy_bark_roughness.png"), std::string::npos) << mtl;
  EXPECT_TRUE(fs::exists(objDir / "ivy_bark_roughness.png"));
  EXPECT_TRUE(fs::exists(objDir / "ivy_leaf0_normal.png"));
}

TEST(MaterialMaps, SceneSettingAndCommandLine) {
  const fs::path dir = test::scratchDir();
  const fs::path file = dir / "maps.json";
  test::writeText(file, R"({"tendril": 1, "plants": [], "output": {"maps": true}})");
  EXPECT_TRUE(session::exportOptions(scene::loadScene(file).output).maps);
  test::writeText(file, R"({"tendril": 1, "plants": []})");
  EXPECT_FALSE(session::exportOptions(scene::loadScene(file).output).maps);
  test::writeText(file, R"({"tendril": 1, "plants": [], "output": {"maps": 1}})");
  try {
    scene::loadScene(file);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(file.string() + ":/output/maps:", 0), 0u) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  const test::CommandResult r = test::runTendril(
      "lsys abop-1.24a -o " + test::quoted(dir / "bush.glb") + " -n 3 --maps -q", dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, (dir / "bush.glb").string())) << err;
  bool normal = false;
  for (const tinygltf::Material& mat : m.materials) normal |= mat.normalTexture.index >= 0;
  EXPECT_TRUE(normal);
}

}  // namespace
}  // namespace tendril::io
