#include "tendril/env/environment.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/env/sdf.h"
#include "tendril/env/stem_layer.h"
#include "tendril/env/topology.h"

#include <embree3/rtcore.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <limits>
#include <mutex>
#include <unordered_map>

namespace tendril::env {

RTCDevice environmentDevice();

namespace {

RTCDevice embreeDevice() { return environmentDevice(); }

}  // namespace

RTCDevice environmentDevice() {
  static RTCDevice device = [] {
    // Embree picks its kernels by CPU, and its 4-, 8- and 16-wide kernels answer some queries with
    // other last bits (a closest point, a hit distance), which growth then amplifies. Asking for the
    // AVX2 kernels wherever the CPU has them gives the same plants on every such machine (an AVX-512
    // one included); elsewhere Embree chooses, and results are the same only among like CPUs.
#if defined(__x86_64__) && defined(__GNUC__)
    static const bool hasAvx2 = __builtin_cpu_supports("avx2");
#else
    static const bool hasAvx2 = false;
#endif
    RTCDevice d = rtcNewDevice(hasAvx2 ? "isa=avx2" : nullptr);
    if (!d) throw Error("Embree", "", "cannot create the ray tracing device");
    rtcSetDeviceErrorFunction(
        d, [](void*, RTCError code, const char* str) { log::error("Embree error {}: {}", int(code), str ? str : ""); },
        nullptr);
    return d;
  }();
  return device;
}

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

}  // namespace

const char* obstacleKindName(ObstacleKind kind) {
  switch (kind) {
    case ObstacleKind::Plane: return "plane";
    case ObstacleKind::Box: return "box";
    case ObstacleKind::Sphere: return "sphere";
    case ObstacleKind::Cylinder: return "cylinder";
    case ObstacleKind::Wall: return "wall";
    case ObstacleKind::Mesh: return "mesh";
  }
  return "mesh";
}

struct Environment::ObstacleData {
  ObstacleInfo info;
  float sdfCell = 0.0f;
  WeldedMesh welded;        // local frame
  Pseudonormals normals;    // local frame, only when closed
  std::vector<Vec3> world;  // welded vertices in world space (+1 padding element for Embree)
  std::vector<Vec3> faceNormalWorld;
  std::vector<uint32_t> neighbors;  // triangle adjacency (3 per triangle), for closest-point walks
  RTCGeometry geometry = nullptr;
  bool moved = true;
  mutable std::once_flag sdfOnce;
  mutable std::atomic<bool> sdfReady{false};  // the grid is built: the query's fast path
  mutable SdfGrid sdf;
  // The transform as matrices for the distance queries (a quaternion rotation costs twice
  // the multiplies of a matrix one): local = localRotation · world + localTranslation.
  Mat3 localRotation = Mat3::Identity();
  Vec3 localTranslation = Vec3::Zero();
  Mat3 worldRotation = Mat3::Identity();

  ~ObstacleData() {
    if (geometry) rtcReleaseGeometry(geometry);
  }

  void updateWorld() {
    const RigidTransform& t = info.worldFromLocal;
    world.resize(welded.positions.size() + 1);
    for (size_t i = 0; i < welded.positions.size(); ++i) world[i] = t.applyPoint(welded.positions[i]);
    world.back() = Vec3::Zero();
    faceNormalWorld.resize(welded.indices.size() / 3);
    for (size_t f = 0; f < faceNormalWorld.size(); ++f) {
      const uint32_t* tri = &welded.indices[3 * f];
      Vec3 n = (world[tri[1]] - world[tri[0]]).cross(world[tri[2]] - world[tri[0]]);
      float len = n.norm();
      faceNormalWorld[f] = len > 0.0f ? Vec3(n / len) : Vec3::UnitY();
    }
    info.worldBounds = Bounds3();
    for (size_t i = 0; i + 1 < world.size(); ++i) info.worldBounds.extend(world[i]);
    worldRotation = t.rotation.normalized().toRotationMatrix();
    localRotation = worldRotation.transpose();
    localTranslation = -(localRotation * t.translation);
  }
};

// Uniform hash grid over stroke points, cell = the largest stroke radius.
struct Environment::StrokeGrid {
  float cell = 1.0f;
  std::vector<Vec3> points;
  std::vector<uint32_t> stroke;  // per point
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells;

  static uint64_t key(int x, int y, int z) {
    auto u = [](int v) { return static_cast<uint64_t>(static_cast<uint32_t>(v + (1 << 20))) & 0x1fffff; };
    return u(x) | (u(y) << 21) | (u(z) << 42);
  }
  Eigen::Vector3i cellOf(const Vec3& p) const {
    return Eigen::Vector3i(int(std::floor(p.x() / cell)), int(std::floor(p.y() / cell)), int(std::floor(p.z() / cell)));
  }
  // Calls f(point index) for the points in the cells round p (every point within the largest
  // stroke radius of p among them); stops early when f returns true.
  template <class F>
  bool anyNear(const Vec3& p, F&& f) const {
    const Eigen::Vector3i c = cellOf(p);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          auto it = cells.find(key(c.x() + dx, c.y() + dy, c.z() + dz));
          if (it == cells.end()) continue;
          for (uint32_t i : it->second)
            if (f(i)) return true;
        }
    return false;
  }
};

namespace {

// Closest point search shared by world queries and SDF construction.
struct ClosestSearch {
  const Vec3* const* vertices;    // per geometry id
  const uint32_t* const* indices; // per geometry id
  Vec3 p;
  float bestDist2;
  const Vec3* facing = nullptr;   // optional filter: skip triangles facing this direction
  float cosLimit = 1.0f;
  Vec3 bestPoint = Vec3::Zero();
  uint32_t bestGeom = RTC_INVALID_GEOMETRY_ID;
  uint32_t bestPrim = RTC_INVALID_GEOMETRY_ID;
  TriangleFeature bestFeature = TriangleFeature::Face;
};

// Triangle `primID` of obstacle `geomID` as a candidate of the search; shrinks `radius` to the
// best distance found. Returns whether it did.
bool considerTriangle(ClosestSearch* s, uint32_t geomID, uint32_t primID, float* radius) {
  const Vec3* v = s->vertices[geomID];
  const uint32_t* tri = s->indices[geomID] + 3 * size_t(primID);
  ClosestOnTriangle c = closestPointOnTriangle(s->p, v[tri[0]], v[tri[1]], v[tri[2]]);
  float d2 = (c.point - s->p).squaredNorm();
  if (s->facing && d2 < s->bestDist2) {
    Vec3 n = (v[tri[1]] - v[tri[0]]).cross(v[tri[2]] - v[tri[0]]);
    if (n.dot(s->p - c.point) < 0.0f) n = -n;  // the side the query point is on
    float len = n.norm();
    if (len > 0.0f && n.dot(*s->facing) > s->cosLimit * len) return false;
  }
  // Ties are broken by (geometry, primitive) so the answer never depends on traversal order.
  bool better = d2 < s->bestDist2 ||
                (d2 == s->bestDist2 && (geomID < s->bestGeom || (geomID == s->bestGeom && primID < s->bestPrim)));
  if (!better) return false;
  s->bestDist2 = d2;
  s->bestPoint = c.point;
  s->bestGeom = geomID;
  s->bestPrim = primID;
  s->bestFeature = c.feature;
  float r = std::sqrt(d2);
  if (r < *radius) {
    *radius = r;
    return true;
  }
  return false;
}

bool closestCallback(RTCPointQueryFunctionArguments* args) {
  return considerTriangle(static_cast<ClosestSearch*>(args->userPtr), args->geomID, args->primID,
                          &args->query->radius);
}

void runClosest(RTCScene scene, ClosestSearch& s, float radius) {
  RTCPointQuery q;
  q.x = s.p.x();
  q.y = s.p.y();
  q.z = s.p.z();
  q.time = 0.0f;
  q.radius = radius;
  RTCPointQueryContext ctx;
  rtcInitPointQueryContext(&ctx);
  rtcPointQuery(scene, &q, &ctx, closestCallback, &s);
}

// A ray Embree accepts (it asserts on others; RayK::valid): origin and direction components
// within ±1.844e18 and no NaN among them or the interval's ends. Others hit nothing.
bool rayAccepted(const Vec3& origin, const Vec3& dir, float tMin, float tMax) {
  constexpr float kLarge = 1.844e18f;
  for (int c = 0; c < 3; ++c)
    if (!(std::fabs(origin[c]) <= kLarge && std::fabs(dir[c]) <= kLarge)) return false;
  return !std::isnan(tMin) && !std::isnan(tMax);
}

// Directions spread evenly over a cone (Fibonacci spiral): deterministic soft-shadow samples.
Vec3 coneSample(const Vec3& axis, float halfAngle, int i, int n) {
  if (n <= 1 || halfAngle <= 0.0f) return axis;
  const float golden = kPi * (3.0f - std::sqrt(5.0f));
  float cosMax = std::cos(halfAngle);
  float c = 1.0f - (float(i) + 0.5f) / float(n) * (1.0f - cosMax);
  float s = std::sqrt(std::max(0.0f, 1.0f - c * c));
  float phi = golden * float(i);
  Vec3 u = anyPerpendicular(axis);
  Vec3 v = axis.cross(u);
  return (axis * c + (u * std::cos(phi) + v * std::sin(phi)) * s).normalized();
}

}  // namespace

// Greedy descent over the triangle adjacency from `start` toward p: while the closest feature
// of the current triangle is an edge or vertex, step to the neighbour across it if that one is
// strictly closer. Ends at a local minimum of the distance — usually the global one — in a few
// steps when `start` was the answer for a nearby point. Returns the squared distance reached.
float Environment::walkTowardClosest(const ObstacleData& o, const Vec3& p, uint32_t start) {
  auto dist2 = [&](uint32_t t, TriangleFeature* f) {
    const uint32_t* tri = &o.welded.indices[3 * size_t(t)];
    ClosestOnTriangle c = closestPointOnTriangle(p, o.world[tri[0]], o.world[tri[1]], o.world[tri[2]]);
    *f = c.feature;
    return (c.point - p).squaredNorm();
  };
  uint32_t cur = start;
  TriangleFeature f;
  float best = dist2(cur, &f);
  for (int step = 0; step < 64 && f != TriangleFeature::Face; ++step) {
    const uint32_t* n = &o.neighbors[3 * size_t(cur)];
    uint32_t candidates[2] = {kNoNeighbor, kNoNeighbor};
    switch (f) {
      case TriangleFeature::EdgeAB: candidates[0] = n[0]; break;
      case TriangleFeature::EdgeBC: candidates[0] = n[1]; break;
      case TriangleFeature::EdgeCA: candidates[0] = n[2]; break;
      case TriangleFeature::VertexA: candidates[0] = n[0], candidates[1] = n[2]; break;
      case TriangleFeature::VertexB: candidates[0] = n[0], candidates[1] = n[1]; break;
      case TriangleFeature::VertexC: candidates[0] = n[1], candidates[1] = n[2]; break;
      case TriangleFeature::Face: break;
    }
    uint32_t next = kNoNeighbor;
    TriangleFeature nextFeature = f;
    float nextBest = best;
    for (uint32_t c : candidates) {
      if (c == kNoNeighbor) continue;
      TriangleFeature cf;
      float d = dist2(c, &cf);
      if (d < nextBest) {
        nextBest = d;
        next = c;
        nextFeature = cf;
      }
    }
    if (next == kNoNeighbor) break;
    cur = next;
    best = nextBest;
    f = nextFeature;
  }
  return best;
}

namespace {
// Revisions are unique in the process: a new environment never repeats an old one's.
uint64_t nextObstacleRevision() {
  static std::atomic<uint64_t> counter{0};
  return counter.fetch_add(1, std::memory_order_relaxed) + 1;
}
}  // namespace

Environment::Environment() : strokeGrid_(std::make_unique<StrokeGrid>()), obstacleRevision_(nextObstacleRevision()) {}

Environment::~Environment() {
  if (scene_) rtcReleaseScene(static_cast<RTCScene>(scene_));
}

uint32_t Environment::addObstacle(ObstacleDef def) {
  auto o = std::make_unique<ObstacleData>();
  o->welded = weld(def.mesh);
  TopologyReport topo = analyzeTopology(o->welded);
  // A closed mesh wound inside-out is turned right-side out so that normals face outward.
  if (topo.closed() && topo.signedVolume < 0.0) {
    for (size_t t = 0; t + 2 < o->welded.indices.size(); t += 3)
      std::swap(o->welded.indices[t + 1], o->welded.indices[t + 2]);
    topo.signedVolume = -topo.signedVolume;
  }
  bool closed = topo.closed() && topo.signedVolume > 0.0;
  if (!closed)
    log::warn("obstacle \"{}\" ({}) is not a closed mesh ({} boundary, {} non-manifold, {} inconsistently "
              "wound edges): its distances are unsigned, so nothing is ever 'inside' it",
              def.name, def.source, topo.boundaryEdges, topo.nonManifoldEdges, topo.inconsistentEdges);
  if (closed) o->normals = computePseudonormals(o->welded);
  o->neighbors = triangleNeighbors(o->welded);
  o->info.name = def.name;
  o->info.kind = def.kind;
  o->info.source = def.source;
  o->info.worldFromLocal = def.worldFromLocal;
  o->info.color = def.color;
  o->info.closed = closed;
  o->info.triangles = o->welded.indices.size() / 3;
  for (const Vec3& p : o->welded.positions) o->info.localBounds.extend(p);
  if (closed && o->info.triangles <= kConvexCheckTriangles) {
    // Every vertex on or behind every face's plane (rounding allowed for, relative to size).
    const std::vector<Vec3>& v = o->welded.positions;
    const std::vector<uint32_t>& idx = o->welded.indices;
    const float tolerance = 1e-5f * std::max(o->info.localBounds.size().maxCoeff(), 1e-6f);
    bool convex = true;
    for (size_t t = 0; convex && t + 2 < idx.size(); t += 3) {
      const Vec3& a = v[idx[t]];
      const Vec3 n = (v[idx[t + 1]] - a).cross(v[idx[t + 2]] - a);
      const float len = n.norm();
      if (!(len > 0.0f)) continue;
      for (const Vec3& p : v)
        if (n.dot(p - a) > tolerance * len) {
          convex = false;
          break;
        }
    }
    o->info.convex = convex;
  }
  o->sdfCell = def.sdfCell;
  o->updateWorld();
  obstacles_.push_back(std::move(o));
  dirty_ = true;
  obstacleRevision_ = nextObstacleRevision();
  return static_cast<uint32_t>(obstacles_.size() - 1);
}

void Environment::setObstacleTransform(uint32_t id, const RigidTransform& t) {
  ObstacleData& o = *obstacles_.at(id);
  o.info.worldFromLocal = t;
  o.updateWorld();
  o.moved = true;
  dirty_ = true;
  obstacleRevision_ = nextObstacleRevision();
}

size_t Environment::obstacleCount() const { return obstacles_.size(); }
const ObstacleInfo& Environment::obstacle(uint32_t id) const { return obstacles_.at(id)->info; }

TriangleMesh Environment::obstacleMesh(uint32_t id) const {
  const ObstacleData& o = *obstacles_.at(id);
  TriangleMesh m;
  m.positions = o.welded.positions;
  m.indices = o.welded.indices;
  return m;
}

void Environment::addLight(const Light& light) { lights_.push_back(light); }

void Environment::addStroke(const Stroke& stroke) {
  strokes_.push_back(stroke);
  dirty_ = true;
}

void Environment::setStrokes(std::vector<Stroke> strokes) {
  strokes_ = std::move(strokes);
  dirty_ = true;
}

void Environment::commit() {
  if (!dirty_ && scene_) return;
  RTCDevice device = embreeDevice();
  if (!scene_) {
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    scene_ = scene;
  }
  RTCScene scene = static_cast<RTCScene>(scene_);
  for (size_t id = 0; id < obstacles_.size(); ++id) {
    ObstacleData& o = *obstacles_[id];
    if (!o.geometry) {
      o.geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      rtcSetSharedGeometryBuffer(o.geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, o.world.data(), 0,
                                 sizeof(Vec3), o.world.size() - 1);
      rtcSetSharedGeometryBuffer(o.geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, o.welded.indices.data(), 0,
                                 3 * sizeof(uint32_t), o.welded.indices.size() / 3);
      rtcCommitGeometry(o.geometry);
      rtcAttachGeometryByID(scene, o.geometry, static_cast<unsigned>(id));
      o.moved = false;
    } else if (o.moved) {
      // The world vertex array may have been reallocated by updateWorld(): re-point the buffer.
      rtcSetSharedGeometryBuffer(o.geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, o.world.data(), 0,
                                 sizeof(Vec3), o.world.size() - 1);
      rtcUpdateGeometryBuffer(o.geometry, RTC_BUFFER_TYPE_VERTEX, 0);
      rtcCommitGeometry(o.geometry);
      o.moved = false;
    }
  }
  rtcCommitScene(scene);
  commitStems();

  // The obstacles' boxes for rays to skip (rayMeetsObstacleBoxes), widened by a margin far above
  // the round-off of Embree's robust hit test; with more obstacles rays do not try.
  rayBoxes_.clear();
  if (obstacles_.size() <= kRayBoxes)
    for (const auto& o : obstacles_) {
      const Bounds3& b = o->info.worldBounds;
      const float margin = 1e-4f * (1.0f + std::max(b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff()));
      rayBoxes_.push_back({b.min - Vec3::Constant(margin), b.max + Vec3::Constant(margin)});
    }

  // A scene of a few triangles in all (walls, boxes, planes): closest-point queries test each
  // triangle's box themselves, which is several times cheaper than a traversal and its callbacks.
  smallScene_ = SmallScene{};
  size_t triangles = 0;
  for (const auto& o : obstacles_) triangles += o->welded.indices.size() / 3;
  if (triangles <= kSmallSceneTriangles) {
    SmallScene& ss = smallScene_;
    for (uint32_t id = 0; id < obstacles_.size(); ++id) {
      const ObstacleData& o = *obstacles_[id];
      for (uint32_t t = 0; t < o.welded.indices.size() / 3; ++t) {
        const uint32_t* tri = &o.welded.indices[3 * size_t(t)];
        const Vec3 &a = o.world[tri[0]], &b = o.world[tri[1]], &c = o.world[tri[2]];
        const Vec3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
        for (int k = 0; k < 3; ++k) ss.lo[k].push_back(lo[k]), ss.hi[k].push_back(hi[k]);
        ss.geom.push_back(id);
        ss.prim.push_back(t);
      }
    }
    ss.count = ss.geom.size();
    // Padding boxes lie infinitely far from every point.
    const float inf = std::numeric_limits<float>::infinity();
    const size_t padded = (ss.count + 7) / 8 * 8;
    for (int k = 0; k < 3; ++k) ss.lo[k].resize(padded, inf), ss.hi[k].resize(padded, inf);
  }

  // Stroke lookup grid.
  StrokeGrid& g = *strokeGrid_;
  g = StrokeGrid();
  float maxRadius = 0.0f;
  for (const Stroke& s : strokes_) maxRadius = std::max(maxRadius, s.radius);
  g.cell = std::max(maxRadius, 1e-3f);
  for (uint32_t si = 0; si < strokes_.size(); ++si)
    for (const Vec3& p : strokes_[si].points) {
      Eigen::Vector3i c = g.cellOf(p);
      g.cells[StrokeGrid::key(c.x(), c.y(), c.z())].push_back(static_cast<uint32_t>(g.points.size()));
      g.points.push_back(p);
      g.stroke.push_back(si);
    }
  dirty_ = false;
}

std::optional<RayHit> Environment::rayCast(const Vec3& origin, const Vec3& dir, float tMax, float tMin) const {
  assert(!dirty_ && "Environment::commit() must be called after edits");
  if (!rayAccepted(origin, dir, tMin, tMax)) return std::nullopt;
  std::optional<RayHit> hit;
  if (!obstacles_.empty()) hit = obstacleRayCast(origin, dir, tMax, tMin);
  if (!stemLayers_.empty()) {
    RayHit stemHit;
    float t = hit ? hit->t : tMax;
    if (stemRayCast(origin, dir, tMin, &stemHit, &t)) hit = stemHit;
  }
  return hit;
}

bool Environment::rayMeetsObstacleBoxes(const Vec3& origin, const Vec3& dir, float tMin, float tMax) const {
  if (rayBoxes_.size() != obstacles_.size() || !origin.allFinite()) return true;
  for (const Bounds3& b : rayBoxes_) {
    // The box's slabs clip [tMin, tMax].
    float t0 = tMin, t1 = tMax;
    for (int k = 0; k < 3 && t0 <= t1; ++k) {
      if (dir[k] == 0.0f) {
        if (origin[k] < b.min[k] || origin[k] > b.max[k]) t1 = -1.0f, t0 = 0.0f;
        continue;
      }
      const float inv = 1.0f / dir[k];
      float a = (b.min[k] - origin[k]) * inv, c = (b.max[k] - origin[k]) * inv;
      if (a > c) std::swap(a, c);
      t0 = std::max(t0, a), t1 = std::min(t1, c);
    }
    if (t0 <= t1) return true;
  }
  return false;
}

std::optional<RayHit> Environment::obstacleRayCast(const Vec3& origin, const Vec3& dir, float tMax, float tMin) const {
  if (!rayMeetsObstacleBoxes(origin, dir, tMin, tMax)) return std::nullopt;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  initRay(rh.ray, origin, dir, tMin, tMax);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(static_cast<RTCScene>(scene_), &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  const ObstacleData& o = *obstacles_[rh.hit.geomID];
  RayHit hit;
  hit.t = rh.ray.tfar;
  hit.point = origin + hit.t * dir;
  hit.normal = o.faceNormalWorld[rh.hit.primID];
  hit.obstacle = rh.hit.geomID;
  hit.triangle = rh.hit.primID;
  return hit;
}

namespace {

// Whether anything in `scene` blocks origin + t·dir for t in [tMin, tMax].
bool sceneOccludes(void* scene, const Vec3& origin, const Vec3& dir, float tMin, float tMax) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay ray;
  initRay(ray, origin, dir, tMin, tMax);
  rtcOccluded1(static_cast<RTCScene>(scene), &ctx, &ray);
  return ray.tfar < 0.0f;  // Embree sets tfar = -inf on a hit
}

}  // namespace

bool Environment::occluded(const Vec3& origin, const Vec3& dir, float tMax, float tMin) const {
  assert(!dirty_ && "Environment::commit() must be called after edits");
  if (!rayAccepted(origin, dir, tMin, tMax)) return false;
  if (!obstacles_.empty() && rayMeetsObstacleBoxes(origin, dir, tMin, tMax) &&
      sceneOccludes(scene_, origin, dir, tMin, tMax))
    return true;
  return !stemLayers_.empty() && stemOccluded(origin, dir, tMin, tMax, false);
}

bool Environment::anySegmentBlocked(const Vec3* from, const Vec3* to, size_t n) const {
  assert(!dirty_ && "Environment::commit() must be called after edits");
  if (obstacles_.empty() && stemLayers_.empty()) return false;
  // One occlusion ray per segment, stopping at the first blocked one. On the climbing bench a
  // single ray along a leaf edge costs 420-470 instructions in Embree, a lane of an 8-wide
  // packet (rtcOccluded8) 620-710: the segments of one leaf point in too many directions for
  // the packet to share its traversal. Stems are tested after all of them, together.
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay ray;
  ray.time = 0.0f;
  ray.mask = 0xffffffffu;
  ray.id = 0;
  ray.flags = 0;
  bool regular = true;  // every segment finite and not absurdly far out
  // The obstacles' rays only when the box round all the segments meets an obstacle's box
  // (widened at commit, so the per-segment test below would reject each ray as well).
  bool obstacleRays = !obstacles_.empty();
  if (obstacleRays && rayBoxes_.size() == obstacles_.size() && n > 0) {
    Bounds3 all{from[0].cwiseMin(to[0]), from[0].cwiseMax(to[0])};
    for (size_t i = 1; i < n; ++i)
      all.min = all.min.cwiseMin(from[i].cwiseMin(to[i])), all.max = all.max.cwiseMax(from[i].cwiseMax(to[i]));
    obstacleRays = false;
    for (const Bounds3& b : rayBoxes_)
      obstacleRays |= !((all.min.array() > b.max.array()).any() || (all.max.array() < b.min.array()).any());
  }
  for (size_t i = 0; i < n; ++i) {
    Vec3 d = to[i] - from[i];
    float len = d.norm();
    if (!(len > 0.0f)) continue;
    d /= len;
    if (!rayAccepted(from[i], d, 0.0f, len)) {
      regular = false;
      continue;
    }
    if (!obstacleRays || !rayMeetsObstacleBoxes(from[i], d, 0.0f, len)) continue;
    ray.org_x = from[i].x();
    ray.org_y = from[i].y();
    ray.org_z = from[i].z();
    ray.dir_x = d.x();
    ray.dir_y = d.y();
    ray.dir_z = d.z();
    ray.tnear = 0.0f;
    ray.tfar = len;
    rtcOccluded1(static_cast<RTCScene>(scene_), &ctx, &ray);
    if (ray.tfar < 0.0f) return true;  // Embree sets tfar = -inf on a hit
  }
  if (stemLayers_.empty()) return false;
  if (regular) return stemSegmentsBlocked(from, to, n);
  for (size_t i = 0; i < n; ++i) {
    Vec3 d = to[i] - from[i];
    float len = d.norm();
    if (!(len > 0.0f)) continue;
    d /= len;
    if (rayAccepted(from[i], d, 0.0f, len) && stemOccluded(from[i], d, 0.0f, len, false)) return true;
  }
  return false;
}

size_t Environment::countSegmentHits(const Vec3& a, const Vec3& b) const {
  Vec3 d = b - a;
  float len = d.norm();
  if (!(len > 0.0f)) return 0;
  d /= len;
  size_t hits = 0;
  float t = 0.0f;
  while (auto h = rayCast(a, d, len, t)) {
    ++hits;
    // Step past this hit; a relative epsilon keeps a hit on a shared edge from counting twice.
    t = h->t + std::max(1e-6f, h->t * 1e-6f);
    if (hits > 1000) break;
  }
  return hits;
}

std::optional<SurfacePoint> Environment::closestPoint(const Vec3& p, float radius) const {
  return closest(p, radius, nullptr, 1.0f);
}

std::optional<SurfacePoint> Environment::closestPoint(const Vec3& p, float radius, const SurfacePoint* hint) const {
  return closest(p, radius, nullptr, 1.0f, hint);
}

std::optional<SurfacePoint> Environment::closestPointFacing(const Vec3& p, float radius, const Vec3& direction,
                                                            float cosLimit, const SurfacePoint* hint) const {
  return closest(p, radius, &direction, cosLimit, hint);
}

std::optional<SurfacePoint> Environment::closest(const Vec3& p, float radius, const Vec3* direction,
                                                 float cosLimit, const SurfacePoint* hint) const {
  assert(!dirty_ && "Environment::commit() must be called after edits");
  std::optional<SurfacePoint> best;
  if (!obstacles_.empty()) best = closestObstacle(p, radius, direction, cosLimit, hint);
  if (!stemLayers_.empty()) {
    SurfacePoint sp;
    if (closestStem(p, best ? best->distance : radius, direction, cosLimit, &sp, nullptr, hint)) best = sp;
  }
  return best;
}

std::optional<SurfacePoint> Environment::closestObstacle(const Vec3& p, float radius, const Vec3* direction,
                                                         float cosLimit, const SurfacePoint* hint) const {
  // Farther than the radius from every obstacle's (widened) box: nothing to find. A climber
  // in a tree asks this at every step, far above the ground.
  if (rayBoxes_.size() == obstacles_.size()) {
    bool near = false;
    for (const Bounds3& b : rayBoxes_) near |= !(b.squaredDistance(p) > radius * radius);
    if (!near) return std::nullopt;
  }
  // Geometry ids equal obstacle indices, so small per-call tables suffice.
  constexpr size_t kStack = 16;
  const Vec3* vStack[kStack];
  const uint32_t* iStack[kStack];
  std::vector<const Vec3*> vHeap;
  std::vector<const uint32_t*> iHeap;
  const Vec3** verts = vStack;
  const uint32_t** inds = iStack;
  if (obstacles_.size() > kStack) {
    vHeap.resize(obstacles_.size());
    iHeap.resize(obstacles_.size());
    verts = vHeap.data();
    inds = iHeap.data();
  }
  for (size_t i = 0; i < obstacles_.size(); ++i) {
    verts[i] = obstacles_[i]->world.data();
    inds[i] = obstacles_[i]->welded.indices.data();
  }
  // A hinted triangle's distance bounds the search: Embree calls back for every triangle the
  // query sphere overlaps, so a tight sphere is far cheaper on fine meshes. The closest point
  // lies inside that sphere, so the answer is the same as for the full radius.
  // The hint is first improved by walking the mesh toward p, so the sphere is as tight as the
  // true answer whenever the walk finds it.
  float r = radius;
  if (hint && hint->obstacle < obstacles_.size() && !direction) {
    const ObstacleData& h = *obstacles_[hint->obstacle];
    if (hint->triangle < h.welded.indices.size() / 3) {
      float d = std::sqrt(walkTowardClosest(h, p, hint->triangle));
      if (d < radius) r = std::min(radius, d * (1.0f + 1e-5f) + 1e-7f);
    }
  }
  ClosestSearch s{verts, inds, p, r * r, direction, cosLimit};
  if (smallScene_.count > 0) {
    // Every triangle whose box is within the best distance so far, in (obstacle, triangle)
    // order: ties included, so the answer is the one the traversal gives. The boxes' distances
    // do not depend on the search, so they are all found first, in one vectorised loop.
    const SmallScene& ss = smallScene_;
    const size_t padded = ss.lo[0].size();
    alignas(32) float boxDist2[kSmallSceneTriangles + 8];
    const float px = p.x(), py = p.y(), pz = p.z();
    const float *lx = ss.lo[0].data(), *ly = ss.lo[1].data(), *lz = ss.lo[2].data();
    const float *hx = ss.hi[0].data(), *hy = ss.hi[1].data(), *hz = ss.hi[2].data();
    for (size_t i0 = 0; i0 < padded; i0 += 8)
      for (size_t i = i0; i < i0 + 8; ++i) {
        const float dx = std::min(std::max(px, lx[i]), hx[i]) - px;
        const float dy = std::min(std::max(py, ly[i]), hy[i]) - py;
        const float dz = std::min(std::max(pz, lz[i]), hz[i]) - pz;
        boxDist2[i] = dx * dx + dy * dy + dz * dz;
      }
    for (size_t i = 0; i < ss.count; ++i)
      if (boxDist2[i] <= s.bestDist2) considerTriangle(&s, ss.geom[i], ss.prim[i], &r);
  } else {
    runClosest(static_cast<RTCScene>(scene_), s, r);
  }
  if (s.bestGeom == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  const ObstacleData& o = *obstacles_[s.bestGeom];
  SurfacePoint sp;
  sp.point = s.bestPoint;
  sp.distance = std::sqrt(s.bestDist2);
  sp.normal = o.faceNormalWorld[s.bestPrim];
  sp.obstacle = s.bestGeom;
  sp.triangle = s.bestPrim;
  // Direction from the surface to the query. On a face interior it is the face normal (signed
  // toward p) — exact, where p − q would be rounding noise for points on the surface. At edges
  // and vertices it is p − q, or the pseudonormal when p sits on the feature itself.
  Vec3 away = p - s.bestPoint;
  float len = away.norm();
  if (s.bestFeature == TriangleFeature::Face) {
    sp.away = away.dot(sp.normal) < 0.0f && len > 1e-5f ? Vec3(-sp.normal) : sp.normal;
  } else if (len > 1e-5f) {
    sp.away = away / len;
  } else if (o.info.closed) {
    const uint32_t* tri = &o.welded.indices[3 * size_t(s.bestPrim)];
    sp.away = o.info.worldFromLocal.applyVector(o.normals.at(s.bestPrim, s.bestFeature, tri));
  } else {
    sp.away = sp.normal;
  }
  return sp;
}

float Environment::exactSignedDistance(const Vec3& p, float maxDistance) const {
  float d = obstacles_.empty() ? maxDistance : exactObstacleDistance(p, maxDistance);
  float stemDistance;
  if (!stemLayers_.empty() && closestStem(p, d, nullptr, 1.0f, nullptr, &stemDistance)) d = stemDistance;
  return d;
}

float Environment::exactObstacleDistance(const Vec3& p, float maxDistance) const {
  std::optional<SurfacePoint> sp = closestObstacle(p, maxDistance, nullptr, 1.0f, nullptr);
  if (!sp) return maxDistance;
  const ObstacleData& o = *obstacles_[sp->obstacle];
  if (!o.info.closed || sp->distance == 0.0f) return sp->distance;
  // Recover the closest feature to pick the right pseudonormal.
  const uint32_t* tri = &o.welded.indices[3 * size_t(sp->triangle)];
  ClosestOnTriangle c = closestPointOnTriangle(p, o.world[tri[0]], o.world[tri[1]], o.world[tri[2]]);
  Vec3 n = o.info.worldFromLocal.applyVector(o.normals.at(sp->triangle, c.feature, tri));
  return (p - sp->point).dot(n) < 0.0f ? -sp->distance : sp->distance;
}

void Environment::buildSdf(ObstacleData& o) const {
  Bounds3 lb = o.info.localBounds;
  float longest = lb.size().maxCoeff();
  float cell = o.sdfCell > 0.0f ? o.sdfCell : std::clamp(longest / 64.0f, 0.01f, 0.05f);
  // Keep the grid under ~16M samples whatever the obstacle size.
  for (;;) {
    Vec3 n = (lb.size() / cell).array() + 9.0f;
    if (double(n.x()) * n.y() * n.z() <= 16.0e6) break;
    cell *= 1.25f;
  }
  Bounds3 grid = lb;
  grid.min -= Vec3::Constant(4.0f * cell);
  grid.max += Vec3::Constant(4.0f * cell);

  // A local-frame BVH of this obstacle alone.
  RTCDevice device = embreeDevice();
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
  std::vector<Vec3> local = o.welded.positions;
  local.push_back(Vec3::Zero());  // Embree reads 16 bytes past the last vertex
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, local.data(), 0, sizeof(Vec3),
                             local.size() - 1);
  rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, o.welded.indices.data(), 0,
                             3 * sizeof(uint32_t), o.welded.indices.size() / 3);
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(scene, geom, 0);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);

  const Vec3* verts[1] = {local.data()};
  const uint32_t* inds[1] = {o.welded.indices.data()};
  o.sdf = SdfGrid(grid, cell, [&](const Vec3& p) {
    ClosestSearch s{verts, inds, p, kInf};
    runClosest(scene, s, kInf);
    float d = std::sqrt(s.bestDist2);
    if (o.info.closed && d > 0.0f) {
      const uint32_t* tri = &o.welded.indices[3 * size_t(s.bestPrim)];
      if ((p - s.bestPoint).dot(o.normals.at(s.bestPrim, s.bestFeature, tri)) < 0.0f) d = -d;
    }
    return d;
  });
  rtcReleaseScene(scene);
}

const SdfGrid& Environment::distanceField(const ObstacleData& o) const {
  if (!o.sdfReady.load(std::memory_order_acquire)) {
    // Built on first use. The build is a parallel loop; isolating it keeps the waiting thread
    // from picking up another task of an enclosing parallel loop, which could enter this same
    // call_once recursively.
    std::call_once(o.sdfOnce, [&] {
      tbb::this_task_arena::isolate([&] { buildSdf(const_cast<ObstacleData&>(o)); });
      o.sdfReady.store(true, std::memory_order_release);
    });
  }
  return o.sdf;
}

void Environment::buildDistanceFields() const {
  for (const auto& o : obstacles_) distanceField(*o);
}

float Environment::signedDistance(const Vec3& p) const { return signedDistance(p, nullptr); }

float Environment::signedDistance(const Vec3& p, Vec3* gradient) const {
  // The obstacles' grids, then the stems seen nearer than they are (exactly: a tube's distance
  // is cheap to compute).
  const size_t n = obstacles_.size();
  if (gradient) *gradient = Vec3::Zero();
  float best = n == 0 ? kInf : obstacleSignedDistance(p, gradient);
  if (!stemLayers_.empty()) {
    SurfacePoint sp;
    float d;
    if (closestStem(p, best, nullptr, 1.0f, &sp, &d)) {
      best = d;
      if (gradient) *gradient = sp.normal;
    }
  }
  return best;
}

float Environment::obstacleSignedDistance(const Vec3& p, Vec3* gradient) const {
  // The minimum over the obstacles whose bounds are no farther than the best distance so far.
  // The obstacle nearest by its bounds is sampled first: a point on a wall then skips the
  // ground and everything else (most collision queries are such points).
  const size_t n = obstacles_.size();
  constexpr size_t kKept = 16;  // bound distances kept for the second loop
  float kept[kKept];
  auto boundsDistance2 = [&](size_t k) {
    return k < kKept ? kept[k] : obstacles_[k]->info.worldBounds.squaredDistance(p);
  };
  size_t first = 0;
  float firstDistance2 = kInf;
  for (size_t k = 0; k < n; ++k) {
    const float d2 = obstacles_[k]->info.worldBounds.squaredDistance(p);
    if (k < kKept) kept[k] = d2;
    if (d2 < firstDistance2) {
      firstDistance2 = d2;
      first = k;
    }
  }
  float best = kInf;
  const ObstacleData* bestObstacle = nullptr;
  Vec3 bestGradient = Vec3::Zero();  // in bestObstacle's frame, unnormalised
  for (size_t visit = 0; visit <= n; ++visit) {
    // The nearest by its bounds, then the others in order unless past the best distance (or
    // inside an obstacle: every bound is farther than that).
    size_t k;
    if (visit == 0) {
      if (!(firstDistance2 < kInf)) continue;
      k = first;
    } else {
      k = visit - 1;
      if (k == first || best < 0.0f || boundsDistance2(k) > best * best) continue;
    }
    const ObstacleData& o = *obstacles_[k];
    const SdfGrid& grid = distanceField(o);
    const Vec3 local = o.localRotation * p + o.localTranslation;
    Vec3 g;
    const float d = gradient ? grid.sampleWithGradient(local, &g) : grid.sample(local);
    if (d < best) {
      best = d;
      bestObstacle = &o;
      if (gradient) bestGradient = g;
    }
  }
  if (gradient && bestObstacle) {
    const float len = bestGradient.norm();
    if (len > 1e-12f) *gradient = bestObstacle->worldRotation * (bestGradient / len);
  }
  return best;
}

LightSample Environment::light(const Vec3& p) const {
  assert(!dirty_ && "Environment::commit() must be called after edits");
  LightSample out;
  float total = 0.0f, visible = 0.0f;
  Vec3 dir = Vec3::Zero(), nominal = Vec3::Zero();
  for (const Light& l : lights_) {
    if (l.intensity <= 0.0f) continue;
    Vec3 toLight;
    float tMax = kInf;
    if (l.type == Light::Type::Directional) {
      toLight = -l.direction.normalized();
    } else {
      toLight = l.position - p;
      tMax = toLight.norm();
      if (!(tMax > 0.0f)) continue;
      toLight /= tMax;
    }
    int n = (l.angularRadius > 0.0f) ? std::max(1, l.samples) : 1;
    int unblocked = 0;
    for (int i = 0; i < n; ++i) {
      Vec3 d = coneSample(toLight, l.angularRadius, i, n);
      // Obstacles, then the stems and leaves of support plants, each tested once.
      const bool blocked = rayAccepted(p, d, 1e-4f, tMax) &&
                           ((!obstacles_.empty() && rayMeetsObstacleBoxes(p, d, 1e-4f, tMax) &&
                             sceneOccludes(scene_, p, d, 1e-4f, tMax)) ||
                            (!stemLayers_.empty() && stemOccluded(p, d, 1e-4f, tMax, true)));
      if (!blocked) ++unblocked;
    }
    float v = float(unblocked) / float(n);
    total += l.intensity;
    visible += l.intensity * v;
    dir += l.intensity * v * toLight;
    nominal += l.intensity * toLight;
  }
  if (total > 0.0f) out.exposure = visible / total;
  float len = dir.norm();
  if (len > 0.0f) out.direction = dir / len;
  len = nominal.norm();
  if (len > 0.0f) out.nominal = nominal / len;
  return out;
}

Vec3 Environment::attraction(const Vec3& p) const {
  const StrokeGrid& g = *strokeGrid_;
  if (g.points.empty()) return Vec3::Zero();
  Vec3 sum = Vec3::Zero();
  float weightSum = 0.0f, maxWeight = 0.0f;
  g.anyNear(p, [&](uint32_t i) {
    const Stroke& s = strokes_[g.stroke[i]];
    Vec3 d = g.points[i] - p;
    float dist = d.norm();
    if (dist >= s.radius || dist < 1e-6f) return false;
    float w = (1.0f - dist / s.radius);
    w *= w;
    sum += w * (s.attract ? s.strength : -s.strength) * (d / dist);
    weightSum += w;
    maxWeight = std::max(maxWeight, w);
    return false;
  });
  if (weightSum <= 0.0f) return Vec3::Zero();
  return sum / weightSum * maxWeight;
}

bool Environment::repelled(const Vec3& p) const {
  const StrokeGrid& g = *strokeGrid_;
  if (g.points.empty()) return false;
  return g.anyNear(p, [&](uint32_t i) {
    const Stroke& s = strokes_[g.stroke[i]];
    if (s.attract) return false;
    const float dist = (g.points[i] - p).norm();
    if (dist >= s.radius) return false;
    const float w = 1.0f - dist / s.radius;
    return s.strength * w * w >= 0.5f;
  });
}

Vec3 Environment::wind(const Vec3& p, float t) const { return wind_.sample(p, t); }

Bounds3 Environment::bounds() const {
  Bounds3 b;
  for (const auto& o : obstacles_) b.extend(o->info.worldBounds);
  return b;
}

}  // namespace tendril::env
