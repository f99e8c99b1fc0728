// Plants as supports: host stems as round cones and host leaves as shade, in Embree scenes of
// their own per owner (environment.h). Rays meet the stems as Embree's round linear curves (a
// cone between two balls, exactly the tube a stem segment sweeps); closest points and signed
// distances come from a user geometry over the same tubes (Embree calls back for every
// primitive a point query's sphere overlaps, which it does not do for curves) and the exact
// distance to a round cone below.
#include "tendril/env/environment.h"
#include "tendril/env/stem_layer.h"

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

TubePoint closestOnTube(const StemTube& t, const Vec3& p) {
  // Distance to the union of balls c(s), r(s) along the axis, s in [0, L]: the minimum over s
  // of |p − c(s)| − r(s), a convex function of s whose minimiser has a closed form.
  const Vec3 axis = t.b - t.a;
  const float length = axis.norm();
  Vec3 c = t.a;
  float r = t.ra;
  Vec3 u = Vec3::UnitY();
  if (length > 1e-9f) {
    u = axis / length;
    const float k = (t.rb - t.ra) / length;
    if (std::fabs(k) >= 1.0f) {
      // One ball holds the other: the tube is the larger ball.
      if (t.rb > t.ra) c = t.b, r = t.rb;
    } else {
      const Vec3 w = p - t.a;
      const float x = w.dot(u);
      const float y = (w - x * u).norm();
      const float s = std::clamp(x + k * y / std::sqrt(1.0f - k * k), 0.0f, length);
      c = t.a + s * u;
      r = t.ra + k * s;
    }
  } else {
    r = std::max(t.ra, t.rb);
  }
  Vec3 d = p - c;
  const float n = d.norm();
  Vec3 dir;
  if (n > 1e-9f) {
    dir = d / n;
  } else {
    dir = anyPerpendicular(u);
  }
  return {c + r * dir, dir, n - r};
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
  const StemTube* tubes;
  Vec3 p;
  const Vec3* facing;
  float cosLimit;
  float best;  // signed distance of the best so far
  uint32_t bestTube = std::numeric_limits<uint32_t>::max();
  TubePoint bestPoint{};
};

bool stemCallback(RTCPointQueryFunctionArguments* args) {
  auto* s = static_cast<StemSearch*>(args->userPtr);
  const TubePoint tp = closestOnTube(s->tubes[args->primID], s->p);
  if (s->facing) {
    const Vec3 towardP = tp.distance < 0.0f ? Vec3(-tp.normal) : tp.normal;
    if (towardP.dot(*s->facing) > s->cosLimit) return false;
  }
  // Ties go to the lower tube index, so the answer never depends on traversal order.
  if (tp.distance < s->best || (tp.distance == s->best && args->primID < s->bestTube)) {
    s->best = tp.distance;
    s->bestTube = args->primID;
    s->bestPoint = tp;
    const float r = std::max(tp.distance, 0.0f);
    if (r < args->query->radius) {
      args->query->radius = r;
      return true;
    }
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

      l.points = rtcNewScene(device);
      rtcSetSceneBuildQuality(l.points, RTC_BUILD_QUALITY_LOW);
      RTCGeometry u = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
      rtcSetGeometryUserPrimitiveCount(u, unsigned(l.tubes.size()));
      rtcSetGeometryUserData(u, l.tubes.data());
      rtcSetGeometryBoundsFunction(u, tubeBounds, nullptr);
      rtcCommitGeometry(u);
      rtcAttachGeometryByID(l.points, u, 0);
      rtcReleaseGeometry(u);
      rtcCommitScene(l.points);
    }
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

bool Environment::stemOccluded(const Vec3& origin, const Vec3& dir, float tMin, float tMax, bool shade) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  for (const auto& lp : stemLayers_) {
    const StemLayer& l = *lp;
    if (!seesLayer(l)) continue;
    for (RTCScene s : {l.rays, shade ? l.shadeScene : nullptr}) {
      if (!s) continue;
      RTCRay ray;
      initRay(ray, origin, dir, tMin, tMax);
      rtcOccluded1(s, &ctx, &ray);
      if (ray.tfar < 0.0f) return true;  // Embree sets tfar = -inf on a hit
    }
  }
  return false;
}

bool Environment::closestStem(const Vec3& p, float radius, const Vec3* direction, float cosLimit,
                              SurfacePoint* best, float* signedDistance) const {
  bool found = false;
  float bound = radius;  // signed distance to beat
  for (const auto& lp : stemLayers_) {
    const StemLayer& l = *lp;
    if (!l.points || !seesLayer(l)) continue;
    StemSearch s{l.tubes.data(), p, direction, cosLimit, bound};
    RTCPointQuery q;
    q.x = p.x(), q.y = p.y(), q.z = p.z();
    q.time = 0.0f;
    q.radius = std::max(bound, 0.0f);
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
