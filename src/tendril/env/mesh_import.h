// Support meshes from the files users already have (OBJ, PLY, STL, glTF/GLB, FBX, and every
// other format Assimp reads), flattened into one triangle mesh with node transforms applied.
#pragma once

#include "tendril/core/triangle_mesh.h"

#include <filesystem>

namespace tendril::env {

// Throws Error(path, "", reason) when the file is missing, unreadable, not a mesh Assimp
// understands, broken, or holds no triangles, or has non-finite coordinates.
TriangleMesh loadMeshFile(const std::filesystem::path& path);

}  // namespace tendril::env
