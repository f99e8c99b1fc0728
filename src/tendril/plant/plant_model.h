// PlantModel: what every growth model produces and everything downstream (mesh, export,
// render, wind motion) consumes. Structure of arrays; parents come before children.
//
// Skeleton: one node = one internode segment = one oriented particle. A node's segment starts
// at `position` and runs `length` metres along the node's local +Y (its growth direction);
// local +Z faces away from the support surface (for climbing plants) or is an arbitrary
// perpendicular otherwise. `orientation` is worldFromNode.
//
// Leaves hang off nodes: nodeFromLeaf = (leafOffset, leafRotation). A leaf's local +Y runs
// from the petiole along the blade, local +Z is the blade's upper-side normal, +X its width.
//
// Primitives are meshes attached to nodes (the graph model's Simple/Revo/... shapes).
#pragma once

#include "tendril/core/math.h"
#include "tendril/core/triangle_mesh.h"

#include <cstdint>
#include <string>
#include <vector>

namespace tendril::plant {

enum NodeFlags : uint32_t {
  kNodeClimbing = 1u << 0,     // the segment grew attached to (near) a support surface
  kNodeBranchStart = 1u << 1,  // first segment of a lateral branch
  kNodeApex = 1u << 2,         // last segment of a branch whose tip is still growing
  kNodeDead = 1u << 3,         // last segment of a branch whose tip died
  kNodeAnchored = 1u << 4,     // held by an anchor to a surface (particle plants)
  kNodeBroken = 1u << 5,       // detached from its plant (a fallen piece)
  kNodeLeafNode = 1u << 6,     // carries leaves
};

// Why a branch's tip stopped growing, kept in bits 8–11 of its last node's flags next to
// kNodeDead (models/diagnosis.h reports plants that stop early by these).
enum class TipEnd : uint8_t {
  Unknown = 0,  // not recorded (the model does not say, or the branch was cut)
  NoSupport,    // a climbing shoot went too long without a support in reach
  Blocked,      // obstacles (or a repelling stroke, Environment::repelled) left it nowhere to grow
  Crowded,      // its own or other plants' stems already fill the space ahead
  Capped,       // the plant reached a cap (max segments, max particles)
  Shortened,    // its internodes became shorter than the species' minimum (wind, decrease)
  Rule,         // the species' own rule ended it (a die rule)
};
inline constexpr uint32_t kNodeTipEndShift = 8;
inline constexpr uint32_t kNodeTipEndMask = 0xFu << kNodeTipEndShift;
inline TipEnd tipEnd(uint32_t flags) { return TipEnd((flags & kNodeTipEndMask) >> kNodeTipEndShift); }
// `flags` as a dead end for `why` (an earlier recorded reason is replaced).
inline uint32_t deadEnd(uint32_t flags, TipEnd why) {
  return (flags & ~kNodeTipEndMask) | kNodeDead | (uint32_t(why) << kNodeTipEndShift);
}

// What a leaf shape id means: the texture drawn on the blade and its proportions.
struct LeafShape {
  std::string texture;       // image path, or "builtin:<name>" for a generated texture
  float aspect = 1.0f;       // blade width / blade length
  Vec3 tint = Vec3::Ones();  // multiplied with the texture colour
};

struct BarkMaterial {
  std::string texture = "builtin:bark";
  Vec3 color = Vec3(0.42f, 0.32f, 0.22f);  // linear RGB base colour
  float roughness = 0.9f;
};

// A mesh in the local frame of a primitive, with its material colour.
struct PrimitiveMesh {
  std::string name;
  TriangleMesh mesh;
  Vec3 color = Vec3(0.8f, 0.8f, 0.8f);  // linear RGB
  std::string texture;                   // optional image path or "builtin:<name>"
};

struct Primitive {
  int32_t node = -1;                     // node it is attached to (-1 = plant root frame)
  uint32_t mesh = 0;                     // index into PlantModel::meshes
  Mat4 nodeFromPrimitive = Mat4::Identity();
};

struct PlantModel {
  std::string name;
  std::string species;
  BarkMaterial bark;
  std::vector<LeafShape> leafShapes;  // leafShape[i] indexes this

  // --- skeleton ---
  std::vector<Vec3> position;     // segment start, world (m)
  std::vector<Quat> orientation;  // worldFromNode
  std::vector<float> length;      // m
  std::vector<float> radius;      // m
  std::vector<int32_t> parent;    // index of the parent node, -1 for a root
  std::vector<float> age;         // s since the node was created
  std::vector<uint16_t> order;    // branch order: 0 main stem, 1 its laterals, ...
  std::vector<uint32_t> flags;    // NodeFlags

  // --- leaves ---
  std::vector<int32_t> leafNode;     // node the leaf is attached to
  std::vector<Vec3> leafOffset;      // nodeFromLeaf translation (m)
  std::vector<Quat> leafRotation;    // nodeFromLeaf rotation
  std::vector<float> leafSize;       // blade length (m)
  std::vector<float> leafThickness;  // blade thickness (m)
  std::vector<float> leafPetiole;    // petiole length (m)
  std::vector<uint16_t> leafShape;   // index into leafShapes
  std::vector<Vec3> leafMotion;      // wind motion state: bend, twist, vibration angles (rad)

  // --- primitives ---
  std::vector<PrimitiveMesh> meshes;
  std::vector<Primitive> primitives;

  size_t nodeCount() const { return position.size(); }
  size_t leafCount() const { return leafNode.size(); }

  struct NodeDef {
    Vec3 position = Vec3::Zero();
    Quat orientation = Quat::Identity();
    float length = 0.0f;
    float radius = 0.0f;
    int32_t parent = -1;
    float age = 0.0f;
    uint16_t order = 0;
    uint32_t flags = 0;
  };
  struct LeafDef {
    int32_t node = -1;
    Vec3 offset = Vec3::Zero();
    Quat rotation = Quat::Identity();
    float size = 0.0f;
    float thickness = 0.0003f;
    float petiole = 0.0f;
    uint16_t shape = 0;
  };
  // Appends a node / leaf and returns its index.
  int32_t addNode(const NodeDef& def);
  int32_t addLeaf(const LeafDef& def);
  // Keeps only the leaves kept[0], kept[1], … (ascending indices), in that order; the others
  // are removed (leafMotion too, where the plant carries it).
  void keepLeaves(const std::vector<uint32_t>& kept);
  void reserve(size_t nodes, size_t leaves);
  void clear();

  Vec3 direction(size_t node) const { return orientation[node] * Vec3::UnitY(); }
  Vec3 tip(size_t node) const { return position[node] + length[node] * direction(node); }
  // worldFromLeaf as a rotation and the leaf's attachment point (world).
  Quat leafWorldRotation(size_t leaf) const { return orientation[leafNode[leaf]] * leafRotation[leaf]; }
  // The blade width / length of leaf `leaf` (its shape's, or the default's for an id without one).
  float leafAspect(size_t leaf) const {
    const size_t shape = leafShape[leaf];
    return shape < leafShapes.size() ? leafShapes[shape].aspect : LeafShape{}.aspect;
  }
  Vec3 leafWorldPosition(size_t leaf) const {
    return position[leafNode[leaf]] + orientation[leafNode[leaf]] * leafOffset[leaf];
  }

  // Children lists (CSR): children of node i are childIndex[childStart[i] .. childStart[i+1]).
  void children(std::vector<int32_t>& childStart, std::vector<int32_t>& childIndex) const;
};

// Throws Error(source, "node N" / "leaf N", what) on the first problem: array sizes that
// disagree, non-finite numbers, negative lengths, non-positive radii, parents that do not come
// before their children, quaternions that are not unit length, leaves on missing nodes.
void validate(const PlantModel& plant, const std::string& source);

struct PlantStats {
  size_t nodes = 0;
  size_t leaves = 0;
  size_t roots = 0;
  size_t tips = 0;       // nodes without children
  size_t branches = 0;   // roots + branch starts
  uint16_t maxOrder = 0;
  double totalLength = 0.0;  // sum of segment lengths (m)
  Bounds3 bounds;            // of segment ends and leaf attachment points
};
PlantStats computeStats(const PlantModel& plant);

// Stable hash of the whole content (every array, bit for bit, and the names and materials).
uint64_t contentHash(const PlantModel& plant);
// Hash of several plants in order.
uint64_t contentHash(const std::vector<PlantModel>& plants);

}  // namespace tendril::plant
