// Support meshes from the files users already have (OBJ, PLY, STL, glTF/GLB, FBX, and every
// other format Assimp reads), flattened into one triangle mesh with node transforms applied.
#pragma once

#include "tendril/core/triangle_mesh.h"

#include <filesystem>

namespace tendril::env {

// What a mesh file may hold: any file fails within these in seconds, with memory about
// proportional to them (docs/scene-format.md, "mesh"). Process-wide; the CLI sets them from
// --max-mesh-triangles.
struct MeshImportLimits {
  uint64_t maxFileBytes = uint64_t(1) << 30;  // 1 GiB
  uint64_t maxTriangles = uint64_t(1) << 24;  // 16.8 million, counted after polygons become triangles
};
void setMeshImportLimits(const MeshImportLimits& limits);
MeshImportLimits meshImportLimits();

// Throws Error(path, "", reason) when the file is missing, unreadable, not a mesh Assimp
// understands, broken, or holds no triangles, or has non-finite coordinates; and before
// anything is read into memory when it is larger than the limits allow, or its header (PLY,
// OFF, binary STL) declares more than the file can hold or more triangles than the limit.
TriangleMesh loadMeshFile(const std::filesystem::path& path);

}  // namespace tendril::env
