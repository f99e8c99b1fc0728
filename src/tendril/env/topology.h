// Mesh topology checks and the geometric kernels behind distance queries.
#pragma once

#include "tendril/core/triangle_mesh.h"

#include <cstdint>
#include <vector>

namespace tendril::env {

// Vertices merged by exact position (attribute seams in imported meshes split vertices that
// are the same point of the surface).
struct WeldedMesh {
  std::vector<Vec3> positions;
  std::vector<uint32_t> indices;    // 3 per triangle, into positions
  std::vector<uint32_t> remap;      // original vertex -> welded vertex
};
WeldedMesh weld(const TriangleMesh& mesh);

struct TopologyReport {
  size_t triangles = 0;
  size_t degenerateTriangles = 0;  // zero area
  size_t boundaryEdges = 0;        // used by one triangle
  size_t nonManifoldEdges = 0;     // used by three or more
  size_t inconsistentEdges = 0;    // two triangles traverse the edge in the same direction
  double signedVolume = 0.0;       // divergence theorem; > 0 for outward winding (m^3)
  bool closed() const { return boundaryEdges == 0 && nonManifoldEdges == 0 && inconsistentEdges == 0; }
};
TopologyReport analyzeTopology(const WeldedMesh& mesh);

// For each triangle, the triangle across each of its edges AB, BC, CA (3 per triangle), or
// kNoNeighbor on boundary and non-manifold edges.
inline constexpr uint32_t kNoNeighbor = 0xffffffffu;
std::vector<uint32_t> triangleNeighbors(const WeldedMesh& mesh);

// Which feature of a triangle a closest point lies on.
enum class TriangleFeature : uint8_t { Face, EdgeAB, EdgeBC, EdgeCA, VertexA, VertexB, VertexC };

struct ClosestOnTriangle {
  Vec3 point;
  TriangleFeature feature;
};
// Closest point to p on triangle abc (Ericson, Real-Time Collision Detection §5.1.5).
ClosestOnTriangle closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// Angle-weighted pseudonormals of a closed mesh (Bærentzen & Aanæs 2005): the sign of
// (p − q)·n at the closest feature's pseudonormal n tells inside from outside exactly.
struct Pseudonormals {
  std::vector<Vec3> face;    // per triangle
  std::vector<Vec3> edge;    // per triangle, 3 per (AB, BC, CA)
  std::vector<Vec3> vertex;  // per welded vertex
  Vec3 at(uint32_t triangle, TriangleFeature f, const uint32_t* tri) const;
};
Pseudonormals computePseudonormals(const WeldedMesh& mesh);

}  // namespace tendril::env
