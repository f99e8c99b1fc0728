// Plant dynamics of seed 000 §4.1 and its appendix: oriented-particle shape matching after
// Müller & Chentanez 2011.
#include "tendril/core/parallel.h"
#include "tendril/particles/shape_matching.h"
#include "tendril/particles/world.h"

#include <algorithm>
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

}  // namespace

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

void ParticleWorld::shapeMatch() {
  const size_t n = capacity();
  groupCenter_.resize(n);
  groupRestCenter_.resize(n);

  // Every connected piece (a plant, or a piece broken off it) is matched on its own, from its
  // root outward (Gauss–Seidel): a group is fitted once its parent has reached its goal, so the
  // root's hold reaches the tips within one pass instead of creeping outward over many steps.
  // Pieces never share particles, so they run in parallel with results independent of the
  // thread count.
  pieceStart_.clear();
  pieceOrder_.clear();
  for (uint32_t r = 0; r < n; ++r) {
    if (!(flags_[r] & kActive) || parent_[r] != kNone) continue;
    pieceStart_.push_back(uint32_t(pieceOrder_.size()));
    pieceOrder_.push_back(r);
    for (size_t k = pieceOrder_.size() - 1; k < pieceOrder_.size(); ++k)
      for (uint32_t c = firstChild_[pieceOrder_[k]]; c != kNone; c = nextSibling_[c]) pieceOrder_.push_back(c);
  }
  pieceStart_.push_back(uint32_t(pieceOrder_.size()));

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
  auto member = [&](uint32_t i, auto&& visit) {
    // A group: the particle, its parent and its children (all currently connected).
    visit(i);
    if (parent_[i] != kNone) visit(parent_[i]);
    for (uint32_t c = firstChild_[i]; c != kNone; c = nextSibling_[c]) visit(c);
  };
  // Eq. 14–15 for the group of g: its optimal rotation (robust extraction) and its centres.
  auto fitGroup = [&](uint32_t g) {
    float mass = 0.0f;
    Vec3 c = Vec3::Zero(), cr = Vec3::Zero();
    member(g, [&](uint32_t i) {
      const float m = matchMass(i);
      mass += m;
      c += m * xp_[i];
      cr += m * xr_[i];
    });
    c /= mass;
    cr /= mass;
    Mat3 A = Mat3::Zero();
    member(g, [&](uint32_t i) {
      // Eq. 14's point terms, centred on the group, plus the ellipsoids' own moments.
      A += ellipsoidMoment_[i] + matchMass(i) * (xp_[i] - c) * (xr_[i] - cr).transpose();
    });
    // Warm-started from the last fit, one iteration of the extraction per pass tracks the
    // rotation (each step makes `iterations` passes).
    groupRotation_[g] = extractRotation(A, groupRotation_[g], 1);
    groupCenter_[g] = c;
    groupRestCenter_[g] = cr;
  };

  // Eq. 15, the ellipsoid's own moment: A_i = m/5 · R_i diag(b², a², b²) R̄_iᵀ (the garbled
  // extraction reads "1/5 m diag(a², b², c²) R"; with both a current and a rest orientation the
  // moment is this product — Müller & Chentanez 2011, eq. 9), written as
  // bb R R̄ᵀ + (aa − bb) r_y r̄_yᵀ. Kept per particle and renewed whenever it turns.
  ellipsoidMoment_.resize(n);
  auto updateMoment = [&](uint32_t i) {
    const Mat3 R = qp_[i].toRotationMatrix();
    const Mat3 Rr = qr_[i].toRotationMatrix();
    const float k = matchMass(i) / 5.0f, bb = k * b_[i] * b_[i], aa = k * a_[i] * a_[i];
    ellipsoidMoment_[i] = bb * (R * Rr.transpose()) + (aa - bb) * R.col(1) * Rr.col(1).transpose();
  };
  parallelFor(0, n, [&](size_t i) {
    if (flags_[i] & kActive) updateMoment(uint32_t(i));
  }, 2048);

  const int iterations = std::max(1, settings_.iterations);
  parallelFor(0, pieceStart_.size() - 1, [&](size_t piece) {
    for (int iteration = 0; iteration < iterations; ++iteration) {
      for (uint32_t k = pieceStart_[piece]; k < pieceStart_[piece + 1]; ++k) {
        const uint32_t i = pieceOrder_[k];
        fitGroup(i);
        if (flags_[i] & kRoot) {
          xp_[i] = xr_[i];
          qp_[i] = qr_[i];
          continue;
        }
        // Eq. 3–4: the goal is the weighted sum of the targets of the groups the particle is
        // in — its parent's (fitted after the parent moved) weighing more than its own.
        Vec3 sum = Vec3::Zero();
        float weight = 0.0f;
        auto target = [&](uint32_t g, float role) {
          const float w = role * m_[g];
          sum += w * (groupRotation_[g] * (xr_[i] - groupRestCenter_[g]) + groupCenter_[g]);  // eq. 3
          weight += w;
        };
        target(i, kOwnGroupWeight);
        if (const uint32_t p = parent_[i]; p != kNone) {
          // The parent has already reached its goal: its group's target for this particle is
          // taken in the parent's own frame (an oriented particle carries its rotation,
          // R_p = q_p q̄_p⁻¹), which holds a chain straight where a three-point fit could bend.
          const float w = kParentGroupWeight * m_[p];
          const Quat Rp = qp_[p] * qr_[p].conjugate();
          sum += w * (Rp * (xr_[i] - xr_[p]) + xp_[p]);
          weight += w;
        }
        const Vec3 xg = sum / weight;  // eq. 4
        const float s = stiffnessOf(i);
        Vec3 x = xp_[i] + s * (xg - xp_[i]);  // x'_g = x_p + s (x_g − x_p), §4.3
        // Orientation: the own group's rotation applied to the rest orientation (MC11), blended
        // by the same stiffness (normalised lerp: the two are close within one step).
        // With a parent, its rotation joins in with the same weights as for the position.
        Quat rotation = groupRotation_[i];
        if (const uint32_t p = parent_[i]; p != kNone) {
          Quat Rp = qp_[p] * qr_[p].conjugate();
          if (Rp.coeffs().dot(rotation.coeffs()) < 0.0f) Rp.coeffs() = -Rp.coeffs();
          const float wp = kParentGroupWeight * m_[p], wo = kOwnGroupWeight * m_[i];
          rotation.coeffs() = wo * rotation.coeffs() + wp * Rp.coeffs();
          rotation.normalize();
        }
        Quat qg = rotation * qr_[i];
        if (qg.coeffs().dot(qp_[i].coeffs()) < 0.0f) qg.coeffs() = -qg.coeffs();
        Quat q;
        q.coeffs() = (1.0f - s) * qp_[i].coeffs() + s * qg.coeffs();
        q.normalize();
        if (i == dragParticle_) x += dragStrength_ * (dragTarget_ - x);
        // Eq. 5 after the shape: x'_p = x_p + φ (x_anchor − x_p) (see applyAnchors()).
        if (flags_[i] & kAnchored) x += anchorPhi_[i] * (anchor_[i] - x);
        xp_[i] = x;
        qp_[i] = q;
        updateMoment(i);
      }
    }
  }, 1);
}

void ParticleWorld::integrate() {
  // Eq. 17–20: v = (x_p − x)/Δt, x = x_p, ω = axis(q_p q⁻¹)·angle(q_p q⁻¹)/Δt, q = q_p.
  const float dt = settings_.dt;
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
    x_[i] = xp_[i];
    q_[i] = qp_[i];
    v_[i] = v * damping;
    w_[i] = w * damping;
    if (!isFinite(x_[i]) || !isFinite(v_[i]) || !isFinite(q_[i]) || !isFinite(w_[i])) {
      // A particle must never carry NaN into the next step: fall back to its rest pose.
      x_[i] = xr_[i];
      q_[i] = qr_[i];
      v_[i] = w_[i] = Vec3::Zero();
    }
    age_[i] += dt;
  }, 512);
}

void ParticleWorld::breakConnections() {
  // §4.3: the stress of a connection is the difference between the rest and the current
  // distance of the two particles; above the plant's threshold t_s the connection is removed
  // and the piece falls. t_s = 0 never breaks.
  std::vector<uint32_t> broken;
  for (uint32_t i = 0; i < capacity(); ++i) {
    // Growing apices are not judged: a particle a few millimetres long shows large relative
    // strain from tiny displacements.
    if (!(flags_[i] & kActive) || parent_[i] == kNone || (flags_[i] & kApex)) continue;
    const ParticleSpecies& s = plants_[plant_[i]].species;
    if (s.breakThreshold <= 0.0f) continue;
    if (strain(i) > (1.0f - s.breakThreshold) * s.maxStrain) broken.push_back(i);
  }
  for (uint32_t i : broken) {
    if (parent_[i] == kNone) continue;
    unlink(i);
    markDetached(i);
  }
}

}  // namespace tendril::particles
