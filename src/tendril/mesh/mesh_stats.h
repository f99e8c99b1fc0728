// Measuring a mesh (the meshoptimizer habit: every generator has an analyze… to check it).
#pragma once

#include "tendril/core/triangle_mesh.h"

#include <cstddef>

namespace tendril::mesh {

struct MeshStats {
  size_t vertices = 0;
  size_t triangles = 0;
  size_t degenerateTriangles = 0;  // area below 1e-12 m² (or an index repeated)
  size_t invalidIndices = 0;       // indices >= vertex count (and a trailing partial triangle)
  size_t nonFinite = 0;            // vertices with a NaN/inf position, normal or uv
  size_t nonUnitNormals = 0;       // | |n| − 1 | > 1e-3
  bool attributesMatch = true;     // normals and uvs empty or one per vertex
  Bounds3 bounds;                  // of all positions
};

MeshStats analyzeMesh(const TriangleMesh& mesh);

}  // namespace tendril::mesh
