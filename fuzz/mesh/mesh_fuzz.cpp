// libFuzzer target for mesh files (docs/scene-format.md, "mesh"): the first byte of an input
// picks the format (OBJ, PLY, OFF, STL, glTF, GLB), the rest is the file, read with
// env::loadMeshFile as a scene's mesh obstacle or an imported support is. Every problem must be
// a tendril::Error naming the file, within the limits below: a crash, a hang, a sanitizer report,
// a run past -rss_limit_mb, another exception, or a mesh with an index out of range or a
// coordinate that is not finite is a bug. Run with `make fuzz` (fuzz/README.md).
#include "../fuzz_init.h"
#include "tendril/core/error.h"
#include "tendril/env/mesh_import.h"

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

using namespace tendril;

[[noreturn]] void bug(const char* what, const std::string& detail) {
  std::fprintf(stderr, "%s: %s\n", what, detail.c_str());
  std::abort();
}

// Limits small enough that any accepted input stays far below the fuzzer's memory limit.
struct Limits {
  Limits() { env::setMeshImportLimits({uint64_t(1) << 20, uint64_t(1) << 16}); }
} gLimits;

const char* const kExtensions[] = {".obj", ".ply", ".off", ".stl", ".gltf", ".glb"};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const char* ext = kExtensions[data[0] % (sizeof kExtensions / sizeof kExtensions[0])];
  // One file per process, rewritten for each input (in memory where /dev/shm exists).
  static const std::filesystem::path dir =
      std::filesystem::exists("/dev/shm") ? std::filesystem::path("/dev/shm") : std::filesystem::temp_directory_path();
  const std::filesystem::path path = dir / ("tendril-mesh-fuzz-" + std::to_string(getpid()) + ext);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data + 1), std::streamsize(size - 1));
  }
  try {
    const TriangleMesh mesh = env::loadMeshFile(path);
    if (mesh.indices.empty() || mesh.indices.size() % 3 != 0) bug("accepted mesh without whole triangles", path.string());
    if (mesh.triangleCount() > env::meshImportLimits().maxTriangles) bug("accepted mesh past the triangle limit", path.string());
    for (uint32_t i : mesh.indices)
      if (i >= mesh.positions.size()) bug("accepted mesh with an index out of range", path.string());
    for (const Vec3& p : mesh.positions)
      if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()))
        bug("accepted mesh with a coordinate that is not finite", path.string());
  } catch (const Error& e) {
    const std::string what = e.what();
    if (what.find('\n') != std::string::npos) bug("error on more than one line", what);
    if (what.find(path.string()) == std::string::npos) bug("error not naming the file", what);
  } catch (const std::exception& e) {
    bug("an exception other than tendril::Error", e.what());
  }
  return 0;
}
