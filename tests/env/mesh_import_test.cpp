#include "tendril/env/mesh_import.h"

#include "support/test_paths.h"
#include "tendril/core/error.h"
#include "tendril/env/topology.h"

#include <gtest/gtest.h>

namespace tendril::env {
namespace {

std::string importError(const std::filesystem::path& p) {
  try {
    loadMeshFile(p);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

const char* kCubeObj =
    "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv -0.5 0.5 -0.5\nv 0.5 0.5 -0.5\n"
    "v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv -0.5 0.5 0.5\nv 0.5 0.5 0.5\n"
    "f 2 4 8 6\nf 1 5 7 3\nf 3 7 8 4\nf 1 2 6 5\nf 5 6 8 7\nf 1 3 4 2\n";

TEST(MeshImport, ObjQuadsAreTriangulatedAndClosed) {
  auto dir = test::scratchDir();
  test::writeText(dir / "cube.obj", kCubeObj);
  TriangleMesh m = loadMeshFile(dir / "cube.obj");
  EXPECT_EQ(m.triangleCount(), 12u);
  TopologyReport r = analyzeTopology(weld(m));
  EXPECT_TRUE(r.closed());
  EXPECT_NEAR(r.signedVolume, 1.0, 1e-5);
}

TEST(MeshImport, AsciiPlyAndStl) {
  auto dir = test::scratchDir();
  test::writeText(dir / "tri.ply",
                  "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(loadMeshFile(dir / "tri.ply").triangleCount(), 1u);
  test::writeText(dir / "tri.stl",
                  "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
                  "endfacet\nendsolid t\n");
  EXPECT_EQ(loadMeshFile(dir / "tri.stl").triangleCount(), 1u);
}

TEST(MeshImport, BinaryPly) {
  auto dir = test::scratchDir();
  std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  bin.append(reinterpret_cast<const char*>(v), sizeof(v));
  bin.push_back('\x03');
  int32_t f[3] = {0, 1, 2};
  bin.append(reinterpret_cast<const char*>(f), sizeof(f));
  test::writeText(dir / "tri.ply", bin);
  TriangleMesh m = loadMeshFile(dir / "tri.ply");
  ASSERT_EQ(m.triangleCount(), 1u);
  EXPECT_TRUE(m.bounds().max.isApprox(Vec3(1, 1, 0)));
}

TEST(MeshImport, MissingFileNamesPath) {
  auto dir = test::scratchDir();
  EXPECT_EQ(importError(dir / "nope.obj"), (dir / "nope.obj").string() + ": mesh file does not exist");
}

TEST(MeshImport, EmptyObjIsAnError) {
  auto dir = test::scratchDir();
  test::writeText(dir / "empty.obj", "");
  EXPECT_EQ(importError(dir / "empty.obj"), (dir / "empty.obj").string() + ": mesh file is empty");
  test::writeText(dir / "comments.obj", "# nothing here\no thing\n");
  std::string msg = importError(dir / "comments.obj");
  EXPECT_EQ(msg.rfind((dir / "comments.obj").string() + ": ", 0), 0u) << msg;
}

TEST(MeshImport, TruncatedPlyIsAnError) {
  auto dir = test::scratchDir();
  test::writeText(dir / "cut.ply",
                  "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 12\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1");
  std::string msg = importError(dir / "cut.ply");
  EXPECT_EQ(msg.rfind((dir / "cut.ply").string() + ": ", 0), 0u) << msg;
  // Binary PLY cut in the middle of its data.
  std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 50\nproperty list uchar int vertex_indices\nend_header\n";
  bin += std::string(37, '\x01');
  test::writeText(dir / "cutbin.ply", bin);
  msg = importError(dir / "cutbin.ply");
  EXPECT_EQ(msg.rfind((dir / "cutbin.ply").string() + ": ", 0), 0u) << msg;
}

TEST(MeshImport, BadGltfIsAnError) {
  auto dir = test::scratchDir();
  test::writeText(dir / "bad.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [{\"primitives\": [{\"attributes\"");
  std::string msg = importError(dir / "bad.gltf");
  EXPECT_EQ(msg.rfind((dir / "bad.gltf").string() + ": ", 0), 0u) << msg;
  test::writeText(dir / "bad.glb", std::string("glTF\x02\x00\x00\x00garbage", 15));
  msg = importError(dir / "bad.glb");
  EXPECT_EQ(msg.rfind((dir / "bad.glb").string() + ": ", 0), 0u) << msg;
}

TEST(MeshImport, UnknownFormatIsAnError) {
  auto dir = test::scratchDir();
  test::writeText(dir / "x.nothing", "hello world");
  std::string msg = importError(dir / "x.nothing");
  EXPECT_EQ(msg.rfind((dir / "x.nothing").string() + ": cannot read mesh", 0), 0u) << msg;
}

}  // namespace
}  // namespace tendril::env
