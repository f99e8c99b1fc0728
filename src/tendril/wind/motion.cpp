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

// atan2(y, x) for y ≥ 0 to about 1e-5 rad (a minimax polynomial for atan on [0, 1]), for the
// sway cap below: a tenth of the cost of the library's, the same on every machine.
float atan2Upper(float y, float x) {
  const float ax = std::fabs(x);
  const float big = std::max(ax, y), small = std::min(ax, y);
  if (!(big > 0.0f)) return 0.0f;
  const float z = small / big, z2 = z * z;
  float a = z * (0.99997726f + z2 * (-0.33262347f + z2 * (0.19354346f + z2 * (-0.11643287f + z2 * (0.05265332f + z2 * -0.01172120f)))));
  if (y > ax) a = 0.5f * kPi - a;
  return x < 0.0f ? kPi - a : a;
}

// The rotation by `angle` about unit `axis`; sway angles are small, so their half-angle sine
// and cosine come from short series (error < 1e-8 below 0.5 rad), the library beyond.
inline Quat swayRotation(float angle, const Vec3& axis) {
  const float h = 0.5f * angle;
  float c, s;
  if (std::fabs(h) < 0.5f) {
    const float h2 = h * h;
    s = h * (1.0f + h2 * (-1.0f / 6.0f + h2 * (1.0f / 120.0f + h2 * (-1.0f / 5040.0f))));
    c = 1.0f + h2 * (-0.5f + h2 * (1.0f / 24.0f + h2 * (-1.0f / 720.0f + h2 * (1.0f / 40320.0f))));
  } else {
    s = std::sin(h);
    c = std::cos(h);
  }
  return Quat(c, s * axis.x(), s * axis.y(), s * axis.z());
}

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
  direction_.resize(n);
  posed_.resize(n);
  force_.resize(n);
  angle_.assign(n, 0.0f);
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
    direction_[i] = rest_.direction(i);
    centre_[i] = rest_.position[i] + 0.5f * l * direction_[i];
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
  chainOf_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    if (chain[i] == int32_t(i)) chainStart_.push_back(uint32_t(i));
    chainOf_[i] = chain[i] == int32_t(i) ? uint32_t(chainStart_.size() - 1) : chainOf_[size_t(chain[i])];
  }
  ease_.resize(chainStart_.size());
  wind_.resize(n);
  moment_.resize(n);
  turned_.resize(n);
  leafKey_.resize(m);
  for (size_t j = 0; j < m; ++j) leafKey_[j] = Rng(RandomKey{settings_.seed, 0, j, 0, kLeafPurpose}).key();

  // Split the tree: a task is a subtree of at most `limit` nodes whose parent's subtree is
  // larger; what is left is the top part (closed under parents).
  std::vector<uint32_t> size(n, 1);
  for (size_t i = n; i-- > 0;)
    if (rest_.parent[i] >= 0) size[size_t(rest_.parent[i])] += size[i];
  const uint32_t limit = uint32_t(std::max<size_t>(1024, n / 64));
  std::vector<int32_t> taskOf(n, -1);
  std::vector<uint32_t> roots;
  for (size_t i = 0; i < n; ++i) {
    const int32_t p = rest_.parent[i];
    if (p >= 0 && taskOf[size_t(p)] >= 0) {
      taskOf[i] = taskOf[size_t(p)];
    } else if (size[i] <= limit) {
      taskOf[i] = int32_t(roots.size());
      roots.push_back(uint32_t(i));
    }
  }
  std::vector<uint32_t> count(roots.size() + 1, 0);
  for (size_t i = 0; i < n; ++i) {
    if (taskOf[i] >= 0) ++count[size_t(taskOf[i]) + 1];
    else topNodes_.push_back(uint32_t(i));
    if (taskOf[i] < 0 || roots[size_t(taskOf[i])] == i) mergeNodes_.push_back(uint32_t(i));
  }
  for (size_t k = 1; k < count.size(); ++k) count[k] += count[k - 1];
  taskStart_ = count;
  taskNodes_.resize(count.back());
  for (size_t i = 0; i < n; ++i)
    if (taskOf[i] >= 0) taskNodes_[count[size_t(taskOf[i])]++] = uint32_t(i);
}

void WindMotion::computeSway(float t, const env::WindField& wind) {
  const size_t n = rest_.nodeCount();
  const env::WindSettings& ws = wind.settings();
  const bool loop = settings_.loopSeconds > 0.0f;
  const float half = 0.5f * settings_.airDensity * species_.dragCoefficient;

  // F_w per node from the wind at its centre of gravity, and its moment about the node. A
  // looping clip uses the steady wind (prevailing + emitters) with gusts that repeat: the gust
  // noise is read on a circle.
  // A constant wind without emitters is the same everywhere: no need to ask the field.
  const bool uniform = !loop && ws.mode == env::WindMode::Constant && ws.emitters.empty();
  parallelFor(size_t(0), n, [&](size_t i) {
    Vec3 w;
    if (uniform) {
      w = ws.velocity;
    } else if (!loop) {
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
    const Vec3& d = direction_[i];
    Vec3 wPerp = w - w.dot(d) * d;
    float leafA = area_[i] - 2.0f * rest_.radius[i] * rest_.length[i];
    force_[i] = half * (2.0f * rest_.radius[i] * rest_.length[i] * wPerp.norm() * wPerp + leafA * w.norm() * w);
    moment_[i] = (centre_[i] - rest_.position[i]).cross(force_[i]);
    wind_[i] = w;
  }, 256);
  // The sinusoidal ease of each chain (§3.1.1): θ = θ* (1 − cos φ) / 2.
  parallelFor(size_t(0), chainStart_.size(), [&](size_t c) {
    const size_t i = chainStart_[c];
    ease_[c] = 0.5f * (1.0f - std::cos(kTwoPi * t / period_[i] + phase_[i]));
  }, 1024);

  // T_r: what the children pass back, as their total force and its moment about this node;
  // children in decreasing index order, within tasks in parallel, then the top part.
  auto passBack = [&](size_t i) {
    const size_t q = size_t(rest_.parent[i]);
    moment_[q] += moment_[i] + (rest_.position[i] - rest_.position[q]).cross(force_[i]);
    force_[q] += force_[i];
  };
  parallelFor(size_t(0), taskStart_.size() - 1, [&](size_t k) {
    for (size_t e = taskStart_[k + 1]; e-- > size_t(taskStart_[k]) + 1;) passBack(taskNodes_[e]);
  }, 1);
  for (size_t e = mergeNodes_.size(); e-- > 0;)
    if (rest_.parent[mergeNodes_[e]] >= 0) passBack(mergeNodes_[e]);

  // Compose parents first: node i's subtree turns about p_i on top of its parent's motion, by
  // the angle of the moment against the segment's spring (eq. 1 balanced by K), eased in and
  // out over the chain's period, toward the wind about u = b × w. A node never turns past the
  // wind: the angles along its path are capped by its rest angle to the wind.
  auto compose = [&](size_t i) {
    const int32_t p = rest_.parent[i];
    const Quat Qp = p < 0 ? Quat::Identity() : Q_[size_t(p)];
    const Vec3 Tp = p < 0 ? Vec3::Zero() : T_[size_t(p)];
    const float before = p < 0 ? 0.0f : turned_[size_t(p)];
    float a = 0.0f;
    Vec3 axis = Vec3::UnitX();
    const Vec3& w = wind_[i];
    const float speed = w.norm();
    if (!held_[i] && speed > 0.0f) {
      const Vec3& d = direction_[i];
      const Vec3 wHat = w * (1.0f / speed);
      const Vec3 u = d.cross(wHat);
      const float s = u.norm();
      if (s >= 1e-6f) {
        const float steady = moment_[i].norm() / stiffness_[i];
        a = std::min(steady, species_.maxSwayAngle) * ease_[chainOf_[i]];
        axis = u * (1.0f / s);
        // §3.1.1's angle to the wind, acos(b·w / bw), is at least its sine s: only a path
        // turned further needs it exactly.
        if (a > 0.0f && before + a > s) {
          const float toWind = atan2Upper(s, d.dot(wHat));
          if (a > toWind - before) a = std::max(0.0f, toWind - before);
        }
      }
    }
    angle_[i] = a;
    turned_[i] = before + a;
    Q_[i] = a > 0.0f ? (Qp * swayRotation(a, axis)).normalized() : Qp;
    posed_[i] = Qp * rest_.position[i] + Tp;  // the node turns about its own base
    T_[i] = posed_[i] - Q_[i] * rest_.position[i];
  };
  for (uint32_t i : topNodes_) compose(i);
  parallelFor(size_t(0), taskStart_.size() - 1, [&](size_t k) {
    for (size_t e = taskStart_[k]; e < taskStart_[k + 1]; ++e) compose(taskNodes_[e]);
  }, 1);
}

void WindMotion::step(float t, float dt, const env::WindField& wind, plant::PlantModel& posed) {
  computeSway(t, wind);
  const size_t n = rest_.nodeCount();

  // Leaves: one motion type and one gust fraction per leaf and frame (Algorithm 2), in the wind
  // of the node they hang on (gusts vary over metres, a leaf is centimetres from its node).
  const size_t m = rest_.leafCount();
  const uint32_t frame = frame_;
  parallelFor(size_t(0), m, [&](size_t j) {
    LeafMotionState& L = leaves_[j];
    if (L.detached) return;
    float w = wind_[size_t(rest_.leafNode[j])].norm();
    Rng rng(mix64(leafKey_[j] ^ (uint64_t(frame) * 0x9e3779b97f4a7c15ull)));
    int type = int(rng.below(3));
    float gust = settings_.gustMin + (1.0f - settings_.gustMin) * rng.uniform();
    updateLeafMotion(L, type, w, gust, dt, species_);
  }, 1024);
  ++frame_;

  // The posed plant: nodes moved rigidly with their subtree transforms, leaves carried along.
  // What does not move is copied into a new `posed` only.
  const bool fresh = posedFor_ != &posed || posed.nodeCount() != n;
  posedFor_ = &posed;
  if (fresh) {
    posed.name = rest_.name;
    posed.species = rest_.species;
    posed.bark = rest_.bark;
    posed.meshes = rest_.meshes;
    posed.primitives = rest_.primitives;
    posed.leafShapes = rest_.leafShapes;
    posed.position.resize(n);
    posed.orientation.resize(n);
    posed.length = rest_.length;
    posed.radius = rest_.radius;
    posed.parent = rest_.parent;
    posed.age = rest_.age;
    posed.order = rest_.order;
    posed.flags = rest_.flags;
  }
  parallelFor(size_t(0), n, [&](size_t i) {
    posed.position[i] = posed_[i];
    posed.orientation[i] = (Q_[i] * rest_.orientation[i]).normalized();
  }, 1024);

  // Leaves still attached, in order, written in parallel; their fixed fields only when the set
  // changed.
  const size_t before = kept_.size();
  kept_.clear();
  for (size_t j = 0; j < m; ++j)
    if (!leaves_[j].detached) kept_.push_back(uint32_t(j));
  const size_t k = kept_.size();
  const bool leavesChanged = fresh || k != before || posed.leafNode.size() != k;
  if (leavesChanged) {
    posed.leafNode.resize(k);
    posed.leafOffset.resize(k);
    posed.leafSize.resize(k);
    posed.leafThickness.resize(k);
    posed.leafPetiole.resize(k);
    posed.leafShape.resize(k);
  }
  posed.leafRotation.resize(k);
  posed.leafMotion.resize(k);
  parallelFor(size_t(0), k, [&](size_t o) {
    const size_t j = kept_[o];
    const LeafMotionState& L = leaves_[j];
    const Quat motion = swayRotation(L.twist, Vec3::UnitY()) * swayRotation(L.petioleBend + L.vibrate, Vec3::UnitX());
    posed.leafRotation[o] = (rest_.leafRotation[j] * motion).normalized();
    posed.leafMotion[o] = Vec3(L.bladeBend, L.twist, L.vibrate);
    if (leavesChanged) {
      posed.leafNode[o] = rest_.leafNode[j];
      posed.leafOffset[o] = rest_.leafOffset[j];
      posed.leafSize[o] = rest_.leafSize[j];
      posed.leafThickness[o] = rest_.leafThickness[j];
      posed.leafPetiole[o] = rest_.leafPetiole[j];
      posed.leafShape[o] = rest_.leafShape[j];
    }
  }, 1024);
}

}  // namespace tendril::wind
