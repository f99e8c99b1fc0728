// Growth-Flow motion (seed 001 §3.1.1, §3.2.1) for any PlantModel: branches sway about their
// node centres, leaves bend, twist and vibrate, and leaves tear off in a wind above their
// strength. Works on every model's output (climbing, L-system, graph, particle snapshots).
//
// Branch sway, eq. 1 as dynamics. For node i (a segment from p_i along b_i, b the vector from
// the node to the segment's centre of gravity) eq. 1 gives the torque N = (F_w + K + R + T_r) × b:
// F_w is the wind's drag on the segment and its leaves (½ ρ C_d A |w⊥| w⊥), T_r the force its
// child branches pass back (their F_w + T_r, with its moment about p_i), K the resistivity and
// R the axial damping. We read K as the rotational spring of the segment, k = E π r⁴ / (4 l)
// (a beam of Young's modulus E), and R as a damper c = 2 ζ √(k I) (ζ: the species' sway
// damping), so that the node's sway, a rotation vector θ about p_i perpendicular to b, obeys
//     I θ'' + c θ' + k θ = τ(t),   τ = the wind's and the children's moment about p_i, less its
//                                       twist about b,
// where I is the moment of inertia about p_i of what the node carries: its own segment (m l² / 3)
// and every segment and leaf further out (point masses at their centres of gravity; a segment's
// mass is its wood, ρ_wood π r² l, a leaf's the species' leaf mass — the paper sets a branch to
// 10 leaves "arbitrarily", we weigh the wood). The natural period 2π √(I / k) is kept within
// [kMinSwayPeriod, kMaxSwayPeriod] by scaling I (the static deflection τ / k is unchanged), so
// that sway stays visible and calm for extreme species. Frame to frame the ODE is solved
// exactly for the torque held over the frame (the damped oscillator's closed form), so the
// integration is stable for any frame length; a step in wind gives the damped response that
// overshoots and settles at θ* = τ / k, and gusts keep the branch swinging toward the wind and
// back: §3.1.1's ease-in/ease-out is the result. A node turns at most maxSwayAngle, and never
// past the wind (its angle to the wind, acos(b̂·ŵ), less what its parents turned toward it).
// Nodes growing on a support (kNodeClimbing, kNodeAnchored) are held by it and do not sway;
// their free children do.
//
// Sway in a loop. With loopSeconds > 0 the wind repeats (gusts read on a circle in noise space),
// and the node's sway is the periodic solution of the same ODE: the torque over one loop,
// sampled kLoopSamples times, as a Fourier series of kLoopHarmonics harmonics, each answered by
// the oscillator's frequency response. So the clip repeats exactly, at any frame rate.
//
// Leaves. Each frame every leaf gets one random motion type and a gust fraction l_s ∈
// [gustMin, 1] of the wind at its node; eq. 10–15 move its angles (growth_flow.h). The type
// follows §3.2.1's rule (plant::leafMotionChances): a blade facing the wind bends, one oblique
// to it twists, one parallel to it vibrates, drawn with chances from the angle between the
// blade's rest normal and the wind at its node (Algorithm 2 draws 1/3 each). A leaf's posed
// rotation is its rest rotation · R_Y(ψ) · R_X(θ + φ) (twist about the petiole, petiole bend and vibration
// about the blade's width axis at the petiole); the blade bend β goes to leafMotion.x, where
// the leaf mesh curls the blade, and leafMotion = (β, ψ, φ). Detached leaves are left out of
// the posed plant from then on.
//
// Leaves in a loop. Algorithm 2's random choice per frame does not repeat, so with
// loopSeconds > 0 each of a leaf's three motions (the bend — of the petiole or of the blade, as
// Algorithm 2 picks —, the twist and the vibration) is the triangle wave eq. 10–15 trace when
// the angle bounces between ±limit at the mean speed Algorithm 2 gives it: w · rate · (1 +
// gustMin) / 2 (the mean gust fraction l_s) · the leaf's chance of that motion (above). Per
// plant and motion the wave makes a whole number of cycles per loop, the number nearest the
// median moving leaf's; a leaf's
// amplitude is what its own speed covers in a quarter period, at most the limit (leaves in
// calmer air move less), and its phase is one of kLeafPhases quarters, drawn per leaf and
// motion. w is the steady wind at the leaf's node (the prevailing wind and the emitters, or the
// simulated air at t = 0); leaves whose steady wind exceeds their strength are torn off from
// the first frame. The glTF clip carries exactly this motion as morph targets (gltf_animation.h).
//
// Results depend only on the rest plant, the wind, the seed and the frames stepped (their
// times and lengths): random choices are keyed by (seed, leaf, frame).
#pragma once

#include "tendril/env/wind_field.h"
#include "tendril/core/match_lanes.h"
#include "tendril/plant/plant_model.h"
#include "tendril/plant/growth_flow.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace tendril::wind {

// The periodic leaf motion of a looping clip (see above). Motions: 0 bend, 1 twist, 2 vibrate.
struct LeafLoop {
  static constexpr int kPhases = 4;
  int cycles[3] = {1, 1, 1};   // per motion: whole cycles per loop
  bool bendsBlade = false;     // the bend moves the blade (β), not the petiole (θ)
  struct Leaf {
    float amplitude[3] = {0, 0, 0};  // rad; all 0 for a leaf torn off
    uint8_t phase[3] = {0, 0, 0};    // the wave starts phase / kPhases of a cycle ahead
    bool torn = false;
  };
  std::vector<Leaf> leaves;
  // The wave of motion `kind` in phase group `phase` at time t: in [−1, 1], a leaf's angle is its
  // amplitude times this.
  float wave(int kind, int phase, float t, float loopSeconds) const;
  // A leaf's motion state at time t.
  plant::LeafMotionState state(size_t leaf, float t, float loopSeconds) const;
};
// The triangle wave of period 1: 0 at x = 0, rising to 1 at ¼, −1 at ¾.
float triangleWave(float x);

// A posed leaf from its rest rotation and motion state: rotation = rest · R_Y(ψ) · R_X(θ + φ),
// motion = (β, ψ, φ) (the leaf mesh curls the blade by β).
void poseLeaf(const Quat& restRotation, const plant::LeafMotionState& leaf, Quat& rotation, Vec3& motion);

struct MotionSettings {
  float airDensity = 1.25f;  // kg/m³
  float gustMin = 0.3f;      // a leaf feels between gustMin and all of the wind each frame
  // > 0: sway repeats exactly after this many seconds (periods rounded to divide it, gusts
  // periodic); for looping animation clips.
  float loopSeconds = 0.0f;
  uint64_t seed = 1;
};

inline constexpr float kMinSwayPeriod = 0.4f, kMaxSwayPeriod = 6.0f;  // s
inline constexpr int kLoopSamples = 32, kLoopHarmonics = 8;

class WindMotion {
 public:
  WindMotion(const plant::PlantModel& rest, const plant::GrowthFlowSpecies& species, MotionSettings settings = {});

  // Advances one frame to time t (s) with frame length dt and writes the posed plant (the rest
  // plant with swayed nodes and moved leaves; detached leaves left out). Without a loop the
  // sway integrates eq. 1 over dt under the wind at t (dt ≤ 0: the pose is recomposed only);
  // in a loop it is the periodic solution at t, whatever frames came before. Pass the same
  // `posed` frame after frame and leave it unchanged in between: what does not move (lengths, radii,
  // topology, primitive meshes) is copied from the rest plant only into a new `posed`.
  void step(float t, float dt, const env::WindField& wind, plant::PlantModel& posed);

  // The plant changed (it grew, or was edited): carry on with `rest` as the rest plant. Nodes
  // and leaves that still exist (by index) keep their motion state.
  void setRest(const plant::PlantModel& rest);

  // Node i's sway angle in the last step (rad), as posed (after the limits).
  float swayAngle(size_t i) const { return angle_[internal_[i]]; }
  // Node i's sway state: its rotation vector θ and angular velocity θ' (before the limits),
  // and the coefficients of its eq. 1: I (kg m², after the period limits), c, k.
  Vec3 swayVector(size_t i) const;
  Vec3 swayVelocity(size_t i) const;
  float inertia(size_t i) const { return inertia_[internal_[i]]; }
  float damping(size_t i) const { return damping_[internal_[i]]; }
  float stiffness(size_t i) const { return stiffness_[internal_[i]]; }
  // The torque τ on node i in the last step (its moment less the twist about b), N m.
  Vec3 torque(size_t i) const { return torque_[internal_[i]]; }
  const std::vector<plant::LeafMotionState>& leaves() const { return leaves_; }
  // The leaves' periodic motion of a looping clip, made at the first step or by
  // prepareLeafLoop (empty before, and without a loop).
  const LeafLoop& leafLoop() const { return leafLoop_; }
  // Makes the loop's leaf motion for `wind` now (once; the first step would), and returns it.
  const LeafLoop& prepareLeafLoop(const env::WindField& wind);
  uint32_t frame() const { return frame_; }
  const plant::PlantModel& rest() const { return rest_; }
  // Posed rigid transform of node i's subtree in the last step: x ↦ rotation·x + translation.
  const Quat& nodeRotation(size_t i) const { return Q_[internal_[i]]; }
  // Computed when asked (the step itself carries positions, not translations).
  std::vector<Vec3> nodeTranslation() const;

 private:
  // What composing node i reads, in one record (one cache line): its rest frame, and the
  // direction of the wind relative to it (set by computeTorques; kept while the wind is uniform
  // and unchanged, as it then depends only on the rest plant).
  struct alignas(64) SwayNode {
    Quat restOrientation;  // normalised
    Vec3 offset;           // rest position minus the parent's (a root: its rest position)
    int32_t parent;        // internal index (see order_)
    Vec3 axis;             // unit b × w: turning about it is turning toward the wind
    float sinToWind;       // |b̂ × ŵ|; 0: no wind across the node (or held)
    float cosToWind;       // b̂ · ŵ
  };
  // Eq. 1's state for nodes 4b … 4b + 3, lane l for node 4b + l: the rotation vector θ, its
  // rate θ', the θ* = τ / k this frame's torque balances, and the exact one-frame solution:
  // with y = θ − θ*, (y, θ') ← (a·y + b·θ', c·y + d·θ').
  struct SwayBlock {
    lanes::V3 theta, omega, target;
    lanes::F4 a, b, c, d;
  };
  // What composing reads of the sway: its unit axis and angle (at most the species' limit).
  struct AxisAngle {
    Vec3 axis;
    float angle;
  };
  // Where composing has got to: node i's posed position and the angle turned from the root.
  struct Pose {
    Vec3 position;
    float turned;
  };

  void computeTorques(float t, const env::WindField& wind);
  void prepareSteps(float dt);
  void prepareSwayLoop(const env::WindField& wind);
  void evaluateSwayLoop(float t);
  // Advances eq. 1 one frame (with `integrate`), then sets swayAxisAngle_ from θ.
  void advance(bool integrate);
  void compose(plant::PlantModel& posed);

  plant::PlantModel rest_;
  plant::GrowthFlowSpecies species_;
  MotionSettings settings_;
  uint32_t frame_ = 0;

  // Nodes are kept in the order the passes visit them (the top part, then task after task):
  // node i of the plant is internal node internal_[i], internal node k is the plant's order_[k].
  // Every per-node array (nodes_ and those below) is in internal order.
  std::vector<uint32_t> order_;
  std::vector<uint32_t> internal_;
  std::vector<SwayNode> nodes_;
  // Per node, from the rest pose, for the torques.
  std::vector<float> stiffness_;   // k (N·m/rad)
  std::vector<float> inertia_;     // I (kg·m²), within the period limits
  std::vector<float> damping_;     // c (N·m·s/rad)
  std::vector<uint8_t> held_;      // held by a support: never sways
  std::vector<Vec3> centre_;       // centre of gravity of the segment (world, rest)
  // The drag's inputs for nodes 4b … 4b + 3, lane l for node 4b + l: b̂, the lever from the
  // node to the centre of gravity, the projected areas of the segment (2 r l) and of its
  // leaves, and whether the node may sway (not held by a support: all bits set).
  struct DragBlock {
    lanes::V3 direction, lever;
    lanes::F4 stemArea, leafArea;
    lanes::M4 free;
  };
  std::vector<DragBlock> dragBlocks_;
  // Per node, per step (torques only when the wind is not uniform or changed).
  std::vector<Vec3> force_;        // F_w + T_r
  std::vector<Vec3> moment_;       // moment of F_w + T_r about the node
  std::vector<Vec3> torque_;       // moment_ less its twist about b (0 for held nodes)
  std::vector<float> speed_;       // the wind speed at the node's centre of gravity
  std::vector<Vec3> windAt_;       // ... and the wind there
  env::GustSampler gusts_;         // the wind's gusts at centre_ (non-uniform wind, not looped)
  bool uniformCached_ = false;     // nodes_' sway and speed_ are those of a uniform `uniformWind_`
  Vec3 uniformWind_ = Vec3::Zero();
  // The sway's state, four nodes to a block, and the one-frame solution for frames of length
  // stepDt_.
  std::vector<SwayBlock> sway_;
  std::vector<AxisAngle> swayAxisAngle_;  // per node
  float stepDt_ = -1.0f;
  // A loop's periodic sway: per node the mean and, per harmonic h = 1 … kLoopHarmonics, the
  // cosine and sine coefficients of θ (node k's at k · (1 + 2 kLoopHarmonics)).
  std::vector<Vec3> loopSway_;
  bool swayLoopReady_ = false;
  std::vector<float> angle_;
  std::vector<Quat> Q_;
  std::vector<Pose> pose_;
  // The tree split for parallel passes over parents and children: subtrees of at most a few
  // thousand nodes (tasks, their nodes in index order) hang below a top part. Every node's
  // arithmetic, sums over children included, happens in the same order as a sequential pass,
  // so results do not depend on the split or the thread count.
  size_t topCount_ = 0;               // internal nodes [0, topCount_): not in any task
  std::vector<uint32_t> mergeNodes_;  // top nodes and task roots (internal), by plant index
  std::vector<uint32_t> taskStart_;   // task k: internal nodes topCount_ + [taskStart_[k], taskStart_[k + 1])
  // Per leaf.
  std::vector<plant::LeafMotionState> leaves_;
  std::vector<Quat> leafRest_;     // rest rotation, normalised
  std::vector<Vec3> leafNormal_;   // the blade's normal at rest (world)
  std::vector<uint32_t> leafNode_; // the (internal) node the leaf hangs on
  std::vector<uint64_t> leafKey_;  // random key of the leaf's motion; each frame mixes in its number
  std::vector<uint32_t> kept_;     // leaves still attached, in order
  std::vector<uint32_t> slot_;     // per leaf: its index in kept_ (the posed plant's leaf)
  LeafLoop leafLoop_;
  bool leafLoopReady_ = false;
  const plant::PlantModel* posedFor_ = nullptr;  // `posed` last written, its rest arrays copied
};

namespace detail {
// Tests: the drag pass four nodes at a time (the default) or one at a time; both give the same
// bits.
void setDragLanes(bool on);
}  // namespace detail

// Climbers on swaying hosts (plants as supports). Per node of a climber: its nearest node at or
// above it that clings to a host (hostPlant >= 0), or -1.
std::vector<int32_t> clingingCarriers(const plant::PlantModel& rest, const std::vector<int32_t>& hostPlant);
// Carries a posed climber with its host: each node whose carrier a clings to host node h is
// moved by h's posed rigid motion, x ↦ Q_h (x − rest_h) + posed_h, applied to a's rest position,
// and keeps its pose relative to a turned by Q_h Q_a⁻¹ (Q_a: a's rotation in the climber's own
// motion `own`, which posed `climber`). `host(h)` gives host plant h's motion and posed plant,
// or {null, null} for a host that does not sway (its nodes are left as `own` posed them).
struct HostPose {
  const WindMotion* motion = nullptr;
  const plant::PlantModel* posed = nullptr;
};
void carryWithHosts(plant::PlantModel& climber, const WindMotion& own, const std::vector<int32_t>& carriers,
                    const std::vector<int32_t>& hostPlant, const std::vector<int32_t>& hostNode,
                    const std::function<HostPose(size_t)>& host);

}  // namespace tendril::wind
