// Plant dynamics of seed 000 §4.1 and its appendix: oriented-particle shape matching after
// Müller & Chentanez 2011.
#include "tendril/core/log.h"
#include "tendril/core/parallel.h"
#include "tendril/core/parallel_largest_first.h"
#include "tendril/core/match_lanes.h"
#include "tendril/particles/shape_matching.h"
#include "tendril/particles/world.h"

#include <algorithm>
#include <atomic>
#include <cmath>

namespace tendril::particles {

Quat extractRotation(const Mat3& A, Quat q, int maxIterations) {
  for (int it = 0; it < maxIterations; ++it) {
    const Mat3 R = q.toRotationMatrix();
    Vec3 omega = R.col(0).cross(A.col(0)) + R.col(1).cross(A.col(1)) + R.col(2).cross(A.col(2));
    omega /= std::abs(R.col(0).dot(A.col(0)) + R.col(1).dot(A.col(1)) + R.col(2).dot(A.col(2))) + 1e-9f;
    const float w = omega.norm();
    if (!(w > 1e-7f)) break;
    q = (Quat(Eigen::AngleAxisf(w, omega / w)) * q).normalized();
  }
  return q;
}

namespace {

// Relative influence of the groups a particle belongs to (eq. 4): its parent's group weighs
// more than its own, so particles follow their parents.
constexpr float kParentGroupWeight = 4.0f;
constexpr float kOwnGroupWeight = 2.0f;
constexpr float kRootMassScale = 1000.0f;  // see shapeMatch()

// The passes of shapeMatch() for the baseline and, where the CPU has it, for AVX2: `passes`
// and everything it calls within this file (the fits and the lane arithmetic) are inlined into
// each (flatten). Four-lane vectors only: their ABI is the same in both.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__AVX2__)
#define TENDRIL_MATCH_AVX2 1
template <class Passes>
[[gnu::target("avx2"), gnu::flatten]] void runPassesAvx2(const Passes& passes) {
  passes();
}
#else
#define TENDRIL_MATCH_AVX2 0
#endif
template <class Passes>
[[gnu::flatten]] void runPassesBaseline(const Passes& passes) {
  passes();
}

std::atomic<bool> gBaselineShapeMatching{false};

}  // namespace

bool avx2ShapeMatching() {
#if TENDRIL_MATCH_AVX2
  static const bool hasAvx2 = __builtin_cpu_supports("avx2");
  return hasAvx2 && !gBaselineShapeMatching.load(std::memory_order_relaxed);
#else
  return false;
#endif
}

void forceBaselineShapeMatching(bool on) { gBaselineShapeMatching.store(on, std::memory_order_relaxed); }

void ParticleWorld::predict() {
  const float dt = settings_.dt;
  const Vec3 g = settings_.gravity;
  parallelFor(0, capacity(), [&](size_t i) {
    if (!(flags_[i] & kActive)) return;
    if (flags_[i] & kRoot) {
      xp_[i] = xr_[i];
      qp_[i] = q_[i];
      return;
    }
    // Eq. 1: x_p = x + v Δt + (a_g + a_e) Δt² / 2.
    xp_[i] = x_[i] + v_[i] * dt + 0.5f * dt * dt * (g + externalAcceleration_[i]);
    // Eq. 16: q_p = [ω̂ sin(|ω|Δt/2), cos(|ω|Δt/2)] q.
    const float w = w_[i].norm();
    if (w > 1e-9f) {
      const float half = 0.5f * w * dt;
      const Vec3 axis = w_[i] / w * std::sin(half);
      qp_[i] = (Quat(std::cos(half), axis.x(), axis.y(), axis.z()) * q_[i]).normalized();
    } else {
      qp_[i] = q_[i];
    }
  }, 512);
}

void ParticleWorld::applyAnchors(const env::Environment& env) {
  // Eq. 5: x'_p = x_p + φ (x_anchor − x_p); anchors let go past a distance threshold.
  parallelFor(0, capacity(), [&](size_t i) {
    if (!(flags_[i] & kActive) || !(flags_[i] & kAnchored)) return;
    const ParticleSpecies& s = plants_[plant_[i]].species;
    // The anchor holds the particle at its bark's clearance off the support, as thick as the
    // particle is now (secondary growth thickens anchored stems to centimetres; an anchor kept
    // where it was set would pull them into the support against the collisions every step).
    placeAnchor(uint32_t(i));
    if ((xp_[i] - anchor_[i]).norm() > s.anchorRelease) {
      flags_[i] &= ~kAnchored;
      anchorPhi_[i] = 0.0f;
      return;
    }
    // The attachment strengthens as the particle grows (φ linear in particle size).
    // The pull itself is applied within shape matching, after each particle's goal.
    anchorPhi_[i] = s.anchorStrength * std::clamp(a_[i] / std::max(targetHalfLength_[i], 1e-6f), 0.0f, 1.0f);
  }, 512);
}

// Every piece's particles breadth first from its root, children in link order: each entry's
// slot, its parent's entry and its children's range of entries, and the pieces' starts.
void ParticleWorld::buildPieceOrder(std::vector<uint32_t>& start, std::vector<uint32_t>& order,
                                    std::vector<uint32_t>& parent, std::vector<uint32_t>& childBegin,
                                    std::vector<uint32_t>& childEnd) const {
  start.clear(), order.clear(), parent.clear(), childBegin.clear(), childEnd.clear();
  for (uint32_t r = 0; r < capacity(); ++r) {
    if (!(flags_[r] & kActive) || parent_[r] != kNone) continue;
    start.push_back(uint32_t(order.size()));
    order.push_back(r);
    parent.push_back(kNone);
    for (size_t k = order.size() - 1; k < order.size(); ++k) {
      childBegin.push_back(uint32_t(order.size()));
      for (uint32_t c = firstChild_[order[k]]; c != kNone; c = nextSibling_[c]) {
        order.push_back(c);
        parent.push_back(uint32_t(k));
      }
      childEnd.push_back(uint32_t(order.size()));
    }
  }
  start.push_back(uint32_t(order.size()));
}

void ParticleWorld::shapeMatch() {
  // Every connected piece (a plant, or a piece broken off it) is matched on its own, from its
  // root outward (Gauss–Seidel): a group is fitted once its parent has reached its goal, so the
  // root's hold reaches the tips within one pass instead of creeping outward over many steps.
  // A particle's fit reads only its parent (already moved in this pass), itself and its
  // children (moved in the last pass), never its siblings: the result does not depend on the
  // order of siblings, and pieces, which never share particles, run in parallel with results
  // independent of the thread count.
  if (pieceOrderVersion_ != topologyVersion_) {
    pieceOrderVersion_ = topologyVersion_;
    buildPieceOrder(pieceStart_, pieceOrder_, matchParent_, matchChildBegin_, matchChildEnd_);
  }
  const size_t count = pieceOrder_.size();
  matchNode_.resize(count);
  matchRest_.resize(count);

  gatherMatchRest();

  const int iterations = std::max(1, settings_.iterations);
  const uint32_t drag = dragParticle_;
  // A piece's passes run in order on one thread; the largest pieces (whole plants) go first.
  std::vector<size_t> pieceSize(pieceStart_.size() - 1);
  for (size_t piece = 0; piece < pieceSize.size(); ++piece)
    pieceSize[piece] = pieceStart_[piece + 1] - pieceStart_[piece];
  const bool avx2 = avx2ShapeMatching();
  parallelForLargestFirst(pieceSize, [&](size_t piece) {
    const uint32_t begin = pieceStart_[piece], end = pieceStart_[piece + 1];
    auto passes = [&] {
      for (int iteration = 0; iteration < iterations; ++iteration) {
        for (uint32_t k = begin; k < end; ++k) {
          // Four particles side by side where none of them is another's parent (their parents
          // come before k: the piece order is breadth first) and none is held by the drag.
          if (k + 4 <= end && matchParent_[k] < k && matchParent_[k + 1] < k && matchParent_[k + 2] < k &&
              matchParent_[k + 3] < k && pieceOrder_[k] != drag && pieceOrder_[k + 1] != drag &&
              pieceOrder_[k + 2] != drag && pieceOrder_[k + 3] != drag) {
            matchFour(k);
            k += 3;
            continue;
          }
          matchOne(k);
        }
      }
    };
#if TENDRIL_MATCH_AVX2
    if (avx2) return runPassesAvx2(passes);
#endif
    (void)avx2;
    runPassesBaseline(passes);
  });

  parallelFor(0, count, [&](size_t k) {
    const uint32_t i = pieceOrder_[k];
    xp_[i] = matchNode_[k].x;
    qp_[i] = matchNode_[k].q;
    groupRotation_[i] = matchNode_[k].rotation;
  }, 2048);
}

// What does not move within a step, per entry of the piece order: masses, rest offsets,
// eq. 4's weights, the stiffness and the anchor pull; and the first pass's starting state.
void ParticleWorld::gatherMatchRest() {
  const size_t count = pieceOrder_.size();
  // A plant's root is held in place and orientation. In its groups it counts as much heavier,
  // so that it fixes their rotation as well as their position — otherwise a two-particle group
  // could turn freely about its centre and the plant would topple.
  // A leaf weighs more than the thin twig it hangs from, but it must not steer the twig's fit:
  // in the groups it counts at most as heavy as its parent (a heavier leaf made the pair of
  // fits feed each other until they oscillated). Gravity acts on it all the same.
  auto matchMass = [&](uint32_t i) {
    if (flags_[i] & kRoot) return kRootMassScale * m_[i];
    if ((flags_[i] & kLeaf) && parent_[i] != kNone) return std::min(m_[i], m_[parent_[i]]);
    return m_[i];
  };
  // Eq. 15, the ellipsoid's own moment: A_i = m/5 · R_i diag(b², a², b²) R̄_iᵀ (the garbled
  // extraction reads "1/5 m diag(a², b², c²) R"; with both a current and a rest orientation the
  // moment is this product — Müller & Chentanez 2011, eq. 9). The part after R_i is fixed during
  // a step; R_i is renewed whenever the particle turns.
  // Everything else that does not move within a step is gathered here once: masses, rest
  // offsets, eq. 4's weights, the stiffness and the anchor pull.
  // Masses first: each group below reads its parent's and children's by their slots.
  parallelFor(0, count, [&](size_t k) { matchRest_[k].matchMass = matchMass(pieceOrder_[k]); }, 4096);
  parallelFor(0, count, [&](size_t k) {
    const uint32_t i = pieceOrder_[k];
    MatchRest& r = matchRest_[k];
    r.parent = matchParent_[k];
    r.childBegin = matchChildBegin_[k];
    r.childEnd = matchChildEnd_[k];
    r.qr = qr_[i];
    const float bb = r.matchMass / 5.0f * b_[i] * b_[i], aa = r.matchMass / 5.0f * a_[i] * a_[i];
    const Mat3 Rr = qr_[i].toRotationMatrix();
    r.restMoment.row(0) = bb * Rr.col(0).transpose();
    r.restMoment.row(1) = aa * Rr.col(1).transpose();
    r.restMoment.row(2) = bb * Rr.col(2).transpose();
    // The group {parent, self, children}: its mass and rest centre (eq. 14's c̄).
    float mass = r.matchMass;
    Vec3 cr = r.matchMass * xr_[i];
    const uint32_t p = parent_[i];
    if (p != kNone) {
      const float mp = matchRest_[r.parent].matchMass;
      mass += mp;
      cr += mp * xr_[p];
    }
    // The children's slots, in the order of the child list.
    for (uint32_t c = r.childBegin; c < r.childEnd; ++c) {
      const float mc = matchRest_[c].matchMass;
      mass += mc;
      cr += mc * xr_[pieceOrder_[c]];
    }
    r.invGroupMass = 1.0f / mass;
    r.restOffset = xr_[i] - cr * r.invGroupMass;
    // Eq. 4: its parent's group weighs more than its own, so particles follow their parents.
    const float own = kOwnGroupWeight * m_[i], parentW = p != kNone ? kParentGroupWeight * m_[p] : 0.0f;
    r.ownWeight = own / (own + parentW);
    r.parentWeight = parentW / (own + parentW);
    r.fromParent = p != kNone ? Vec3(xr_[i] - xr_[p]) : Vec3::Zero();
    r.stiffness = stiffnessOf(i);
    r.phi = (flags_[i] & kAnchored) ? anchorPhi_[i] : 0.0f;
    r.anchor = anchor_[i];
    MatchNode& node = matchNode_[k];
    node.x = xp_[i];
    node.q = qp_[i];
    node.rotation = groupRotation_[i];
    node.frame = qp_[i] * qr_[i].conjugate();
    node.moment = qp_[i].toRotationMatrix() * r.restMoment;
  }, 1024);
}

// The fit of matchOne() for the four particles k … k + 3 (none a root, each with a
// parent, none dragged), one per lane (core/match_lanes.h): bit for bit the scalar fit of each, and
// the four independent chains of arithmetic run side by side (about 40 % less time here than
// the same work one particle after the other, bench/README.md).
inline void ParticleWorld::matchFour(uint32_t k) {
  using namespace lanes;
  MatchNode* n[4] = {&matchNode_[k], &matchNode_[k + 1], &matchNode_[k + 2], &matchNode_[k + 3]};
  const MatchRest* r[4] = {&matchRest_[k], &matchRest_[k + 1], &matchRest_[k + 2], &matchRest_[k + 3]};
  const MatchNode* p[4] = {&matchNode_[r[0]->parent], &matchNode_[r[1]->parent], &matchNode_[r[2]->parent],
                           &matchNode_[r[3]->parent]};
  const V3 x = pack(n[0]->x, n[1]->x, n[2]->x, n[3]->x);
  const V3 restOffset = pack(r[0]->restOffset, r[1]->restOffset, r[2]->restOffset, r[3]->restOffset);
  const V3 fromParent = pack(r[0]->fromParent, r[1]->fromParent, r[2]->fromParent, r[3]->fromParent);
  // Eq. 14–15: the own moment, the parent's terms, then each child's in list order.
  M3 A = pack(n[0]->moment, n[1]->moment, n[2]->moment, n[3]->moment);
  const V3 px = pack(p[0]->x, p[1]->x, p[2]->x, p[3]->x);
  const V3 d = pack(matchRest_[r[0]->parent].matchMass, matchRest_[r[1]->parent].matchMass,
                    matchRest_[r[2]->parent].matchMass, matchRest_[r[3]->parent].matchMass) *
               (px - x);
  const M4 all = {-1, -1, -1, -1};
  addMomentTerm(A, pack(p[0]->moment, p[1]->moment, p[2]->moment, p[3]->moment), d, restOffset - fromParent, all);
  V3 offset = V3{splat(0.0f), splat(0.0f), splat(0.0f)} + d;
  uint32_t most = 0;
  for (int l = 0; l < 4; ++l) most = std::max(most, r[l]->childEnd - r[l]->childBegin);
  for (uint32_t c = 0; c < most; ++c) {
    uint32_t ck[4];
    M4 has;
    for (int l = 0; l < 4; ++l) {
      has[l] = r[l]->childBegin + c < r[l]->childEnd ? -1 : 0;
      ck[l] = has[l] ? r[l]->childBegin + c : k;  // a lane out of children reads anything and keeps its sums
    }
    const MatchNode* cn[4] = {&matchNode_[ck[0]], &matchNode_[ck[1]], &matchNode_[ck[2]], &matchNode_[ck[3]]};
    const MatchRest* cr[4] = {&matchRest_[ck[0]], &matchRest_[ck[1]], &matchRest_[ck[2]], &matchRest_[ck[3]]};
    const V3 dc = pack(cr[0]->matchMass, cr[1]->matchMass, cr[2]->matchMass, cr[3]->matchMass) *
                  (pack(cn[0]->x, cn[1]->x, cn[2]->x, cn[3]->x) - x);
    addMomentTerm(A, pack(cn[0]->moment, cn[1]->moment, cn[2]->moment, cn[3]->moment), dc,
                  pack(cr[0]->fromParent, cr[1]->fromParent, cr[2]->fromParent, cr[3]->fromParent) + restOffset, has);
    offset = select(has, offset + dc, offset);
  }
  const V3 center = x + pack(r[0]->invGroupMass, r[1]->invGroupMass, r[2]->invGroupMass, r[3]->invGroupMass) * offset;
  const Q4 own = extractRotationOnce(A, pack(n[0]->rotation, n[1]->rotation, n[2]->rotation, n[3]->rotation));
  // Eq. 3–4 and §4.3, as in the loop below.
  const F4 ownWeight = pack(r[0]->ownWeight, r[1]->ownWeight, r[2]->ownWeight, r[3]->ownWeight);
  const F4 parentWeight = pack(r[0]->parentWeight, r[1]->parentWeight, r[2]->parentWeight, r[3]->parentWeight);
  const Q4 parentFrame = pack(p[0]->frame, p[1]->frame, p[2]->frame, p[3]->frame);
  const V3 xg =
      ownWeight * (rotate(own, restOffset) + center) + parentWeight * (rotate(parentFrame, fromParent) + px);
  const Q4 Rp = select(dot4(parentFrame, own) < 0.0f, negate(parentFrame), parentFrame);
  const Q4 rotation = normalized({ownWeight * own.x + parentWeight * Rp.x, ownWeight * own.y + parentWeight * Rp.y,
                                  ownWeight * own.z + parentWeight * Rp.z, ownWeight * own.w + parentWeight * Rp.w});
  const F4 s = pack(r[0]->stiffness, r[1]->stiffness, r[2]->stiffness, r[3]->stiffness);
  V3 xn = x + s * (xg - x);
  const Q4 qr = pack(r[0]->qr, r[1]->qr, r[2]->qr, r[3]->qr);
  const Q4 nq = pack(n[0]->q, n[1]->q, n[2]->q, n[3]->q);
  Q4 qg = rotation * qr;
  qg = select(dot4(qg, nq) < 0.0f, negate(qg), qg);
  const F4 keep = 1.0f - s;
  const Q4 q =
      normalized({keep * nq.x + s * qg.x, keep * nq.y + s * qg.y, keep * nq.z + s * qg.z, keep * nq.w + s * qg.w});
  xn = xn + pack(r[0]->phi, r[1]->phi, r[2]->phi, r[3]->phi) *
                (pack(r[0]->anchor, r[1]->anchor, r[2]->anchor, r[3]->anchor) - xn);  // eq. 5
  const Q4 frame = q * conjugate(qr);
  const M3 moment =
      toRotationMatrix(q) * pack(r[0]->restMoment, r[1]->restMoment, r[2]->restMoment, r[3]->restMoment);
  for (int l = 0; l < 4; ++l) n[l]->x = lane(xn, l);
  store(q, &n[0]->q, &n[1]->q, &n[2]->q, &n[3]->q);
  store(own, &n[0]->rotation, &n[1]->rotation, &n[2]->rotation, &n[3]->rotation);
  store(frame, &n[0]->frame, &n[1]->frame, &n[2]->frame, &n[3]->frame);
  store(moment, &n[0]->moment, &n[1]->moment, &n[2]->moment, &n[3]->moment);
}

// One particle's fit in its pass (eq. 3–5, 14–15, §4.3): its group's moment and rotation, the
// goal blended from its own and its parent's group, the drag and the anchor.
inline void ParticleWorld::matchOne(uint32_t k) {
  const MatchRest& r = matchRest_[k];
  MatchNode& node = matchNode_[k];
  const uint32_t i = pieceOrder_[k];
  if (flags_[i] & kRoot) {
    node.x = xr_[i];
    node.q = r.qr;
    node.frame = Quat::Identity();
    node.moment = r.qr.toRotationMatrix() * r.restMoment;
    return;
  }
  // Eq. 14–15 for the group of k: A = Σ A_j + Σ m_j (x_j − c)(x̄_j − c̄)ᵀ. As Σ m_j (x̄_j − c̄)
  // is zero, x_j − c may be replaced by x_j − x_k: this particle's own point term drops
  // out, and positions are differences of nearby points, exact far from the origin.
  Mat3 A = node.moment;
  Vec3 offset = Vec3::Zero();  // Σ m_j (x_j − x_k)
  if (r.parent != kNone) {
    const MatchNode& pn = matchNode_[r.parent];
    const float m = matchRest_[r.parent].matchMass;
    const Vec3 d = m * (pn.x - node.x);
    A += pn.moment + d * (r.restOffset - r.fromParent).transpose();
    offset += d;
  }
  for (uint32_t c = r.childBegin; c < r.childEnd; ++c) {
    const MatchNode& cn = matchNode_[c];
    const MatchRest& cr = matchRest_[c];
    const Vec3 d = cr.matchMass * (cn.x - node.x);
    A += cn.moment + d * (cr.fromParent + r.restOffset).transpose();
    offset += d;
  }
  const Vec3 center = node.x + offset * r.invGroupMass;
  // Warm-started from the last fit, one iteration of the extraction per pass tracks the
  // rotation (each step makes `iterations` passes).
  node.rotation = extractRotation(A, node.rotation, 1);

  // Eq. 3–4: the goal is the weighted sum of the targets of the groups the particle is
  // in — its own (eq. 3: R (x̄ − c̄) + c) and its parent's, which weighs more. The parent
  // has already reached its goal: its group's target for this particle is taken in the
  // parent's own frame (an oriented particle carries its rotation, R_p = q_p q̄_p⁻¹), which
  // holds a chain straight where a three-point fit could bend.
  Vec3 xg = r.ownWeight * (node.rotation * r.restOffset + center);
  // Orientation: the own group's rotation applied to the rest orientation (MC11), blended
  // by the same stiffness (normalised lerp: the two are close within one step).
  // With a parent, its rotation joins in with the same weights as for the position.
  Quat rotation = node.rotation;
  if (r.parent != kNone) {
    const MatchNode& pn = matchNode_[r.parent];
    xg += r.parentWeight * (pn.frame * r.fromParent + pn.x);
    Quat Rp = pn.frame;
    if (Rp.coeffs().dot(rotation.coeffs()) < 0.0f) Rp.coeffs() = -Rp.coeffs();
    rotation.coeffs() = r.ownWeight * rotation.coeffs() + r.parentWeight * Rp.coeffs();
    rotation.normalize();
  }
  const float s = r.stiffness;
  Vec3 x = node.x + s * (xg - node.x);  // x'_g = x_p + s (x_g − x_p), §4.3
  Quat qg = rotation * r.qr;
  if (qg.coeffs().dot(node.q.coeffs()) < 0.0f) qg.coeffs() = -qg.coeffs();
  Quat q;
  q.coeffs() = (1.0f - s) * node.q.coeffs() + s * qg.coeffs();
  q.normalize();
  if (i == dragParticle_) x += dragStrength_ * (dragTarget_ - x);
  // Eq. 5 after the shape: x'_p = x_p + φ (x_anchor − x_p) (see applyAnchors()).
  x += r.phi * (r.anchor - x);
  node.x = x;
  node.q = q;
  node.frame = q * r.qr.conjugate();
  node.moment = q.toRotationMatrix() * r.restMoment;
}

void ParticleWorld::integrate() {
  // Eq. 17–20: v = (x_p − x)/Δt, x = x_p, ω = axis(q_p q⁻¹)·angle(q_p q⁻¹)/Δt, q = q_p.
  const float dt = settings_.dt;
  speedLimited_.assign(capacity(), 0);
  parallelFor(0, capacity(), [&](size_t i) {
    if (!(flags_[i] & kActive)) return;
    const ParticleSpecies& species = plants_[plant_[i]].species;
    const float damping = 1.0f - species.damping;
    Vec3 v = (xp_[i] - x_[i]) / dt;
    if (i < correction_.size() && correction_[i].squaredNorm() > 0.0f) {
      // §5.2 contact response: the velocity the particle came in with, split at the surface
      // normal; the normal part is reflected times the elasticity, the tangential part keeps
      // (1 − friction). The push out of the obstacle itself adds no velocity.
      const Vec3 n = correction_[i].normalized();
      const Vec3 in = (xp_[i] - correction_[i] - x_[i]) / dt;
      const float vn = in.dot(n);
      const Vec3 vt = in - vn * n;
      v = (vn < 0.0f ? -species.elasticity * vn : vn) * n + (1.0f - species.friction) * vt;
    }
    Quat dq = (qp_[i] * q_[i].conjugate()).normalized();
    if (dq.w() < 0.0f) dq.coeffs() = -dq.coeffs();  // the short way round
    const float sinHalf = dq.vec().norm();
    Vec3 w = Vec3::Zero();
    if (sinHalf > 1e-9f) w = dq.vec() / sinHalf * (2.0f * std::atan2(sinHalf, dq.w()) / dt);
    if (flags_[i] & kDetached) {
      // A broken-off piece rests when it stops moving: its displacement over the step, not the
      // velocity the contact response gives it (a particle lying on the ground is pushed back
      // up each step by what gravity took, and leaves with that velocity reflected, however
      // still it lies).
      const bool still = (xp_[i] - x_[i]).norm() < settings_.restingSpeed * dt;
      restTime_[i] = still ? restTime_[i] + dt : 0.0f;
    }
    x_[i] = xp_[i];
    q_[i] = qp_[i];
    v_[i] = v * damping;
    w_[i] = w * damping;
    if (const float speed = v_[i].norm(); speed > kMaxSpeed) {
      v_[i] *= kMaxSpeed / speed;
      speedLimited_[i] = 1;
    }
    if (!isFinite(x_[i]) || !isFinite(v_[i]) || !isFinite(q_[i]) || !isFinite(w_[i])) {
      // A particle must never carry NaN into the next step: fall back to its rest pose.
      x_[i] = xr_[i];
      q_[i] = qr_[i];
      v_[i] = w_[i] = Vec3::Zero();
    }
    age_[i] += dt;
  }, 512);
}

void ParticleWorld::reportSpeedLimit() {
  speedWarned_.resize(plants_.size(), 0);
  for (uint32_t i = 0; i < speedLimited_.size(); ++i) {
    if (!speedLimited_[i] || !(flags_[i] & kActive) || plant_[i] >= plants_.size() || speedWarned_[plant_[i]])
      continue;
    speedWarned_[plant_[i]] = 1;
    const Plant& pl = plants_[plant_[i]];
    log::warn("plant \"{}\": particles reached {} m/s and were held to it (a drag that fast, or the solver "
              "amplifying the motion of a long free shoot, most at stiffness below 1: here stiffness {}, "
              "stiffness_start {}; docs/particles.md, \"Known limits\")",
              pl.name, kMaxSpeed, pl.species.stiffness, pl.species.stiffnessStart);
  }
}

void ParticleWorld::breakConnections() {
  // §4.3: the stress of a connection is the difference between the rest and the current
  // distance of the two particles; above the plant's threshold t_s the connection is removed
  // and the piece falls. t_s = 0 never breaks.
  std::vector<uint32_t> broken;
  for (uint32_t i = 0; i < capacity(); ++i) {
    if (!judgedForBreaking(i)) continue;
    const ParticleSpecies& s = plants_[plant_[i]].species;
    if (s.breakThreshold <= 0.0f) continue;
    if (strain(i) > breakingStrain(s)) broken.push_back(i);
  }
  for (uint32_t i : broken) {
    if (parent_[i] == kNone) continue;
    unlink(i);
    markDetached(i);
  }
}

}  // namespace tendril::particles
