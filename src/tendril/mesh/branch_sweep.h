// Bark geometry: the skeleton split into branch chains, each swept as one smooth generalised
// cylinder (seed 003 §3.10: "branches are created using cylindrical NURBS surfaces, where each
// internode segment signifies a vertex with a radius"; see curve.h for the spline and frames).
//
// Per chain: a centripetal Catmull-Rom spline through the segment start points and the last
// tip, `subdivisions` samples per segment, the radius interpolated linearly along each
// segment, rotation-minimising frames (no twist), `radialSegments` vertices per ring plus a
// duplicated seam vertex. UVs: u runs around the ring in [0, 1]; v is arc length divided by
// the circumference of the chain's base (2π · base radius), so a square bark texture is not
// stretched, and it is continuous along the whole chain. v grows with the image's up
// direction (OpenGL/OBJ convention; the glTF writer flips it). Optional fan caps close the base
// (facing back along the chain) and the tip.
//
// Node ids (TriangleMesh::nodeIds): every vertex carries the skeleton node whose segment its
// ring was swept from — rings from a segment's start up to (not including) the next segment's
// start, the chain's last ring and the caps those of their ring's segment. A node merged into
// the point after it (kMergeDistance) has no segment of its own and no vertices; the point
// belongs to the last node that starts there.
//
// Geometry is written into caller-owned arrays at offsets planned beforehand, chains and ring
// samples in parallel, so the output is bit-identical for any thread count.
#pragma once

#include "tendril/core/triangle_mesh.h"
#include "tendril/mesh/mesh_options.h"
#include "tendril/plant/plant_model.h"

#include <cstdint>
#include <span>
#include <vector>

namespace tendril::mesh {

// Skeleton nodes grouped into chains (CSR): chain c is nodes[start[c] .. start[c+1]).
// A chain runs from a root, a kNodeBranchStart node, or a second (third, ...) unflagged child
// of a node, and continues through each node's first child that is not a branch start.
struct BranchChains {
  std::vector<uint32_t> start{0};
  std::vector<int32_t> nodes;

  size_t size() const { return start.size() - 1; }
  std::span<const int32_t> chain(size_t c) const {
    return {nodes.data() + start[c], nodes.data() + start[c + 1]};
  }
};

// Chains in the order of their first node. O(nodes).
BranchChains buildBranchChains(const plant::PlantModel& plant);

// Where each chain's samples, vertices and indices go (prefix sums, size chains + 1). A chain
// whose points all coincide gets no geometry.
struct SweepLayout {
  std::vector<uint32_t> sampleStart{0};
  std::vector<uint32_t> vertexStart{0};
  std::vector<uint32_t> indexStart{0};

  size_t sampleCount() const { return sampleStart.back(); }
  size_t vertexCount() const { return vertexStart.back(); }
  size_t indexCount() const { return indexStart.back(); }
};

// Points closer than this (m) to the previous point of their chain are merged with it, so
// zero-length segments and duplicate points produce no degenerate frames.
inline constexpr float kMergeDistance = 1e-6f;

// Samples (rings) of a chain of `points` distinct spline points: (points − 1) · subdivisions + 1.
// Vertices: samples · (radialSegments + 1), plus radialSegments + 1 per cap.
SweepLayout planSweep(const plant::PlantModel& plant, const BranchChains& chains, const MeshOptions& options);

// Caller-owned output arrays, each at least the size the layout asks for. `baseVertex` is
// added to every index written (for sweeping into the middle of a larger vertex buffer).
struct MeshSpans {
  std::span<Vec3> positions;
  std::span<Vec3> normals;
  std::span<Vec2> uvs;
  std::span<uint32_t> indices;
  uint32_t baseVertex = 0;
  std::span<uint32_t> nodeIds = {};  // optional: left unwritten when empty
};

void sweepBranches(const plant::PlantModel& plant, const BranchChains& chains, const MeshOptions& options,
                   const SweepLayout& layout, const MeshSpans& out);

// Convenience: plans, allocates and sweeps every chain of the plant into one mesh.
TriangleMesh sweepBranches(const plant::PlantModel& plant, const MeshOptions& options);
// The same into `mesh`, whose arrays are resized (a mesh reused from plant to plant keeps its
// memory: the streaming .glb writer meshes hundreds of plants through a few of them).
void sweepBranches(const plant::PlantModel& plant, const MeshOptions& options, TriangleMesh& mesh);

}  // namespace tendril::mesh
