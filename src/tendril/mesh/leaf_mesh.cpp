#include "tendril/mesh/leaf_mesh.h"

#include "tendril/core/parallel.h"

#include <algorithm>
#include <cmath>

namespace tendril::mesh {

using plant::PlantModel;

size_t leafShapeCount(const PlantModel& plant) {
  size_t count = plant.leafShapes.size();
  for (uint16_t s : plant.leafShape) count = std::max(count, static_cast<size_t>(s) + 1);
  return count;
}

plant::LeafShape leafShapeFor(const PlantModel& plant, size_t shape) {
  plant::LeafShape result;
  if (shape < plant.leafShapes.size()) result = plant.leafShapes[shape];
  if (result.texture.empty()) result.texture = kDefaultLeafTexture;
  return result;
}

void buildLeafQuad(const PlantModel& plant, size_t leaf, float aspect, const MeshOptions& options,
                   Vec3* positions, Vec3* normals, Vec2* uvs, uint32_t* indices, uint32_t baseVertex) {
  const int rows = options.leafSubdivisions;
  Quat worldFromLeaf = plant.leafWorldRotation(leaf);
  Mat3 axes = worldFromLeaf.toRotationMatrix();
  Vec3 x = axes.col(0), y = axes.col(1), z = axes.col(2);
  float size = plant.leafSize[leaf];
  Vec3 halfWidth = (0.5f * size * aspect) * x;
  Vec3 p = plant.leafWorldPosition(leaf) + plant.leafPetiole[leaf] * y;
  float bend = plant.leafMotion[leaf].x();
  float step = size / static_cast<float>(rows);
  for (int k = 0; k <= rows; ++k) {
    float t = static_cast<float>(k) / static_cast<float>(rows);
    // Rotation about leaf X by the bend reached at this row: Y -> cos·Y + sin·Z,
    // Z -> −sin·Y + cos·Z.
    float angle = bend * t;
    Vec3 normal = bend == 0.0f ? z : Vec3(std::cos(angle) * z - std::sin(angle) * y);
    positions[2 * k] = p - halfWidth;
    positions[2 * k + 1] = p + halfWidth;
    normals[2 * k] = normal;
    normals[2 * k + 1] = normal;
    uvs[2 * k] = Vec2(0.0f, t);
    uvs[2 * k + 1] = Vec2(1.0f, t);
    if (k == rows) break;
    // Advance along the blade in the direction at the middle of the quad (arc midpoint rule),
    // so the bent blade keeps its length.
    float mid = bend * (static_cast<float>(k) + 0.5f) / static_cast<float>(rows);
    Vec3 dir = bend == 0.0f ? y : Vec3(std::cos(mid) * y + std::sin(mid) * z);
    p += step * dir;
  }
  // Counter-clockwise seen from +Z: base-left, base-right, tip-right, then tip-left.
  for (int k = 0; k < rows; ++k) {
    uint32_t a = baseVertex + 2 * k, b = a + 1, c = a + 3, d = a + 2;
    uint32_t* t = indices + 6 * k;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    t[3] = a;
    t[4] = c;
    t[5] = d;
  }
}

std::vector<TriangleMesh> buildLeafQuads(const PlantModel& plant, const MeshOptions& options) {
  std::vector<TriangleMesh> meshes;
  buildLeafQuads(plant, options, meshes);
  return meshes;
}

void buildLeafQuads(const PlantModel& plant, const MeshOptions& options, std::vector<TriangleMesh>& meshes) {
  size_t shapes = leafShapeCount(plant);
  size_t leaves = plant.leafCount();
  // Each leaf's slot within its shape's mesh, in leaf order.
  std::vector<uint32_t> slot(leaves);
  std::vector<uint32_t> perShape(shapes, 0);
  for (size_t i = 0; i < leaves; ++i) slot[i] = perShape[plant.leafShape[i]]++;
  std::vector<float> aspect(shapes);
  for (size_t s = 0; s < shapes; ++s) aspect[s] = leafShapeFor(plant, s).aspect;

  size_t nv = leafVertexCount(options), ni = leafIndexCount(options);
  meshes.resize(shapes);
  for (size_t s = 0; s < shapes; ++s) {
    meshes[s].positions.resize(perShape[s] * nv);
    meshes[s].normals.resize(perShape[s] * nv);
    meshes[s].uvs.resize(perShape[s] * nv);
    meshes[s].indices.resize(perShape[s] * ni);
    meshes[s].nodeIds.resize(perShape[s] * nv);
  }
  parallelFor(0, leaves, [&](size_t i) {
    uint16_t s = plant.leafShape[i];
    TriangleMesh& m = meshes[s];
    size_t v = slot[i] * nv;
    buildLeafQuad(plant, i, aspect[s], options, &m.positions[v], &m.normals[v], &m.uvs[v],
                  &m.indices[slot[i] * ni], static_cast<uint32_t>(v));
    std::fill_n(m.nodeIds.begin() + v, nv, static_cast<uint32_t>(plant.leafNode[i]));
  }, 1024);
}

}  // namespace tendril::mesh
