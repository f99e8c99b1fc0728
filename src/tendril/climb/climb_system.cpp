#include "tendril/climb/climb_system.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/parallel.h"
#include "tendril/core/random.h"
#include "tendril/env/seed_check.h"

#include <fmt/format.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>

namespace tendril::climb {

namespace {

constexpr uint64_t kPurposeRule = purposeId("climb.rule");
constexpr uint64_t kPurposeRandomTropism = purposeId("climb.random-tropism");
constexpr uint64_t kPurposeBranch = purposeId("climb.branch");
constexpr uint64_t kPurposeLeaf = purposeId("climb.leaf");
constexpr uint64_t kPurposeHold = purposeId("climb.hold");
const float kCos45 = std::cos(radians(45.0f));

// Where a new segment may go: the end point and direction after collision avoidance, and the
// closest surface within `reach` of the end (the tip's support at the next step).
struct Avoided {
  bool ok = false;
  Vec3 end = Vec3::Zero();
  Vec3 dir = Vec3::Zero();
  Vec3 normal = Vec3::Zero();  // away from the surface that was hit last, if any
  bool hit = false;
  std::optional<env::SurfacePoint> endSupport;
};

// Seed 003 §3.5, eq. 5: a tip about to grow into an obstacle is turned parallel to the hit
// triangle (d' = d − n(n·d)). We repeat the test for the turned segment (corners), and keep
// the segment end at least `offset` from every surface — the role of eq. 5's translation,
// which moves the tip to the intersection point: a branch of radius r must not sink into the
// wall it climbs, and rays must not start on a surface.
Avoided avoidCollisions(const env::Environment& env, const Vec3& p, Vec3 d, float len, float offset, float reach,
                        Vec3 normal, const env::SurfacePoint* hint) {
  Avoided out;
  for (int attempt = 0; attempt < 6; ++attempt) {
    if (auto hit = env.rayCast(p, d, len + offset)) {
      Vec3 n = hit->normal;
      if (n.dot(d) > 0.0f) n = -n;  // open meshes: use the side facing the tip
      Vec3 turned = d - n * n.dot(d);
      if (turned.squaredNorm() < 1e-6f) {
        // Head-on: slide along the surface in the direction of the previous frame normal's
        // projection, or any tangent.
        turned = normal - n * n.dot(normal);
        if (turned.squaredNorm() < 1e-6f) turned = anyPerpendicular(n);
      }
      d = turned.normalized();
      normal = n;
      out.hit = true;
      continue;
    }
    Vec3 end = p + d * len;
    std::optional<env::SurfacePoint> sp = env.closestPoint(end, std::max(reach, offset), hint);
    if (sp && sp->distance < offset) {
      end = sp->point + sp->away * offset;
      Vec3 seg = end - p;
      float l = seg.norm();
      if (l < 1e-5f) return out;
      Vec3 nd = seg / l;
      if (env.rayCast(p, nd, l)) {  // pushing out of one surface led into another
        d = nd;
        continue;
      }
      d = nd;
      // Pushed straight out along `away`: the same surface point, now exactly `offset` away.
      sp->distance = offset;
    }
    out.ok = true;
    out.end = end;
    out.dir = d;
    out.normal = normal;
    if (sp && sp->distance <= reach) out.endSupport = sp;
    return out;
  }
  return out;
}

// Seed 003 eq. 3–4: rotate the direction toward the tropism vector v about d × v, by an angle
// proportional to |d × v| (the strength-weighted sine, as in ABOP §2.4) but never past v.
Vec3 applyTropism(const Vec3& d, const Vec3& v) {
  Vec3 axis = d.cross(v);
  float s = axis.norm();
  if (s < 1e-7f) return d;
  float angle = std::min(s, angleBetween(d, v));
  return (axisAngle(axis, angle) * d).normalized();
}

}  // namespace

struct ClimbSystem::Outcome {
  bool addNode = false;
  plant::PlantModel::NodeDef node;
  Vec3 end = Vec3::Zero();
  int leafCount = 0;
  plant::PlantModel::LeafDef leaves[2];
  bool dies = false;
  plant::TipEnd why = plant::TipEnd::Unknown;  // when it dies
  bool branch = false;
  Tip updated;
  Tip branchTip;
};

ClimbSystem::ClimbSystem(uint64_t sceneSeed, float stepTime) : sceneSeed_(sceneSeed), stepTime_(stepTime) {}
ClimbSystem::~ClimbSystem() = default;
ClimbSystem::ClimbSystem(ClimbSystem&&) noexcept = default;
ClimbSystem& ClimbSystem::operator=(ClimbSystem&&) noexcept = default;

uint32_t ClimbSystem::addPlant(const ClimbPlantDef& def, const env::Environment& env) {
  const ClimbSpecies& s = def.species;
  auto plant = std::make_unique<Plant>();
  plant->def = def;
  plant->id = static_cast<uint32_t>(plants_.size());
  plant->model.name = def.name;
  plant->model.species = s.name;
  plant->model.bark = s.bark;
  plant->model.leafShapes = s.leafShapes;

  Vec3 p = def.position;
  env::checkSeedPosition(env, p, def.direction, def.name);
  Tip tip;
  tip.id = plant->nextTipId++;
  tip.dir = def.direction.normalized();
  tip.normal = anyPerpendicular(tip.dir);
  if (auto sp = env.closestPoint(p, s.surfaceOffset)) {
    // Seeds usually sit on the ground: lift them to the stand-off distance.
    p = sp->point + sp->away * s.surfaceOffset;
    tip.normal = sp->away;
  }
  tip.support = env.closestPoint(p, s.adhesionDistance);
  if (tip.support) tip.normal = tip.support->away;
  tip.position = p;
  // Crowding queries are cheapest with cells twice the largest crowding radius.
  float cell = 2.0f * s.crowdingRadius;
  for (const auto& other : plants_) cell = std::max(cell, 2.0f * other->def.species.crowdingRadius);
  if (cell > 0.0f) occupancy_.setCell(cell);
  tip.radius = s.radius;
  tip.length = s.segmentLength;
  tip.leafSize = s.leafSize;
  tip.leafThickness = s.leafThickness;
  tip.shootStart = Vec3(s.radius, s.segmentLength, s.leafSize);
  plant->tips.push_back(tip);
  plants_.push_back(std::move(plant));
  return plants_.back()->id;
}

// Program 1's segment(Tip) from the tip along `growDir`: kept clear of surfaces by eq. 5's
// collision avoidance when the species has that rule, and held onto its support over edges and
// round corners (surface hold). Updates the tip's normal; nothing when the tip is boxed in.
std::optional<ClimbSystem::Segment> ClimbSystem::placeSegment(const ClimbSpecies& s, Tip& t, const Vec3& growDir,
                                                              bool climbing, Rng hold,
                                                              const env::Environment& env) const {
  bool avoid = false;
  for (const Rule& r : s.rules) avoid |= r.kind == RuleKind::CollisionAvoidance;
  Segment seg{t.position + growDir * t.length, growDir, std::nullopt};
  Vec3& end = seg.end;
  Vec3& dir = seg.dir;
  std::optional<env::SurfacePoint>& endSupport = seg.endSupport;
  const env::SurfacePoint* hint = t.support ? &*t.support : nullptr;
  if (avoid) {
    Avoided a = avoidCollisions(env, t.position, growDir, t.length, s.surfaceOffset, s.adhesionDistance, t.normal, hint);
    if (!a.ok) return std::nullopt;
    end = a.end;
    dir = a.dir;
    endSupport = a.endSupport;
    if (a.hit) t.normal = a.normal;
    // Hold on: a climbing tip whose segment would end out of reach of every surface bends
    // back toward the nearest one (over an edge, round a corner), unless it breaks free.
    if (climbing && !endSupport && s.surfaceHold > 0.0f && hold.bernoulli(s.surfaceHold)) {
      if (auto q = env.closestPoint(end, t.length + s.adhesionDistance)) {
        Vec3 target = q->point + q->away * s.surfaceOffset - t.position;
        if (target.squaredNorm() > 1e-10f) {
          Avoided b = avoidCollisions(env, t.position, target.normalized(), t.length, s.surfaceOffset,
                                      s.adhesionDistance, q->away, &*q);
          if (b.ok) {
            end = b.end;
            dir = b.dir;
            endSupport = b.endSupport;
            t.normal = b.hit ? b.normal : q->away;
          }
        }
      }
    }
  } else {
    endSupport = env.closestPoint(end, s.adhesionDistance, hint);
  }
  return seg;
}

// Seed 003's PlaceLeaf rule at the end of the tip's new segment (out.node): two blades parted
// by the species' spread, lying parallel to the nearest surface (upper side away from it) or
// turned to the light in free air, each shrunk or dropped until its outline touches nothing.
void ClimbSystem::placeLeaves(const ClimbSpecies& s, const Tip& t, const Vec3& dir,
                              const std::optional<env::SurfacePoint>& endSupport, Rng lr,
                              const env::Environment& env, Outcome& out) const {
  plant::PlantModel::NodeDef& node = out.node;
  const Vec3 end = out.end;
  const Mat3 frame = node.orientation.toRotationMatrix();
  // Attachment: the segment end, lifted over the stem's surface along the frame normal.
  const Vec3 attachLocal(0.0f, node.length, node.radius + s.leafLift);
  const Vec3 attach = node.position + node.orientation * attachLocal;
  if (env.rayCast(end, frame.col(2), node.radius + s.leafLift)) return;
  // Blades lie parallel to the surface nearest to them, upper side away from it (seed
  // 003 §3.10); in free air they turn toward the light (seed 000 §4.3).
  Vec3 leafUp = frame.col(2);
  const std::optional<env::SurfacePoint> near =
      env.closestPoint(attach, s.adhesionDistance, endSupport ? &*endSupport : nullptr);
  if (near) {
    leafUp = near->away;
  } else if (s.light > 0.0f) {
    Vec3 toLight = env.light(attach).nominal;
    if (toLight.squaredNorm() > 0.0f) leafUp = toLight;
  }
  // The blade's base direction: the growth direction laid into the blade's plane.
  const Quat worldFromBlade = frameFromYZ(dir - leafUp * leafUp.dot(dir), leafUp);
  const Quat nodeFromBlade = node.orientation.conjugate() * worldFromBlade;
  struct Blade {
    Quat nodeFromLeaf;
    Mat3 frame;
    uint16_t shape;
    float aspect;
  } blades[2];
  for (int side = 0; side < 2; ++side) {
    float angle = (side == 0 ? 1.0f : -1.0f) * (s.leafSpread + s.leafJitter * lr.uniform(-1.0f, 1.0f));
    Blade& b = blades[side];
    b.nodeFromLeaf = (nodeFromBlade * axisAngle(Vec3::UnitZ(), angle)).normalized();
    // On a curved support a blade laid on the tangent plane at its attachment rises off the
    // surface toward its tip, by the arc its centre spans (on a 15 cm column 7.5° for half the
    // blades, 15° or more for one in 20: tests/climb/climb_leaf_angle_test.cpp). It lies on
    // the surface under its centre instead, where a flat leaf pressed on the bark touches it,
    // when that is the same surface curving: the same obstacle, its normal within 45° of the
    // one at the attachment (at a corner the other surface would turn the blade into the one
    // it grows from).
    if (near) {
      const Quat world = node.orientation * b.nodeFromLeaf;
      const Vec3 centre = attach + world * Vec3(0.0f, s.leafPetiole + 0.5f * t.leafSize, 0.0f);
      const std::optional<env::SurfacePoint> under = env.closestPoint(centre, s.adhesionDistance, &*near);
      if (under && env::sameSupport(*under, *near, env) && under->away.dot(near->away) > kCos45 &&
          under->away.dot(near->away) < 1.0f - 1e-6f)
        b.nodeFromLeaf = (node.orientation.conjugate() * laidOn(world, under->away)).normalized();
    }
    b.shape = static_cast<uint16_t>(lr.below(uint32_t(s.leafShapes.size())));
    b.aspect = s.leafShapes[b.shape].aspect;
    b.frame = (node.orientation * b.nodeFromLeaf).toRotationMatrix();
  }
  // The blade must not pass through a surface. One closed path of segments per blade,
  // attachment -> c0 -> c1 -> c2 -> c3 -> c0, touching nothing: then every corner is
  // reached from the attachment without crossing a surface (none lies behind one) and
  // all four blade edges are clear. Blades that do not fit shrink, or are dropped.
  auto path = [&](const Blade& b, float scale, Vec3* from, Vec3* to) {
    float size = t.leafSize * scale, petiole = s.leafPetiole * scale, hw = 0.5f * size * b.aspect;
    const Vec3 c[4] = {attach + b.frame * Vec3(-hw, petiole, 0), attach + b.frame * Vec3(hw, petiole, 0),
                       attach + b.frame * Vec3(hw, petiole + size, 0),
                       attach + b.frame * Vec3(-hw, petiole + size, 0)};
    from[0] = attach;
    to[0] = c[0];
    for (int k = 0; k < 4; ++k) {
      from[k + 1] = c[k];
      to[k + 1] = c[(k + 1) % 4];
    }
  };
  float fitted[2] = {0.0f, 0.0f};
  Vec3 from[10], to[10];
  path(blades[0], 1.0f, from, to);
  path(blades[1], 1.0f, from + 5, to + 5);
  if (!env.anySegmentBlocked(from, to, 10)) {
    fitted[0] = fitted[1] = 1.0f;  // the common case: both blades fit as they are
  } else {
    for (int side = 0; side < 2; ++side)
      for (float scale : {1.0f, 0.7f, 0.45f}) {
        path(blades[side], scale, from, to);
        if (!env.anySegmentBlocked(from, to, 5)) {
          fitted[side] = scale;
          break;
        }
      }
  }
  for (int side = 0; side < 2; ++side) {
    if (fitted[side] == 0.0f) continue;
    plant::PlantModel::LeafDef& leaf = out.leaves[out.leafCount++];
    leaf.offset = attachLocal;
    leaf.rotation = blades[side].nodeFromLeaf;
    leaf.size = t.leafSize * fitted[side];
    leaf.petiole = s.leafPetiole * fitted[side];
    leaf.thickness = t.leafThickness;
    leaf.shape = blades[side].shape;
  }
  if (out.leafCount > 0) node.flags |= plant::kNodeLeafNode;
}

void ClimbSystem::growTip(const Plant& plant, const Tip& tip, const env::Environment& env, Outcome& out) const {
  const ClimbSpecies& s = plant.def.species;
  const uint64_t seed = plant.def.seed ^ mix64(sceneSeed_);
  auto rng = [&](uint64_t purpose) { return Rng(RandomKey{seed, plant.id, tip.id, step_, purpose}); };
  Tip t = tip;

  // Climbing state (seed 003 §3.6): is a support surface within reach of the tip? The closest
  // surface was found when the previous segment ended here; surfaces the tip grows away from
  // do not hold it, so only when that one faces the growth direction is a filtered search due.
  const float cosRelease = std::cos(s.releaseAngle);
  const env::SurfacePoint* support = tip.support ? &*tip.support : nullptr;  // (t.support changes below)
  std::optional<env::SurfacePoint> filtered;
  if (support && support->away.dot(t.dir) > cosRelease) {
    filtered = env.closestPointFacing(t.position, s.adhesionDistance, t.dir, cosRelease, support);
    support = filtered ? &*filtered : nullptr;
  }
  const bool climbing = support != nullptr;
  if (climbing) t.normal = support->away;
  t.unsupported = climbing ? 0 : t.unsupported + 1;
  if (s.maxUnsupported > 0 && t.unsupported > uint32_t(s.maxUnsupported)) {
    out.dies = true;  // too long without support: the shoot flops and dies
    out.why = plant::TipEnd::NoSupport;
    return;
  }

  // Growth-Flow (seed 001, Algorithm 1): in a wind above the species' w_min this shoot's
  // segments grow shorter (eq. 8) and thicker (eq. 7), its leaves smaller (eq. 17) and thicker
  // (eq. 16), one unit of growth time per segment, and it grows along its still-air direction
  // turned downwind by eq. 9's growth angle α_t. Calm wind leaves every value untouched.
  plant::GrowthFlowStep flow;
  Vec3 windHere = Vec3::Zero();
  if (!env.windField().settings().calm()) {
    windHere = env.wind(t.position, float(step_) * stepTime_);
    flow = plant::growthStep(windHere.norm(), s.growthFlow);
  }
  Quat windTurn = Quat::Identity();  // still-air direction -> the direction grown in the wind
  if (flow.active())
    t.windAngle = plant::nextGrowthAngle(t.windAngle < 0.0f ? s.growthFlow.angle0 : t.windAngle, flow);
  // The angle grows only while f(w) > 0, but a shoot keeps the turn it has grown when a gust
  // drops below w_min (it turns toward the wind there is): snapping back to its still-air
  // direction would make it zig-zag in gusty wind.
  const bool turned = t.windAngle > 0.0f && windHere.squaredNorm() > 0.0f;
  if (turned) windTurn = Quat::FromTwoVectors(t.dir, plant::windGrowthDirection(t.dir, windHere, t.windAngle));
  if (flow.active()) {
    t.length *= flow.length;
    t.windLength *= flow.length;
    if (s.growthFlow.maxLength > 0.0f) t.length = std::min(t.length, s.growthFlow.maxLength);
    t.radius *= flow.radius;
    t.leafSize *= flow.leafRadius;
    t.leafThickness *= flow.leafThickness;
    if (t.length < s.minLength) {
      out.dies = true;
      out.why = plant::TipEnd::Shortened;
      return;
    }
  }

  // Program 1: Tip -> segment(Tip) Tip.
  const Vec3 growDir = turned ? Vec3((windTurn * t.dir).normalized()) : t.dir;
  std::optional<Segment> segment = placeSegment(s, t, growDir, climbing, rng(kPurposeHold), env);
  // Boxed in (nowhere to grow), or grown into a region a repelling stroke keeps growth out of.
  if (!segment || env.repelled(segment->end)) {
    out.dies = true;
    out.why = plant::TipEnd::Blocked;
    return;
  }
  const Vec3 end = segment->end, dir = segment->dir;
  const std::optional<env::SurfacePoint>& endSupport = segment->endSupport;
  // Crowding is judged on the shoot's own scale: a shoot whose internodes the wind has made
  // shorter (eq. 8) grows a smaller copy of its still-air self, and looks for crowding within
  // as many of its own internodes as in still air. In a fixed sphere its shorter internodes
  // would merely pack more segment ends together, and branching would stop in strong wind
  // (0.14 of the still-air segments at 14 m/s, tests/wind/wind_on_a_wall_test.cpp). Still air
  // leaves the radius exactly the species' one.
  const float crowdingRadius = s.crowdingRadius * std::min(1.0f, t.windLength);
  int crowd = s.crowdingRadius > 0.0f ? occupancy_.countWithin(end, crowdingRadius, s.crowdingLimit) : 0;
  if (s.crowdingRadius > 0.0f && crowd >= s.crowdingLimit) {
    out.dies = true;  // the plant already covers this spot
    out.why = plant::TipEnd::Crowded;
    return;
  }

  plant::PlantModel::NodeDef& node = out.node;
  node.position = t.position;
  node.orientation = frameFromYZ(dir, t.normal);
  node.length = (end - t.position).norm();
  node.radius = std::max(t.radius, s.minRadius);
  node.order = t.order;
  node.flags = (climbing ? plant::kNodeClimbing : 0u) |
               ((t.startsBranch && t.segments == 0) ? plant::kNodeBranchStart : 0u);
  out.addNode = true;
  out.end = end;

  const Mat3 frame = node.orientation.toRotationMatrix();
  t.normal = frame.col(2);
  t.position = end;
  // The shoot keeps its still-air direction; the wind's growth angle bends what it grows.
  t.dir = turned ? Vec3((windTurn.conjugate() * dir).normalized()) : dir;
  t.segments += 1;
  t.support = endSupport;

  // The rules of Table 1, in the species' order.
  for (size_t ri = 0; ri < s.rules.size() && !out.dies; ++ri) {
    const Rule& r = s.rules[ri];
    if (t.segments % uint32_t(r.every) != 0) continue;
    if (r.probability < 1.0f && !rng(kPurposeRule + ri).bernoulli(r.probability)) continue;
    switch (r.kind) {
      case RuleKind::Tropism: {
        // Eq. 6 (not climbing) and eq. 7 (climbing: adhesion toward the support and the upward
        // pseudo-tropism v_up replace gravity).
        Vec3 v = Vec3::Zero();
        if (climbing) v += s.adhesion * (-support->away) + s.up * Vec3(0, 1, 0);
        else v += s.gravity * Vec3(0, -1, 0);
        if (s.light > 0.0f) {
          env::LightSample l = env.light(t.position);
          v += s.light * (l.exposure * l.direction + s.lightAmbient * (1.0f - l.exposure) * l.nominal);
        }
        if (s.randomness > 0.0f) v += s.randomness * rng(kPurposeRandomTropism).unitVector();
        if (s.userDirectionStrength > 0.0f) v += s.userDirectionStrength * s.userDirection;
        if (s.windStrength > 0.0f) v += s.windStrength * env.wind(t.position, float(step_) * stepTime_);
        if (s.attraction > 0.0f) v += s.attraction * env.attraction(t.position);
        t.dir = applyTropism(t.dir, v);
        break;
      }
      case RuleKind::Decrease:  // eq. 8
        t.radius *= s.decreaseRadius;
        t.length *= s.decreaseLength;
        t.leafSize *= s.decreaseLeafSize;
        if (t.length < s.minLength) {
          out.dies = true;
          out.why = plant::TipEnd::Shortened;
        }
        break;
      case RuleKind::CollisionAvoidance:
        break;  // applied to every segment as it is added (above)
      case RuleKind::Die:
        out.dies = true;
        out.why = plant::TipEnd::Rule;
        break;
      case RuleKind::PlaceLeaf: {
        if (s.leafShapes.empty() || t.leafSize <= 0.0f) break;
        // Algorithm 2: a leaf in a wind beyond its petiole's or blade's strength tears off.
        if (flow.active() && plant::leafDetaches(windHere.norm(), s.growthFlow)) break;
        placeLeaves(s, t, dir, endSupport, rng(kPurposeLeaf), env, out);
        break;
      }
      case RuleKind::Branch: {
        // Seed 003 §3.7: a node at the splitting point and a new tip turned 35–40° away.
        if (s.crowdingRadius > 0.0f && crowd >= std::max(1, s.crowdingLimit / 2)) break;
        Rng br = rng(kPurposeBranch);
        float angle = br.uniform(s.branchAngleMin, s.branchAngleMax) * (br.bernoulli(0.5f) ? 1.0f : -1.0f);
        // Climbing shoots branch within the surface plane; free ones about a random axis.
        Vec3 axis = climbing ? t.normal : Vec3(dir.cross(br.unitVector()));
        if (axis.squaredNorm() < 1e-8f) axis = anyPerpendicular(dir);
        Tip& b = out.branchTip;  // built in place (a copy trips GCC's maybe-uninitialized on optional)
        b = Tip{};
        b.position = end;
        b.dir = (axisAngle(axis, angle) * dir).normalized();
        b.normal = t.normal;
        b.shootStart = t.shootStart.cwiseProduct(s.branchFalloff);
        b.radius = b.shootStart.x();
        b.length = b.shootStart.y();
        b.leafSize = b.shootStart.z();
        b.leafThickness = s.leafThickness;
        b.order = static_cast<uint16_t>(t.order + 1);
        b.unsupported = t.unsupported;
        b.support = endSupport;
        b.startsBranch = true;
        out.branch = true;
        break;
      }
    }
  }
  out.updated = t;
}

void ClimbSystem::step(const env::Environment& env) {
  // Gather every live tip of every plant; grow them in parallel into their own outcomes.
  refs_.clear();
  firstOutcome_.clear();
  resumeCappedPlants();
  for (const auto& p : plants_) {
    firstOutcome_.push_back(static_cast<uint32_t>(refs_.size()));
    if (p->capped) continue;  // its tips wait for room
    for (uint32_t i = 0; i < p->tips.size(); ++i) refs_.push_back({p->id, i});
  }
  firstOutcome_.push_back(static_cast<uint32_t>(refs_.size()));
  outcomes_.resize(refs_.size());
  parallelFor(0, refs_.size(), [&](size_t i) {
    const Plant& p = *plants_[refs_[i].plant];
    outcomes_[i] = Outcome();
    growTip(p, p.tips[refs_[i].tip], env, outcomes_[i]);
  }, 8);

  // Merge in tip order: node and tip ids depend only on the order, never on the threads. Each
  // plant merges its own outcomes (in parallel with the others) while the new segment ends go
  // into the shared crowding grid, whose counts do not depend on the order of insertion.
  tbb::parallel_invoke(
      [&] {
        for (const Outcome& o : outcomes_)
          if (o.addNode) occupancy_.insert(o.end);
      },
      [&] {
        parallelFor(0, plants_.size(), [&](size_t i) {
          if (!plants_[i]->capped) mergePlant(*plants_[i], firstOutcome_[i]);
        }, 1);
      });
  for (auto& pp : plants_) {
    Plant& p = *pp;
    if (!p.capped && p.model.nodeCount() >= size_t(p.def.species.maxSegments)) {
      p.capped = true;
      // The tips wait (resumeCappedPlants); their nodes say why they stopped meanwhile.
      for (const Tip& t : p.tips)
        if (t.lastNode >= 0) p.model.flags[t.lastNode] = plant::deadEnd(p.model.flags[t.lastNode], plant::TipEnd::Capped);
      log::warn("plant \"{}\" reached max_segments ({}): growth stopped; raise the species' max_segments to grow "
                "further",
                p.def.name, p.def.species.maxSegments);
    }
  }
  ++step_;
}

void ClimbSystem::resumeCappedPlants() {
  // A plant stopped at max_segments grows on from the tips it had once a cut has left it room for
  // a twentieth of the cap again (not at every segment cut off: a plant pruned a little would
  // start and stop, and warn, over and over).
  for (auto& pp : plants_) {
    Plant& p = *pp;
    if (!p.capped) continue;
    const size_t cap = size_t(std::max(p.def.species.maxSegments, 1));
    if (p.model.nodeCount() + std::max<size_t>(cap / 20, 1) > cap) continue;
    p.capped = false;
    for (const Tip& t : p.tips)
      if (t.lastNode >= 0) p.model.flags[t.lastNode] &= ~(plant::kNodeDead | plant::kNodeTipEndMask);
  }
}

void ClimbSystem::mergePlant(Plant& p, size_t k) {
  std::vector<Tip>& next = p.nextTips;
  next.clear();
  for (uint32_t i = 0; i < p.tips.size(); ++i, ++k) {
    Outcome& o = outcomes_[k];
    int32_t nodeIndex = p.tips[i].lastNode;
    if (o.addNode) {
      o.node.parent = p.tips[i].lastNode;
      nodeIndex = p.model.addNode(o.node);
      p.birthStep.push_back(step_);
      p.nodeEnd.push_back(o.end);
      for (int l = 0; l < o.leafCount; ++l) {
        o.leaves[l].node = nodeIndex;
        p.model.addLeaf(o.leaves[l]);
      }
    }
    if (o.dies) {
      if (nodeIndex >= 0) p.model.flags[nodeIndex] = plant::deadEnd(p.model.flags[nodeIndex], o.why);
      else p.seedEnd = o.why;  // the seed's own tip, before its first segment
    } else {
      o.updated.lastNode = nodeIndex;
      next.push_back(o.updated);
    }
    if (o.branch && nodeIndex >= 0) {
      o.branchTip.lastNode = nodeIndex;
      o.branchTip.id = p.nextTipId++;
      next.push_back(o.branchTip);
    }
  }
  p.tips.swap(next);
}

namespace {

// The length of stem a species' first shoot grows in `steps` steps with nothing in its way and
// no wind: one segment a step, shortened by its decrease rules (at their mean rate), until it is
// shorter than min_length or a certain die rule ends it.
double unhinderedStemLength(const ClimbSpecies& s, uint32_t steps) {
  double length = s.segmentLength, total = 0.0;
  for (uint32_t k = 1; k <= steps; ++k) {
    total += length;
    bool dies = false;
    for (const Rule& r : s.rules) {
      if (k % uint32_t(r.every) != 0) continue;
      if (r.kind == RuleKind::Decrease) {
        length *= std::pow(double(s.decreaseLength), double(r.probability));
        dies |= length < s.minLength;
      } else if (r.kind == RuleKind::Die && r.probability >= 1.0f) {
        dies = true;
      }
    }
    if (dies) break;
  }
  return total;
}

}  // namespace

models::GrowthGauge::Reading ClimbSystem::growthReading(uint32_t plant) const {
  const Plant& p = *plants_.at(plant);
  const ClimbSpecies& s = p.def.species;
  models::GrowthGauge::Reading r;
  r.growing = !p.capped && !p.tips.empty();
  for (float l : p.model.length) r.grown += double(l);
  // Its first segment grew in the step it was seeded in (a seed whose tip died at once has
  // none: counted from the start).
  const uint32_t born = p.birthStep.empty() ? 0 : p.birthStep.front();
  r.steps = step_ - born;
  r.lastGrowth = p.birthStep.empty() ? 0 : p.birthStep.back() - born + 1;
  if (p.capped) r.cap = fmt::format("max_segments ({})", s.maxSegments);
  r.seedEnd = p.seedEnd;
  // A shoot grows max_unsupported segments before it must have a surface within adhesion distance.
  if (s.maxUnsupported > 0) {
    r.supportReach = s.adhesionDistance;
    r.unsupportedRun = float(s.maxUnsupported) * s.segmentLength;
  }
  return r;
}

double ClimbSystem::unhinderedGrowth(uint32_t plant, uint32_t steps) const {
  return unhinderedStemLength(plants_.at(plant)->def.species, steps);
}

bool ClimbSystem::finished() const {
  for (const auto& p : plants_)
    if (!p->capped && !p->tips.empty()) return false;
  return true;
}

plant::PlantModel ClimbSystem::snapshot(uint32_t id) const {
  const Plant& p = *plants_.at(id);
  plant::PlantModel m = p.model;
  for (size_t i = 0; i < m.nodeCount(); ++i) m.age[i] = float(step_ - p.birthStep[i]) * stepTime_;
  if (!p.capped)
    for (const Tip& t : p.tips)
      if (t.lastNode >= 0) m.flags[t.lastNode] |= plant::kNodeApex;
  if (p.def.species.pipeModel) {
    // Pipe model (Shinozaki et al. 1964; seed 003's future work): a segment carries the
    // cross-sections of everything above it, r_parent² >= Σ r_child². Children come after
    // parents, so one reverse pass accumulates whole subtrees.
    std::vector<float> carried(m.nodeCount(), 0.0f);
    for (size_t i = m.nodeCount(); i-- > 0;) {
      float r2 = std::max(m.radius[i] * m.radius[i], carried[i]);
      m.radius[i] = std::sqrt(r2);
      if (m.parent[i] >= 0) carried[m.parent[i]] += r2;
    }
  }
  return m;
}

ClimbStats ClimbSystem::stats(uint32_t id) const {
  const Plant& p = *plants_.at(id);
  ClimbStats s;
  s.segments = p.model.nodeCount();
  s.leaves = p.model.leafCount();
  s.aliveTips = p.capped ? 0 : p.tips.size();
  for (uint32_t f : p.model.flags)
    if (f & plant::kNodeClimbing) ++s.climbingSegments;
  return s;
}

ClimbStats ClimbSystem::stats() const {
  ClimbStats s;
  for (uint32_t i = 0; i < plants_.size(); ++i) {
    ClimbStats t = stats(i);
    s.segments += t.segments;
    s.leaves += t.leaves;
    s.aliveTips += t.aliveTips;
    s.climbingSegments += t.climbingSegments;
  }
  return s;
}

}  // namespace tendril::climb
