// Malformed mesh files (docs/scene-format.md, "mesh"): each one, referenced by a scene, makes
// `tendril validate` fail with exit 2 and one line naming the file, in under 10 s and 1 GiB of
// address space (the shell's ulimit; past it an allocation fails rather than the machine
// swapping). Absurd declared counts are refused from the header, before anything is allocated
// for them: without the header checks an OFF file declaring 3·10⁹ vertices asked for 36 GB.
#include "support/run_command.h"
#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace tendril {
namespace {

namespace fs = std::filesystem;

void writeBytes(const fs::path& path, const std::string& bytes) { test::writeText(path, bytes); }

std::string le32(uint32_t v) {
  std::string s(4, '\0');
  std::memcpy(s.data(), &v, 4);
  return s;
}

std::string base64(const std::string& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const uint32_t v = uint8_t(in[i]) << 16 | uint8_t(in[i + 1]) << 8 | uint8_t(in[i + 2]);
    out += {k[v >> 18], k[(v >> 12) & 63], k[(v >> 6) & 63], k[v & 63]};
  }
  if (i + 1 == in.size()) {
    const uint32_t v = uint8_t(in[i]) << 16;
    out += {k[v >> 18], k[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == in.size()) {
    const uint32_t v = uint8_t(in[i]) << 16 | uint8_t(in[i + 1]) << 8;
    out += {k[v >> 18], k[(v >> 12) & 63], k[(v >> 6) & 63], '='};
  }
  return out;
}

// A glTF triangle: three float positions and three ushort indices in one embedded buffer, with
// `accessorCount` vertices declared and the node list given.
std::string gltf(uint64_t accessorCount, const std::string& nodes) {
  std::string buf;
  const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  buf.append(reinterpret_cast<const char*>(p), sizeof p);
  const uint16_t idx[4] = {0, 1, 2, 0};
  buf.append(reinterpret_cast<const char*>(idx), sizeof idx);
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": )" + nodes +
         R"(, "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,)" + base64(buf) + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": )" + std::to_string(accessorCount) +
         R"(, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]})";
}

struct Case {
  std::string file;
  std::string bytes;
  std::string says;  // part of the one-line message
};

std::vector<Case> malformedMeshes() {
  const std::string tetra = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  std::string binaryStl(80, '\0');
  binaryStl += le32(4000000000u) + std::string(100, '\0');
  std::string truncatedStl(80, '\0');
  truncatedStl += le32(12) + std::string(50 * 5, '\0');
  return {
      // Absurd declared counts.
      {"huge.off", "OFF\n3000000000 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "OFF header declares 3000000000"},
      {"huge.ply",
       "ply\nformat ascii 1.0\nelement vertex 3000000000\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
       "PLY"},
      {"huge-binary.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 4000000000\nproperty list uchar int vertex_indices\nend_header\n" + std::string(36, '\0'),
       "PLY header declares at least 4000000000"},
      {"huge.stl", binaryStl, "binary STL declares 4000000000"},
      {"huge.gltf", gltf(1500000000, R"([{"mesh": 0}])"), "out of range"},
      // A header line the importer does not know (it looped forever on this one, found by fuzz/mesh).
      {"keyword.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\npropat ascii uchar int vertex_indices\nat z\n"
       "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
       "PLY header: unknown keyword \"propat\""},
      {"end-header.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 0\nproperty list uchar int vertex_indices\nend_headerBIN 5\n1 0 0\n0 1 0\n3 0 1 2\n",
       "end_header must be on a line of its own"},
      {"magic.ply",
       "plY\nformat ascii 1+0\nelement vertex 3\nproperty float x\npropetrnt vertex_ind\nseeicnd_header\n0 0 0\n",
       "a PLY file starts with a line \"ply\""},
      {"keyword.off", "OFF3 40294967295 2 1\n3 0 1\n", "an OFF file starts with \"OFF\""},
      {"degenerate.off", "OFF\n4 4 6\n0 0 0\n2 4 6\n0 0 0\n2 0 0\n0 1 0\n 0 0\n0 1 0\n0 001\n3 0\nf 1\n3 0 1 3\n",
       "face 0: \"0\" is not a polygon's vertex count"},
      // Truncated.
      {"truncated.stl", truncatedStl, "binary STL declares 12"},
      {"truncated.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n" + std::string(20, '\0'),
       "truncated PLY"},
      {"truncated.obj", "v 0 0 0\nv 1 0", "cannot read mesh"},
      {"truncated.glb", std::string("glTF") + le32(2) + le32(4000) + le32(100) + "JSON{\"asset\"", "cannot read mesh"},
      // Values that are not numbers.
      {"nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "not finite"},
      {"inf.off", "OFF\n3 1 0\n0 0 inf\n1 0 0\n0 1 0\n3 0 1 2\n", "not finite"},
      // Indices out of range.
      {"index.obj", tetra + "f 1 2 99999999\n", "out of range"},
      {"index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "vertex index \"7\" out of range"},
      {"truncated.off", "OFF\n4 2 0\n0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1.0 0.0\n0.0 0.0 1.0\n3 0 1 2\n3 0 1\n",
       "truncated OFF: the data ends inside face 1 of 2"},
      {"short.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1\n", "more than the file's 48 bytes"},
      // Cycles in node graphs.
      {"cycle.gltf", gltf(3, R"([{"mesh": 0, "children": [1]}, {"children": [0]}])"), "recursive"},
      // Not a mesh at all.
      {"text.obj", "hello\n", "cannot read mesh"},
      {"empty.stl", "", "empty"},
  };
}

TEST(MalformedMeshes, FailInSecondsOnOneLineWithinAGigabyte) {
  const fs::path dir = test::scratchDir();
  for (const Case& c : malformedMeshes()) {
    SCOPED_TRACE(c.file);
    writeBytes(dir / c.file, c.bytes);
    const fs::path scene = dir / ("scene-" + c.file + ".json");
    test::writeText(scene, R"({"tendril": 1, "environment": {"obstacles": [{"name": "support", "type": "mesh", "path": ")" +
                               c.file + R"("}]}, "plants": []})");
    const auto t0 = std::chrono::steady_clock::now();
    // 1 GiB of address space (ulimit -v is in KiB); `timeout` stops a run past 10 s with 124.
    const test::CommandResult r =
        test::runCommand("ulimit -v 1048576; timeout 10 " + test::quoted(test::cliPath()) + " validate " +
                             test::quoted(scene),
                         dir);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(r.exitCode, 2) << r.err;
    EXPECT_LT(seconds, 10.0);
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(c.file), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
  }
}

// The limit on triangles applies to what the header declares and to what is read:
// --max-mesh-triangles 3 refuses a tetrahedron (4 triangles) in every format that says how
// many it has, and a closed tetrahedron passes without the option.
TEST(MalformedMeshes, TheTriangleLimitIsCheckedBeforeReading) {
  const fs::path dir = test::scratchDir();
  const std::vector<std::pair<std::string, std::string>> files = {
      {"tetra.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"},
      {"tetra.off", "OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"},
  };
  for (const auto& [file, bytes] : files) {
    SCOPED_TRACE(file);
    writeBytes(dir / file, bytes);
    const fs::path scene = dir / ("scene-" + file + ".json");
    test::writeText(scene, R"({"tendril": 1, "environment": {"obstacles": [{"type": "mesh", "path": ")" + file +
                               R"("}]}, "plants": []})");
    const test::CommandResult ok = test::runTendril("validate " + test::quoted(scene), dir);
    EXPECT_EQ(ok.exitCode, 0) << ok.err;
    const test::CommandResult capped = test::runTendril("validate --max-mesh-triangles 3 " + test::quoted(scene), dir);
    EXPECT_EQ(capped.exitCode, 2) << capped.err;
    EXPECT_NE(capped.err.find("more than the 3 a mesh may have (--max-mesh-triangles)"), std::string::npos) << capped.err;
  }
}

}  // namespace
}  // namespace tendril
