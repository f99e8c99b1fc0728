// Plants as supports: host stems as round cones and host leaves as shade, in Embree scenes of
// their own per owner (environment.h). Rays meet the stems as Embree's round linear curves (a
// cone between two balls, exactly the tube a stem segment sweeps); closest points and signed
// distances come from a user geometry over the same tubes (Embree calls back for every
// primitive a point query's sphere overlaps, which it does not do for curves) and the exact
// distance to a round cone below.
#include "tendril/env/environment.h"
#include "tendril/env/stem_layer.h"

#include "tendril/core/segments.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tendril::env {

RTCDevice environmentDevice();  // environment.cpp

namespace {
// Depth within a stem that still counts as on its surface (round-off of rays and cones).
constexpr float kOnSurface = 1e-5f;
}  // namespace

TubeShape::TubeShape(const StemTube& t) : a(t.a), r(t.ra) {
  // The distance to the union of balls c(s), r(s) along the axis, s in [0, L], is the minimum
  // over s of |p − c(s)| − r(s), a convex function of s whose minimiser has a closed form; what
  // does not depend on p is worked out here, once per tube.
  const Vec3 axis = t.b - t.a;
  const float len = axis.norm();
  if (len > 1e-9f) {
    u = axis / len;
    const float slope = (t.rb - t.ra) / len;
    if (std::fabs(slope) >= 1.0f) {
      // One ball holds the other: the tube is the larger ball.
      if (t.rb > t.ra) a = t.b, r = t.rb;
    } else {
      length = len;
      k = slope;
      root = std::sqrt(1.0f - k * k);
    }
  } else {
    r = std::max(t.ra, t.rb);
  }
  rMax = std::max(r, length > 0.0f ? r + k * length : r);
}

TubePoint TubeShape::closest(const Vec3& p) const {
  Vec3 c = a;
  float rc = r;
  if (length > 0.0f) {
    const Vec3 w = p - a;
    const float x = w.dot(u);
    const float y = (w - x * u).norm();
    const float s = std::clamp(x + k * y / root, 0.0f, length);
    c = a + s * u;
    rc = r + k * s;
  }
  Vec3 d = p - c;
  const float n = d.norm();
  const Vec3 dir = n > 1e-9f ? Vec3(d / n) : anyPerpendicular(u);
  return {c + rc * dir, dir, n - rc};
}

float TubeShape::lowerBound2(const Vec3& p, float best) const {
  // |p − axis| − rMax bounds the signed distance from below; as a square, with a margin of
  // round-off, for the callers' quick rejection. Negative: no bound.
  const float limit = best + rMax;
  if (limit < 0.0f) return -1.0f;
  const Vec3 w = p - a;
  const float x = std::clamp(w.dot(u), 0.0f, length);
  const float d2 = (w - x * u).squaredNorm();
  const float m = limit * 1.0001f + 1e-6f;
  return d2 - m * m;
}

TubePoint closestOnTube(const StemTube& t, const Vec3& p) { return TubeShape(t).closest(p); }

bool TubeShape::meets(const Vec3& p, const Vec3& q) const {
  // The tube holds the capsule of its smallest radius round its axis and lies in the capsule
  // of its largest: the distance between the segment and the axis decides, except between
  // the two radii (a tapering tube, met near its thinner end), where the signed distance along
  // the segment, a convex function, is minimised by golden-section search.
  // First the cheap bound: every point of the segment lies within half its length of its middle.
  if (lowerBound2(0.5f * (p + q), 0.5f * (q - p).norm()) > 0.0f) return false;
  Vec3 onSegment, onAxis;
  closestSegmentPoints(p, q, a, a + length * u, &onSegment, &onAxis);
  const float d = (onSegment - onAxis).norm();
  const float rMin = length > 0.0f ? std::min(r, r + k * length) : r;
  if (d > rMax) return false;
  if (d <= rMin) return true;
  constexpr float kInvPhi = 0.618034f;
  float lo = 0.0f, hi = 1.0f;
  float x1 = hi - kInvPhi * (hi - lo), x2 = lo + kInvPhi * (hi - lo);
  float f1 = closest(p + x1 * (q - p)).distance, f2 = closest(p + x2 * (q - p)).distance;
  for (int i = 0; i < 40; ++i) {
    if (f1 <= 0.0f || f2 <= 0.0f) return true;
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1;
      x1 = hi - kInvPhi * (hi - lo);
      f1 = closest(p + x1 * (q - p)).distance;
    } else {
      lo = x1, x1 = x2, f1 = f2;
      x2 = lo + kInvPhi * (hi - lo);
      f2 = closest(p + x2 * (q - p)).distance;
    }
  }
  return f1 <= 0.0f || f2 <= 0.0f || closest(p).distance <= 0.0f || closest(q).distance <= 0.0f;
}

namespace {

void tubeBounds(const RTCBoundsFunctionArguments* args) {
  const auto* tubes = static_cast<const StemTube*>(args->geometryUserPtr);
  const StemTube& t = tubes[args->primID];
  const Vec3 lo = (t.a - Vec3::Constant(t.ra)).cwiseMin(t.b - Vec3::Constant(t.rb));
  const Vec3 hi = (t.a + Vec3::Constant(t.ra)).cwiseMax(t.b + Vec3::Constant(t.rb));
  RTCBounds* b = args->bounds_o;
  b->lower_x = lo.x(), b->lower_y = lo.y(), b->lower_z = lo.z();
  b->upper_x = hi.x(), b->upper_y = hi.y(), b->upper_z = hi.z();
}

bool validTube(const StemTube& t) {
  return t.a.allFinite() && t.b.allFinite() && std::isfinite(t.ra) && std::isfinite(t.rb) && t.ra >= 0.0f &&
         t.rb >= 0.0f && (t.ra > 0.0f || t.rb > 0.0f);
}

// The tube whose surface is nearest with sign: the smallest signed distance, so a point inside
// one tube and just outside another is inside the union (stems overlap at their joints).
struct StemSearch {
  const TubeShape* shapes;
  Vec3 p;
  const Vec3* facing;
  float cosLimit;
  float best;  // signed distance of the best so far
  uint32_t bestTube = std::numeric_limits<uint32_t>::max();
  TubePoint bestPoint{};

  // Whether tube i is nearer than the best so far (and faces the right way): then it is the best.
  bool offer(uint32_t i) {
    const TubeShape& shape = shapes[i];
    if (shape.lowerBound2(p, best) > 0.0f) return false;
    const TubePoint tp = shape.closest(p);
    if (facing) {
      const Vec3 towardP = tp.distance < 0.0f ? Vec3(-tp.normal) : tp.normal;
      if (towardP.dot(*facing) > cosLimit) return false;
    }
    // Ties go to the lower tube index, so the answer never depends on traversal order.
    if (!(tp.distance < best || (tp.distance == best && i < bestTube))) return false;
    best = tp.distance;
    bestTube = i;
    bestPoint = tp;
    return true;
  }
};

bool stemCallback(RTCPointQueryFunctionArguments* args) {
  auto* s = static_cast<StemSearch*>(args->userPtr);
  if (!s->offer(args->primID)) return false;
  const float r = std::max(s->best, 0.0f);
  if (r < args->query->radius) {
    args->query->radius = r;
    return true;
  }
  return false;
}

}  // namespace

void Environment::setStems(uint32_t owner, std::vector<StemTube> tubes, std::vector<ShadeTriangle> shade) {
  tubes.erase(std::remove_if(tubes.begin(), tubes.end(), [](const StemTube& t) { return !validTube(t); }),
              tubes.end());
  shade.erase(std::remove_if(shade.begin(), shade.end(),
                             [](const ShadeTriangle& t) {
                               return !(t.a.allFinite() && t.b.allFinite() && t.c.allFinite());
                             }),
              shade.end());
  auto it = std::find_if(stemLayers_.begin(), stemLayers_.end(), [&](const auto& l) { return l->owner == owner; });
  if (tubes.empty() && shade.empty()) {
    if (it != stemLayers_.end()) stemLayers_.erase(it), dirty_ = true;
  } else {
    if (it == stemLayers_.end()) {
      auto layer = std::make_unique<StemLayer>();
      layer->owner = owner;
      it = stemLayers_.insert(
          std::upper_bound(stemLayers_.begin(), stemLayers_.end(), owner,
                           [](uint32_t o, const auto& l) { return o < l->owner; }),
          std::move(layer));
    }
    (*it)->tubes = std::move(tubes);
    (*it)->shade = std::move(shade);
    (*it)->dirty = true;
    dirty_ = true;
  }
  ++stemRevision_;
  stemIndex_.clear();
  for (uint32_t l = 0; l < stemLayers_.size(); ++l) {
    stemLayers_[l]->first = uint32_t(stemIndex_.size());
    for (uint32_t t = 0; t < stemLayers_[l]->tubes.size(); ++t) stemIndex_.emplace_back(l, t);
  }
}

void Environment::clearStems() {
  if (stemLayers_.empty()) return;
  stemLayers_.clear();
  stemIndex_.clear();
  ++stemRevision_;
  dirty_ = true;
}

const StemTube& Environment::stem(uint32_t index) const {
  const auto [l, t] = stemIndex_.at(index);
  return stemLayers_[l]->tubes[t];
}

uint32_t Environment::stemOwner(uint32_t index) const { return stemLayers_[stemIndex_.at(index).first]->owner; }

bool Environment::seesLayer(const StemLayer& layer) const {
  return stemViewer_ != kNoStems && layer.owner != stemViewer_;
}

bool Environment::seesStems() const {
  for (const auto& l : stemLayers_)
    if (seesLayer(*l)) return true;
  return false;
}

void Environment::commitStems() {
  RTCDevice device = environmentDevice();
  for (auto& lp : stemLayers_) {
    StemLayer& l = *lp;
    if (!l.dirty) continue;
    l.release();
    if (!l.tubes.empty()) {
      // Stems are given again whenever their host grows or moves: built fast rather than best.
      l.rays = rtcNewScene(device);
      rtcSetSceneFlags(l.rays, RTC_SCENE_FLAG_ROBUST);
      rtcSetSceneBuildQuality(l.rays, RTC_BUILD_QUALITY_LOW);
      RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE);
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                                            4 * sizeof(float), 2 * l.tubes.size()));
      auto* idx = static_cast<uint32_t*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, sizeof(uint32_t), l.tubes.size()));
      for (size_t i = 0; i < l.tubes.size(); ++i) {
        const StemTube& t = l.tubes[i];
        float* q = v + 8 * i;
        q[0] = t.a.x(), q[1] = t.a.y(), q[2] = t.a.z(), q[3] = t.ra;
        q[4] = t.b.x(), q[5] = t.b.y(), q[6] = t.b.z(), q[7] = t.rb;
        idx[i] = uint32_t(2 * i);
      }
      rtcCommitGeometry(g);
      rtcAttachGeometryByID(l.rays, g, 0);
      rtcReleaseGeometry(g);
      rtcCommitScene(l.rays);

      // The closest-point scene is built at high quality: for a user geometry that costs about
      // what the low one does (no spatial splits), and its tighter boxes spare about two thirds
      // of the calls back for tubes (bench/README.md, "Climbing on plants").
      l.points = rtcNewScene(device);
      rtcSetSceneBuildQuality(l.points, RTC_BUILD_QUALITY_HIGH);
      RTCGeometry u = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
      rtcSetGeometryUserPrimitiveCount(u, unsigned(l.tubes.size()));
      rtcSetGeometryUserData(u, l.tubes.data());
      rtcSetGeometryBoundsFunction(u, tubeBounds, nullptr);
      rtcCommitGeometry(u);
      rtcAttachGeometryByID(l.points, u, 0);
      rtcReleaseGeometry(u);
      rtcCommitScene(l.points);
    }
    l.shapes.clear();
    for (const StemTube& t : l.tubes) l.shapes.emplace_back(t);
    if (!l.shade.empty()) {
      // Shade needs no robust traversal: a shadow ray slipping between two leaves' edges is light.
      l.shadeScene = rtcNewScene(device);
      rtcSetSceneBuildQuality(l.shadeScene, RTC_BUILD_QUALITY_LOW);
      RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                            3 * sizeof(float), 3 * l.shade.size() + 1));
      auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(uint32_t), l.shade.size()));
      for (size_t i = 0; i < l.shade.size(); ++i) {
        const ShadeTriangle& t = l.shade[i];
        for (int c = 0; c < 3; ++c) {
          const Vec3& q = c == 0 ? t.a : c == 1 ? t.b : t.c;
          v[9 * i + 3 * c + 0] = q.x(), v[9 * i + 3 * c + 1] = q.y(), v[9 * i + 3 * c + 2] = q.z();
          idx[3 * i + c] = uint32_t(3 * i + c);
        }
      }
      rtcCommitGeometry(g);
      rtcAttachGeometryByID(l.shadeScene, g, 0);
      rtcReleaseGeometry(g);
      rtcCommitScene(l.shadeScene);
    }
    l.dirty = false;
  }
}

bool Environment::stemRayCast(const Vec3& origin, const Vec3& dir, float tMin, RayHit* hit, float* tMax) const {
  bool found = false;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  for (const auto& lp : stemLayers_) {
    const StemLayer& l = *lp;
    if (!l.rays || !seesLayer(l)) continue;
    RTCRayHit rh;
    initRay(rh.ray, origin, dir, tMin, *tMax);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(l.rays, &ctx, &rh);
    // A hit at exactly the best distance so far is not closer: obstacles and earlier layers win.
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || !(rh.ray.tfar < *tMax)) continue;
    *tMax = rh.ray.tfar;
    hit->t = rh.ray.tfar;
    hit->point = origin + hit->t * dir;
    const TubePoint surface = closestOnTube(l.tubes[rh.hit.primID], hit->point);
    hit->normal = surface.normal;
    hit->point = surface.point;  // on the surface exactly, not a hair within it
    hit->obstacle = kOnStem;
    hit->triangle = l.first + rh.hit.primID;
    found = true;
  }
  return found;
}

bool Environment::layerOccluded(const StemLayer& l, const Vec3& origin, const Vec3& dir, float tMin, float tMax,
                                bool shade) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  // The leaves first: under a crown most shadow rays end in a leaf soon, where the stems'
  // traversal would have followed the whole ray (the answer is the same either way).
  for (RTCScene s : {shade ? l.shadeScene : nullptr, l.rays}) {
    if (!s) continue;
    RTCRay ray;
    initRay(ray, origin, dir, tMin, tMax);
    rtcOccluded1(s, &ctx, &ray);
    if (ray.tfar < 0.0f) return true;  // Embree sets tfar = -inf on a hit
  }
  return false;
}

bool Environment::stemOccluded(const Vec3& origin, const Vec3& dir, float tMin, float tMax, bool shade) const {
  for (const auto& lp : stemLayers_)
    if (seesLayer(*lp) && layerOccluded(*lp, origin, dir, tMin, tMax, shade)) return true;
  return false;
}

namespace {

// The tubes that may come within `radius` of a point (a point query that never shrinks).
struct StemGather {
  const TubeShape* shapes;
  Vec3 centre;
  float radius;
  static constexpr size_t kMax = 48;
  uint32_t found[kMax];
  size_t count = 0;
  bool overflow = false;
};

bool gatherCallback(RTCPointQueryFunctionArguments* args) {
  auto* g = static_cast<StemGather*>(args->userPtr);
  if (g->shapes[args->primID].lowerBound2(g->centre, g->radius) > 0.0f) return false;
  if (g->count == StemGather::kMax) g->overflow = true;
  else g->found[g->count++] = args->primID;
  return false;
}

}  // namespace

bool Environment::stemSegmentsBlocked(const Vec3* from, const Vec3* to, size_t n) const {
  if (n == 0) return false;
  // Short segments near each other (a leaf's outline): the few tubes near all of them are
  // found with one point query and each segment is tested against those, instead of a ray
  // per segment through every tube's hierarchy. Too many tubes near: rays after all.
  Vec3 lo = from[0].cwiseMin(to[0]), hi = from[0].cwiseMax(to[0]);
  for (size_t i = 1; i < n; ++i) lo = lo.cwiseMin(from[i].cwiseMin(to[i])), hi = hi.cwiseMax(from[i].cwiseMax(to[i]));
  const Vec3 centre = 0.5f * (lo + hi);
  const float radius = 0.5f * (hi - lo).norm();
  for (const auto& lp : stemLayers_) {
    const StemLayer& l = *lp;
    if (!l.points || !seesLayer(l)) continue;
    StemGather g{l.shapes.data(), centre, radius};
    RTCPointQuery q;
    q.x = centre.x(), q.y = centre.y(), q.z = centre.z();
    q.time = 0.0f;
    q.radius = radius;
    RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    rtcPointQuery(l.points, &q, &ctx, gatherCallback, &g);
    if (g.count == 0) continue;
    if (g.overflow) {
      for (size_t i = 0; i < n; ++i) {
        Vec3 d = to[i] - from[i];
        const float len = d.norm();
        if (len > 0.0f && layerOccluded(l, from[i], d / len, 0.0f, len, false)) return true;
      }
      continue;
    }
    // The segments in runs of up to kRun (a leaf's outline: one run per blade), each run's
    // tubes those its bounding sphere may touch; then each segment against those.
    constexpr size_t kRun = 5;
    for (size_t first = 0; first < n; first += kRun) {
      const size_t last = std::min(n, first + kRun);
      Vec3 rlo = from[first].cwiseMin(to[first]), rhi = from[first].cwiseMax(to[first]);
      for (size_t i = first + 1; i < last; ++i)
        rlo = rlo.cwiseMin(from[i].cwiseMin(to[i])), rhi = rhi.cwiseMax(from[i].cwiseMax(to[i]));
      const Vec3 rc = 0.5f * (rlo + rhi);
      const float rr = 0.5f * (rhi - rlo).norm();
      uint32_t near[StemGather::kMax];
      size_t count = 0;
      for (size_t c = 0; c < g.count; ++c)
        if (!(l.shapes[g.found[c]].lowerBound2(rc, rr) > 0.0f)) near[count++] = g.found[c];
      for (size_t i = first; i < last; ++i)
        for (size_t c = 0; c < count; ++c)
          if (l.shapes[near[c]].meets(from[i], to[i])) return true;
    }
  }
  return false;
}

bool Environment::closestStem(const Vec3& p, float radius, const Vec3* direction, float cosLimit,
                              SurfacePoint* best, float* signedDistance, const SurfacePoint* hint) const {
  bool found = false;
  float bound = radius;  // signed distance to beat
  // The hinted stem (where the caller found a surface last) and its neighbours in the host's
  // node order start the search: the sphere Embree searches is then about as small as the
  // answer's distance from the start. The answer is the same without them.
  const std::pair<uint32_t, uint32_t> hinted = hint && hint->onStem() && hint->stem() < stemIndex_.size()
                                                   ? stemIndex_[hint->stem()]
                                                   : std::pair<uint32_t, uint32_t>(~0u, 0);
  for (uint32_t li = 0; li < stemLayers_.size(); ++li) {
    const StemLayer& l = *stemLayers_[li];
    if (!l.points || !seesLayer(l)) continue;
    StemSearch s{l.shapes.data(), p, direction, cosLimit, bound};
    if (li == hinted.first) {
      const uint32_t t = hinted.second, n = uint32_t(l.shapes.size());
      for (uint32_t i = t > 0 ? t - 1 : 0; i <= t + 1 && i < n; ++i) s.offer(i);
    }
    RTCPointQuery q;
    q.x = p.x(), q.y = p.y(), q.z = p.z();
    q.time = 0.0f;
    q.radius = std::max(s.best, 0.0f);
    RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    rtcPointQuery(l.points, &q, &ctx, stemCallback, &s);
    if (s.bestTube == std::numeric_limits<uint32_t>::max() || !(s.best < bound)) continue;
    bound = s.best;
    if (best) {
      best->point = s.bestPoint.point;
      best->normal = s.bestPoint.normal;
      // A point within round-off of the surface (a ray's hit, a seed placed there) is on it:
      // away from the stem, as outside.
      best->away = s.bestPoint.distance < -kOnSurface ? Vec3(-s.bestPoint.normal) : s.bestPoint.normal;
      best->distance = std::fabs(s.best);
      best->obstacle = kOnStem;
      best->triangle = l.first + s.bestTube;
    }
    if (signedDistance) *signedDistance = s.best;
    found = true;
  }
  return found;
}

bool sameSupport(const SurfacePoint& a, const SurfacePoint& b, const Environment& env) {
  if (a.onStem() != b.onStem()) return false;
  if (!a.onStem()) return a.obstacle == b.obstacle;
  return env.stem(a.stem()).plant == env.stem(b.stem()).plant;
}

}  // namespace tendril::env
