// Growth-Flow (seed 001): how wind changes the growth and the motion of branches and leaves.
//
// Growth (§3.1.2, §3.2.2). The wind growth factor f(w) ∈ [0, 1] (eq. 6) is 0 at or below the
// species' w_min and 1 at or above w_max. Over t units of growth time in a wind of speed w:
//   radius      r_t = r0 (1 + g_r Δr)^t,  Δr = 1 + s_r f(w)        (eq. 7)
//   length      l_t = l0 (g_l Δl)^t,      Δl = 1 − s_l f(w)        (eq. 8, clamped to l_max)
//   growth angle α_t = α0 (1 + Δα)^t,     Δα = c_α s_α f(w)        (eq. 9)
//   leaf thickness h_t = h0 (1 + g_h Δh)^t,  Δh = 1 + s_h f(w)      (eq. 16)
//   leaf radius    d_t = d0 (g_d Δd)^t,      Δd = 1 − s_d f(w)      (eq. 17)
// Eq. 16–17 are garbled in the paper's text ("h_t = h0(1 + g_h w s_h)^t", "d_t = d0(g_d w
// s_d)^t", the latter zero in still air although the text defines a proportional change Δd);
// we reconstruct them in the form of eq. 7–8, through f(w), so that a wind at or below w_min
// changes nothing, as §3.1.2 says of all growth.
//
// Growth models apply these as per-step factors *relative to their own still-air growth*
// (GrowthFlowStep): an organ that grows t steps in a constant wind ends up exactly eq. 7/8/16/17
// times the size it has in still air, whatever the model's own growth law is. Each model's
// docs say what its unit of growth time is.
//
// Motion (§3.2.1). Leaves bend (at the petiole when t_p ≤ t_b, else at the blade), twist and
// vibrate, one motion type per frame chosen at random; each angle follows the bounce rule of
// eq. 10–15: it moves by s·w·c·Δt and reverses direction before it would leave its limits.
// Leaves detach when the wind exceeds c_p t_p or c_b t_b (Algorithm 2).
#pragma once

#include "tendril/core/math.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace tendril {
class JsonObject;
}

namespace tendril::plant {

struct GrowthFlowSpecies {
  // eq. 6: wind speeds (m/s) where growth starts to respond, and responds fully.
  float windMin = 4.0f;  // aspen responds above 4 m/s (seed 001 §2.2.2)
  float windMax = 12.0f;
  // eq. 7: normal radius growth rate g_r (per unit growth time) and the species' sensitivity.
  float radiusRate = 0.01f;
  float radiusSensitivity = 0.5f;  // s_r ∈ [0, 1]
  // eq. 8: normal elongation factor g_l is the model's own (e.g. the climbing decrease ratio);
  // s_l is the sensitivity, l_max the cap (m; 0 = the model's own maximum).
  float lengthSensitivity = 0.03f;  // s_l ∈ [0, 1]
  float maxLength = 0.0f;
  // eq. 9: growth angle toward the wind, α_t = α0 (1 + c_α s_α f)^t; a shoot turns by its
  // increase each unit of growth time. (The paper's c_α converts m/s to degrees per second; with
  // f(w) dimensionless it is a plain rate here.)
  float angle0 = radians(2.0f);      // α0 (rad)
  float angleConversion = 0.2f;      // c_α (per unit growth time)
  float angleSensitivity = 0.5f;     // s_α ∈ [0, 1]
  // eq. 16–17: leaf thickness and leaf radius.
  float leafThicknessRate = 0.01f;        // g_h
  float leafThicknessSensitivity = 0.5f;  // s_h ∈ [0, 1]
  float leafRadiusSensitivity = 0.02f;    // s_d ∈ [0, 1]
  // Algorithm 2: a leaf detaches when w > c_p t_p or w > c_b t_b (t: tensile strengths).
  float petioleStrength = 1.0f;    // t_p
  float bladeStrength = 1.2f;      // t_b
  float strengthToWind = 20.0f;    // c_p = c_b (m/s per unit of strength)
  // eq. 10–15: angle rates per m/s (c_θ, c_β, c_ψ, c_φ, rad per (m/s · s)) and the paper's
  // limits (§4): θ ±5°, β ±10°, ψ ±15°, φ ±5°.
  float petioleBendRate = radians(4.0f);
  float bladeBendRate = radians(6.0f);
  float twistRate = radians(8.0f);
  float vibrateRate = radians(10.0f);
  float petioleBendLimit = radians(5.0f);
  float bladeBendLimit = radians(10.0f);
  float twistLimit = radians(15.0f);
  float vibrateLimit = radians(5.0f);
  // Branch sway (eq. 1, wind/motion.h): Young's modulus of the wood (Pa) for the resistivity K,
  // its density (kg/m³) for a segment's mass (its wood: §3.1.1 sets a branch to 10 leaves
  // "arbitrarily", we weigh it), the drag coefficient, a leaf's mass (kg), and the axial
  // damping R as a damping ratio ζ (the fraction of critical damping).
  float youngModulus = 2.0e8f;
  float woodDensity = 700.0f;
  float dragCoefficient = 1.2f;
  float leafMass = 0.002f;
  float swayDamping = 0.15f;
  float maxSwayAngle = radians(20.0f);  // per node, on top of the limit acos(b·w) of §3.1.1
  // Units of growth time an organ of a re-read string (L-system) grows in before it appears;
  // it keeps the factors of those units for the rest of its life (GrowthFlowHistory).
  uint32_t growthUnits = 10;

};

// Reads the "growth_flow" object of a species file into `s` (every key optional, keeping the
// value in `s`; angles in degrees).
void readGrowthFlow(JsonObject& o, GrowthFlowSpecies& s);

// eq. 6.
float windGrowthFactor(float windSpeed, float windMin, float windMax);
// eq. 7–9, 16–17 in closed form, for t units of growth time in a constant wind of speed w.
// gl and gd are the model's normal elongation and leaf-radius factors.
double radiusAt(double r0, double t, double w, const GrowthFlowSpecies& s);
double lengthAt(double l0, double t, double w, double gl, const GrowthFlowSpecies& s);
double angleAt(double t, double w, const GrowthFlowSpecies& s);
double leafThicknessAt(double h0, double t, double w, const GrowthFlowSpecies& s);
double leafRadiusAt(double d0, double t, double w, double gd, const GrowthFlowSpecies& s);

// One unit of growth time in a wind w: the factors a model multiplies into its still-air
// growth. All are exactly 1 (and the angle step 0) when f(w) = 0, so wind at or below w_min
// leaves every result bit-identical.
struct GrowthFlowStep {
  float f = 0.0f;              // eq. 6
  float radius = 1.0f;         // (1 + g_r Δr) / (1 + g_r): eq. 7 relative to still air
  float length = 1.0f;         // Δl: eq. 8 relative to still air
  float leafThickness = 1.0f;  // (1 + g_h Δh) / (1 + g_h): eq. 16 relative to still air
  float leafRadius = 1.0f;     // Δd: eq. 17 relative to still air
  float angleGrowth = 0.0f;    // Δα: eq. 9's growth rate of the accumulated angle
  bool active() const { return f > 0.0f; }
};
GrowthFlowStep growthStep(float windSpeed, const GrowthFlowSpecies& s);

// eq. 9 one unit of growth time on: α ← α (1 + Δα), at most π.
float nextGrowthAngle(float angle, const GrowthFlowStep& step);
// Algorithm 1's rotation: the direction a shoot grows in the wind — its still-air direction b
// turned by the growth angle α about u = b × w, never past the wind direction (§3.1.1). The
// shoot keeps its still-air direction (what its tropisms steer) and grows along this one.
Vec3 windGrowthDirection(const Vec3& direction, const Vec3& wind, float angle);

// Algorithm 2's detachment test.
inline bool leafDetaches(float w, const GrowthFlowSpecies& s) {
  return w > s.strengthToWind * s.petioleStrength || w > s.strengthToWind * s.bladeStrength;
}

// The wind a whole plant grew in, one record per unit of growth time, for models whose organs
// are not grown one at a time but live in a string that is re-read (L-systems). An organ grows
// in the `growthUnits` units before the one it appears in and then keeps what it got (mature
// wood does not shrink nor turn): organ(b, t) gives, for an organ born at unit b seen at unit t,
// the product of those units' growthStep factors (prefix sums of logarithms: O(1) per organ),
// the growth angle eq. 9 reached over them and the wind of the last one, which it turned toward.
// Tearing (Algorithm 2) is damage, not growth: a leaf is torn by any unit from its growth on.
class GrowthFlowHistory {
 public:
  struct Factors {
    bool active = false;         // some unit of its life had f(w) > 0
    bool torn = false;           // some unit's wind exceeded the leaf strength (Algorithm 2)
    float radius = 1.0f;         // eq. 7 relative to still air
    float length = 1.0f;         // eq. 8
    float leafThickness = 1.0f;  // eq. 16
    float leafRadius = 1.0f;     // eq. 17
    float angle = 0.0f;          // eq. 9's α_t (0 when not active)
    Vec3 wind = Vec3::Zero();    // the wind of the organ's last unit of growth (eq. 9 turns toward it)
  };

  // Appends one unit of growth time in `wind`.
  void record(const Vec3& wind, const GrowthFlowSpecies& s);
  // Units recorded so far.
  uint32_t units() const { return uint32_t(active_.size() - 1); }
  // Factors of an organ born at unit `birth` (0 = before the first) seen at unit `now`: its
  // growth over units birth − growthUnits … birth − 1, and tearing over those up to `now`.
  // organ(now + 1, now) is what the next organ to appear will get.
  Factors organ(uint32_t birth, uint32_t now, const GrowthFlowSpecies& s) const;
  // The wind of unit u (zero for u = 0, before the first).
  const Vec3& windAt(uint32_t u) const { return winds_[std::min<size_t>(u, winds_.size() - 1)]; }
  // Every member, for saving and restoring a plant's state.
  struct Sums {
    double radius = 0, length = 0, leafThickness = 0, leafRadius = 0, angle = 0;
  };
  const std::vector<Sums>& sums() const { return sums_; }
  const std::vector<uint32_t>& activeCounts() const { return active_; }
  const std::vector<uint32_t>& tornCounts() const { return torn_; }
  const std::vector<Vec3>& winds() const { return winds_; }
  void restore(std::vector<Sums> sums, std::vector<uint32_t> active, std::vector<uint32_t> torn,
               std::vector<Vec3> winds);

 private:
  std::vector<Sums> sums_{Sums{}};    // prefix sums of log factors, entry u = units 1 … u
  std::vector<uint32_t> active_{0};  // prefix counts of units with f > 0
  std::vector<uint32_t> torn_{0};    // prefix counts of units that tear leaves off
  std::vector<Vec3> winds_{Vec3::Zero()};  // entry u = unit u's wind
};

// eq. 10–15: one angle with its direction of motion. Returns the new angle; flips `sign`
// before the angle would leave [−limit, limit]. (Inline with updateLeafMotion: the motion of
// every leaf of a plant runs through them each frame.)
inline float bounceAngle(float angle, int8_t& sign, float w, float rate, float dt, float limit) {
  // eq. 10 (12, 14): reverse before leaving [−limit, limit]; eq. 11 (13, 15): move.
  float delta = w * rate * dt;
  float next = angle + float(sign) * delta;
  if (next > limit || next < -limit) sign = int8_t(-sign);
  next = angle + float(sign) * delta;
  // A step larger than the whole range (violent wind, long frame) would overshoot the other
  // way too: stop at the limit instead.
  return std::clamp(next, -limit, limit);
}

// §3.2.1's rule for which motion the wind makes of a leaf: a blade facing the wind bends, one
// oblique to it twists, one parallel to it vibrates. Algorithm 2 draws one motion per frame; we
// draw it with these chances, from c = |n̂ · ŵ| (n̂ the blade's normal): bend c², twist
// 2 c (1 − c), vibrate (1 − c)² — only bending when facing (c = 1), only vibrating when parallel
// (c = 0), twisting most at 45°, and Algorithm 2's 1/3 each nowhere in particular. `chance`
// gets the three in the order bend, twist, vibrate.
inline void leafMotionChances(float facing, float chance[3]) {
  const float c = std::clamp(facing, 0.0f, 1.0f);
  chance[0] = c * c;
  chance[1] = 2.0f * c * (1.0f - c);
  chance[2] = (1.0f - c) * (1.0f - c);
}
// The motion type for a uniform draw u ∈ [0, 1) with those chances.
inline int leafMotionType(float facing, float u) {
  float chance[3];
  leafMotionChances(facing, chance);
  return u < chance[0] ? 0 : u < chance[0] + chance[1] ? 1 : 2;
}

// A leaf's motion state (Algorithm 2): the four angles and their directions.
struct LeafMotionState {
  float petioleBend = 0, bladeBend = 0, twist = 0, vibrate = 0;  // θ, β, ψ, φ (rad)
  int8_t sPetiole = 1, sBlade = 1, sTwist = 1, sVibrate = 1;
  bool detached = false;
};
// One frame of Algorithm 2's motion: `motionType` ∈ {0, 1, 2} (bend, twist, vibrate), `gust`
// ∈ [0, 1] is l_s, the fraction of the wind that reaches the leaf this frame.
inline void updateLeafMotion(LeafMotionState& leaf, int type, float w, float gust, float dt,
                             const GrowthFlowSpecies& s) {
  if (leaf.detached) return;
  if (leafDetaches(w, s)) {
    leaf.detached = true;
    return;
  }
  const float ws = gust * w;  // l_s: the fraction of the wind felt this frame
  // The angle the motion type moves, picked by index: the type is random, and a branch on it
  // would be mispredicted for two leaves in three.
  float* const angles[4] = {&leaf.petioleBend, &leaf.bladeBend, &leaf.twist, &leaf.vibrate};
  int8_t* const signs[4] = {&leaf.sPetiole, &leaf.sBlade, &leaf.sTwist, &leaf.sVibrate};
  const float rates[4] = {s.petioleBendRate, s.bladeBendRate, s.twistRate, s.vibrateRate};
  const float limits[4] = {s.petioleBendLimit, s.bladeBendLimit, s.twistLimit, s.vibrateLimit};
  // Type 0 bends the petiole, or the blade when t_p > t_b; 1 twists; anything else vibrates.
  const unsigned t = unsigned(type) < 2u ? unsigned(type) : 2u;
  const unsigned k = t + 1u - unsigned(t == 0u && s.petioleStrength <= s.bladeStrength);
  *angles[k] = bounceAngle(*angles[k], *signs[k], ws, rates[k], dt, limits[k]);
}

}  // namespace tendril::plant
