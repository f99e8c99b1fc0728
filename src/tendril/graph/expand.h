// Expansion of the p-graph into the instance tree (i-tree), seed 004 "Modeling with
// components" and Fig. 2: "When our system traverses the p-graph, it builds a temporary tree of
// component instances that we call the i-tree. This tree is used to generate the geometry."
//
// Each link creates instances of its target where its source has one: one per child link,
// `n` per multiplier (Hydra, Wreath, Phiball, and the Tree's branch links along its stem),
// numbered 0 .. n-1 (the iteration number i). A component in a cycle is instantiated again
// until its recursion depth is reached; leaf links of a recursive component are followed only
// where the recursion has ended. Flag lists (exclude / only) drop given iteration numbers.
//
// Expansion also lays out what later becomes geometry, because children are placed relative to
// it: stems (Horn and Tree) are built segment by segment here, with curvature, gnarl, deviation
// and the tropisms of the World in effect, and become skeleton nodes (parents before children).
// Leaves, primitives, point sets and deformers are recorded for buildPlant (build_plant.h).
//
// Random numbers come from Rng keyed by (graph seed, component, instance path key, slot,
// purpose), so the result does not depend on evaluation order or thread count.
#pragma once

#include "tendril/core/math.h"
#include "tendril/graph/graph.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace tendril::graph {

class ParamEvaluator;

// A similarity transform in world space: the frame a component instance works in.
struct Frame {
  Quat rotation = Quat::Identity();
  Vec3 position = Vec3::Zero();
  float scale = 1.0f;

  Vec3 point(const Vec3& local) const { return position + scale * (rotation * local); }
  Vec3 vector(const Vec3& local) const { return scale * (rotation * local); }
  Vec3 localPoint(const Vec3& world) const { return rotation.conjugate() * (world - position) / scale; }
  Frame operator*(const Frame& local) const {
    return {rotation * local.rotation, point(local.position), scale * local.scale};
  }
  Mat4 matrix() const;
};

struct Instance {
  int32_t component = -1;  // -1: the root (camera) component
  int32_t parent = -1;
  LinkType link = LinkType::Child;
  int32_t iteration = 0;   // i, from the nearest multiplier (inherited through child links)
  int32_t count = 1;       // n
  int32_t depth = 0;       // recursion level (1 for the first instance of a recursive component)
  uint64_t key = 0;        // path key: keys every random stream of the instance
  Frame frame;             // after the component's basic transform
  float lengthScale = 1.0f;  // stems of this instance only: a Tree's branch_length (and outline)
  int32_t anchor = -1;     // skeleton node the instance hangs from (-1: the plant's root frame)
  int32_t chain = -1;      // deformation chain in effect (index into ITree::chains), -1: none
  int32_t world = -1;      // World in effect (index into ITree::worlds), -1: default fields
  int32_t pointSet = -1;   // the point set this instance produced (ITree::pointSets), -1: none
  bool hasColor = false;
  Vec3 color = Vec3(0.8f, 0.8f, 0.8f);
  int32_t texture = -1;    // index into ITree::textures, -1: none set
};

struct StemNode {
  Vec3 position = Vec3::Zero();
  Quat orientation = Quat::Identity();
  float length = 0.0f;
  float radius = 0.0f;
  int32_t parent = -1;
  int32_t stem = -1;  // index into ITree::stems
  uint16_t order = 0;
  uint32_t flags = 0;
};

// A Horn or Tree stem: nodes [firstNode, firstNode + nodeCount) of ITree::nodes.
struct Stem {
  int32_t instance = -1;
  int32_t firstNode = 0;
  int32_t nodeCount = 0;
  int32_t anchor = -1;  // node the first node hangs from
};

struct LeafItem {
  int32_t instance = -1;
  Frame frame;             // attachment point; +Y along the blade, +Z its upper side (unscaled)
  float size = 0.1f;       // blade length (m)
  float aspect = 1.0f;
  float petiole = 0.0f;    // m
  float thickness = 0.0003f;
  float curvature = 0.0f;  // radians
  float fold = 0.0f;       // radians
  int32_t rows = 8, columns = 4;
  bool mesh = false;       // a curved or outlined blade (a primitive), else a textured card
  Vec3 color = Vec3::Ones();
  int32_t texture = -1;
};

enum class ShapeKind : uint8_t { Solid, Revo, HornSection };

// A primitive: a Simple solid, a Revo surface, a Horn bead or a Horn with a cross-section.
struct ShapeItem {
  int32_t instance = -1;
  ShapeKind kind = ShapeKind::Solid;
  Shape shape = Shape::Cube;
  Frame frame;             // the primitive's frame (its size is baked into the mesh)
  Vec3 size = Vec3::Ones();
  int32_t segments = 16;
  int32_t samples = 0;     // Revo: spline samples per profile span
  int32_t firstRing = 0, ringCount = 0;  // HornSection: rings in ITree::rings
  Vec3 color = Vec3(0.8f, 0.8f, 0.8f);
  int32_t texture = -1;
};

// One ring of a Horn with a cross-section: the frame of the ring and its radius (m).
struct Ring {
  Frame frame;
  float radius = 0.0f;
};

// A Simple "area" (open) or "tube" (closed) point set; consecutive sets of the i-tree are
// triangulated (seed 004 sidebar: "The point sets generated by subsequent instances in the
// i-tree are triangulated").
struct PointSetItem {
  int32_t instance = -1;
  int32_t predecessor = -1;  // nearest ancestor's point set, -1: none
  bool closed = false;
  bool caps = false;
  std::vector<Vec3> points;  // world space
  Vec3 color = Vec3(0.8f, 0.8f, 0.8f);
  int32_t texture = -1;
};

// An FFD or Hyperpatch instance.
struct Deformer {
  int32_t instance = -1;
  int32_t component = -1;
  DeformMode mode = DeformMode::All;
  Frame frame;
  EvalVars vars;                 // the instance's i, n, t, depth (FFD functions)
  std::vector<Vec3> offsets;     // Hyperpatch: (degree+1)^3 control point offsets, i fastest
  int degree = 0;
  Vec3 size = Vec3::Ones();
  bool identity = false;         // moves nothing (an FFD without functions, an undisplaced lattice)
};

// Deformers in effect for an instance, innermost first: chains[c].deformer, then
// chains[chains[c].next] ... (-1 ends the list).
struct ChainLink {
  int32_t deformer = -1;
  int32_t next = -1;
};

struct WorldItem {
  int32_t instance = -1;
  int32_t component = -1;
  EvalVars vars;
  Vec3 gravity = Vec3(0, -1, 0), light = Vec3(0, 1, 0);  // when constant (unit or zero)
  bool gravityConstant = true, lightConstant = true;
  Vec3 cylinderCenter = Vec3::Zero(), cylinderAxis = Vec3::UnitY();
  float cylinderRadius = 0.05f, cylinderStrength = 0.0f, cylinderPitch = 0.0f;  // m, rad/stem, rad
  Vec3 wind = Vec3::Zero();  // horizontal direction times strength (rad per stem length)
};

struct ExpandOptions {
  uint64_t seed = 1;
  Frame placement;  // where the root component stands (world)
};

struct ITree {
  std::shared_ptr<const Graph> graph;
  uint64_t seed = 1;
  std::vector<Instance> instances;  // depth-first, parents before children; [0] is the root
  std::vector<StemNode> nodes;      // the skeleton, parents before children
  std::vector<Stem> stems;
  std::vector<LeafItem> leaves;
  std::vector<ShapeItem> shapes;
  std::vector<Ring> rings;
  std::vector<PointSetItem> pointSets;
  std::vector<Deformer> deformers;
  std::vector<ChainLink> chains;
  std::vector<WorldItem> worlds;
  std::vector<std::string> textures;  // texture specs used ("" = untextured)
  std::shared_ptr<ParamEvaluator> evaluator;  // this expansion's compiled functions

  // Instances of one component (by index; -1 counts the root).
  size_t countOf(int32_t component) const;
  size_t countOf(std::string_view name) const;
  // Children of an instance, in creation order.
  std::vector<int32_t> childrenOf(int32_t instance) const;
};

// Expands the graph. Errors in functions (evaluation errors, values out of range) name the file
// and the parameter's JSON pointer; more than graph.maxInstances instances is an Error saying
// which limit to raise.
ITree expand(std::shared_ptr<const Graph> graph, const ExpandOptions& options = {});

// The golden-section placement of seed 004's sidebar "Golden Section Placement on a Sphere":
// object i at azimuth Φ_i = i·dΦ, dΦ = 2π/τ (τ the golden ratio), and polar angle θ_i where the
// section between θ1 and θ_i holds the area of the objects before it plus half its own:
// cos θ_i = cos θ1 − (A_i / A_N)(cos θ1 − cos θ2), A_i = Σ_{j<i} a_j + a_i/2. With equal areas
// this places the objects on equal-area bands, so they cover the section evenly. `areas` may
// be empty (equal sizes). Angles in radians; θ from the +Y pole.
struct SpherePlacement {
  float theta = 0.0f, phi = 0.0f;
  Vec3 normal = Vec3::UnitY();          // unit, from the centre
  Quat rotation = Quat::Identity();     // +Y along the normal, +Z toward the pole
};
std::vector<SpherePlacement> phiballPlacements(int count, float open, float close, const std::vector<float>& areas);
// The sphere radius that holds objects of total area `area` on the section (sidebar:
// R = sqrt(A_N / (2π (cos θ1 − cos θ2)))).
float phiballRadius(float area, float open, float close);

// Weber & Penn's envelope shapes (seed 004 cites them for the overall shape of trees): the
// factor applied to branch lengths at relative position `x` in [0, 1] along the branching zone.
float outlineRatio(Outline outline, float x);

}  // namespace tendril::graph
