// Plant growth of seed 000 §4.2–4.3.
#include "tendril/core/log.h"
#include "tendril/core/parallel.h"
#include "tendril/core/random.h"
#include "tendril/particles/world.h"
#include "tendril/plant/growth_flow.h"

#include <algorithm>
#include <cmath>

namespace tendril::particles {

namespace {

constexpr uint64_t kPurposeWalk = purposeId("particles.random-walk");
constexpr uint64_t kPurposeBud = purposeId("particles.lateral-bud");
constexpr uint64_t kPurposeLeaf = purposeId("particles.leaf");
constexpr int kOcclusionInterval = 8;  // steps between rebuilds of the occlusion grid

// Rotation turning unit `from` toward unit `to` by `angle` (never past it).
Quat turnToward(const Vec3& from, const Vec3& to, float angle) {
  const float between = angleBetween(from, to);
  if (!(between > 1e-6f) || !(angle > 0.0f)) return Quat::Identity();
  Vec3 axis = from.cross(to);
  if (axis.squaredNorm() < 1e-12f) axis = anyPerpendicular(from);
  return axisAngle(axis, std::min(angle, between));
}

}  // namespace

void ParticleWorld::buildOcclusion(const env::Environment& env) {
  // Plants compete for light (Fig. 11): every branch and leaf particle shades the cells it
  // occupies by its projected area; occlusion at a point is 1 − exp(−Σ coverage) along the
  // way to the light. (The paper reads occlusion from its variance shadow map; a coverage grid
  // gives the same competition without a GPU.)
  Occlusion& o = occlusion_;
  Bounds3 b;
  for (uint32_t i = 0; i < capacity(); ++i)
    if ((flags_[i] & kActive) && !(flags_[i] & kDetached)) b.extend(x_[i]);
  o.density.clear();
  if (b.empty()) return;
  o.cell = 0.1f;
  o.origin = b.min - Vec3::Constant(o.cell);
  Vec3 size = b.size() + Vec3::Constant(2 * o.cell);
  for (int k = 0; k < 3; ++k) o.dims[k] = std::max(1, int(std::ceil(size[k] / o.cell)));
  if (double(o.dims.x()) * o.dims.y() * o.dims.z() > 8e6) {
    // Very large scenes: coarser cells.
    float scale = float(std::cbrt(double(o.dims.x()) * o.dims.y() * o.dims.z() / 8e6));
    o.cell *= scale;
    for (int k = 0; k < 3; ++k) o.dims[k] = std::max(1, int(std::ceil(size[k] / o.cell)));
  }
  o.density.assign(size_t(o.dims.x()) * o.dims.y() * o.dims.z(), 0.0f);
  const float area = o.cell * o.cell;
  auto add = [&](const Vec3& p, float a) {
    Eigen::Vector3i c = ((p - o.origin) / o.cell).cast<int>();
    if ((c.array() < 0).any() || (c.array() >= o.dims.array()).any()) return;
    o.density[(size_t(c.z()) * o.dims.y() + c.y()) * o.dims.x() + c.x()] += a / area;
  };
  for (uint32_t i = 0; i < capacity(); ++i) {
    if (!(flags_[i] & kActive) || (flags_[i] & kDetached)) continue;
    if (flags_[i] & kLeaf) add(x_[i], 2.0f * a_[i] * a_[i] * 0.8f);  // blade ≈ 0.8 of a square
    else add(x_[i], 4.0f * a_[i] * b_[i]);
  }
  for (const AttachedLeaf& l : leaves_)
    if (flags_[l.particle] & kActive) add(head(l.particle), 0.8f * l.size * l.size);
  (void)env;
}

float ParticleWorld::occlusion(const Vec3& p, const Vec3& towardLight) const {
  const Occlusion& o = occlusion_;
  if (o.density.empty() || towardLight.squaredNorm() == 0.0f) return 0.0f;
  float depth = 0.0f;
  Eigen::Vector3i start = ((p - o.origin) / o.cell).cast<int>();
  // March in half-cell steps; the particle's own cell does not shade it.
  for (int k = 1; k < 64; ++k) {
    Vec3 q = p + towardLight * (0.5f * o.cell * float(k));
    Eigen::Vector3i c = ((q - o.origin) / o.cell).cast<int>();
    if ((c.array() < 0).any() || (c.array() >= o.dims.array()).any()) break;
    if (c == start) continue;
    depth += 0.5f * o.density[(size_t(c.z()) * o.dims.y() + c.y()) * o.dims.x() + c.x()];
  }
  return 1.0f - std::exp(-depth);
}

Vec3 ParticleWorld::crowdAway(uint32_t i, float radius, int* count) const {
  // Reads the spatial hash of the last collision pass (positions move little in a step).
  *count = 0;
  if (hashEntries_.empty() || hashStart_.size() < 2) return Vec3::Zero();
  // The apex's own branch behind it and branches forking off it are not "others".
  uint32_t ancestors[8];
  int na = 0;
  for (uint32_t p = i; p != kNone && na < 8; p = parent_[p]) ancestors[na++] = p;
  auto related = [&](uint32_t j) {
    for (uint32_t q = j, k = 0; q != kNone && k < 4; q = parent_[q], ++k)
      if (std::find(ancestors, ancestors + na, q) != ancestors + na) return true;
    return false;
  };
  const uint32_t mask = uint32_t(hashStart_.size() - 2);
  const Vec3 p = x_[i];
  auto cellOf = [&](const Vec3& q) {
    return Eigen::Vector3i(int(std::floor(q.x() * hashInv_)), int(std::floor(q.y() * hashInv_)),
                           int(std::floor(q.z() * hashInv_)));
  };
  const int reach = std::clamp(int(std::ceil(radius * hashInv_)), 1, 2);
  radius = std::min(radius, float(reach) / hashInv_);
  const Eigen::Vector3i c = cellOf(p);
  uint32_t buckets[125];
  int nb = 0;
  for (int dz = -reach; dz <= reach; ++dz)
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        const uint32_t h = spatialHash(c + Eigen::Vector3i(dx, dy, dz), mask);
        if (std::find(buckets, buckets + nb, h) == buckets + nb) buckets[nb++] = h;
      }
  Vec3 away = Vec3::Zero();
  for (int k = 0; k < nb; ++k)
    for (uint32_t e = hashStart_[buckets[k]]; e < hashStart_[buckets[k] + 1]; ++e) {
      const uint32_t j = hashEntries_[e];
      if (!(flags_[j] & kActive) || (flags_[j] & (kLeaf | kDetached))) continue;
      const Vec3 d = p - x_[j];
      const float dist2 = d.squaredNorm();
      if (dist2 > radius * radius || related(j)) continue;
      ++*count;
      if (dist2 > 1e-12f) away += d / std::sqrt(dist2);
    }
  return away;
}

struct ParticleWorld::ApexUpdate {
  Quat growth = Quat::Identity();  // R_g (eq. 8), world frame
  float halfLength = 0.0f;
  bool grown = false;
  bool anchor = false;
  bool dormant = false;  // the apex stops growing (crowded, or in a region painted to repel growth)
  plant::TipEnd stop = plant::TipEnd::Crowded;  // why, when dormant
  Vec3 anchorSupport = Vec3::Zero(), anchorNormal = Vec3::Zero();  // the support point under the particle, its normal
  Vec3 leafUp = Vec3::Zero();  // preferred leaf normal here (away from the surface / to the light)
  bool leafOnSupport = false;  // leafUp is a support's normal: blades lie on it
};

size_t ParticleWorld::particlesPerGrowth(const Plant& pl) const {
  // The successor, up to B lateral buds, and a leaf where leaves are particles of their own.
  const ParticleSpecies& s = pl.species;
  const bool leafParticle = s.leafStep > 0 && s.leafSize > 0.0f && !s.leafShapes.empty() &&
                            pl.particles < size_t(std::max(s.leafParticleLimit, 0));
  return 1 + size_t(std::max(s.maxLateralBuds, 0)) + (leafParticle ? 1 : 0);
}

void ParticleWorld::resumeCappedPlants() {
  // A plant stopped at max_particles grows on once it has room again: pruning (a cut that
  // removes), pieces that broke off and were removed at rest, or a raised max_particles. Not at
  // every particle freed: it waits for room for a twentieth of the cap, so that a plant shedding
  // a few particles now and then does not start and stop (and warn) over and over.
  for (uint32_t p = 0; p < plants_.size(); ++p) {
    Plant& pl = plants_[p];
    if (!pl.capped) continue;
    const ParticleSpecies& s = pl.species;
    const size_t room = size_t(std::max(s.maxParticles / 20, 1)) + particlesPerGrowth(pl);
    if (pl.particles + room > size_t(std::max(s.maxParticles, 0))) continue;
    pl.capped = false;
    // The tips that stopped for the cap grow on; the apices that waited for it resume by themselves.
    const uint32_t cappedEnd = uint32_t(plant::TipEnd::Capped) << plant::kNodeTipEndShift;
    for (uint32_t i = 0; i < capacity(); ++i)
      if ((flags_[i] & kActive) && plant_[i] == p && !(flags_[i] & (kDetached | kLeaf | kApex)) &&
          (flags_[i] & plant::kNodeTipEndMask) == cappedEnd && !hasBranchChild(i))
        flags_[i] = (flags_[i] & ~plant::kNodeTipEndMask) | kApex;
  }
}

void ParticleWorld::grow(const env::Environment& env) {
  if (step_ % kOcclusionInterval == 0) buildOcclusion(env);
  resumeCappedPlants();

  std::vector<uint32_t> apices;
  for (uint32_t i = 0; i < capacity(); ++i)
    if ((flags_[i] & kActive) && (flags_[i] & kApex) && !(flags_[i] & kDetached) && !plants_[plant_[i]].capped)
      apices.push_back(i);

  // Parallel: every apex decides its growth from the environment (reads only).
  std::vector<ApexUpdate> updates(apices.size());
  parallelFor(0, apices.size(), [&](size_t k) { decideApex(apices[k], env, updates[k]); }, 16);

  // Sequential: apply in apex order (eq. 8–10), spawn successors, buds and leaves.
  for (size_t k = 0; k < apices.size(); ++k) {
    const uint32_t i = apices[k];
    if (!(flags_[i] & kActive) || !(flags_[i] & kApex)) continue;
    applyApex(i, updates[k], env);
  }

  growLeaves();
  attachLeavesOfLargePlants();
  thicken();
}

// An apex's growth this step from the light, the surfaces, other branches, the user's strokes
// and a random walk (eq. 6–7, §3, §5.1); reads only.
void ParticleWorld::decideApex(uint32_t i, const env::Environment& env, ApexUpdate& u) const {
  const float dt = settings_.dt;
  const Plant& pl = plants_[plant_[i]];
  const ParticleSpecies& s = pl.species;
  const float gdt = dt * s.growthSpeed;  // growth time of this step
  // The tropisms steer the still-air orientation of an apex grown in wind (Growth-Flow
  // §3.1.1: the shoot keeps its still-air direction and grows along it turned toward the
  // wind), so they never undo the wind's turn: its forward vector here is the still-air one,
  // and the growth rotation found for it is carried into the turned frame at the end.
  const Quat turn = flow_[i].turn;
  const bool turned = turn.coeffs() != Quat::Identity().coeffs();
  const Vec3 forward = turned ? Vec3((turn.conjugate() * q_[i]) * Vec3::UnitY()) : Vec3(q_[i] * Vec3::UnitY());
  Vec3 vf = forward;
  // A shoot that reached the region a repelling stroke keeps growth out of stops there (the
  // stroke steers the shoots round it away, below): what the user painted stays clear.
  if (env.repelled(head(i))) {
    u.dormant = true;
    u.stop = plant::TipEnd::Blocked;
    return;
  }

  // Light (eq. 7's occlusion O counts obstacles by shadow rays and plants by coverage).
  const env::LightSample light = env.light(x_[i]);
  const Vec3 toLight = light.nominal;
  const float occluded = 1.0f - light.exposure * (1.0f - occlusion(x_[i], toLight));
  const float exposure = 1.0f - occluded;
  // Growth rate scales with the light the apex receives.
  float rate = s.growthRate * (s.minGrowthLight + (1.0f - s.minGrowthLight) * exposure);
  // Growth-Flow's unit of growth time is one internode, here one particle (docs/wind.md): wind
  // shortens what grows in a unit (eq. 8), not the unit. A particle of a lineage grown in wind
  // elongates in proportion to its shortened length, so it takes as long as a still-air one;
  // at the still-air speed, short particles came faster, and with each its chance to branch.
  if (flow_[i].length != 1.0f)
    rate *= std::clamp(targetHalfLength_[i] / std::max(0.5f * s.particleLength, 1e-6f), 0.0f, 1.0f);
  u.halfLength = std::min(a_[i] + 0.5f * rate * gdt, targetHalfLength_[i]);
  u.grown = u.halfLength >= targetHalfLength_[i] * 0.999f;

  Quat rg = Quat::Identity();
  u.leafUp = toLight;
  Vec3 lightPull = toLight;  // the direction phototropism turns toward
  // Surface adaption (eq. 6): a_a = v̂_s × v̂_f, α_a = (v̂_s · v̂_f) τ Δt turns the apex parallel
  // to the surface it approaches. Farther than touching distance, it also turns toward the
  // support ("the plant searches for a nearby support structure and directs its growth
  // towards this direction").
  if (auto sp = env.closestPoint(x_[i], s.adhesionDistance)) {
    const Vec3 vs = -sp->away;
    const float along = vs.dot(vf);
    Vec3 axis = vs.cross(vf);
    if (axis.squaredNorm() > 1e-12f) rg = axisAngle(axis, along * s.surfaceAdaption * gdt) * rg;
    const float touch = b_[i] + s.anchorDistance;
    if (sp->distance > touch) rg = turnToward(rg * vf, vs, s.surfaceAdaption * gdt) * rg;
    // A climber on its support follows the light along the surface rather than leaving it.
    const Vec3 along2 = toLight - toLight.dot(sp->away) * sp->away;
    if (along2.squaredNorm() > 1e-8f) lightPull = along2.normalized();
    u.leafUp = sp->away;
    u.leafOnSupport = true;
    if (sp->distance <= touch) {
      u.anchor = true;
      u.anchorSupport = sp->point;
      u.anchorNormal = sp->away;
    }
  }
  vf = (rg * forward).normalized();
  // Branches spread out (as seed 003's tips avoid each other): stems of other branches —
  // of any plant — within one particle length push the apex aside; where more of them than
  // the species' crowding limit surround it, the apex stops.
  if (s.crowding > 0) {
    int count = 0;
    const Vec3 away = crowdAway(i, 2.0f * targetHalfLength_[i], &count);
    if (count > s.crowding) {
      u.dormant = true;
      return;
    }
    Vec3 side = away - away.dot(vf) * vf;
    if (side.squaredNorm() > 1e-12f && s.spreading > 0.0f)
      rg = turnToward(vf, side.normalized(), std::min(1.0f, float(count) / float(s.crowding)) * s.spreading * gdt) * rg;
  }
  vf = (rg * forward).normalized();
  // Phototropism (eq. 7): α_p = (1 − O) η Δt toward the light (axis v̂_f × v̂_l).
  if (lightPull.squaredNorm() > 0.0f)
    rg = turnToward(vf, lightPull, (1.0f - occluded) * s.phototropism * gdt) * rg;
  vf = (rg * forward).normalized();
  // Attractors and repulsors painted by the user (§5.1): the weighted average of nearby
  // stroke points.
  const Vec3 pull = env.attraction(x_[i]);
  if (pull.squaredNorm() > 1e-12f)
    rg = turnToward(vf, pull.normalized(), s.attraction * gdt * std::min(1.0f, pull.norm())) * rg;
  vf = (rg * forward).normalized();
  // Directed random walk (§3).
  if (s.randomWalk > 0.0f) {
    Rng r(RandomKey{pl.seed ^ mix64(settings_.seed), plant_[i], i, step_, kPurposeWalk});
    Vec3 axis = vf.cross(r.unitVector());
    if (axis.squaredNorm() > 1e-8f) rg = axisAngle(axis, s.randomWalk * gdt * r.uniform(-1.0f, 1.0f)) * rg;
  }
  u.growth = turned ? Quat((turn * rg.normalized() * turn.conjugate()).normalized()) : rg.normalized();
}

// Applies an apex's update (eq. 8–10); a full-grown apex spawns its successor, lateral buds
// and a leaf, in wind as Growth-Flow says.
void ParticleWorld::applyApex(uint32_t i, const ApexUpdate& u, const env::Environment& env) {
  Plant& pl = plants_[plant_[i]];
  const ParticleSpecies& s = pl.species;
  if (u.dormant) {
    flags_[i] = (flags_[i] & ~(kApex | plant::kNodeTipEndMask)) | (uint32_t(u.stop) << plant::kNodeTipEndShift);
    return;
  }
  // Eq. 9: R = R R_g, R̄ = R̄ R⁻¹ R_g — the growth rotation enters the current and the rest
  // state alike, keeping the particle's deformation (current relative to rest).
  const Quat deformation = (q_[i] * qr_[i].conjugate()).normalized();
  q_[i] = (u.growth * q_[i]).normalized();
  qr_[i] = (deformation.conjugate() * q_[i]).normalized();
  qp_[i] = q_[i];
  a_[i] = u.halfLength;
  placeOnParent(i);
  updateMass(i);
  if (u.anchor && !(flags_[i] & kAnchored)) {
    flags_[i] |= kAnchored;
    anchorSupport_[i] = u.anchorSupport;
    anchorNormal_[i] = u.anchorNormal;
    placeAnchor(i);
  }
  if (!u.grown) return;

  flags_[i] = (flags_[i] & ~kApex) | kGrown;
  if (pl.particles + particlesPerGrowth(pl) > size_t(std::max(s.maxParticles, 0))) {
    if (!pl.capped)
      log::warn("plant \"{}\" reached max_particles ({}): growth stopped; raise the species' max_particles to "
                "grow further",
                pl.name, s.maxParticles);
    pl.capped = true;
    flags_[i] = (flags_[i] & ~plant::kNodeTipEndMask) | (uint32_t(plant::TipEnd::Capped) << plant::kNodeTipEndShift);
    return;
  }
  // Growth-Flow (seed 001, Algorithm 1): each new internode is one unit of growth time. In a
  // wind above the species' w_min the internodes that grow from this one are shorter (eq. 8)
  // and thicker (eq. 7), bear smaller (eq. 17) and thicker (eq. 16) leaves, and grow along
  // their still-air direction b turned by the whole of eq. 9's angle α_t about b × w (their
  // tropisms keep steering b, see above); leaves are not grown where the wind would tear them
  // off (Algorithm 2). A calm wind changes nothing.
  plant::GrowthFlowStep flow;
  Vec3 windHere = Vec3::Zero();
  if (!env.windField().settings().calm()) {
    windHere = env.wind(head(i), time_);
    flow = plant::growthStep(windHere.norm(), s.growthFlow);
  }
  FlowState grown = flow_[i];
  if (flow.active()) {
    grown.angle = plant::nextGrowthAngle(grown.angle < 0.0f ? s.growthFlow.angle0 : grown.angle, flow);
    grown.length *= flow.length;
    grown.leafSize *= flow.leafRadius;
    grown.leafThickness *= flow.leafThickness;
  }
  // Sets a new internode's Growth-Flow state, length and rest orientation after spawn().
  // The length factor stays with the lineage (a calm unit multiplies it by 1), applied to
  // the species' current length, so live edits of particle_length still take effect.
  auto windGrowth = [&](uint32_t c, const Quat& deformation) {
    if (!flow.active() && grown.length == 1.0f) return;  // never grew in wind: untouched
    flow_[c] = grown;
    const float full = targetHalfLength_[c];  // spawn() set the species' length
    float half = full * grown.length;
    if (flow.active() && s.growthFlow.maxLength > 0.0f) half = std::min(half, 0.5f * s.growthFlow.maxLength);
    targetHalfLength_[c] = half;
    // It starts as the same share of its length as a still-air particle does, and grows in as
    // long (decideApex).
    a_[c] = std::min(a_[c] * (half / std::max(full, 1e-9f)), half);
    if (flow.active()) {
      // The new internode's still-air orientation is its spawned one without the parent's
      // turn; it grows along that turned by the lineage's whole angle α_t (Algorithm 1).
      const Quat still = (flow_[i].turn.conjugate() * q_[c]).normalized();
      const Vec3 b = still * Vec3::UnitY();
      flow_[c].turn = Quat::FromTwoVectors(b, plant::windGrowthDirection(b, windHere, grown.angle)).normalized();
      q_[c] = qp_[c] = (flow_[c].turn * still).normalized();
    }
    qr_[c] = (deformation.conjugate() * q_[c]).normalized();
    groupRotation_[c] = (q_[c] * qr_[c].conjugate()).normalized();
    x_[c] = xp_[c] = head(i) + q_[c] * Vec3(0, a_[c], 0);
    xr_[c] = xr_[i] + qr_[i] * Vec3(0, a_[i], 0) + qr_[c] * Vec3(0, a_[c], 0);
    updateMass(c);
  };
  // The successor continues the branch.
  const uint32_t plantId = plant_[i];
  const Quat deform = (q_[i] * qr_[i].conjugate()).normalized();
  uint32_t next = spawn(plantId, i, q_[i], qr_[i], b_[i] * s.apexTaper * flow.radius, kApex);
  windGrowth(next, deform);
  branchIndex_[next] = branchIndex_[i] + 1;
  // Lateral buds: up to B of them, each with probability BP, turned by up to V · 90°.
  Rng bud(RandomKey{pl.seed ^ mix64(settings_.seed), plantId, i, step_, kPurposeBud});
  for (int b = 0; b < s.maxLateralBuds; ++b) {
    if (!bud.bernoulli(s.branchProbability)) continue;
    const Vec3 forward = q_[i] * Vec3::UnitY();
    Vec3 axis = forward.cross(bud.unitVector());
    if (axis.squaredNorm() < 1e-8f) axis = anyPerpendicular(forward);
    // Half to full V·90°, so that laterals part from the successor.
    const float angle = s.branchVariance * radians(90.0f) * bud.uniform(0.5f, 1.0f);
    const Quat turn = axisAngle(axis, angle);
    const Quat q = (turn * q_[i]).normalized();
    uint32_t lateral = spawn(plantId, i, q, (deform.conjugate() * q).normalized(),
                             b_[i] * s.thicknessFalloff * flow.radius, kApex);
    windGrowth(lateral, deform);
    order_[lateral] = static_cast<uint16_t>(order_[i] + 1);
    branchIndex_[lateral] = 1;
  }
  // Leaves: phyllotaxis angle and step along the branch, a little random jitter, turned
  // toward the light and away from a nearby surface.
  const bool leafTorn = flow.active() && plant::leafDetaches(windHere.norm(), s.growthFlow);
  if (s.leafStep > 0 && s.leafSize > 0.0f && !s.leafShapes.empty() && branchIndex_[i] % uint32_t(s.leafStep) == 0 &&
      !leafTorn) {
    const float leafSize = s.leafSize * flow_[i].leafSize;
    const float leafThickness = s.leafThickness * flow_[i].leafThickness;
    Rng lr(RandomKey{pl.seed ^ mix64(settings_.seed), plantId, i, step_, kPurposeLeaf});
    const float around = float(branchIndex_[i]) * s.phyllotaxisAngle + s.leafJitter * lr.uniform(-1.0f, 1.0f);
    // Particle frame: the blade leaves the stem sideways (+Z turned `around` the stem), upper
    // side up the stem; then it turns toward the preferred normal.
    Quat local = axisAngle(Vec3::UnitY(), around) * axisAngle(Vec3::UnitX(), radians(80.0f));
    Quat world = q_[i] * local;
    if (u.leafOnSupport) {
      // Near a support the blade lies on it, upper side away, as clinging ivy holds its
      // leaves (and as the stand-off pass, models/stand_off.h, lays any blade that enters it).
      world = laidOn(world, u.leafUp);
    } else if (u.leafUp.squaredNorm() > 0.0f) {
      const Vec3 normal = world * Vec3::UnitZ();
      world = turnToward(normal, u.leafUp, s.leafLightTurn * angleBetween(normal, u.leafUp)) * world;
    }
    const uint16_t shape = static_cast<uint16_t>(lr.below(uint32_t(s.leafShapes.size())));
    if (pl.particles < size_t(s.leafParticleLimit)) {
      // Small plants: the leaf is a particle of its own (§4.3), hanging from the stem.
      uint32_t leaf = spawn(plantId, i, world, (deform.conjugate() * world).normalized(),
                            std::max(s.leafThickness * 4.0f, s.minRadius), kLeaf);
      targetHalfLength_[leaf] = 0.5f * leafSize;
      a_[leaf] = 0.05f * leafSize;
      flow_[leaf] = flow_[i];
      leafShape_[leaf] = shape;
      order_[leaf] = order_[i];
      x_[leaf] = xp_[leaf] = head(i) + world * Vec3(0, a_[leaf], 0);
      xr_[leaf] = xr_[i] + qr_[i] * Vec3(0, a_[i], 0) + qr_[leaf] * Vec3(0, a_[leaf], 0);
      updateMass(leaf);
    } else {
      leaves_.push_back({.particle = i,
                         .particleFromLeaf = (q_[i].conjugate() * world).normalized(),
                         .size = 0.05f * leafSize,
                         .maxSize = leafSize,
                         .shape = shape,
                         .thickness = leafThickness});
    }
  }
}

// Eq. 10: x = x_h + R u_f (current), x̄ = x̄_h + R̄ u_f (rest), from the parent's head.
void ParticleWorld::placeOnParent(uint32_t i) {
  const uint32_t p = parent_[i];
  if (p != kNone) {
    x_[i] = head(p) + q_[i] * Vec3(0, a_[i], 0);
    xr_[i] = xr_[p] + qr_[p] * Vec3(0, a_[p], 0) + qr_[i] * Vec3(0, a_[i], 0);
    xp_[i] = x_[i];
  }
}

void ParticleWorld::growLeaves() {
  const float dt = settings_.dt;
  // Leaves grow with their branch (relative to the branch's growth speed).
  for (uint32_t i = 0; i < capacity(); ++i) {
    if (!(flags_[i] & kActive) || !(flags_[i] & kLeaf) || (flags_[i] & kDetached)) continue;
    const ParticleSpecies& s = plants_[plant_[i]].species;
    const float gdt = dt * s.growthSpeed;
    if (a_[i] >= targetHalfLength_[i]) continue;
    const float rate = s.growthRate * targetHalfLength_[i] / std::max(0.5f * s.particleLength, 1e-6f);
    a_[i] = std::min(targetHalfLength_[i], a_[i] + 0.5f * rate * gdt);
    placeOnParent(i);
    updateMass(i);
  }
  for (AttachedLeaf& l : leaves_) {
    const ParticleSpecies& s = plants_[plant_[l.particle]].species;
    if (l.size < l.maxSize)
      l.size = std::min(l.maxSize, l.size + s.growthRate * l.maxSize / std::max(s.particleLength, 1e-6f) * dt * s.growthSpeed);
  }
}

void ParticleWorld::attachLeavesOfLargePlants() {
  // Large plants keep their leaves attached to branch particles instead (§4.3).
  for (uint32_t pid = 0; pid < plants_.size(); ++pid) {
    const ParticleSpecies& s = plants_[pid].species;
    if (plants_[pid].particles < size_t(s.leafParticleLimit)) continue;
    for (uint32_t i = 0; i < capacity(); ++i) {
      if (!(flags_[i] & kActive) || !(flags_[i] & kLeaf) || plant_[i] != pid || parent_[i] == kNone) continue;
      const uint32_t p = parent_[i];
      leaves_.push_back({.particle = p,
                         .particleFromLeaf = (q_[p].conjugate() * q_[i]).normalized(),
                         .size = 2.0f * a_[i],
                         .maxSize = 2.0f * targetHalfLength_[i],
                         .shape = leafShape_[i],
                         .thickness = s.leafThickness * flow_[i].leafThickness});
      release(i);
    }
  }
}

void ParticleWorld::thicken() {
  const float dt = settings_.dt;
  // Secondary growth: older particles thicken toward the pipe-model radius of what they carry.
  const size_t n = capacity();
  std::vector<float>& nextRadius = nextRadius_;
  nextRadius.assign(b_.begin(), b_.end());
  parallelFor(0, n, [&](size_t ii) {
    const uint32_t i = uint32_t(ii);
    if (!(flags_[i] & kActive) || (flags_[i] & (kLeaf | kDetached))) return;
    float carried = 0.0f;
    for (uint32_t c = firstChild_[i]; c != kNone; c = nextSibling_[c])
      if (!(flags_[c] & kLeaf)) carried += b_[c] * b_[c];
    const float pipe = std::sqrt(carried);
    if (pipe <= b_[i]) return;
    const ParticleSpecies& s = plants_[plant_[i]].species;
    nextRadius[i] = b_[i] + std::min(pipe - b_[i], s.secondaryGrowth * dt * s.growthSpeed * b_[i]);
  }, 512);
  for (uint32_t i = 0; i < n; ++i)
    if ((flags_[i] & kActive) && nextRadius[i] != b_[i]) {
      b_[i] = nextRadius[i];
      updateMass(i);
    }
}

}  // namespace tendril::particles
