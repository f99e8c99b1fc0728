// The eleven component types of seed 004 (sidebar "Component Types of the Modeler") and their
// compiled parameters. Units: metres; angles in degrees as in the files (converted where used).
// docs/graph-format.md describes every parameter, its default, range and natural variable.
#pragma once

#include "tendril/graph/param.h"

#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace tendril::graph {

enum class ComponentType : uint8_t {
  Simple, Revo, Horn, Leaf, Tree, Hydra, Wreath, Phiball, Ffd, Hyperpatch, World
};
const char* componentTypeName(ComponentType type);

// The basic parameter set every component has (seed 004: "All components offer a basic set of
// parameters that define a geometric primitive and transform the data of child components"):
// a transform applied to the component's own geometry and to its children, and the colour and
// texture of subsequent geometry (inherited down the i-tree until a component sets its own).
struct BasicParams {
  Vec3Param translate;  // m, in the frame the parent hands down
  Vec3Param rotate;     // degrees, Euler X then Y then Z
  ParamDef scale;       // uniform, > 0
  bool hasColor = false;
  Vec3Param color;      // linear RGB in [0, 1]
  std::optional<std::string> texture;  // "" = untextured ("none" in files)
};

// Simple solids and the two point sets of the sidebar.
enum class Shape : uint8_t { Cube, Sphere, Cylinder, Cone, Disc, Area, Tube };
const char* shapeName(Shape shape);

struct SimpleParams {
  Shape shape = Shape::Cube;
  Vec3Param size;        // m: width (x), height (y), depth (z); solids stand on the origin
  ParamDef segments;     // tessellation around / along
  std::vector<Vec2> section;  // point sets: [x, z] points replacing the default circle/line (m)
  bool caps = false;          // Tube chains: close the first and last ring
};

struct RevoParams {
  std::vector<Vec2> profile;  // [radius, height] points, bottom to top (m)
  bool spline = true;         // Catmull-Rom through the profile points (else a polyline)
  ParamDef samples;           // spline samples per profile span
  ParamDef segments;          // around the axis
  bool caps = true;           // close ends whose radius is not zero
};

// Shared by Horn and Tree: the stem as a chain of segments built by relative transforms
// (seed 004 sidebar, Horn: "a sequence of primitives is generated either along a spline or by
// defining relative transformations between primitives").
struct StemParams {
  ParamDef length;        // m
  ParamDef segments;      // skeleton segments
  ParamDef radius;        // m, natural variable s (along the stem)
  ParamDef curvature;     // degrees of bend over the whole stem, natural variable s
  ParamDef bendDirection; // degrees about the stem axis: which way the curvature bends
  ParamDef twist;         // degrees of roll about the stem axis over the whole stem
  ParamDef gnarl;         // degrees of random deviation per segment, natural variable s
  ParamDef gravitropism;  // rotation toward gravity, radians per stem length (negative: away)
  ParamDef phototropism;  // rotation toward the light, radians per stem length
  ParamDef flexibility;   // scales the World's cylindrical and wind tropisms
};

enum class HornPrimitive : uint8_t { Tube, Cube, Sphere, Cylinder, Cone, Disc };

struct HornParams {
  StemParams stem;
  HornPrimitive primitive = HornPrimitive::Tube;
  std::vector<Vec2> section;  // closed cross-section [x, z] in units of the radius
  std::vector<Vec3> path;     // optional spline through [x, y, z] points (m, horn frame)
};

enum class Outline : uint8_t { None, Conical, Spherical, Hemispherical, Cylindrical, Tapered, Flame, InverseConical };

struct TreeParams {
  StemParams stem;
  ParamDef branches;      // branch positions along the stem
  ParamDef branchStart;   // fraction of the stem where branching starts
  ParamDef branchEnd;     // ... and ends
  ParamDef branchAngle;   // degrees from the stem axis, natural variable: branch t
  ParamDef phyllotaxis;   // degrees of azimuth between successive branch levels
  ParamDef whorl;         // branches per level
  ParamDef branchScale;   // size of branch children (everything), natural variable: branch t
  ParamDef branchLength;  // length of branch children's stems only, natural variable: branch t
  ParamDef branchRoll;    // degrees a child turns about its own axis
  ParamDef deviation;     // degrees the stem turns away from each branch
  Outline outline = Outline::None;  // envelope multiplying branchLength along the stem
};

struct LeafParams {
  ParamDef size;          // blade length (m)
  ParamDef aspect;        // blade width / length
  ParamDef petiole;       // m
  ParamDef curvature;     // degrees the blade bends along its length (positive: tip toward its lower side)
  ParamDef fold;          // degrees of lateral curvature (positive: edges rise toward the upper side)
  ParamDef phototropism;  // 0..1: how far the blade turns to face the light
  ParamDef roll;          // degrees about the blade axis
  ParamDef pitch;         // degrees about the blade's width axis at its base
  ParamDef thickness;     // m
  ParamDef rows;          // mesh resolution along the blade
  ParamDef columns;       // ... and across
  std::vector<Vec2> outline;  // [position along the blade 0..1, half width in blade lengths]
  bool outlineSpline = true;
};

struct HydraParams {
  ParamDef count;
  ParamDef angle;       // degrees from the axis, natural variable t
  ParamDef radius;      // m: children start this far out along their direction
  ParamDef offset;      // degrees of azimuth of the first child
  ParamDef childScale;  // natural variable t
  ParamDef roll;        // degrees about each child's axis
};

struct WreathParams {
  ParamDef count;
  ParamDef radius;      // m
  ParamDef open;        // degrees: first position on the circle
  ParamDef close;       // degrees: last position (360 closes the ring)
  ParamDef tilt;        // degrees the children lean outward
  ParamDef childScale;  // natural variable t
};

struct PhiballParams {
  ParamDef count;
  ParamDef radius;        // m
  ParamDef open;          // theta_1, degrees from the pole
  ParamDef close;         // theta_2
  ParamDef childScale;    // natural variable t
  ParamDef sizeInfluence; // 0..1: how much a child's size widens its share of the area
  ParamDef childArea;     // m²; > 0 computes the radius from the children's area (sidebar)
};

enum class DeformMode : uint8_t { Skeleton, All };

struct FfdParams {
  ParamDef x, y, z;       // deformed local coordinates as functions of x, y, z
  bool hasX = false, hasY = false, hasZ = false;  // a missing function is the identity
  DeformMode mode = DeformMode::All;
  bool disablePrevious = false;
};

struct HyperpatchParams {
  int degree = 2;
  Vec3 size = Vec3::Ones();  // lattice box: x in [-sx/2, sx/2], y in [0, sy], z in [-sz/2, sz/2]
  struct Point {
    int i = 0, j = 0, k = 0;
    Vec3Param offset;     // m
  };
  std::vector<Point> points;
  DeformMode mode = DeformMode::All;
  bool disablePrevious = false;
};

struct WorldParams {
  Vec3Param gravity;      // field of x, y, z (world position)
  Vec3Param light;        // field of x, y, z
  Vec3 cylinderCenter = Vec3::Zero();
  Vec3 cylinderAxis = Vec3::UnitY();
  ParamDef cylinderRadius;    // m
  ParamDef cylinderStrength;  // radians per stem length
  ParamDef cylinderPitch;     // degrees the path around the cylinder climbs
  ParamDef wind;              // radians per stem length
  ParamDef windDirection;     // degrees about +Y, 0 = +X
};

using ComponentParams = std::variant<SimpleParams, RevoParams, HornParams, LeafParams, TreeParams, HydraParams,
                                     WreathParams, PhiballParams, FfdParams, HyperpatchParams, WorldParams>;

}  // namespace tendril::graph
