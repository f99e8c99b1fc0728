#include "tendril/io/gltf_writer.h"
#include "tendril/io/obj_writer.h"

#include "support/determinism.h"
#include "support/gltf_validator.h"
#include "support/synthetic_plants.h"
#include "tendril/core/error.h"
#include "tendril/core/hash.h"
#include "tendril/io/atomic_file.h"
#include "tendril/io/image.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>

namespace tendril::io {
namespace {

namespace fs = std::filesystem;
using plant::PlantModel;

// Two plants (one with three leaf shapes, a primitive and a custom bark), an empty plant and
// an obstacle mesh.
ExportScene testScene() {
  ExportScene scene;
  PlantModel tree = meshtest::branchingTree();
  meshtest::addLeaves(tree, 3);
  TriangleMesh bud;
  bud.positions = {Vec3(0, 0, 0), Vec3(0.02f, 0, 0), Vec3(0, 0.02f, 0), Vec3(0, 0, 0.02f)};
  bud.indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  tree.meshes.push_back({"bud", bud, Vec3(0.9f, 0.2f, 0.3f), ""});
  plant::Primitive pr;
  pr.node = 5;
  pr.mesh = 0;
  tree.primitives.push_back(pr);
  scene.plants.push_back(tree);

  PlantModel ivy = meshtest::syntheticIvy(400);
  ivy.name = "ivy on the wall";
  ivy.bark.roughness = 0.7f;
  scene.plants.push_back(ivy);

  PlantModel empty;
  empty.name = "seedling";
  scene.plants.push_back(empty);

  NamedMesh wall;
  wall.name = "wall";
  wall.mesh.positions = {Vec3(-1, 0, -0.05f), Vec3(1, 0, -0.05f), Vec3(1, 2, -0.05f), Vec3(-1, 2, -0.05f)};
  wall.mesh.indices = {0, 1, 2, 0, 2, 3};
  scene.meshes.push_back(wall);
  return scene;
}

// Parts of the test scene as the exporters see them.
struct Expected {
  size_t parts = 0;
  std::vector<size_t> vertices, triangles;  // per part in file order
  size_t materials = 0, images = 0, texturedMaterials = 0;
};

Expected expectedFor(const ExportScene& scene) {
  ExportModel model = buildExportModel(scene, ExportOptions{});
  Expected e;
  for (const ExportObject& o : model.objects)
    for (const ExportPart& p : o.parts) {
      ++e.parts;
      e.vertices.push_back(p.mesh->vertexCount());
      e.triangles.push_back(p.mesh->triangleCount());
    }
  e.materials = model.materials.size();
  e.images = model.images.size();
  for (const ExportMaterial& m : model.materials) e.texturedMaterials += m.texture >= 0;
  return e;
}

void expectValid(const fs::path& file) {
  meshtest::GltfValidation v = meshtest::validateGltf(file);
  EXPECT_EQ(v.exitCode, 0) << v.output;
  EXPECT_EQ(v.errors, 0) << v.output;
  EXPECT_EQ(v.warnings, 0) << v.output;
}

TEST(IoExportModel, SharesTexturesAndMaterials) {
  ExportScene scene = testScene();
  ExportModel model = buildExportModel(scene, ExportOptions{});
  ASSERT_EQ(model.objects.size(), 4u);
  EXPECT_EQ(model.objects[0].name, "tree");
  EXPECT_EQ(model.objects[2].name, "seedling");
  EXPECT_TRUE(model.objects[2].parts.empty());
  // tree: bark, 3 leaf shapes, 1 primitive group; ivy: bark, 3 leaf shapes; wall.
  EXPECT_EQ(model.objects[0].parts.size(), 5u);
  EXPECT_EQ(model.objects[1].parts.size(), 4u);
  // Images: bark, ivy-0, ivy-1, heart-0, ivy-2 — each once.
  std::set<std::string> specs;
  for (const ExportImage& i : model.images) specs.insert(i.spec);
  EXPECT_EQ(specs, (std::set<std::string>{"builtin:bark", "builtin:ivy-0", "builtin:ivy-1", "builtin:heart-0",
                                          "builtin:ivy-2"}));
  EXPECT_EQ(model.images.size(), specs.size());
  // Two bark materials (roughness differs), uniquely named.
  std::set<std::string> names;
  for (const ExportMaterial& m : model.materials) EXPECT_TRUE(names.insert(m.name).second) << m.name;
  EXPECT_TRUE(names.count("bark"));
  EXPECT_TRUE(names.count("bark-2"));
}

TEST(IoGlb, PassesTheKhronosValidator) {
  fs::path dir = meshtest::exportTestDir();
  writeGlb(testScene(), dir / "scene.glb");
  expectValid(dir / "scene.glb");
}

TEST(IoGlb, EmptyScenesAndPlantsAreValid) {
  fs::path dir = meshtest::exportTestDir();
  ExportScene scene;
  writeGlb(scene, dir / "nothing.glb");
  expectValid(dir / "nothing.glb");
  scene.plants.emplace_back();
  scene.plants.back().name = "empty";
  writeGlb(scene, dir / "empty.glb");
  expectValid(dir / "empty.glb");
  // Leaves only on a zero-length node (no bark).
  PlantModel bare = meshtest::straightChain(1);
  bare.length[0] = 0.0f;
  meshtest::addLeaves(bare, 1);
  scene.plants = {bare};
  writeGlb(scene, dir / "bare.glb");
  expectValid(dir / "bare.glb");
}

TEST(IoGlb, LargeMeshesUse32BitIndicesAndStayValid) {
  fs::path dir = meshtest::exportTestDir();
  ExportScene scene;
  scene.plants.push_back(meshtest::syntheticIvy(3000));  // > 65535 bark vertices
  ExportModel model = buildExportModel(scene, ExportOptions{});
  ASSERT_GT(model.plantMeshes[0].bark.vertexCount(), 65535u);
  writeGlb(model, dir / "big.glb");
  expectValid(dir / "big.glb");
}

TEST(IoGlb, ReimportsThroughAssimp) {
  fs::path dir = meshtest::exportTestDir();
  ExportScene scene = testScene();
  Expected e = expectedFor(scene);
  writeGlb(scene, dir / "scene.glb");
  Assimp::Importer importer;
  const aiScene* s = importer.ReadFile((dir / "scene.glb").string(), 0);
  ASSERT_NE(s, nullptr) << importer.GetErrorString();
  ASSERT_EQ(s->mNumMeshes, e.parts);
  for (size_t i = 0; i < e.parts; ++i) {
    EXPECT_EQ(s->mMeshes[i]->mNumVertices, e.vertices[i]) << i;
    EXPECT_EQ(s->mMeshes[i]->mNumFaces, e.triangles[i]) << i;
    EXPECT_TRUE(s->mMeshes[i]->HasNormals());
  }
  EXPECT_EQ(s->mNumTextures, e.images);  // embedded
  // Assimp's glTF importer adds its own default material to the ones in the file.
  EXPECT_GE(s->mNumMaterials, e.materials);
  EXPECT_LE(s->mNumMaterials, e.materials + 1);
  std::set<std::string> names;
  for (unsigned i = 0; i < s->mNumMaterials; ++i) names.insert(s->mMaterials[i]->GetName().C_Str());
  EXPECT_TRUE(names.count("bark"));
  EXPECT_TRUE(names.count("leaf-ivy-0"));
  // Nodes named after the plants.
  std::set<std::string> nodes;
  for (unsigned i = 0; i < s->mRootNode->mNumChildren; ++i) nodes.insert(s->mRootNode->mChildren[i]->mName.C_Str());
  EXPECT_TRUE(nodes.count("tree"));
  EXPECT_TRUE(nodes.count("ivy on the wall"));
  EXPECT_TRUE(nodes.count("wall"));
}

TEST(IoGlb, LeafUvsPutTheImageBottomAtTheBladeBase) {
  // glTF's v runs down the image: a leaf's base (mesh v = 0) must read v = 1 back.
  fs::path dir = meshtest::exportTestDir();
  ExportScene scene;
  PlantModel p = meshtest::straightChain(1);
  meshtest::addLeaves(p, 1);
  scene.plants.push_back(p);
  writeGlb(scene, dir / "leaf.glb");
  Assimp::Importer importer;
  const aiScene* s = importer.ReadFile((dir / "leaf.glb").string(), 0);
  ASSERT_NE(s, nullptr);
  const aiMesh* leaf = s->mMeshes[1];
  ASSERT_EQ(leaf->mNumVertices, 4u);
  // Assimp flips glTF's v back to the OpenGL convention, so the mesh's own uvs come back.
  mesh::PlantMesh pm = mesh::buildPlantMesh(p);
  for (unsigned i = 0; i < 4; ++i) {
    EXPECT_NEAR(leaf->mTextureCoords[0][i].x, pm.leaves[0].uvs[i].x(), 1e-6f);
    EXPECT_NEAR(leaf->mTextureCoords[0][i].y, pm.leaves[0].uvs[i].y(), 1e-6f);
  }
}

TEST(IoGlb, BytesDoNotDependOnThreadCount) {
  fs::path dir = meshtest::exportTestDir();
  ExportScene scene = testScene();
  scene.plants.push_back(meshtest::syntheticIvy(5000));
  tendril::test::sameAtEveryThreadCount([&] {
    writeGlb(scene, dir / "plant.glb");
    return readFileBytes(dir / "plant.glb");
  });
}

// A .glb's two chunks: the JSON text without its padding, and the binary chunk.
struct GlbChunks {
  uint32_t jsonChunkBytes = 0;
  std::string json;
  std::vector<uint8_t> bin;
};

GlbChunks readGlb(const fs::path& path) {
  std::vector<uint8_t> b = readFileBytes(path);
  GlbChunks c;
  auto u32 = [&](size_t at) {
    uint32_t v;
    std::memcpy(&v, b.data() + at, 4);
    return v;
  };
  EXPECT_EQ(u32(8), b.size());
  c.jsonChunkBytes = u32(12);
  c.json.assign(b.begin() + 20, b.begin() + 20 + c.jsonChunkBytes);
  c.json.erase(c.json.find_last_not_of(' ') + 1);
  const size_t bin = 20 + size_t(c.jsonChunkBytes);
  if (bin < b.size()) {
    EXPECT_EQ(size_t(u32(bin)) + bin + 8, b.size());
    c.bin.assign(b.begin() + bin + 8, b.end());
  }
  return c;
}

// A scene's .glb is written plant by plant (the JSON chunk last, into room reserved before the
// geometry): the same JSON and the same binary chunk as when the whole model is built first.
TEST(IoGlb, StreamedFileMatchesTheWholeModelsFile) {
  fs::path dir = meshtest::exportTestDir();
  ExportScene scene = testScene();
  // A large plant first (32-bit indices), so that the smaller plants after it are meshed into
  // the meshes it grew; more plants than the writer has meshes in flight.
  scene.plants.insert(scene.plants.begin(), meshtest::syntheticIvy(3000));
  for (int k = 0; k < 12; ++k) scene.plants.push_back(meshtest::syntheticIvy(40 + 30 * k));
  PlantModel second = meshtest::syntheticIvy(200);
  second.name = std::string(300, '"');  // a name every byte of which is escaped
  scene.plants.push_back(second);
  scene.meshes[0].name = std::string(200, '\x01');
  writeGlb(scene, dir / "streamed.glb");
  writeGlb(buildExportModel(scene, ExportOptions{}), dir / "whole.glb");
  expectValid(dir / "streamed.glb");
  GlbChunks streamed = readGlb(dir / "streamed.glb"), whole = readGlb(dir / "whole.glb");
  EXPECT_EQ(streamed.json, whole.json);
  EXPECT_EQ(streamed.bin, whole.bin);
  // The streamed file's JSON chunk is the reserved room (the whole model's is padded to 4
  // bytes at most): it was streamed, not written again the simple way.
  EXPECT_GT(streamed.jsonChunkBytes, streamed.json.size() + 3);
  EXPECT_LE(whole.jsonChunkBytes, whole.json.size() + 3);
  // The room is generous, but not wasteful: under twice the JSON here.
  EXPECT_LT(streamed.jsonChunkBytes, 2 * streamed.json.size());
}

TEST(IoGlb, BadTextureIsAnErrorAndTheOldFileSurvives) {
  fs::path dir = meshtest::exportTestDir();
  writeFileAtomic(dir / "scene.glb", std::string_view("old content"));
  ExportScene scene = testScene();
  scene.plants[0].leafShapes[1].texture = (dir / "missing-leaf.png").string();
  try {
    writeGlb(scene, dir / "scene.glb");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.source(), (dir / "missing-leaf.png").string());
  }
  std::vector<uint8_t> bytes = readFileBytes(dir / "scene.glb");
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "old content");
  // A missing output directory names the output path.
  try {
    writeGlb(testScene(), dir / "nope" / "scene.glb");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.source(), (dir / "nope" / "scene.glb").string());
  }
}

TEST(IoExportModel, RejectsColoursThatAreNotFinite) {
  ExportScene scene = testScene();
  scene.plants[0].leafShapes[2].tint.y() = std::numeric_limits<float>::quiet_NaN();
  try {
    buildExportModel(scene, ExportOptions{});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.source(), "tree");
    EXPECT_EQ(e.location(), "leaf shape 2");
  }
  // Out-of-range colours are clamped into glTF's [0, 1].
  scene = testScene();
  scene.plants[0].leafShapes[0].tint = Vec3(2.0f, -1.0f, 0.5f);
  ExportModel model = buildExportModel(scene, ExportOptions{});
  EXPECT_EQ(model.materials[model.objects[0].parts[1].material].baseColor, Vec4(1.0f, 0.0f, 0.5f, 1.0f));
}

TEST(IoGlb, FileTexturesAreEmbedded) {
  fs::path dir = meshtest::exportTestDir();
  Image red = makeImage(8, 8, 255, 0, 0, 255);
  writePng(red, dir / "red.png");
  ExportScene scene;
  PlantModel p = meshtest::straightChain(3);
  p.bark.texture = (dir / "red.png").string();
  scene.plants.push_back(p);
  writeGlb(scene, dir / "red.glb");
  expectValid(dir / "red.glb");
  Assimp::Importer importer;
  const aiScene* s = importer.ReadFile((dir / "red.glb").string(), 0);
  ASSERT_NE(s, nullptr);
  ASSERT_EQ(s->mNumTextures, 1u);
  std::vector<uint8_t> png = readFileBytes(dir / "red.png");
  ASSERT_EQ(s->mTextures[0]->mHeight, 0u);  // compressed: mWidth is the byte count
  EXPECT_EQ(s->mTextures[0]->mWidth, png.size());
  EXPECT_EQ(std::memcmp(s->mTextures[0]->pcData, png.data(), png.size()), 0);
}

TEST(IoObj, WritesObjMtlAndTexturesThatReimport) {
  fs::path dir = meshtest::exportTestDir();
  ExportScene scene = testScene();
  Expected e = expectedFor(scene);
  writeObj(scene, dir / "scene.obj");
  for (const char* f : {"scene.obj", "scene.mtl", "scene_bark.png", "scene_leaf0.png", "scene_leaf1.png",
                        "scene_leaf2.png", "scene_leaf3.png"})
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  EXPECT_FALSE(fs::exists(dir / "scene_leaf4.png"));
  // The texture files are the PNGs the glTF would embed.
  EXPECT_EQ(decodeImage(readFileBytes(dir / "scene_bark.png"), "bark").width, kBuiltinTextureSize);

  std::vector<uint8_t> mtlBytes = readFileBytes(dir / "scene.mtl");
  std::string mtl(mtlBytes.begin(), mtlBytes.end());
  EXPECT_NE(mtl.find("newmtl bark\n"), std::string::npos);
  EXPECT_NE(mtl.find("map_Kd scene_bark.png\n"), std::string::npos);
  EXPECT_NE(mtl.find("map_d scene_leaf0.png\n"), std::string::npos);

  // Record counts in the .obj itself.
  std::ifstream in(dir / "scene.obj");
  std::map<std::string, size_t> records;
  for (std::string line; std::getline(in, line);) ++records[line.substr(0, line.find(' '))];
  size_t vertices = 0, triangles = 0;
  for (size_t i = 0; i < e.parts; ++i) {
    vertices += e.vertices[i];
    triangles += e.triangles[i];
  }
  EXPECT_EQ(records["v"], vertices);
  EXPECT_EQ(records["vn"], vertices);
  EXPECT_EQ(records["f"], triangles);
  EXPECT_EQ(records["o"], 4u);
  EXPECT_EQ(records["g"], e.parts);

  Assimp::Importer importer;
  const aiScene* s = importer.ReadFile((dir / "scene.obj").string(), 0);
  ASSERT_NE(s, nullptr) << importer.GetErrorString();
  ASSERT_EQ(s->mNumMeshes, e.parts);
  size_t faces = 0;
  for (unsigned i = 0; i < s->mNumMeshes; ++i) {
    faces += s->mMeshes[i]->mNumFaces;
    EXPECT_EQ(s->mMeshes[i]->mNumFaces, e.triangles[i]) << i;
    // Assimp's OBJ reader keeps one vertex per face corner.
    EXPECT_EQ(s->mMeshes[i]->mNumVertices, 3 * e.triangles[i]) << i;
  }
  EXPECT_EQ(faces, triangles);
  EXPECT_GE(s->mNumMaterials, e.materials);
  EXPECT_LE(s->mNumMaterials, e.materials + 1);  // plus Assimp's default material
  size_t textured = 0;
  for (unsigned i = 0; i < s->mNumMaterials; ++i) {
    aiString path;
    if (s->mMaterials[i]->GetTexture(aiTextureType_DIFFUSE, 0, &path) == AI_SUCCESS) {
      ++textured;
      EXPECT_TRUE(fs::exists(dir / path.C_Str())) << path.C_Str();
    }
  }
  EXPECT_EQ(textured, e.texturedMaterials);  // two barks and six leaf materials (tints differ)
  EXPECT_EQ(e.texturedMaterials, 8u);
}

TEST(IoObj, MatchesTheMeshAfterJoiningVertices) {
  fs::path dir = meshtest::exportTestDir();
  ExportScene scene;
  PlantModel p = meshtest::arcChain(8);
  meshtest::addLeaves(p, 1);
  scene.plants.push_back(p);
  writeObj(scene, dir / "arc.obj");
  mesh::PlantMesh pm = mesh::buildPlantMesh(p);
  Assimp::Importer importer;
  const aiScene* s = importer.ReadFile((dir / "arc.obj").string(), aiProcess_JoinIdenticalVertices);
  ASSERT_NE(s, nullptr);
  ASSERT_EQ(s->mNumMeshes, 2u);
  EXPECT_EQ(s->mMeshes[0]->mNumVertices, pm.bark.vertexCount());
  EXPECT_EQ(s->mMeshes[1]->mNumVertices, pm.leaves[0].vertexCount());
}

}  // namespace
}  // namespace tendril::io
