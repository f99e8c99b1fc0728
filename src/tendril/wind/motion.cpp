#include "tendril/wind/motion.h"

#include "tendril/core/parallel.h"
#include "tendril/core/random.h"
#include "tendril/mesh/leaf_mesh.h"
#include "tendril/core/match_lanes.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>

namespace tendril::wind {

namespace {

constexpr uint64_t kLeafPurpose = purposeId("wind.leaf-motion");

// Four nodes per pass of the drag (false: one at a time, for the tests).
std::atomic<bool> gLanes{true};

inline lanes::F4 load(const float* p) {
  lanes::F4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

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
// and cosine mostly come from sinCos's short series.
inline Quat swayRotation(float angle, const Vec3& axis) {
  float c, s;
  sinCos(0.5f * angle, &s, &c);
  return Quat(c, s * axis.x(), s * axis.y(), s * axis.z());
}

// q scaled to unit length, for q a product of unit quaternions: |q|² = 1 + ε with ε of float
// round-off, where one Newton step for 1 / √(1 + ε), 1 − ε / 2, is as good as a square root and
// a division and much shorter (composing is a chain of these from root to tip).
inline Quat renormalized(const Quat& q) {
  const float n2 = q.squaredNorm();
  if (!(std::fabs(n2 - 1.0f) < 1e-4f)) return q.normalized();
  return Quat(q.coeffs() * (1.5f - 0.5f * n2));
}

// A leaf's posed rotation: its rest rotation · R_Y(ψ) · R_X(θ + φ), the last product written
// out for the two axes. `rest` is of unit length, so the product is too (to float round-off,
// as a normalised one).
inline Quat posedLeafRotation(const Quat& rest, const plant::LeafMotionState& L) {
  const Quat y = swayRotation(L.twist, Vec3::UnitY());
  const Quat x = swayRotation(L.petioleBend + L.vibrate, Vec3::UnitX());
  return rest * Quat(y.w() * x.w(), y.w() * x.x(), y.y() * x.w(), -(y.y() * x.x()));
}

inline Vec3 leafMotionOf(const plant::LeafMotionState& L) { return Vec3(L.bladeBend, L.twist, L.vibrate); }

bool heldBySupport(uint32_t flags) {
  return (flags & (plant::kNodeClimbing | plant::kNodeAnchored)) != 0;
}

}  // namespace

namespace detail {
void setDragLanes(bool on) { gLanes.store(on, std::memory_order_relaxed); }
}  // namespace detail

void poseLeaf(const Quat& restRotation, const plant::LeafMotionState& leaf, Quat& rotation, Vec3& motion) {
  rotation = posedLeafRotation(restRotation, leaf);
  motion = leafMotionOf(leaf);
}

float triangleWave(float x) {
  const float f = x - std::floor(x);  // [0, 1)
  if (f < 0.25f) return 4.0f * f;
  if (f < 0.75f) return 2.0f - 4.0f * f;
  return 4.0f * f - 4.0f;
}

float LeafLoop::wave(int kind, int phase, float t, float loopSeconds) const {
  // Whole cycles per loop: t / loopSeconds · cycles, reduced first so that t = loopSeconds
  // gives the same value as t = 0 exactly.
  const float u = t / loopSeconds;
  const float cyclesDone = (u - std::floor(u)) * float(cycles[kind]);
  return triangleWave(cyclesDone + float(phase) / float(kPhases));
}

plant::LeafMotionState LeafLoop::state(size_t leaf, float t, float loopSeconds) const {
  plant::LeafMotionState L;
  const Leaf& f = leaves[leaf];
  if (f.torn) {
    L.detached = true;
    return L;
  }
  float a[3];
  for (int k = 0; k < 3; ++k) a[k] = f.amplitude[k] > 0.0f ? f.amplitude[k] * wave(k, f.phase[k], t, loopSeconds) : 0.0f;
  (bendsBlade ? L.bladeBend : L.petioleBend) = a[0];
  L.twist = a[1];
  L.vibrate = a[2];
  return L;
}

WindMotion::WindMotion(const plant::PlantModel& rest, const plant::GrowthFlowSpecies& species, MotionSettings settings)
    : rest_(rest), species_(species), settings_(settings) {
  const size_t n = rest_.nodeCount();
  nodes_.resize(n);
  stiffness_.resize(n);
  inertia_.resize(n);
  damping_.resize(n);
  std::vector<float> area(n);
  std::vector<uint8_t> held(n);
  std::vector<Vec3> direction(n);
  centre_.resize(n);
  force_.resize(n);
  moment_.resize(n);
  torque_.assign(n, Vec3::Zero());
  sway_.assign((n + 3) / 4, SwayBlock{});
  swayAxisAngle_.assign(n, AxisAngle{Vec3::UnitX(), 0.0f});
  speed_.resize(n);
  windAt_.assign(n, Vec3::Zero());
  angle_.assign(n, 0.0f);
  Q_.assign(n, Quat::Identity());
  pose_.resize(n);

  // Leaf areas and the leaves' share of each node's drag and mass.
  const size_t m = rest_.leafCount();
  leaves_.assign(m, plant::LeafMotionState{});
  std::vector<float> mass(n);
  for (size_t i = 0; i < n; ++i) {
    float r = rest_.radius[i], l = rest_.length[i];
    stiffness_[i] = species_.youngModulus * kPi * r * r * r * r / (4.0f * std::max(l, 1e-4f));
    area[i] = 2.0f * r * l;
    mass[i] = species_.woodDensity * kPi * r * r * l;
    held[i] = heldBySupport(rest_.flags[i]);
    direction[i] = rest_.direction(i);
    centre_[i] = rest_.position[i] + 0.5f * l * direction[i];
    pose_[i] = Pose{rest_.position[i], 0.0f};
  }
  std::vector<float> leafAreaOfNode(n, 0.0f);
  for (size_t j = 0; j < m; ++j) {
    float aspect = rest_.leafAspect(j);
    float area = 0.7f * rest_.leafSize[j] * rest_.leafSize[j] * aspect;  // a leaf fills ~70 % of its quad
    int32_t node = rest_.leafNode[j];
    leafAreaOfNode[size_t(node)] += area;
    mass[size_t(node)] += species_.leafMass;
  }
  for (size_t i = 0; i < n; ++i) area[i] += leafAreaOfNode[i];
  // Moments of inertia about each node of all it carries: its own segment (m l² / 3 about its
  // end) and, as point masses at their centres of gravity, every node further out. Sums over a
  // subtree of m, m c and m |c|² (children after parents, so a reverse pass adds them up), in
  // double: Σ m |c − p|² = Σ m |c|² − 2 p · Σ m c + |p|² Σ m.
  std::vector<double> m0(n, 0.0), m2(n, 0.0);
  std::vector<Eigen::Vector3d> m1(n, Eigen::Vector3d::Zero());
  for (size_t i = n; i-- > 0;) {
    const int32_t q = rest_.parent[i];
    if (q < 0) continue;
    const Eigen::Vector3d c = centre_[i].cast<double>();
    m0[size_t(q)] += m0[i] + mass[i];
    m1[size_t(q)] += m1[i] + double(mass[i]) * c;
    m2[size_t(q)] += m2[i] + double(mass[i]) * c.squaredNorm();
  }
  const float zeta = std::clamp(species_.swayDamping, 0.01f, 0.95f);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p = rest_.position[i].cast<double>();
    const double l = rest_.length[i];
    const double own = double(mass[i]) * l * l / 3.0;
    const double carried = std::max(0.0, m2[i] - 2.0 * p.dot(m1[i]) + p.squaredNorm() * m0[i]);
    const double k = std::max(double(stiffness_[i]), 1e-12);
    // The natural period 2π √(I / k) within its limits (I scaled; θ* = τ / k is not).
    const double lo = k * std::pow(kMinSwayPeriod / kTwoPi, 2), hi = k * std::pow(kMaxSwayPeriod / kTwoPi, 2);
    const double I = std::clamp(own + carried, lo, hi);
    inertia_[i] = float(I);
    damping_[i] = float(2.0 * zeta * std::sqrt(k * I));
  }
  for (size_t i = 0; i < n; ++i) {
    const int32_t p = rest_.parent[i];
    SwayNode& r = nodes_[i];
    r.restOrientation = rest_.orientation[i].normalized();
    r.parent = p;
    r.offset = p < 0 ? rest_.position[i] : Vec3(rest_.position[i] - rest_.position[size_t(p)]);
    r.axis = Vec3::UnitX();
    r.sinToWind = 0.0f;
    r.cosToWind = 1.0f;
  }
  held_ = held;
  leafKey_.resize(m);
  leafRest_.resize(m);
  for (size_t j = 0; j < m; ++j) leafRest_[j] = rest_.leafRotation[j].normalized();
  leafNormal_.resize(m);
  for (size_t j = 0; j < m; ++j) leafNormal_[j] = (rest_.leafWorldRotation(j) * Vec3::UnitZ()).normalized();
  for (size_t j = 0; j < m; ++j) leafKey_[j] = Rng(RandomKey{settings_.seed, 0, j, 0, kLeafPurpose}).key();
  slot_.assign(m, 0);

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
  std::vector<uint32_t> topNodes, taskNodes;  // ascending within the top part and within each task
  std::vector<uint32_t> count(roots.size() + 1, 0);
  for (size_t i = 0; i < n; ++i) {
    if (taskOf[i] >= 0) ++count[size_t(taskOf[i]) + 1];
    else topNodes.push_back(uint32_t(i));
    if (taskOf[i] < 0 || roots[size_t(taskOf[i])] == i) mergeNodes_.push_back(uint32_t(i));
  }
  for (size_t k = 1; k < count.size(); ++k) count[k] += count[k - 1];
  taskStart_ = count;
  taskNodes.resize(count.back());
  for (size_t i = 0; i < n; ++i)
    if (taskOf[i] >= 0) taskNodes[count[size_t(taskOf[i])]++] = uint32_t(i);

  // Internally the nodes are kept in the order the passes visit them: the top part, then task
  // after task (each in index order), so that a task's nodes lie together in memory. Every sum
  // is still taken in the same order, so the results are those of the plant's own numbering.
  order_ = topNodes;
  order_.insert(order_.end(), taskNodes.begin(), taskNodes.end());
  internal_.resize(n);
  for (size_t k = 0; k < n; ++k) internal_[order_[k]] = uint32_t(k);
  auto permute = [&](auto& v) {
    const auto byIndex = v;
    for (size_t k = 0; k < n; ++k) v[k] = byIndex[order_[k]];
  };
  permute(nodes_);
  for (SwayNode& r : nodes_)
    if (r.parent >= 0) r.parent = int32_t(internal_[size_t(r.parent)]);
  permute(stiffness_);
  permute(inertia_);
  permute(damping_);
  permute(held_);
  permute(centre_);
  permute(windAt_);
  permute(pose_);
  for (uint32_t& i : mergeNodes_) i = internal_[i];
  topCount_ = topNodes.size();
  leafNode_.resize(m);
  for (size_t j = 0; j < m; ++j) leafNode_[j] = internal_[size_t(rest_.leafNode[j])];

  // The drag's inputs per four nodes, one per lane (the lanes past the last node zero).
  dragBlocks_.assign((n + 3) / 4, DragBlock{});
  for (size_t k = 0; k < n; ++k) {
    DragBlock& B = dragBlocks_[k / 4];
    const size_t l = k % 4, i = order_[k];
    const float stemA = 2.0f * rest_.radius[i] * rest_.length[i];
    const Vec3 lever = centre_[k] - rest_.position[i];
    B.direction.x[l] = direction[i].x(), B.direction.y[l] = direction[i].y(), B.direction.z[l] = direction[i].z();
    B.lever.x[l] = lever.x(), B.lever.y[l] = lever.y(), B.lever.z[l] = lever.z();
    B.stemArea[l] = stemA;
    B.leafArea[l] = area[i] - stemA;
    B.free[l] = held[i] ? 0 : -1;
  }
}

void WindMotion::setRest(const plant::PlantModel& rest) {
  const uint32_t frame = frame_;
  std::vector<plant::LeafMotionState> leaves = std::move(leaves_);
  // The sway state by the plant's node index.
  const size_t before = nodes_.size();
  std::vector<Vec3> theta(before), omega(before);
  for (size_t i = 0; i < before; ++i) theta[i] = swayVector(i), omega[i] = swayVelocity(i);
  *this = WindMotion(rest, species_, settings_);
  frame_ = frame;
  for (size_t j = 0; j < leaves.size() && j < leaves_.size(); ++j) leaves_[j] = leaves[j];
  for (size_t i = 0; i < before && i < nodes_.size(); ++i) {
    const size_t k = internal_[i];
    if (held_[k]) continue;
    SwayBlock& B = sway_[k / 4];
    const size_t l = k % 4;
    B.theta.x[l] = theta[i].x(), B.theta.y[l] = theta[i].y(), B.theta.z[l] = theta[i].z();
    B.omega.x[l] = omega[i].x(), B.omega.y[l] = omega[i].y(), B.omega.z[l] = omega[i].z();
  }
}

Vec3 WindMotion::swayVector(size_t i) const {
  const size_t k = internal_[i];
  const SwayBlock& B = sway_[k / 4];
  return Vec3(B.theta.x[k % 4], B.theta.y[k % 4], B.theta.z[k % 4]);
}

Vec3 WindMotion::swayVelocity(size_t i) const {
  const size_t k = internal_[i];
  const SwayBlock& B = sway_[k / 4];
  return Vec3(B.omega.x[k % 4], B.omega.y[k % 4], B.omega.z[k % 4]);
}

std::vector<Vec3> WindMotion::nodeTranslation() const {
  std::vector<Vec3> T(pose_.size());
  for (size_t i = 0; i < T.size(); ++i) T[i] = pose_[internal_[i]].position - Q_[internal_[i]] * rest_.position[i];
  return T;
}

void WindMotion::computeTorques(float t, const env::WindField& wind) {
  const size_t n = rest_.nodeCount();
  const env::WindSettings& ws = wind.settings();
  const bool loop = settings_.loopSeconds > 0.0f;
  const float half = 0.5f * settings_.airDensity * species_.dragCoefficient;

  // A constant wind without emitters is the same everywhere: no need to ask the field, and
  // while it stays the same, neither torques nor steady angles change from frame to frame.
  const bool uniform = !loop && ws.mode == env::WindMode::Constant && ws.emitters.empty();
  if (uniform && uniformCached_ && ws.velocity == uniformWind_) return;

  // The gusts at the nodes' centres of gravity come from a sampler kept with the rest plant
  // (the same numbers as wind.sample, without hashing the noise per node).
  const bool simulated = ws.mode == env::WindMode::Sph;
  if (!uniform && !loop && !simulated) {
    if (!gusts_.preparedFor(wind, n)) gusts_.prepare(wind, centre_.data(), n);
    gusts_.beginFrame(t);
  }

  // F_w per node from the wind at its centre of gravity, and its moment about the node; the
  // node's sway axis u = b × w and its angle to the wind. A looping clip uses the steady wind
  // (prevailing + emitters) with gusts that repeat: the gust noise is read on a circle.
  auto windAt = [&](size_t i) {
    Vec3 w;
    if (uniform) {
      w = ws.velocity;
    } else if (simulated) {
      w = wind.sample(centre_[i], t);
    } else if (!loop) {
      w = gusts_.ambient(i);  // wind.sample: the ambient wind and the emitters' jets
      for (const env::WindEmitter& e : ws.emitters) w += env::WindField::jet(e, centre_[i]);
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
    return w;
  };
  auto dragOne = [&](size_t i, const Vec3& w) {
    const DragBlock& B = dragBlocks_[i / 4];
    const size_t l = i % 4;
    const Vec3 d(B.direction.x[l], B.direction.y[l], B.direction.z[l]);
    const Vec3 lever(B.lever.x[l], B.lever.y[l], B.lever.z[l]);
    const float along = w.dot(d), speed = w.norm();
    const Vec3 wPerp = w - along * d;
    const float stemA = B.stemArea[l], leafA = B.leafArea[l];
    force_[i] = half * (stemA * wPerp.norm() * wPerp + leafA * speed * w);
    moment_[i] = lever.cross(force_[i]);
    speed_[i] = speed;
    windAt_[i] = w;
    SwayNode& r = nodes_[i];
    r.axis = Vec3::UnitX();
    r.sinToWind = 0.0f;  // below the threshold: does not sway
    r.cosToWind = 1.0f;
    if (B.free[l] != 0 && speed > 0.0f) {
      // u = b × ŵ: |b × w| / |w| is the sine of the angle to the wind, b · w / |w| its cosine.
      const Vec3 u = d.cross(w);
      const float un = u.norm(), invSpeed = 1.0f / speed, s = un * invSpeed;
      if (s >= 1e-6f) {
        r.axis = u * (1.0f / un);
        r.sinToWind = s;
        r.cosToWind = along * invSpeed;
      }
    }
  };
  // Four nodes at a time, one per lane, the same steps as dragOne (the same bits); the nodes
  // past the last whole four one at a time.
  const size_t blocks = gLanes.load(std::memory_order_relaxed) ? n / 4 : 0;
  const bool tabled = !uniform && !simulated && !loop && ws.emitters.empty() && gusts_.tabled();
  parallelFor(size_t(0), blocks, [&](size_t b) {
    using namespace lanes;
    const size_t i = 4 * b;
    alignas(16) float x[4], y[4], z[4];
    if (tabled) {
      gusts_.ambient4(i, x, y, z);
    } else {
      for (size_t l = 0; l < 4; ++l) {
        const Vec3 w = windAt(i + l);
        x[l] = w.x(), y[l] = w.y(), z[l] = w.z();
      }
    }
    const DragBlock& B = dragBlocks_[b];
    const V3 w{load(x), load(y), load(z)};
    const F4 along = dot(w, B.direction), speed = sqrt4(dot(w, w));
    const V3 wPerp = w - along * B.direction;
    const F4 stem = B.stemArea * sqrt4(dot(wPerp, wPerp)), leaf = B.leafArea * speed;
    const V3 drag = stem * wPerp + leaf * w;
    const V3 force = splat(half) * drag;
    const V3 moment = cross(B.lever, force);
    const V3 u = cross(B.direction, w);
    const F4 un = sqrt4(dot(u, u)), invSpeed = 1.0f / speed, s = un * invSpeed;
    const M4 sways = B.free & (speed > 0.0f) & (s >= 1e-6f);
    const V3 axis = select(sways, (1.0f / un) * u, V3{splat(1.0f), splat(0.0f), splat(0.0f)});
    const F4 sinToWind = sways ? s : splat(0.0f), cosToWind = sways ? along * invSpeed : splat(1.0f);
    for (int l = 0; l < 4; ++l) {
      force_[i + size_t(l)] = Vec3(force.x[l], force.y[l], force.z[l]);
      moment_[i + size_t(l)] = Vec3(moment.x[l], moment.y[l], moment.z[l]);
      speed_[i + size_t(l)] = speed[l];
      windAt_[i + size_t(l)] = Vec3(w.x[l], w.y[l], w.z[l]);
      SwayNode& r = nodes_[i + size_t(l)];
      r.axis = Vec3(axis.x[l], axis.y[l], axis.z[l]);
      r.sinToWind = sinToWind[l];
      r.cosToWind = cosToWind[l];
    }
  }, 64);
  for (size_t i = 4 * blocks; i < n; ++i) dragOne(i, windAt(i));

  // T_r: what the children pass back, as their total force and its moment about this node;
  // children in decreasing index order, within tasks in parallel, then the top part.
  auto passBack = [&](size_t i) {
    const SwayNode& r = nodes_[i];
    const size_t q = size_t(r.parent);
    moment_[q] += moment_[i] + r.offset.cross(force_[i]);
    force_[q] += force_[i];
  };
  const size_t top = topCount_;
  parallelFor(size_t(0), taskStart_.size() - 1, [&](size_t k) {
    for (size_t i = top + taskStart_[k + 1]; i-- > top + taskStart_[k] + 1;) passBack(i);
  }, 1);
  for (size_t e = mergeNodes_.size(); e-- > 0;)
    if (nodes_[mergeNodes_[e]].parent >= 0) passBack(mergeNodes_[e]);

  // The torque τ, the moment less its twist about b (which turns a segment about itself, not
  // its subtree), and the rotation θ* = τ / k it balances against the segment's spring.
  parallelFor(size_t(0), n, [&](size_t i) {
    SwayBlock& S = sway_[i / 4];
    const size_t lane = i % 4;
    if (held_[i]) {
      torque_[i] = Vec3::Zero();
      S.target.x[lane] = S.target.y[lane] = S.target.z[lane] = 0.0f;
      return;
    }
    const DragBlock& B = dragBlocks_[i / 4];
    const size_t l = i % 4;
    const Vec3 d(B.direction.x[l], B.direction.y[l], B.direction.z[l]);
    const Vec3 tau = moment_[i] - moment_[i].dot(d) * d;
    torque_[i] = tau;
    const Vec3 target = tau * (1.0f / stiffness_[i]);
    S.target.x[lane] = target.x(), S.target.y[lane] = target.y(), S.target.z[lane] = target.z();
  }, 1024);
  uniformCached_ = uniform;
  uniformWind_ = ws.velocity;
}

void WindMotion::prepareSteps(float dt) {
  if (dt == stepDt_) return;
  // The damped oscillator over dt in closed form (ζ < 1): with ω_n = √(k / I), σ = ζ ω_n,
  // ω_d = ω_n √(1 − ζ²), e = exp(−σ dt), C = cos ω_d dt, S = sin ω_d dt:
  //   y(dt)  = e (y (C + σ/ω_d S) + y' S / ω_d)
  //   y'(dt) = e (y' (C − σ/ω_d S) − y ω_n²/ω_d S).
  const size_t n = nodes_.size();
  parallelFor(size_t(0), n, [&](size_t i) {
    const double k = std::max(double(stiffness_[i]), 1e-12), I = inertia_[i];
    const double wn = std::sqrt(k / I), sigma = double(damping_[i]) / (2.0 * I);
    const double wd = std::sqrt(std::max(wn * wn - sigma * sigma, 1e-12 * wn * wn));
    const double e = std::exp(-sigma * double(dt)), C = std::cos(wd * double(dt)), S = std::sin(wd * double(dt));
    SwayBlock& B = sway_[i / 4];
    const size_t l = i % 4;
    B.a[l] = float(e * (C + sigma / wd * S));
    B.b[l] = float(e * S / wd);
    B.c[l] = float(-e * wn * wn / wd * S);
    B.d[l] = float(e * (C - sigma / wd * S));
  }, 1024);
  stepDt_ = dt;
}

void WindMotion::prepareSwayLoop(const env::WindField& wind) {
  // The torque over one loop, sampled kLoopSamples times, as a Fourier series; harmonic h of
  // the torque, A cos ω t + B sin ω t (ω = 2π h / L), moves the node by the oscillator's answer
  // Re[H(ω) (A − iB) e^{iωt}], H(ω) = 1 / (k − I ω² + i c ω).
  swayLoopReady_ = true;
  const size_t n = nodes_.size();
  constexpr int H = kLoopHarmonics, M = kLoopSamples, kCoefficients = 1 + 2 * H;
  const float L = settings_.loopSeconds;
  std::vector<Vec3> cosSum(n * (H + 1), Vec3::Zero()), sinSum(n * (H + 1), Vec3::Zero());
  for (int sample = 0; sample < M; ++sample) {
    computeTorques(L * float(sample) / float(M), wind);
    parallelFor(size_t(0), n, [&](size_t i) {
      for (int h = 0; h <= H; ++h) {
        const double a = kTwoPi * double(h * sample % M) / double(M);
        cosSum[i * (H + 1) + size_t(h)] += float(std::cos(a)) * torque_[i];
        sinSum[i * (H + 1) + size_t(h)] += float(std::sin(a)) * torque_[i];
      }
    }, 1024);
  }
  loopSway_.assign(n * kCoefficients, Vec3::Zero());
  parallelFor(size_t(0), n, [&](size_t i) {
    const double k = std::max(double(stiffness_[i]), 1e-12), I = inertia_[i], c = damping_[i];
    Vec3* out = &loopSway_[i * kCoefficients];
    out[0] = cosSum[i * (H + 1)] * float(1.0 / (double(M) * k));
    for (int h = 1; h <= H; ++h) {
      const double w = kTwoPi * double(h) / double(L);
      const double kr = k - I * w * w, ci = c * w, D = kr * kr + ci * ci;
      const Vec3 A = cosSum[i * (H + 1) + size_t(h)] * float(2.0 / M), B = sinSum[i * (H + 1) + size_t(h)] * float(2.0 / M);
      out[2 * h - 1] = (float(kr / D) * A - float(ci / D) * B);  // times cos ω t
      out[2 * h] = (float(kr / D) * B + float(ci / D) * A);      // times sin ω t
    }
  }, 1024);
}

void WindMotion::evaluateSwayLoop(float t) {
  constexpr int H = kLoopHarmonics, kCoefficients = 1 + 2 * H;
  // t reduced to the loop first, so that t = loopSeconds poses as t = 0 exactly.
  const float u = t / settings_.loopSeconds;
  const double phase = double(u - std::floor(u));
  float C[H + 1], S[H + 1];
  for (int h = 1; h <= H; ++h) C[h] = float(std::cos(kTwoPi * phase * h)), S[h] = float(std::sin(kTwoPi * phase * h));
  parallelFor(size_t(0), nodes_.size(), [&](size_t i) {
    const Vec3* c = &loopSway_[i * kCoefficients];
    Vec3 theta = c[0];
    for (int h = 1; h <= H; ++h) theta += C[h] * c[2 * h - 1] + S[h] * c[2 * h];
    SwayBlock& B = sway_[i / 4];
    const size_t l = i % 4;
    B.theta.x[l] = theta.x(), B.theta.y[l] = theta.y(), B.theta.z[l] = theta.z();
  }, 1024);
}

void WindMotion::advance(bool integrate) {
  // Four nodes at a time: eq. 1 over the frame, the species' limit as a stop (a node that
  // reaches it rests there), then the axis and angle composing turns the node by.
  using namespace lanes;
  const float limit = species_.maxSwayAngle;
  const F4 limit4 = splat(limit), limit2 = splat(limit * limit), zero = splat(0.0f), one = splat(1.0f);
  const size_t n = nodes_.size();
  parallelFor(size_t(0), sway_.size(), [&](size_t b) {
    SwayBlock& B = sway_[b];
    if (integrate) {
      const V3 y = B.theta - B.target, v = B.omega;
      V3 th = B.target + (B.a * y + B.b * v);
      V3 om = B.c * y + B.d * v;
      const F4 a2 = dot(th, th);
      const M4 over = a2 > limit2;
      const F4 scale = over ? limit4 / sqrt4(over ? a2 : one) : one;
      th = scale * th;
      om = select(over, V3{zero, zero, zero}, om);
      B.theta = th;
      B.omega = om;
    }
    const F4 a = sqrt4(dot(B.theta, B.theta));
    const M4 moves = a > zero;
    const F4 inv = one / (moves ? a : one);
    const V3 axis = select(moves, inv * B.theta, V3{one, zero, zero});
    const F4 angle = a < limit4 ? a : limit4;
    for (size_t l = 0; l < 4 && 4 * b + l < n; ++l)
      swayAxisAngle_[4 * b + l] = AxisAngle{Vec3(axis.x[l], axis.y[l], axis.z[l]), angle[l]};
  }, 256);
}

void WindMotion::compose(plant::PlantModel& posed) {
  // Parents first: node i's subtree turns about p_i on top of its parent's motion by its sway
  // (swayAxisAngle_), and never past the wind: the angles toward the wind along its path are
  // capped by its rest angle to the wind.
  // Plain pointers: Eigen's stores may alias anything, so members would be reloaded per node.
  const SwayNode* const nodes = nodes_.data();
  const AxisAngle* const sway = swayAxisAngle_.data();
  Quat* const rotation = Q_.data();
  Pose* const pose = pose_.data();
  float* const angle = angle_.data();
  Vec3* const position = posed.position.data();
  Quat* const orientation = posed.orientation.data();
  const uint32_t* const order = order_.data();
  auto composeNode = [=](size_t i) {
    const SwayNode& r = nodes[i];
    Quat Qp = Quat::Identity();
    Vec3 p = r.offset;
    float before = 0.0f;
    if (r.parent >= 0) {
      const size_t parent = size_t(r.parent);
      Qp = rotation[parent];
      before = pose[parent].turned;
      // The node turns about its own base, which its parent carries; rotating the rest offset
      // from the parent keeps round-off small far from the origin.
      p = pose[parent].position + Qp * r.offset;
    }
    const AxisAngle& s = sway[i];
    float a = s.angle;
    // How far it turns toward the wind; §3.1.1's angle to the wind, acos(b·w / bw), is at least
    // its sine: only a path turned further needs it exactly.
    float toward = a > 0.0f && r.sinToWind > 0.0f ? a * s.axis.dot(r.axis) : 0.0f;
    if (toward > 0.0f && before + toward > r.sinToWind) {
      const float room = std::max(0.0f, atan2Upper(r.sinToWind, r.cosToWind) - before);
      if (toward > room) {
        a *= room / toward;
        toward = room;
      }
    }
    const Quat Q = a > 0.0f ? renormalized(Qp * swayRotation(a, s.axis)) : Qp;
    angle[i] = a;
    rotation[i] = Q;
    pose[i] = Pose{p, before + toward};
    position[order[i]] = p;
    orientation[order[i]] = Q * r.restOrientation;  // both of unit length: so is the product
  };
  const size_t top = topCount_;
  for (size_t i = 0; i < top; ++i) composeNode(i);
  const uint32_t* const taskStart = taskStart_.data();
  parallelFor(size_t(0), taskStart_.size() - 1, [=](size_t k) {
    for (size_t i = top + taskStart[k]; i < top + taskStart[k + 1]; ++i) composeNode(i);
  }, 1);
}

const LeafLoop& WindMotion::prepareLeafLoop(const env::WindField& wind) {
  if (leafLoopReady_ || !(settings_.loopSeconds > 0.0f)) return leafLoop_;
  leafLoopReady_ = true;
  const size_t m = rest_.leafCount();
  LeafLoop& loop = leafLoop_;
  loop.leaves.assign(m, LeafLoop::Leaf{});
  // Algorithm 2's choice of bend (updateLeafMotion): the petiole when t_p > t_b, else the blade.
  loop.bendsBlade = species_.petioleStrength <= species_.bladeStrength;
  const float rates[3] = {loop.bendsBlade ? species_.bladeBendRate : species_.petioleBendRate, species_.twistRate,
                          species_.vibrateRate};
  const float limits[3] = {loop.bendsBlade ? species_.bladeBendLimit : species_.petioleBendLimit, species_.twistLimit,
                           species_.vibrateLimit};
  // The steady wind at each leaf's node (at its segment's centre of gravity, as for the sway).
  const env::WindSettings& ws = wind.settings();
  std::vector<float> speed(m, 0.0f), facing(m, 0.0f);
  for (size_t j = 0; j < m; ++j) {
    const Vec3& c = centre_[leafNode_[j]];
    Vec3 w;
    if (ws.mode == env::WindMode::Sph) {
      w = wind.sample(c, 0.0f);
    } else {
      w = ws.velocity;
      for (const env::WindEmitter& e : ws.emitters) w += env::WindField::jet(e, c);
    }
    speed[j] = w.norm();
    facing[j] = speed[j] > 0.0f ? std::fabs(leafNormal_[j].dot(w)) / speed[j] : 0.0f;
  }
  // Mean angular speed of each motion: w · rate · E[l_s] · the leaf's chance of the motion.
  const float meanGust = 0.5f * (1.0f + settings_.gustMin);
  const float L = settings_.loopSeconds;
  std::vector<std::array<float, 3>> meanSpeed(m, std::array<float, 3>{0.0f, 0.0f, 0.0f});
  for (size_t j = 0; j < m; ++j) {
    loop.leaves[j].torn = plant::leafDetaches(speed[j], species_);
    if (loop.leaves[j].torn) continue;
    float chance[3];
    plant::leafMotionChances(facing[j], chance);
    for (int k = 0; k < 3; ++k) meanSpeed[j][size_t(k)] = speed[j] * rates[k] * meanGust * chance[k];
  }
  for (int k = 0; k < 3; ++k) {
    // The median leaf that makes this motion at all; a wave bouncing between ±limit at speed v
    // has period 4 · limit / v.
    std::vector<float> live;
    for (size_t j = 0; j < m; ++j)
      if (meanSpeed[j][size_t(k)] > 0.0f) live.push_back(meanSpeed[j][size_t(k)]);
    float v = 0.0f;
    if (!live.empty()) {
      std::nth_element(live.begin(), live.begin() + live.size() / 2, live.end());
      v = live[live.size() / 2];
    }
    const float period = v > 0.0f && limits[k] > 0.0f ? 4.0f * limits[k] / v : L;
    loop.cycles[k] = int(std::clamp(std::round(L / period), 1.0f, 1000.0f));
  }
  for (size_t j = 0; j < m; ++j) {
    LeafLoop::Leaf& f = loop.leaves[j];
    Rng rng(mix64(leafKey_[j] ^ 0x5851f42d4c957f2dull));
    for (int k = 0; k < 3; ++k) {
      f.phase[k] = uint8_t(rng.below(LeafLoop::kPhases));
      if (f.torn) continue;
      const float v = meanSpeed[j][size_t(k)];
      const float quarter = 0.25f * L / float(loop.cycles[k]);
      f.amplitude[k] = std::min(limits[k], v * quarter);
    }
    leaves_[j] = loop.state(j, 0.0f, L);
  }
  return leafLoop_;
}

void WindMotion::step(float t, float dt, const env::WindField& wind, plant::PlantModel& posed) {
  const size_t n = rest_.nodeCount();
  const size_t m = rest_.leafCount();

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

  // Branch sway; the posed nodes moved rigidly with their subtree transforms.
  if (settings_.loopSeconds > 0.0f) {
    if (!swayLoopReady_) prepareSwayLoop(wind);
    evaluateSwayLoop(t);
    computeTorques(t, wind);  // the wind's direction at the nodes, for the limits
    advance(false);
  } else {
    computeTorques(t, wind);
    if (dt > 0.0f) prepareSteps(dt);
    advance(dt > 0.0f);
  }
  compose(posed);

  // Leaves: one motion type and one gust fraction per leaf and frame (Algorithm 2), in the wind
  // of the node they hang on (gusts vary over metres, a leaf is centimetres from its node).
  // While no leaf tears off, each is written straight to its place in the posed plant.
  const size_t k = kept_.size();
  const bool inPlace = !fresh && posed.leafNode.size() == k && posed.leafRotation.size() == k &&
                       posed.leafMotion.size() == k;
  std::atomic<bool> tore{false};
  const uint32_t frame = frame_;
  const float gustMin = settings_.gustMin;
  const plant::GrowthFlowSpecies& species = species_;
  // Plain pointers, as in compose().
  plant::LeafMotionState* const leaves = leaves_.data();
  const uint64_t* const keys = leafKey_.data();
  const uint32_t* const leafNode = leafNode_.data();
  const Quat* const restRotation = leafRest_.data();
  const float* const speed = speed_.data();
  const Vec3* const windAt = windAt_.data();
  const Vec3* const normal = leafNormal_.data();
  const uint32_t* const slot = k == m ? nullptr : slot_.data();  // none torn off: leaf j is posed leaf j
  Quat* const rotation = posed.leafRotation.data();
  Vec3* const motion = posed.leafMotion.data();
  // In a loop every leaf follows its periodic motion; leaves torn off are so from the start.
  const bool loop = settings_.loopSeconds > 0.0f;
  if (loop && !leafLoopReady_) prepareLeafLoop(wind);
  const LeafLoop* const leafLoop = loop ? &leafLoop_ : nullptr;
  const float loopSeconds = settings_.loopSeconds;
  parallelFor(size_t(0), m, [=, &tore](size_t j) {
    plant::LeafMotionState& L = leaves[j];
    if (L.detached) return;
    if (leafLoop) {
      L = leafLoop->state(j, t, loopSeconds);
    } else {
      Rng rng(mix64(keys[j] ^ (uint64_t(frame) * 0x9e3779b97f4a7c15ull)));
      const size_t node = leafNode[j];
      const float w = speed[node];
      // §3.2.1: the blade's angle to the wind decides how it moves.
      const float facing = w > 0.0f ? std::fabs(normal[j].dot(windAt[node])) / w : 0.0f;
      const int type = plant::leafMotionType(facing, rng.uniform());
      const float gust = gustMin + (1.0f - gustMin) * rng.uniform();
      plant::updateLeafMotion(L, type, w, gust, dt, species);
    }
    if (L.detached) {
      tore.store(true, std::memory_order_relaxed);
    } else if (inPlace) {
      const size_t o = slot ? slot[j] : j;
      rotation[o] = posedLeafRotation(restRotation[j], L);
      motion[o] = leafMotionOf(L);
    }
  }, 1024);
  ++frame_;
  if (inPlace && !tore.load()) return;

  // The set of leaves changed (or `posed` is new): leaves still attached, in order, with their
  // fixed fields.
  kept_.clear();
  for (size_t j = 0; j < m; ++j)
    if (!leaves_[j].detached) {
      slot_[j] = uint32_t(kept_.size());
      kept_.push_back(uint32_t(j));
    }
  const size_t kept = kept_.size();
  posed.leafNode.resize(kept);
  posed.leafOffset.resize(kept);
  posed.leafSize.resize(kept);
  posed.leafThickness.resize(kept);
  posed.leafPetiole.resize(kept);
  posed.leafShape.resize(kept);
  posed.leafRotation.resize(kept);
  posed.leafMotion.resize(kept);
  parallelFor(size_t(0), kept, [&](size_t o) {
    const size_t j = kept_[o];
    posed.leafRotation[o] = posedLeafRotation(leafRest_[j], leaves_[j]);
    posed.leafMotion[o] = leafMotionOf(leaves_[j]);
    posed.leafNode[o] = rest_.leafNode[j];
    posed.leafOffset[o] = rest_.leafOffset[j];
    posed.leafSize[o] = rest_.leafSize[j];
    posed.leafThickness[o] = rest_.leafThickness[j];
    posed.leafPetiole[o] = rest_.leafPetiole[j];
    posed.leafShape[o] = rest_.leafShape[j];
  }, 1024);
}

std::vector<int32_t> clingingCarriers(const plant::PlantModel& rest, const std::vector<int32_t>& hostPlant) {
  std::vector<int32_t> carrier(rest.nodeCount(), -1);
  if (hostPlant.size() != rest.nodeCount()) return carrier;
  for (size_t i = 0; i < rest.nodeCount(); ++i)  // parents come before children
    carrier[i] = hostPlant[i] >= 0 ? int32_t(i) : rest.parent[i] < 0 ? -1 : carrier[size_t(rest.parent[i])];
  return carrier;
}

void carryWithHosts(plant::PlantModel& climber, const WindMotion& own, const std::vector<int32_t>& carriers,
                    const std::vector<int32_t>& hostPlant, const std::vector<int32_t>& hostNode,
                    const std::function<HostPose(size_t)>& host) {
  const size_t n = climber.nodeCount();
  if (carriers.size() != n || hostPlant.size() != n || hostNode.size() != n) return;
  // Each carrier's rigid motion: rotation R = Q_h Q_a⁻¹ and where a goes, before any node moves.
  struct Carry {
    Quat R = Quat::Identity();
    Vec3 from = Vec3::Zero(), to = Vec3::Zero();
    bool moves = false;
  };
  std::vector<Carry> carry(n);
  for (size_t a = 0; a < n; ++a) {
    if (hostPlant[a] < 0) continue;
    const HostPose h = host(size_t(hostPlant[a]));
    const size_t hn = size_t(hostNode[a]);
    if (!h.motion || !h.posed || hn >= h.posed->nodeCount()) continue;
    const Quat& Qh = h.motion->nodeRotation(hn);
    Carry& c = carry[a];
    c.R = (Qh * own.nodeRotation(a).conjugate()).normalized();
    c.from = climber.position[a];
    c.to = Qh * (own.rest().position[a] - h.motion->rest().position[hn]) + h.posed->position[hn];
    c.moves = true;
  }
  parallelFor(size_t(0), n, [&](size_t i) {
    const int32_t a = carriers[i];
    if (a < 0 || !carry[size_t(a)].moves) return;
    const Carry& c = carry[size_t(a)];
    climber.position[i] = c.to + c.R * (climber.position[i] - c.from);
    climber.orientation[i] = (c.R * climber.orientation[i]).normalized();
  }, 1024);
}

}  // namespace tendril::wind
