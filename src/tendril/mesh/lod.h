// Levels of detail of one plant, all from its one grown skeleton (issue 26, docs/scene-format.md
// "Levels of detail"). LOD0 is the plant meshed as always. Each lower level k has a triangle
// budget (LOD0's triangles × ratio^k, or an explicit count, and never more than the level above
// it has) and is made, in this order, by
//
//   1. pruning twigs: every side branch whose whole subtree is shorter than a length growing
//      with the level (a fraction of the plant's size) goes; the leaves and primitives it
//      carried stay where they were, re-hung on the nearest node that stays;
//   2. thinning leaves: fewer leaves (a stratified, nested choice along the branches, at least
//      one of every shape), each blade larger about its centre so that every shape keeps its
//      total leaf area; primitives (a graph plant's leaves, seeds, petals) likewise, never
//      fewer than the fraction f of them (f: the level's budget over LOD0's triangles), so
//      that the enlarged ones stay within the plant's bounds;
//   3. lowering the tessellation: fewer radial segments and subdivisions, one quad per leaf,
//      the branch radii widened so that the coarser rings (polygons inscribed in the circle)
//      have LOD0's mean width (perimeter / π);
//   4. simplifying with meshoptimizer (meshopt_simplify, and meshopt_simplifySloppy where the
//      topology-keeping simplifier stops short) what is still over the bark's and the
//      primitives' share of the budget. Primitive groups made only of kinds too few to thin (a
//      flower head, a sunflower's dozen large leaves) stay whole while the budget allows: each
//      is a large part of the outline, and simplifying curved, folded blades pulled their
//      outlines in (the sunflower lost 11-14 % of its side views); what they take beyond their
//      share comes out of the other primitives' and the bark's.
//
// A level that cannot be brought within its budget (a budget below what one leaf per shape and
// the roughest bark take) is kept at the fewest triangles reached and marked `overBudget()`;
// the exporters warn about it. Every level, and LOD0 when a chain is written, then has its
// triangles ordered for the post-transform vertex cache and its vertices for fetch
// (optimizeMeshOrder). The levels are made in parallel (each on the budget it has if the levels
// above meet theirs; a level whose real budget differs is made again), and large meshes are
// ordered in runs of vertex-disjoint triangles in parallel. Everything here is deterministic
// and independent of the thread count.
#pragma once

#include "tendril/mesh/mesh_options.h"
#include "tendril/mesh/plant_mesh.h"
#include "tendril/plant/plant_model.h"

#include <cstdint>
#include <string>
#include <vector>

namespace tendril::mesh {

inline constexpr int kMaxLods = 8;

struct LodSettings {
  int levels = 1;                   // LOD0 included; 1 = no chain (1..kMaxLods)
  float ratio = 0.45f;              // LODk's budget: LOD0's triangles × ratio^k (0.01..1)
  std::vector<uint64_t> triangles;  // or explicit budgets of LOD1, LOD2, … (levels − 1, non-increasing, > 0)
};

// Throws Error(source, "lods" / "lod_ratio" / "lod_triangles/<i>", what was expected).
void validateLodSettings(const LodSettings& lods, const std::string& source);

// The settings' budget of LOD `level` (>= 1) of a plant whose LOD0 has `lod0Triangles`.
uint64_t lodBudget(const LodSettings& lods, size_t lod0Triangles, int level);

// One lower level of detail and how it was made.
struct LodLevel {
  PlantMesh mesh;
  uint64_t budget = 0;     // the triangles it may have (at most the level above's count)
  size_t triangles = 0;    // the triangles it has
  MeshOptions options;     // the tessellation it was meshed with
  float twigLength = 0.0f; // side branches with less stem than this in their subtree were pruned (m)
  size_t prunedNodes = 0;
  size_t leaves = 0;       // leaves kept
  float leafScale = 1.0f;  // mean factor on the kept blades' size (each shape keeps its leaf area)
  size_t primitives = 0;   // primitives kept
  float primitiveScale = 1.0f;  // mean factor on the kept primitives' size (each mesh keeps its area)
  bool simplified = false; // meshopt_simplify ran on a part
  bool sloppy = false;     // ... and meshopt_simplifySloppy was needed
  bool overBudget() const { return triangles > budget; }
};

// LOD1 … LOD(levels − 1) of `plant`, whose LOD0 mesh is `lod0` (meshed with `options`), into
// `out` (resized; its meshes keep their memory). Vertex node ids (TriangleMesh::nodeIds) are
// the plant's own node indices. Each level is ordered with optimizeMeshOrder; `lod0` is not
// touched. Throws what buildPlantMesh throws.
void buildLods(const plant::PlantModel& plant, const MeshOptions& options, const PlantMesh& lod0,
               const LodSettings& lods, std::vector<LodLevel>& out);

// The screen coverage (fraction of the viewport's height) below which each level, LOD0 first,
// gives way to the next (glTF MSFT_lod's MSFT_screencoverage), from their triangle counts:
// a constant triangle density on screen, so level k+1 takes over at sqrt(triangles_{k+1} /
// triangles_0); the last level is drawn down to 1 % (or half the value before it, if smaller).
std::vector<float> lodScreenCoverage(const std::vector<size_t>& triangles);

// --- the steps, for tests ---

// The plant without the side branches (chains starting at a branch start or a second child)
// whose whole subtree has less than `minLength` of stem; leaves and primitives of pruned nodes
// are re-hung, unmoved, on their nearest kept ancestor. `keptNodes` (if given) receives, per
// node of the result, its index in `plant`.
plant::PlantModel pruneTwigs(const plant::PlantModel& plant, float minLength, std::vector<uint32_t>* keptNodes = nullptr);

// Keeps about `keep` leaves (at least one of every shape in use; every leaf if keep >= count),
// chosen along the branches so that the kept ones spread evenly, and the choice for fewer
// leaves is a subset of that for more. Each shape's kept blades are scaled about their centres
// so that the shape's total blade area (size² × aspect) is what it was. Returns the mean scale.
float thinLeaves(plant::PlantModel& plant, size_t keep);

// The same for primitives (plant::Primitive; a graph plant's leaves, seeds and petals): about
// `keep` of them, at least one of each mesh, each kept one scaled about the centre of its
// mesh's bounds so that each mesh's instances keep their total surface. Kinds (texture and
// mesh size) with fewer than 16 instances are kept whole. Returns the mean scale.
float thinPrimitives(plant::PlantModel& plant, size_t keep);

// Reorders the mesh's triangles for the post-transform vertex cache
// (meshopt_optimizeVertexCache) and then its vertices in the order the triangles use them
// (meshopt_optimizeVertexFetchRemap; every per-vertex array follows, unreferenced vertices go).
// The triangles and the surface are unchanged. A mesh of 2^17 triangles or more is cut, where
// the triangles before use only vertices below those after (a branch chain's tube, a run of
// leaf quads), into runs of at least 2^16 triangles, ordered each on its own in parallel (the
// runs depend on the mesh alone); a plant mesh's parts are ordered in parallel.
void optimizeMeshOrder(TriangleMesh& mesh);
void optimizeMeshOrder(PlantMesh& mesh);

}  // namespace tendril::mesh
