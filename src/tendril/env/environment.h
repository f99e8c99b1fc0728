// The Environment answers geometric questions about a scene and nothing else: ray casts,
// closest surface point, signed distance, light exposure, attraction from painted strokes and
// wind velocity. Growth models ask; they never look inside meshes themselves.
//
// Obstacles are triangle meshes in their own frame plus a rigid worldFromLocal transform that
// may change between steps (setObstacleTransform + commit). Ray and closest-point queries run
// on one Embree BVH over all obstacles in world space; signed distances come from a per-
// obstacle grid in local space (built on first use), so moving an obstacle never rebuilds it.
//
// Plants can be supports too: a host plant's stem segments, given as tubes (setStems), answer
// the same queries as obstacles — ray casts, closest point, signed distance, occlusion — and its
// leaves shade the light. Stems belong to an owner (the model system of the host plant); the
// queries see every owner's stems but the viewer's (setStemViewer), since plants of one model
// already meet inside their own system.
//
// Queries are const and thread-safe after commit(); edits and commit() are not.
#pragma once

#include "tendril/core/math.h"
#include "tendril/core/triangle_mesh.h"
#include "tendril/env/wind_field.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tendril::env {

class SdfGrid;

enum class ObstacleKind { Plane, Box, Sphere, Cylinder, Wall, Mesh };

struct ObstacleDef {
  std::string name;
  ObstacleKind kind = ObstacleKind::Mesh;
  std::string source;  // where it came from (file path, or the scene file), for messages
  TriangleMesh mesh;   // local frame, any scale already applied
  RigidTransform worldFromLocal;
  // Signed-distance grid cell edge (m); 0 = automatic: longest side / 64, clamped to [1, 5] cm.
  float sdfCell = 0.0f;
  Vec3 color = Vec3(0.6f, 0.6f, 0.6f);  // linear RGB, for rendering and preview export
};

struct ObstacleInfo {
  std::string name;
  ObstacleKind kind;
  std::string source;
  RigidTransform worldFromLocal;
  Vec3 color;
  bool closed = false;       // watertight, manifold, consistently wound: distances are signed
  // Closed and convex (every vertex on or behind every face's plane; checked for meshes of up
  // to kConvexCheckTriangles triangles, others count as not convex). The plane through a
  // convex obstacle's closest point to an outside point, facing that point, has the whole
  // obstacle behind it: distances to it are at least the distances to that plane.
  bool convex = false;
  size_t triangles = 0;
  Bounds3 localBounds;
  Bounds3 worldBounds;
};

inline constexpr size_t kConvexCheckTriangles = 2048;

// What a hit or a closest point lies on: obstacle `obstacle` (its triangle `triangle`), or,
// when obstacle == kOnStem, the plant stem whose index is in `triangle` (Environment::stem).
// (The layout stays that of an obstacle answer: the climbing model saves answers as they are.)
inline constexpr uint32_t kOnStem = 0xffffffffu;
inline constexpr uint32_t kNoStem = 0xffffffffu;

struct RayHit {
  float t = 0.0f;
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::Zero();  // unit face normal (outward for closed obstacles and stems)
  uint32_t obstacle = 0;
  uint32_t triangle = 0;
  bool onStem() const { return obstacle == kOnStem; }
  uint32_t stem() const { return onStem() ? triangle : kNoStem; }
};

struct SurfacePoint {
  Vec3 point = Vec3::Zero();   // closest point on any obstacle
  Vec3 normal = Vec3::Zero();  // unit normal of the closest triangle (outward if closed)
  Vec3 away = Vec3::Zero();    // unit direction from `point` to the query (normal if they coincide)
  float distance = 0.0f;
  uint32_t obstacle = 0;
  uint32_t triangle = 0;
  bool onStem() const { return obstacle == kOnStem; }
  uint32_t stem() const { return onStem() ? triangle : kNoStem; }
};

// One stem segment of a host plant as a support: a round cone (the convex hull of a ball of
// radius ra at a and one of radius rb at b). `plant` and `node` say where it is on its host.
struct StemTube {
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();
  float ra = 0.0f, rb = 0.0f;
  uint32_t plant = 0;  // the host plant (the Session's plant index)
  uint32_t node = 0;   // the host node whose segment this is
};

// A leaf of a host plant as a shade: a triangle that blocks light and nothing else.
struct ShadeTriangle {
  Vec3 a, b, c;
};

// Closest point of a round cone's surface to p: the point, the unit outward normal there and
// the signed distance (negative inside).
struct TubePoint {
  Vec3 point;
  Vec3 normal;
  float distance;
};
TubePoint closestOnTube(const StemTube& t, const Vec3& p);

struct Light {
  enum class Type { Directional, Point };
  Type type = Type::Directional;
  Vec3 direction = Vec3(0, -1, 0);  // Directional: the direction the light travels (unit)
  Vec3 position = Vec3::Zero();     // Point
  float intensity = 1.0f;           // relative weight among lights
  float angularRadius = 0.0f;       // soft shadows: cone half-angle of the light (rad)
  int samples = 1;                  // shadow rays per query when angularRadius > 0
};

struct LightSample {
  float exposure = 0.0f;          // in [0, 1]: 1 − occlusion, intensity-weighted over lights
  Vec3 direction = Vec3::Zero();  // unit direction toward the visible light (zero if none)
  Vec3 nominal = Vec3::Zero();    // unit direction toward all lights, occluded or not
};

// A painted stroke: points on surfaces that attract (or repel) growth within `radius`.
struct Stroke {
  bool attract = true;
  float radius = 0.3f;    // m
  float strength = 1.0f;  // >= 0
  std::vector<Vec3> points;
};

class Environment {
 public:
  Environment();
  ~Environment();
  Environment(const Environment&) = delete;
  Environment& operator=(const Environment&) = delete;

  // Adds an obstacle; warns (log) when the mesh is open, in which case its distances are
  // unsigned. Returns its id. Takes effect at the next commit().
  uint32_t addObstacle(ObstacleDef def);
  void setObstacleTransform(uint32_t id, const RigidTransform& worldFromLocal);
  size_t obstacleCount() const;
  const ObstacleInfo& obstacle(uint32_t id) const;
  // Changes whenever an obstacle is added or moved, and differs between Environment objects,
  // so a cache of distances keyed by it (the SPH air's) also notices another environment.
  uint64_t obstacleRevision() const { return obstacleRevision_; }
  // The obstacle's mesh in its local frame (welded).
  TriangleMesh obstacleMesh(uint32_t id) const;

  void addLight(const Light& light);
  const std::vector<Light>& lights() const { return lights_; }
  void setLights(std::vector<Light> lights) { lights_ = std::move(lights); }

  void addStroke(const Stroke& stroke);
  const std::vector<Stroke>& strokes() const { return strokes_; }
  void setStrokes(std::vector<Stroke> strokes);

  void setWind(const Vec3& velocity) {
    WindSettings w;
    w.velocity = velocity;
    wind_.setSettings(std::move(w));
  }
  void setWind(WindSettings settings) { wind_.setSettings(std::move(settings)); }
  // The simulated air the sph wind mode samples (not owned; null = none).
  void setAirFlow(const AirFlow* air) { wind_.setAirFlow(air); }
  const WindField& windField() const { return wind_; }

  // --- plants as supports ---
  // Replaces the stems and leaf shade of `owner` (any number; the Session uses its model
  // systems' indices). Takes effect at the next commit(). Tubes with a non-finite end or radius,
  // a negative radius, or both radii zero are dropped.
  void setStems(uint32_t owner, std::vector<StemTube> tubes, std::vector<ShadeTriangle> shade = {});
  void clearStems();
  // Queries see the stems and shade of every owner but `viewer` (kEveryStem: all of them,
  // kNoStems: none). Cheap; not thread-safe with queries.
  static constexpr uint32_t kEveryStem = 0xffffffffu;
  static constexpr uint32_t kNoStems = 0xfffffffeu;
  void setStemViewer(uint32_t viewer) { stemViewer_ = viewer; }
  uint32_t stemViewer() const { return stemViewer_; }
  // Whether the queries see any stem or shade now (caches of obstacle distances must then also
  // key on stemRevision(), which changes whenever any owner's stems are replaced).
  bool seesStems() const;
  uint64_t stemRevision() const { return stemRevision_; }
  // Every stem of every owner, numbered across owners in owner order; SurfacePoint::stem and
  // RayHit::stem index this.
  size_t stemCount() const { return stemIndex_.size(); }
  const StemTube& stem(uint32_t index) const;
  uint32_t stemOwner(uint32_t index) const;

  // Rebuilds the BVH (and stroke lookup) after edits. Cheap when nothing changed.
  void commit();

  // First hit along origin + t·dir for t in [tMin, tMax] (dir unit length).
  std::optional<RayHit> rayCast(const Vec3& origin, const Vec3& dir, float tMax, float tMin = 0.0f) const;
  bool occluded(const Vec3& origin, const Vec3& dir, float tMax, float tMin = 0.0f) const;
  // True if any of the n segments from[i]–to[i] touches an obstacle (one occlusion ray per
  // segment, no hit point computed, stopping at the first that is blocked) or a seen stem
  // (passes through it or lies in it; segments close together, such as a leaf's outline, are
  // tested against the few tubes near them all).
  bool anySegmentBlocked(const Vec3* from, const Vec3* to, size_t n) const;
  // Number of surface crossings on the segment a-b (0 = the segment touches no obstacle).
  size_t countSegmentHits(const Vec3& a, const Vec3& b) const;
  // Closest obstacle surface point within `radius` of p (Embree point query).
  std::optional<SurfacePoint> closestPoint(const Vec3& p, float radius) const;
  // The same, with a hint: a triangle that is probably (not necessarily) the closest, e.g. the
  // answer for a nearby point. Its distance bounds the search, which is then much cheaper on
  // fine meshes; the answer is exactly that of closestPoint(p, radius).
  std::optional<SurfacePoint> closestPoint(const Vec3& p, float radius, const SurfacePoint* hint) const;
  // The same, ignoring triangles that face `direction`: those whose normal (turned toward p)
  // has n·direction > cosLimit. A shoot growing away from a surface is not held by it. A hint
  // (as above) speeds up the search among plants' stems only.
  std::optional<SurfacePoint> closestPointFacing(const Vec3& p, float radius, const Vec3& direction,
                                                 float cosLimit, const SurfacePoint* hint = nullptr) const;
  // Exact signed distance (negative inside closed obstacles) from the closest point and the
  // angle-weighted pseudonormal; +maxDistance when nothing is that close.
  float exactSignedDistance(const Vec3& p, float maxDistance) const;
  // Builds every obstacle's SDF grid now (they are otherwise built on first use), so that the
  // first simulation step does not pay for them.
  void buildDistanceFields() const;
  // Signed distance from the obstacles' SDF grids (trilinear), min over obstacles.
  float signedDistance(const Vec3& p) const;
  // signedDistance and its unit gradient (pointing away from the nearest obstacle).
  float signedDistance(const Vec3& p, Vec3* gradient) const;
  // Light exposure and direction at p (shadow rays against obstacles only).
  LightSample light(const Vec3& p) const;
  // Pull toward painted strokes: the weighted average of ±strength·(unit direction to each
  // stroke point within its radius), weights (1 − d/r)², scaled by the largest weight.
  // Zero when no stroke is near.
  Vec3 attraction(const Vec3& p) const;
  // Whether p lies in the region a repelling stroke keeps growth out of: where one of its
  // points weighs half or more, strength·(1 − d/r)² ≥ ½ (within 0.29 r at strength 1). The
  // models stop a shoot that reaches it; around it the stroke steers growth away (attraction).
  bool repelled(const Vec3& p) const;
  // Wind velocity (m/s) at p and time t: the wind field (constant, gusty, emitter jets or SPH air).
  Vec3 wind(const Vec3& p, float t) const;

  Bounds3 bounds() const;

 private:
  struct ObstacleData;
  struct StrokeGrid;
  void buildSdf(ObstacleData& o) const;
  static float walkTowardClosest(const ObstacleData& o, const Vec3& p, uint32_t start);
  std::optional<SurfacePoint> closest(const Vec3& p, float radius, const Vec3* direction, float cosLimit,
                                      const SurfacePoint* hint = nullptr) const;
  // The same queries over the obstacles alone.
  std::optional<SurfacePoint> closestObstacle(const Vec3& p, float radius, const Vec3* direction, float cosLimit,
                                              const SurfacePoint* hint) const;
  std::optional<RayHit> obstacleRayCast(const Vec3& origin, const Vec3& dir, float tMax, float tMin) const;
  // False when the ray origin + t·dir, t in [tMin, tMax] (which may be infinite), certainly
  // misses every obstacle's box (widened for round-off): it can hit none of them (scenes of up
  // to kRayBoxes obstacles; others: true).
  bool rayMeetsObstacleBoxes(const Vec3& origin, const Vec3& dir, float tMin, float tMax) const;
  static constexpr size_t kRayBoxes = 8;
  std::vector<Bounds3> rayBoxes_;  // per obstacle, widened (commit)
  float exactObstacleDistance(const Vec3& p, float maxDistance) const;
  float obstacleSignedDistance(const Vec3& p, Vec3* gradient) const;
  // o's distance grid, built on first use (thread-safe).
  const SdfGrid& distanceField(const ObstacleData& o) const;

  std::vector<std::unique_ptr<ObstacleData>> obstacles_;
  struct StemLayer;
  std::vector<std::unique_ptr<StemLayer>> stemLayers_;  // by owner order
  std::vector<std::pair<uint32_t, uint32_t>> stemIndex_;  // global stem index → (layer, tube)
  uint32_t stemViewer_ = kEveryStem;
  uint64_t stemRevision_ = 0;
  bool seesLayer(const StemLayer& layer) const;
  void commitStems();
  // The stem surface nearest p with sign (inside a tube counts as nearer than any outside
  // surface) if its signed distance is below `radius`: into `best` and `signedDistance`. A
  // `hint` on a stem (a nearby answer) makes the search quicker, not different.
  bool closestStem(const Vec3& p, float radius, const Vec3* direction, float cosLimit, SurfacePoint* best,
                   float* signedDistance = nullptr, const SurfacePoint* hint = nullptr) const;
  // The first stem hit closer than *tMax (then lowered to it), into `hit`.
  bool stemRayCast(const Vec3& origin, const Vec3& dir, float tMin, RayHit* hit, float* tMax) const;
  // Whether a seen stem (or, with `shade`, a seen leaf) blocks the ray.
  bool stemOccluded(const Vec3& origin, const Vec3& dir, float tMin, float tMax, bool shade) const;
  bool layerOccluded(const StemLayer& layer, const Vec3& origin, const Vec3& dir, float tMin, float tMax,
                     bool shade) const;
  // Whether a seen stem touches any of the n segments from[i]-to[i] (anySegmentBlocked).
  bool stemSegmentsBlocked(const Vec3* from, const Vec3* to, size_t n) const;
  // With at most kSmallSceneTriangles triangles in all, every triangle's world box (by obstacle,
  // then triangle): closest-point queries test them in turn instead of traversing Embree's BVH.
  // The boxes are kept coordinate by coordinate, so the distances to all of them are found
  // four or eight at a time before any triangle is looked at.
  static constexpr size_t kSmallSceneTriangles = 64;
  struct SmallScene {
    size_t count = 0;
    std::vector<float> lo[3], hi[3];  // per box, padded to a multiple of 8 with empty boxes
    std::vector<uint32_t> geom, prim;
  };
  SmallScene smallScene_;
  std::vector<Light> lights_;
  std::vector<Stroke> strokes_;
  std::unique_ptr<StrokeGrid> strokeGrid_;
  WindField wind_;
  void* scene_ = nullptr;  // RTCScene
  bool dirty_ = true;
  uint64_t obstacleRevision_;
};

const char* obstacleKindName(ObstacleKind kind);

// Whether two answers lie on the same support: the same obstacle, or the same host plant.
bool sameSupport(const SurfacePoint& a, const SurfacePoint& b, const Environment& env);

}  // namespace tendril::env
