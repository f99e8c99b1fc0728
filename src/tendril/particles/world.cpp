#include "tendril/particles/world.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/parallel.h"
#include "tendril/core/parallel_largest_first.h"
#include "tendril/core/timer.h"
#include "tendril/env/seed_check.h"
#include "tendril/models/stand_off.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace tendril::particles {

ParticleWorld::ParticleWorld(WorldSettings settings) : settings_(settings) {}

uint32_t ParticleWorld::allocate() {
  ++topologyVersion_;
  uint32_t i;
  if (!freeList_.empty()) {
    // Reuse the lowest free slot, so slot order does not depend on the order pieces died in.
    auto it = std::min_element(freeList_.begin(), freeList_.end());
    i = *it;
    *it = freeList_.back();
    freeList_.pop_back();
  } else {
    i = static_cast<uint32_t>(flags_.size());
    const size_t n = i + 1;
    x_.resize(n), xp_.resize(n), v_.resize(n), w_.resize(n), xr_.resize(n);
    q_.resize(n), qp_.resize(n), qr_.resize(n), groupRotation_.resize(n);
    a_.resize(n), b_.resize(n), m_.resize(n), age_.resize(n);
    flags_.resize(n), plant_.resize(n), parent_.resize(n), firstChild_.resize(n), nextSibling_.resize(n);
    targetHalfLength_.resize(n), restTime_.resize(n), anchor_.resize(n), anchorPhi_.resize(n);
    anchorSupport_.resize(n), anchorNormal_.resize(n);
    branchIndex_.resize(n), order_.resize(n), leafShape_.resize(n), leafTarget_.resize(n);
    flow_.resize(n);
  }
  x_[i] = xp_[i] = v_[i] = w_[i] = xr_[i] = anchor_[i] = anchorSupport_[i] = anchorNormal_[i] = Vec3::Zero();
  q_[i] = qp_[i] = qr_[i] = groupRotation_[i] = Quat::Identity();
  a_[i] = b_[i] = m_[i] = age_[i] = targetHalfLength_[i] = restTime_[i] = anchorPhi_[i] = leafTarget_[i] = 0.0f;
  flags_[i] = kActive;
  plant_[i] = 0;
  parent_[i] = firstChild_[i] = nextSibling_[i] = kNone;
  branchIndex_[i] = 0;
  order_[i] = 0;
  leafShape_[i] = 0;
  flow_[i] = FlowState{};
  ++active_;
  return i;
}

void ParticleWorld::release(uint32_t i) {
  ++topologyVersion_;
  // Children become roots of their own (detached) pieces.
  for (uint32_t c = firstChild_[i]; c != kNone;) {
    uint32_t next = nextSibling_[c];
    parent_[c] = kNone;
    nextSibling_[c] = kNone;
    flags_[c] |= kDetached;
    c = next;
  }
  firstChild_[i] = kNone;
  unlink(i);
  if (plant_[i] < plants_.size() && plants_[plant_[i]].particles > 0) --plants_[plant_[i]].particles;
  flags_[i] = 0;
  if (dragParticle_ == i) dragParticle_ = kNone;
  std::erase_if(leaves_, [i](const AttachedLeaf& l) { return l.particle == i; });
  freeList_.push_back(i);
  --active_;
}

void ParticleWorld::link(uint32_t parent, uint32_t child) {
  ++topologyVersion_;
  parent_[child] = parent;
  nextSibling_[child] = kNone;
  // Append, so children stay in creation order.
  if (firstChild_[parent] == kNone) {
    firstChild_[parent] = child;
  } else {
    uint32_t c = firstChild_[parent];
    while (nextSibling_[c] != kNone) c = nextSibling_[c];
    nextSibling_[c] = child;
  }
}

void ParticleWorld::unlink(uint32_t child) {
  uint32_t p = parent_[child];
  if (p == kNone) return;
  ++topologyVersion_;
  if (firstChild_[p] == child) {
    firstChild_[p] = nextSibling_[child];
  } else {
    for (uint32_t c = firstChild_[p]; c != kNone; c = nextSibling_[c])
      if (nextSibling_[c] == child) {
        nextSibling_[c] = nextSibling_[child];
        break;
      }
  }
  parent_[child] = kNone;
  nextSibling_[child] = kNone;
}

void ParticleWorld::updateMass(uint32_t i) {
  // Eq. 2: m = V ρ = 4/3 π a b c ρ, with b = c.
  const float density = plants_[plant_[i]].species.density;
  m_[i] = std::max(1e-9f, 4.0f / 3.0f * kPi * std::max(a_[i], 1e-4f) * b_[i] * b_[i] * density);
}

float ParticleWorld::contactDistance(uint32_t i) const {
  constexpr float kRoundingSlack = 1e-5f;  // m, beyond the bark's clearance
  return models::barkClearance(b_[i]) + kRoundingSlack;
}

void ParticleWorld::placeAnchor(uint32_t i) {
  if (anchorNormal_[i] != Vec3::Zero()) anchor_[i] = anchorSupport_[i] + anchorNormal_[i] * contactDistance(i);
}

float ParticleWorld::stiffnessOf(uint32_t i) const {
  // §4.3: s = t_l / t_m clamped to [0, 1], starting from `stiffnessStart` at birth (the paper
  // initialises t_l = 0.2 and increases it over 10 s), scaled by the species' stiffness.
  const ParticleSpecies& s = plants_[plant_[i]].species;
  float ramp = std::clamp(s.stiffnessStart + (1.0f - s.stiffnessStart) * age_[i] / s.stiffnessTime, 0.0f, 1.0f);
  return ramp * s.stiffness;
}

uint32_t ParticleWorld::spawn(uint32_t plant, uint32_t parent, Quat orientation, Quat restOrientation,
                              float radius, uint32_t flags) {
  uint32_t i = allocate();
  plant_[i] = plant;
  flags_[i] |= flags;
  q_[i] = qp_[i] = orientation.normalized();
  qr_[i] = restOrientation.normalized();
  b_[i] = std::max(radius, plants_[plant].species.minRadius);
  const float full = 0.5f * plants_[plant].species.particleLength;
  targetHalfLength_[i] = full;
  a_[i] = (flags & kRoot) ? b_[i] : 0.1f * full;
  if (parent != kNone) {
    link(parent, i);
    x_[i] = head(parent) + q_[i] * Vec3(0, a_[i], 0);
    xr_[i] = xr_[parent] + qr_[parent] * Vec3(0, a_[parent], 0) + qr_[i] * Vec3(0, a_[i], 0);
    order_[i] = order_[parent];
    v_[i] = v_[parent];
    flow_[i] = flow_[parent];
  }
  xp_[i] = x_[i];
  groupRotation_[i] = (q_[i] * qr_[i].conjugate()).normalized();
  updateMass(i);
  ++plants_[plant].particles;
  return i;
}

uint32_t ParticleWorld::addPlant(const std::string& name, const ParticleSpecies& species, const Vec3& position,
                                 const Vec3& direction, uint64_t seed, const env::Environment& env) {
  env::checkSeedPosition(env, position, direction, name);
  env.buildDistanceFields();  // collisions read them every step
  Plant p;
  p.name = name;
  p.species = species;
  p.seed = seed;
  plants_.push_back(std::move(p));
  const uint32_t id = static_cast<uint32_t>(plants_.size() - 1);

  Vec3 dir = direction.normalized();
  Vec3 zHint = anyPerpendicular(dir);
  Vec3 pos = position;
  if (auto sp = env.closestPoint(position, species.radius)) {
    // Seeds on a surface sit one radius above it.
    pos = sp->point + sp->away * species.radius;
    zHint = sp->away;
  }
  const Quat frame = frameFromYZ(dir, zHint);
  uint32_t root = spawn(id, kNone, frame, frame, species.radius, kRoot);
  x_[root] = xp_[root] = xr_[root] = pos;
  plants_[id].root = root;
  uint32_t apex = spawn(id, root, frame, frame, species.radius * species.apexTaper, kApex);
  branchIndex_[apex] = 1;
  (void)apex;
  return id;
}

void ParticleWorld::setSpecies(uint32_t plant, const ParticleSpecies& species) {
  // Every particle keeps the target length its growth gave it — Growth-Flow's shorter internodes
  // and smaller leaves in wind, a leaf particle's blade length — and follows a changed
  // particle_length or leaf size in proportion. (Setting every target to the species' still-air
  // particle length made any live edit, even of an unrelated key, undo the wind's effect on the
  // growing particles and give leaf particles a stem's length.)
  Plant& pl = plants_.at(plant);
  const float stemScale = species.particleLength / std::max(pl.species.particleLength, 1e-6f);
  const float leafScale = pl.species.leafSize > 0.0f ? species.leafSize / pl.species.leafSize : 1.0f;
  pl.species = species;
  for (uint32_t i = 0; i < capacity(); ++i)
    if ((flags_[i] & kActive) && plant_[i] == plant) {
      targetHalfLength_[i] *= (flags_[i] & kLeaf) ? leafScale : stemScale;
      updateMass(i);
    }
}

size_t ParticleWorld::particleCount(uint32_t plant) const { return plants_.at(plant).particles; }

bool ParticleWorld::hasBranchChild(uint32_t i) const {
  for (uint32_t c = firstChild_[i]; c != kNone; c = nextSibling_[c])
    if (!(flags_[c] & kLeaf)) return true;
  return false;
}

models::GrowthGauge::Reading ParticleWorld::growthReading(uint32_t plant) const {
  const Plant& pl = plants_.at(plant);
  const ParticleSpecies& s = pl.species;
  models::GrowthGauge::Reading r;
  float newest = 0.0f;  // age of its youngest stem particle
  bool any = false;
  for (uint32_t i = 0; i < capacity(); ++i) {
    const uint32_t f = flags_[i];
    if (!(f & kActive) || plant_[i] != plant || (f & (kLeaf | kDetached))) continue;
    r.grown += 2.0 * double(a_[i]);
    if ((f & kApex) && !pl.capped) r.growing = true;
    newest = any ? std::min(newest, age_[i]) : age_[i];
    any = true;
  }
  // The seed particle's age is the plant's.
  const float age = pl.root != kNone && (flags_[pl.root] & kActive) ? age_[pl.root] : 0.0f;
  const float dt = settings_.dt > 0.0f ? settings_.dt : 1.0f;
  r.steps = uint32_t(std::lround(age / dt));
  r.lastGrowth = uint32_t(std::lround((age - newest) / dt));
  if (pl.capped) r.cap = fmt::format("max_particles ({})", s.maxParticles);
  r.lightDriven = s.minGrowthLight < 1.0f;
  return r;
}

double ParticleWorld::unhinderedGrowth(uint32_t plant, uint32_t steps) const {
  // Its first apex lengthens at growth_rate per second of growth time in full light.
  const ParticleSpecies& s = plants_.at(plant).species;
  return double(s.growthRate) * double(s.growthSpeed) * double(settings_.dt) * double(steps);
}

float ParticleWorld::strain(uint32_t i) const {
  // §4.3: the stress of a connection is the difference between the current and the rest
  // distance of the two particles; it breaks when they are pulled apart. The rest distance is
  // that of the connection as grown, straight: a_parent + a_child (the particles joined end to
  // end; no bend of the joint is longer), and the strain is how far the two centres are pulled
  // beyond it, relative to it. Not against the rest state's own distance of the centres:
  // growth turns an apex by up to a radian a step (surface adaption, spreading) and its rest
  // frame with it (eq. 9), so a connection it folded has a rest distance of a few millimetres,
  // which the bend, held open by collisions and anchors, never returns to. Measured that way,
  // an undisturbed ivy on a wall at `break_threshold` 0.3 lost its first shoot after 20 steps
  // and stopped growing. Bending a joint open or shut is shape matching's business (the
  // stiffness), not breaking's.
  // A root is held where it was seeded, and the plant's first particle joins its surface: the
  // foot connection is as long as the particle's half length plus the root's radius, which
  // secondary growth increases (collisions hold the first particle a radius off the ground, and
  // so away from a root thickened to centimetres).
  const uint32_t p = parent_[i];
  if (p == kNone) return 0.0f;
  const float length = a_[i] + ((flags_[p] & kRoot) ? std::max(a_[p], b_[p]) : a_[p]);
  if (!(length > 0.0f)) return 0.0f;
  return std::max(0.0f, (x_[i] - x_[p]).norm() - length) / length;
}

models::AirBodies ParticleWorld::airBodies() const {
  airIds_.clear();
  for (uint32_t i = 0; i < capacity(); ++i)
    if ((flags_[i] & kActive) && (flags_[i] & kGrown) && !(flags_[i] & kLeaf)) airIds_.push_back(i);
  models::AirBodies b;
  b.ids = airIds_;
  b.position = x_, b.velocity = v_, b.orientation = q_;
  b.halfLength = a_, b.radius = b_, b.mass = m_;
  b.slots = capacity();
  return b;
}

double ParticleWorld::kineticEnergy() const {
  double e = 0.0;
  for (uint32_t i = 0; i < capacity(); ++i) {
    if (!(flags_[i] & kActive)) continue;
    // Rotational energy of a solid ellipsoid: I = m/5 (b² + c²) etc.; with b = c about the
    // long axis and m/5 (a² + b²) about the others. An upper bound is enough here.
    const double inertia = m_[i] / 5.0 * (double(a_[i]) * a_[i] + double(b_[i]) * b_[i]);
    e += 0.5 * m_[i] * v_[i].squaredNorm() + 0.5 * inertia * w_[i].squaredNorm();
  }
  return e;
}

size_t ParticleWorld::carryWithObstacle(const env::Environment& env, uint32_t obstacle, const RigidTransform& motion) {
  if (obstacle >= env.obstacleCount()) return 0;
  // Whether a point `gap` off a surface lies on the moving obstacle: its nearest surface, within
  // a centimetre more than that, is one of the obstacle's triangles.
  auto onObstacle = [&](const Vec3& p, float gap) {
    const std::optional<env::SurfacePoint> sp = env.closestPoint(p, gap + 0.01f);
    return sp && !sp->onStem() && sp->obstacle == obstacle;
  };
  const Quat turn = motion.rotation;
  auto carry = [&](uint32_t i) {
    x_[i] = motion.applyPoint(x_[i]);
    xp_[i] = motion.applyPoint(xp_[i]);
    q_[i] = (turn * q_[i]).normalized();
    qp_[i] = (turn * qp_[i]).normalized();
    v_[i] = turn * v_[i];
    w_[i] = turn * w_[i];
  };
  // An anchor on the moved obstacle: its point, the support under it and the normal there.
  auto carryAnchor = [&](uint32_t i) {
    anchor_[i] = motion.applyPoint(anchor_[i]);
    anchorSupport_[i] = motion.applyPoint(anchorSupport_[i]);
    anchorNormal_[i] = turn * anchorNormal_[i];
  };
  // Plants seeded on the obstacle: every particle of theirs, rest shape and anchors too.
  std::vector<uint8_t> whole(plants_.size(), 0);
  for (uint32_t p = 0; p < plants_.size(); ++p) {
    const uint32_t r = plants_[p].root;
    whole[p] = r != kNone && r < capacity() && (flags_[r] & kActive) && onObstacle(xr_[r], b_[r]);
  }
  std::vector<uint8_t> moved(capacity(), 0);
  parallelFor(0, capacity(), [&](size_t i) {
    if (!(flags_[i] & kActive)) return;
    const bool anchoredHere = (flags_[i] & kAnchored) && onObstacle(anchor_[i], b_[i]);
    if (whole[plant_[i]] && !(flags_[i] & kDetached)) {
      carry(uint32_t(i));
      xr_[i] = motion.applyPoint(xr_[i]);
      qr_[i] = (turn * qr_[i]).normalized();
      // An anchor on another surface lets go: the plant has left it.
      if (flags_[i] & kAnchored) {
        if (anchoredHere) carryAnchor(uint32_t(i));
        else flags_[i] &= ~kAnchored;
      }
      moved[i] = 1;
    } else if (anchoredHere) {
      carry(uint32_t(i));
      carryAnchor(uint32_t(i));
      moved[i] = 1;
    }
  }, 256);
  size_t count = 0;
  for (uint8_t m : moved) count += m;
  return count;
}

void ParticleWorld::setDrag(uint32_t particle, const Vec3& target, float strength) {
  if (particle >= capacity() || !(flags_[particle] & kActive)) {
    dragParticle_ = kNone;
    return;
  }
  dragParticle_ = particle;
  dragTarget_ = target;
  dragStrength_ = std::clamp(strength, 0.0f, 1.0f);
}

void ParticleWorld::clearDrag() { dragParticle_ = kNone; }

void ParticleWorld::markDetached(uint32_t root) {
  std::vector<uint32_t> stack = {root};
  while (!stack.empty()) {
    uint32_t i = stack.back();
    stack.pop_back();
    flags_[i] |= kDetached;
    flags_[i] &= ~(kApex | kAnchored);
    anchorPhi_[i] = 0.0f;
    restTime_[i] = 0.0f;
    for (uint32_t c = firstChild_[i]; c != kNone; c = nextSibling_[c]) stack.push_back(c);
  }
}

void ParticleWorld::cut(uint32_t particle, bool remove) {
  if (particle >= capacity() || !(flags_[particle] & kActive) || (flags_[particle] & kRoot)) return;
  unlink(particle);
  markDetached(particle);
  if (!remove) return;
  std::vector<uint32_t> piece, stack = {particle};
  while (!stack.empty()) {
    const uint32_t i = stack.back();
    stack.pop_back();
    piece.push_back(i);
    for (uint32_t c = firstChild_[i]; c != kNone; c = nextSibling_[c]) stack.push_back(c);
  }
  for (uint32_t i : piece) release(i);
}

uint32_t ParticleWorld::seedBranch(uint32_t particle, const Vec3& direction) {
  if (particle >= capacity() || !(flags_[particle] & kActive) || (flags_[particle] & (kDetached | kLeaf)))
    return kNone;
  const uint32_t plant = plant_[particle];
  const ParticleSpecies& s = plants_[plant].species;
  Vec3 dir = direction.squaredNorm() > 0.0f ? Vec3(direction.normalized()) : Vec3(q_[particle] * Vec3::UnitY());
  Quat q = frameFromYZ(dir, q_[particle] * Vec3::UnitZ());
  // The same turn, expressed in the rest frame, keeps the particle's deformation.
  Quat deformation = q_[particle] * qr_[particle].conjugate();
  Quat qr = deformation.conjugate() * q;
  uint32_t i = spawn(plant, particle, q, qr, b_[particle] * s.thicknessFalloff, kApex);
  order_[i] = static_cast<uint16_t>(order_[particle] + 1);
  branchIndex_[i] = 1;
  return i;
}

void ParticleWorld::removeRestingPieces() {
  for (uint32_t i = 0; i < capacity(); ++i)
    if ((flags_[i] & kActive) && (flags_[i] & kResting)) release(i);
}

void ParticleWorld::updateRestingPieces(const env::Environment& env) {
  // A broken-off piece that has fallen past everything it could land on — more than
  // kFallenOffDepth below the lowest obstacle and the lowest plant root (a piece thrown off a
  // finite ground) — never comes to rest: it would fall for ever. It is removed with the resting
  // pieces.
  bool anyDetached = false;
  for (uint32_t i = 0; i < capacity() && !anyDetached; ++i)
    anyDetached = (flags_[i] & kActive) && (flags_[i] & kDetached);
  if (!anyDetached) return;
  if (settings_.removeRestingAfter > 0.0f) {
    const Bounds3 world = env.bounds();
    float lowest = world.empty() ? std::numeric_limits<float>::infinity() : world.min.y();
    for (uint32_t i = 0; i < capacity(); ++i)
      if ((flags_[i] & kActive) && (flags_[i] & kRoot)) lowest = std::min(lowest, x_[i].y());
    if (std::isfinite(lowest)) {
      const float floor = lowest - kFallenOffDepth;
      for (uint32_t i = 0; i < capacity(); ++i)
        if ((flags_[i] & kActive) && (flags_[i] & kDetached) && x_[i].y() < floor) release(i);
    }
  }
  for (uint32_t i = 0; i < capacity(); ++i)  // (restTime_ is counted in integrate())
    if ((flags_[i] & kActive) && (flags_[i] & kDetached) && restTime_[i] >= settings_.restingTime)
      flags_[i] |= kResting;
  if (settings_.removeRestingAfter > 0.0f) {
    const float limit = settings_.restingTime + settings_.removeRestingAfter;
    for (uint32_t i = 0; i < capacity(); ++i)
      if ((flags_[i] & kActive) && (flags_[i] & kResting) && restTime_[i] >= limit) release(i);
  }
}

void ParticleWorld::step(const env::Environment& env) {
  if (externalAcceleration_.size() != capacity()) externalAcceleration_.resize(capacity(), Vec3::Zero());
  {
    Timer t;
    grow(env);
    timings_.growth = t.seconds();
  }
  if (externalAcceleration_.size() != capacity()) externalAcceleration_.resize(capacity(), Vec3::Zero());
  {
    Timer t;
    predict();
    applyAnchors(env);
    shapeMatch();
    timings_.dynamics = t.seconds();
  }
  {
    Timer t;
    collideObstacles(env);
    if (settings_.plantCollisions) collideParticles();
    timings_.collisions = t.seconds();
  }
  {
    Timer t;
    integrate();
    reportSpeedLimit();
    breakConnections();
    updateRestingPieces(env);
    timings_.breaking = t.seconds();
  }
  time_ += settings_.dt;
  ++step_;
}

plant::PlantModel ParticleWorld::snapshot(uint32_t plantId) const {
  (void)plants_.at(plantId);  // range check
  SnapshotParts parts;
  for (uint32_t i = 0; i < capacity(); ++i) {
    if (!(flags_[i] & kActive) || plant_[i] != plantId) continue;
    if (flags_[i] & kLeaf) {
      parts.leafParticles.push_back(i);
      continue;
    }
    ++parts.branchParticles;
    if ((flags_[i] & kDetached) && parent_[i] == kNone) parts.brokenRoots.push_back(i);
  }
  for (uint32_t k = 0; k < leaves_.size(); ++k)
    if (plant_[leaves_[k].particle] == plantId) parts.attachedLeaves.push_back(k);
  std::vector<int32_t> node(capacity(), -1);
  return snapshotFrom(plantId, parts, node);
}

std::vector<plant::PlantModel> ParticleWorld::snapshots() const {
  std::vector<SnapshotParts> parts(plants_.size());
  for (uint32_t i = 0; i < capacity(); ++i) {
    if (!(flags_[i] & kActive) || plant_[i] >= plants_.size()) continue;
    SnapshotParts& part = parts[plant_[i]];
    if (flags_[i] & kLeaf) {
      part.leafParticles.push_back(i);
      continue;
    }
    ++part.branchParticles;
    if ((flags_[i] & kDetached) && parent_[i] == kNone) part.brokenRoots.push_back(i);
  }
  for (uint32_t k = 0; k < leaves_.size(); ++k) {
    const uint32_t p = plant_[leaves_[k].particle];
    if (p < plants_.size()) parts[p].attachedLeaves.push_back(k);
  }
  // Every particle belongs to one plant, so one map serves them all, and the plants, which
  // read and write only their own particles' entries, are taken in parallel.
  std::vector<int32_t> node(capacity(), -1);
  std::vector<plant::PlantModel> out(plants_.size());
  std::vector<size_t> size(plants_.size());
  for (size_t p = 0; p < size.size(); ++p)
    size[p] = parts[p].branchParticles + parts[p].leafParticles.size() + parts[p].attachedLeaves.size();
  parallelForLargestFirst(size, [&](size_t p) { out[p] = snapshotFrom(uint32_t(p), parts[p], node); });
  return out;
}

plant::PlantModel ParticleWorld::snapshotFrom(uint32_t plantId, const SnapshotParts& parts,
                                              std::vector<int32_t>& node) const {
  const Plant& pl = plants_[plantId];
  plant::PlantModel m;
  m.name = pl.name;
  m.species = pl.species.name;
  m.bark = pl.species.bark;
  m.leafShapes = pl.species.leafShapes;
  m.reserve(parts.branchParticles, parts.attachedLeaves.size() + parts.leafParticles.size());

  std::vector<uint32_t> stack;
  auto addTree = [&](uint32_t root, bool broken) {
    stack.assign(1, root);
    while (!stack.empty()) {
      uint32_t i = stack.back();
      stack.pop_back();
      if (flags_[i] & kLeaf) continue;
      plant::PlantModel::NodeDef d;
      d.orientation = q_[i];
      d.length = 2.0f * a_[i];
      d.position = x_[i] - q_[i] * Vec3(0, a_[i], 0);
      d.radius = b_[i];
      d.parent = parent_[i] == kNone ? -1 : node[parent_[i]];
      d.age = age_[i];
      d.order = order_[i];
      d.flags = 0;
      if (flags_[i] & kApex) d.flags |= plant::kNodeApex;
      if (flags_[i] & kAnchored) d.flags |= plant::kNodeAnchored;
      if (broken) d.flags |= plant::kNodeBroken;
      // A tip that stopped (crowded, capped) and has grown nothing since: a dead end, and why.
      if (plant::tipEnd(flags_[i]) != plant::TipEnd::Unknown && !hasBranchChild(i))
        d.flags = plant::deadEnd(d.flags, plant::tipEnd(flags_[i]));
      if (parent_[i] != kNone && order_[i] > order_[parent_[i]]) d.flags |= plant::kNodeBranchStart;
      node[i] = m.addNode(d);
      // Children reversed on the stack, so they come out in creation order.
      const size_t mark = stack.size();
      for (uint32_t c = firstChild_[i]; c != kNone; c = nextSibling_[c]) stack.push_back(c);
      std::reverse(stack.begin() + std::ptrdiff_t(mark), stack.end());
    }
  };
  if (pl.root != kNone && (flags_[pl.root] & kActive)) addTree(pl.root, false);
  for (uint32_t i : parts.brokenRoots) addTree(i, true);

  // Leaves: attached records and leaf particles, both relative to their branch node.
  for (uint32_t k : parts.attachedLeaves) {
    const AttachedLeaf& l = leaves_[k];
    if (node[l.particle] < 0 || l.size <= 0.0f) continue;
    plant::PlantModel::LeafDef d;
    d.node = node[l.particle];
    d.offset = Vec3(0, 2.0f * a_[l.particle], b_[l.particle]);
    d.rotation = l.particleFromLeaf;
    d.size = l.size;
    d.petiole = pl.species.leafPetiole * (l.size / std::max(l.maxSize, 1e-6f));
    d.thickness = l.thickness;
    d.shape = l.shape;
    m.addLeaf(d);
  }
  for (uint32_t i : parts.leafParticles) {
    uint32_t p = parent_[i];
    if (p == kNone || node[p] < 0) continue;
    const Vec3 base = x_[i] - q_[i] * Vec3(0, a_[i], 0);
    const Vec3 nodeBase = x_[p] - q_[p] * Vec3(0, a_[p], 0);
    plant::PlantModel::LeafDef d;
    d.node = node[p];
    d.offset = q_[p].conjugate() * (base - nodeBase);
    d.rotation = (q_[p].conjugate() * q_[i]).normalized();
    d.size = 2.0f * a_[i];
    d.petiole = 0.0f;
    d.thickness = pl.species.leafThickness * flow_[i].leafThickness;
    d.shape = leafShape_[i];
    m.addLeaf(d);
  }
  return m;
}

}  // namespace tendril::particles
