#include "tendril/wind/motion.h"

#include "tendril/core/parallel.h"
#include "tendril/core/random.h"
#include "tendril/mesh/leaf_mesh.h"

#include <algorithm>
#include <cmath>

namespace tendril::wind {

namespace {

constexpr uint64_t kPhasePurpose = purposeId("wind.sway-phase");
constexpr uint64_t kLeafPurpose = purposeId("wind.leaf-motion");

bool heldBySupport(uint32_t flags) {
  return (flags & (plant::kNodeClimbing | plant::kNodeAnchored)) != 0;
}

}  // namespace

WindMotion::WindMotion(const plant::PlantModel& rest, const GrowthFlowSpecies& species, MotionSettings settings)
    : rest_(rest), species_(species), settings_(settings) {
  const size_t n = rest_.nodeCount();
  stiffness_.resize(n);
  area_.resize(n);
  period_.resize(n);
  phase_.resize(n);
  held_.resize(n);
  centre_.resize(n);
  force_.resize(n);
  angle_.assign(n, 0.0f);
  axis_.assign(n, Vec3::UnitX());
  Q_.assign(n, Quat::Identity());
  T_.assign(n, Vec3::Zero());

  // Leaf areas and the leaves' share of each node's drag and mass.
  const size_t m = rest_.leafCount();
  leaves_.assign(m, LeafMotionState{});
  leafArea_.resize(m);
  std::vector<float> mass(n);
  for (size_t i = 0; i < n; ++i) {
    float r = rest_.radius[i], l = rest_.length[i];
    stiffness_[i] = species_.youngModulus * kPi * r * r * r * r / (4.0f * std::max(l, 1e-4f));
    area_[i] = 2.0f * r * l;
    mass[i] = species_.woodDensity * kPi * r * r * l;
    held_[i] = heldBySupport(rest_.flags[i]);
    centre_[i] = rest_.position[i] + 0.5f * l * rest_.direction(i);
  }
  std::vector<float> leafAreaOfNode(n, 0.0f);
  for (size_t j = 0; j < m; ++j) {
    float aspect = mesh::leafShapeFor(rest_, rest_.leafShape[j]).aspect;
    leafArea_[j] = 0.7f * rest_.leafSize[j] * rest_.leafSize[j] * aspect;  // a leaf fills ~70 % of its quad
    int32_t node = rest_.leafNode[j];
    leafAreaOfNode[size_t(node)] += leafArea_[j];
    mass[size_t(node)] += species_.leafMass;
  }
  // Subtree masses (children after parents, so a reverse pass sums them).
  std::vector<float> carried = mass;
  for (size_t i = n; i-- > 0;)
    if (rest_.parent[i] >= 0) carried[size_t(rest_.parent[i])] += carried[i];

  // Chains: a branch start (or root) and the nodes up to the next branch start share phase and
  // period, set by the chain's base segment: 2π √(I / k), I = m l² / 3 with m all it carries.
  std::vector<int32_t> chain(n);
  for (size_t i = 0; i < n; ++i) {
    int32_t p = rest_.parent[i];
    bool start = p < 0 || (rest_.flags[i] & plant::kNodeBranchStart);
    chain[i] = start ? int32_t(i) : chain[size_t(p)];
  }
  for (size_t i = 0; i < n; ++i) {
    size_t c = size_t(chain[i]);
    float l = std::max(rest_.length[c], 1e-3f);
    float inertia = carried[c] * l * l / 3.0f;
    float period = kTwoPi * std::sqrt(inertia / std::max(stiffness_[c], 1e-12f));
    period = std::clamp(period, 0.4f, 6.0f);  // keep sway visible and calm for extreme species
    if (settings_.loopSeconds > 0.0f) {
      float cycles = std::max(1.0f, std::round(settings_.loopSeconds / period));
      period = settings_.loopSeconds / cycles;
    }
    period_[i] = period;
    phase_[i] = Rng(RandomKey{settings_.seed, 0, c, 0, kPhasePurpose}).uniform(0.0f, kTwoPi);
    area_[i] += leafAreaOfNode[i];
  }
}

void WindMotion::computeSway(float t, const env::WindField& wind) {
  const size_t n = rest_.nodeCount();
  const env::WindSettings& ws = wind.settings();
  const bool loop = settings_.loopSeconds > 0.0f;
  const float half = 0.5f * settings_.airDensity * species_.dragCoefficient;

  // F_w per node from the wind at its centre of gravity. A looping clip uses the steady wind
  // (prevailing + emitters) with gusts that repeat: the gust noise is read on a circle.
  parallelFor(size_t(0), n, [&](size_t i) {
    Vec3 w;
    if (!loop) {
      w = wind.sample(centre_[i], t);
    } else {
      w = ws.velocity;
      for (const env::WindEmitter& e : ws.emitters) w += env::WindField::jet(e, centre_[i]);
      if (ws.mode == env::WindMode::Gusty && ws.velocity.squaredNorm() > 0.0f) {
        float speed = ws.velocity.norm();
        float a = kTwoPi * (t - centre_[i].dot(ws.velocity) / (speed * speed)) / settings_.loopSeconds;
        float radius = settings_.loopSeconds / (kTwoPi * ws.gustPeriod);
        float g = env::WindField::noise(radius * std::cos(a), radius * std::sin(a), ws.seed);
        w *= std::max(0.0f, 1.0f + ws.gustStrength * g);
      }
    }
    Vec3 d = rest_.direction(i);
    Vec3 wPerp = w - w.dot(d) * d;
    float leafA = area_[i] - 2.0f * rest_.radius[i] * rest_.length[i];
    force_[i] = half * (2.0f * rest_.radius[i] * rest_.length[i] * wPerp.norm() * wPerp + leafA * w.norm() * w);
    axis_[i] = w;  // the wind at the node, for the axis below
  });

  // T_r: what the children pass back, as their total force and its moment about this node.
  std::vector<Vec3> moment(n);
  for (size_t i = 0; i < n; ++i) moment[i] = (centre_[i] - rest_.position[i]).cross(force_[i]);
  for (size_t i = n; i-- > 0;) {
    int32_t p = rest_.parent[i];
    if (p < 0) continue;
    size_t q = size_t(p);
    moment[q] += moment[i] + (rest_.position[i] - rest_.position[q]).cross(force_[i]);
    force_[q] += force_[i];
  }

  std::vector<float> toWind(n, 0.0f);
  std::vector<Quat> R(n, Quat::Identity());  // each node's own turn, before the cap below
  // The angle each node turns by: the moment against the segment's spring (eq. 1 balanced by
  // K), eased in and out over the chain's period, toward the wind about u = b × w.
  parallelFor(size_t(0), n, [&](size_t i) {
    Vec3 w = axis_[i];
    float speed = w.norm();
    if (held_[i] || speed <= 0.0f) {
      angle_[i] = 0.0f;
      axis_[i] = Vec3::UnitX();
      return;
    }
    Vec3 d = rest_.direction(i);
    Vec3 u = d.cross(w / speed);
    float s = u.norm();
    if (s < 1e-6f) {
      angle_[i] = 0.0f;
      axis_[i] = Vec3::UnitX();
      return;
    }
    float steady = moment[i].norm() / stiffness_[i];
    float ease = 0.5f * (1.0f - std::cos(kTwoPi * t / period_[i] + phase_[i]));
    angle_[i] = std::min(steady, species_.maxSwayAngle) * ease;
    toWind[i] = std::atan2(s, d.dot(w / speed));  // §3.1.1: acos(b·w / bw)
    axis_[i] = u / s;
    R[i] = Quat(Eigen::AngleAxisf(angle_[i], axis_[i]));
  });

  // Compose parents first: node i's subtree turns about p_i on top of its parent's motion.
  // A node never turns past the wind: the angles along its path are capped by its rest angle
  // to the wind.
  std::vector<float> turned(n, 0.0f);
  for (size_t i = 0; i < n; ++i) {
    int32_t p = rest_.parent[i];
    Quat Qp = p < 0 ? Quat::Identity() : Q_[size_t(p)];
    Vec3 Tp = p < 0 ? Vec3::Zero() : T_[size_t(p)];
    float before = p < 0 ? 0.0f : turned[size_t(p)];
    float a = angle_[i];
    if (a > 0.0f && a > toWind[i] - before) {  // rare: recompute the capped turn
      a = std::max(0.0f, toWind[i] - before);
      angle_[i] = a;
      R[i] = Quat(Eigen::AngleAxisf(a, axis_[i]));
    }
    turned[i] = before + a;
    Q_[i] = (Qp * R[i]).normalized();
    T_[i] = Qp * rest_.position[i] + Tp - Q_[i] * rest_.position[i];
  }
}

void WindMotion::step(float t, float dt, const env::WindField& wind, plant::PlantModel& posed) {
  computeSway(t, wind);
  const size_t n = rest_.nodeCount();

  // Leaves: one motion type and one gust fraction per leaf and frame (Algorithm 2).
  const size_t m = rest_.leafCount();
  const uint32_t frame = frame_;
  parallelFor(size_t(0), m, [&](size_t j) {
    LeafMotionState& L = leaves_[j];
    if (L.detached) return;
    Vec3 at = rest_.leafWorldPosition(j);
    float w = wind.sample(at, t).norm();
    Rng rng(RandomKey{settings_.seed, 0, j, frame, kLeafPurpose});
    int type = int(rng.below(3));
    float gust = settings_.gustMin + (1.0f - settings_.gustMin) * rng.uniform();
    updateLeafMotion(L, type, w, gust, dt, species_);
  });
  ++frame_;

  // The posed plant: nodes moved rigidly with their subtree transforms, leaves carried along.
  posed.name = rest_.name;
  posed.species = rest_.species;
  posed.bark = rest_.bark;
  // Primitive meshes ride on their nodes unchanged: copy them once, not every frame.
  if (posed.meshes.size() != rest_.meshes.size() || posed.primitives.size() != rest_.primitives.size()) {
    posed.meshes = rest_.meshes;
    posed.primitives = rest_.primitives;
  }
  posed.leafShapes = rest_.leafShapes;
  posed.position.resize(n);
  posed.orientation.resize(n);
  posed.length = rest_.length;
  posed.radius = rest_.radius;
  posed.parent = rest_.parent;
  posed.age = rest_.age;
  posed.order = rest_.order;
  posed.flags = rest_.flags;
  parallelFor(size_t(0), n, [&](size_t i) {
    posed.position[i] = Q_[i] * rest_.position[i] + T_[i];
    posed.orientation[i] = (Q_[i] * rest_.orientation[i]).normalized();
  });

  // Leaves still attached, in order, written in parallel.
  std::vector<uint32_t> kept;
  kept.reserve(m);
  for (size_t j = 0; j < m; ++j)
    if (!leaves_[j].detached) kept.push_back(uint32_t(j));
  const size_t k = kept.size();
  posed.leafNode.resize(k);
  posed.leafOffset.resize(k);
  posed.leafRotation.resize(k);
  posed.leafSize.resize(k);
  posed.leafThickness.resize(k);
  posed.leafPetiole.resize(k);
  posed.leafShape.resize(k);
  posed.leafMotion.resize(k);
  parallelFor(size_t(0), k, [&](size_t o) {
    const size_t j = kept[o];
    const LeafMotionState& L = leaves_[j];
    Quat motion = Quat(Eigen::AngleAxisf(L.twist, Vec3::UnitY())) *
                  Quat(Eigen::AngleAxisf(L.petioleBend + L.vibrate, Vec3::UnitX()));
    posed.leafNode[o] = rest_.leafNode[j];
    posed.leafOffset[o] = rest_.leafOffset[j];
    posed.leafRotation[o] = (rest_.leafRotation[j] * motion).normalized();
    posed.leafSize[o] = rest_.leafSize[j];
    posed.leafThickness[o] = rest_.leafThickness[j];
    posed.leafPetiole[o] = rest_.leafPetiole[j];
    posed.leafShape[o] = rest_.leafShape[j];
    posed.leafMotion[o] = Vec3(L.bladeBend, L.twist, L.vibrate);
  }, 1024);
}

}  // namespace tendril::wind
