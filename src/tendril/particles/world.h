// Plants as chains of oriented, anisotropic particles (seed 000: Hädrich, Beneš, Deussen,
// Pirk — Interactive Modeling and Authoring of Climbing Plants).
//
// Every plant's particles live in one set of dense arrays with active/inactive slots that are
// reused, as the paper's single particle buffer. A particle is one internode: an ellipsoid
// with long half-axis `halfLength` along its local +Y (the growth direction) and radius b = c.
// Its group is {parent, itself, children}; each step predicts positions (eq. 1, 16), matches
// the groups' rest shapes (eq. 3, 14–15, with a rotation extraction that stays stable for
// collinear chains) from each piece's root outward, blends the targets into goals (eq. 4) with
// age-dependent stiffness (§4.3), applies anchors (eq. 5), resolves collisions with obstacle
// SDFs and with other particles (§5.2), integrates (eq. 17–20) and breaks over-stretched
// connections (§4.3).
// Growth (§4.2) elongates apices, spawns successors and lateral branches, turns apices toward
// surfaces and light (eq. 6–10), thickens older particles and grows leaves.
//
// Parallel loops write only to their own particle's slots (shape matching: to their own
// connected piece's) and read the previous state, and topology changes are made sequentially in
// particle order: results are bit-identical for any thread count. Random numbers are keyed by (seed, plant, particle, step, purpose).
#pragma once

#include "tendril/core/archive.h"
#include "tendril/env/environment.h"
#include "tendril/models/capabilities.h"
#include "tendril/particles/species.h"
#include "tendril/plant/plant_model.h"

#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace tendril::particles {

inline constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// Spatial hash of a grid cell (Teschner et al. 2003); `mask` is the table size − 1.
inline uint32_t spatialHash(const Eigen::Vector3i& c, uint32_t mask) {
  return (uint32_t(c.x()) * 73856093u ^ uint32_t(c.y()) * 19349663u ^ uint32_t(c.z()) * 83492791u) & mask;
}

enum ParticleFlags : uint32_t {
  kActive = 1u << 0,
  kApex = 1u << 1,      // growing tip of a branch
  kLeaf = 1u << 2,      // a leaf particle (small plants)
  kGrown = 1u << 3,     // reached its full length
  kRoot = 1u << 4,      // a plant's seed particle, held in place
  kDetached = 1u << 5,  // belongs to a piece that broke off
  kResting = 1u << 6,   // a fallen piece that has come to rest
  kAnchored = 1u << 7,  // held to a surface by an anchor
  // Bits 8–11 (plant::kNodeTipEndMask): why a tip stopped (plant::TipEnd), as on snapshot nodes.
};

struct WorldSettings {
  float dt = 0.025f;                  // physics step (s), as in seed 000 §6
  Vec3 gravity = Vec3(0, -9.81f, 0);  // m/s²
  int iterations = 3;                 // shape-matching passes per step
  bool plantCollisions = true;        // plant–plant and self collisions
  uint8_t padding0[3] = {};           // (the world's state is saved as bytes: no padding left unset)
  float restingSpeed = 0.05f;         // a fallen piece moving slower than this (m/s, over a step)...
  float restingTime = 1.0f;           // ...for this long (s) is at rest
  float removeRestingAfter = 3.0f;    // resting pieces disappear after this long (s); 0 keeps them
  uint32_t padding1 = 0;
  uint64_t seed = 1;                  // scene seed
};
static_assert(sizeof(WorldSettings) == 48, "WorldSettings is saved as bytes: make every padding byte a member");

struct StepTimings {
  double growth = 0, dynamics = 0, collisions = 0, breaking = 0;  // seconds of the last step
};

// A leaf attached to a branch particle (large plants): it follows the particle rigidly.
struct AttachedLeaf {
  uint32_t particle = kNone;
  uint8_t padding0[sizeof(Quat) - sizeof(uint32_t)] = {};  // (saved as bytes: no padding left unset)
  Quat particleFromLeaf = Quat::Identity();
  float size = 0.0f;     // current blade length (m)
  float maxSize = 0.0f;  // full-grown blade length (m)
  uint16_t shape = 0;
  uint16_t padding1 = 0;
  float thickness = 0.0f;  // blade thickness (m)
};
static_assert(sizeof(AttachedLeaf) == 2 * sizeof(Quat) + 4 * sizeof(float),
              "AttachedLeaf is saved as bytes: make every padding byte a member");

// The world takes part in the simulated air (models::AirCoupling): its grown branch particles
// (not leaves) are the air's bodies, and the air's push is the external acceleration of eq. 1.
class ParticleWorld final : public models::AirCoupling {
 public:
  // No particle moves faster (m/s). A plant's parts in a 20 m/s gale move at most at the gale's
  // speed and a piece falling 3 m reaches 8 m/s; faster is a drag that fast or the solver
  // amplifying the motion of a long free shoot (docs/particles.md, "Known limits"), which this
  // bounds (a soft plant would otherwise fly to kilometres, past what the spatial hash's cells
  // can address).
  static constexpr float kMaxSpeed = 50.0f;
  explicit ParticleWorld(WorldSettings settings = {});

  // --- plants ---
  // Seeds a plant: a root particle held at `position` and a first apex growing along
  // `direction`. Throws Error when the seed lies inside an obstacle (env::seedInsideObstacle).
  uint32_t addPlant(const std::string& name, const ParticleSpecies& species, const Vec3& position,
                    const Vec3& direction, uint64_t seed, const env::Environment& env);
  size_t plantCount() const { return plants_.size(); }
  const std::string& plantName(uint32_t plant) const { return plants_[plant].name; }
  const ParticleSpecies& species(uint32_t plant) const { return plants_[plant].species; }
  // Replaces a plant's species (live parameter edits).
  void setSpecies(uint32_t plant, const ParticleSpecies& species);

  // --- simulation ---
  void step(const env::Environment& env);
  float time() const { return time_; }
  uint32_t stepCount() const { return step_; }
  const WorldSettings& settings() const { return settings_; }
  void setSettings(const WorldSettings& s) { settings_ = s; }
  const StepTimings& timings() const { return timings_; }
  // External acceleration per particle (e.g. from the SPH wind), added in eq. 1; empty = none.
  std::vector<Vec3>& externalAcceleration() { return externalAcceleration_; }
  // models::AirCoupling: the grown branch particles, and the external acceleration.
  models::AirBodies airBodies() const override;
  std::vector<Vec3>& airAcceleration() override { return externalAcceleration_; }
  float airTimeStep() const override { return settings_.dt; }

  // --- interaction (§5.1) ---
  // Obstacle `obstacle` of `env`, as it stands before the move, is about to move by `motion`
  // (Fig. 9): a plant whose root sits on it moves with it whole, rest shape included (it keeps
  // its shape and strain); elsewhere the particles anchored on it move and turn with it, anchors
  // included, and the shape matching draws the rest of their stems after them. Particles on
  // other surfaces, and plants' stems, stay. Returns how many particles were carried.
  size_t carryWithObstacle(const env::Environment& env, uint32_t obstacle, const RigidTransform& motion);
  // Pulls a particle toward `target` through a soft constraint of the given strength (0–1).
  void setDrag(uint32_t particle, const Vec3& target, float strength);
  void clearDrag();
  // Cuts the connection above `particle`: it and everything beyond it fall and disappear, or,
  // with `remove`, are removed at once (pruning).
  void cut(uint32_t particle, bool remove = false);
  // A new lateral apex on a grown branch particle, growing along `direction`.
  uint32_t seedBranch(uint32_t particle, const Vec3& direction);
  // Removes detached pieces that have come to rest (also done automatically, see settings).
  void removeRestingPieces();

  // --- queries ---
  size_t capacity() const { return flags_.size(); }
  size_t particleCount() const { return active_; }
  size_t particleCount(uint32_t plant) const;
  bool active(uint32_t i) const { return flags_[i] & kActive; }
  uint32_t flags(uint32_t i) const { return flags_[i]; }
  uint32_t plantOf(uint32_t i) const { return plant_[i]; }
  uint32_t parent(uint32_t i) const { return parent_[i]; }
  const Vec3& position(uint32_t i) const { return x_[i]; }
  const Quat& orientation(uint32_t i) const { return q_[i]; }
  const Vec3& velocity(uint32_t i) const { return v_[i]; }
  const Vec3& restPosition(uint32_t i) const { return xr_[i]; }
  float halfLength(uint32_t i) const { return a_[i]; }
  float radius(uint32_t i) const { return b_[i]; }
  float mass(uint32_t i) const { return m_[i]; }
  float age(uint32_t i) const { return age_[i]; }
  // The same per particle slot, as whole arrays (capacity() entries each).
  std::span<const Vec3> positions() const { return x_; }
  std::span<const Vec3> velocities() const { return v_; }
  std::span<const Quat> orientations() const { return q_; }
  std::span<const float> halfLengths() const { return a_; }
  std::span<const float> radii() const { return b_; }
  std::span<const float> masses() const { return m_; }
  // Strain of the connection to the parent (§4.3): max(0, d − (a + a_parent)) / (a + a_parent),
  // how far the two centres are pulled apart beyond the connection's length as grown (the
  // particles end to end; a root reaches its radius if that is more than its half length),
  // relative to it (0 for roots). Breaking compares it with breakingStrain(species); the
  // studio's stress colours show it.
  float strain(uint32_t i) const;
  // Whether breaking judges particle i's connection to its parent: a connection of a grown
  // particle. Growing ones (apices, young leaves) are not judged: a particle a few millimetres
  // long, placed on its parent's head as it lengthens and pushed off a surface by collisions,
  // shows large relative strain from tiny displacements (young leaves on an ivy on a wall
  // read 0.4 and broke off within 15 s).
  bool judgedForBreaking(uint32_t i) const {
    return (flags_[i] & kActive) && (flags_[i] & kGrown) && parent_[i] != kNone;
  }
  // The plant's growth against its first apex's unhindered growth (models/diagnosis.h).
  models::GrowthGauge::Reading growthReading(uint32_t plant) const;
  double unhinderedGrowth(uint32_t plant, uint32_t steps) const;
  // The particle's tip ("head"): where its successor attaches.
  Vec3 head(uint32_t i) const { return x_[i] + q_[i] * Vec3(0, a_[i], 0); }
  const std::vector<AttachedLeaf>& attachedLeaves() const { return leaves_; }
  double kineticEnergy() const;  // J, translational + rotational, over all active particles

  // The plant as a PlantModel; detached pieces that belong to it come out as extra roots with
  // kNodeBroken.
  plant::PlantModel snapshot(uint32_t plant) const;
  // Every plant's snapshot in plant order, the same as snapshot(p) for each p but in one pass
  // over the particle buffer instead of one per plant (the studio draws every frame).
  std::vector<plant::PlantModel> snapshots() const;
  // The particle of each node of snapshot(plant), in node order.
  std::vector<uint32_t> snapshotParticles(uint32_t plant) const;

  // --- state (world_state.cpp) ---
  // Every field that decides future steps (the list is in world_state.cpp: a field added to
  // this class must be added there). loadState expects the same plants, added with the same
  // species; their species are not written (the Session keeps the plant specs).
  void saveState(ArchiveWriter& out) const;
  void loadState(ArchiveReader& in);

 private:
  template <class Self, class Visit>
  static void visitState(Self& self, Visit&& visit);
  struct Plant {
    std::string name;
    ParticleSpecies species;
    uint64_t seed = 1;
    uint32_t root = kNone;
    size_t particles = 0;
    bool capped = false;
  };

  // What a snapshot walks besides the plant's tree: its broken-off pieces' roots and its leaf
  // particles in slot order, and its attached leaves in leaves_ order.
  struct SnapshotParts {
    std::vector<uint32_t> brokenRoots, leafParticles, attachedLeaves;
    size_t branchParticles = 0;  // active particles that are not leaves: at most this many nodes
  };
  // `node` (capacity() entries) receives the node index of every particle of the plant.
  plant::PlantModel snapshotFrom(uint32_t plant, const SnapshotParts& parts, std::vector<int32_t>& node) const;

  bool hasBranchChild(uint32_t i) const;  // a child that is not a leaf particle
  uint32_t allocate();
  void release(uint32_t i);
  void link(uint32_t parent, uint32_t child);
  void unlink(uint32_t child);
  void updateMass(uint32_t i);
  float stiffnessOf(uint32_t i) const;
  // Orientations by value: callers pass elements of arrays that allocate() may reallocate.
  uint32_t spawn(uint32_t plant, uint32_t parent, Quat orientation, Quat restOrientation,
                 float radius, uint32_t flags);
  void markDetached(uint32_t root);

  // phases (dynamics.cpp, growth.cpp, collisions.cpp)
  void grow(const env::Environment& env);
  // A plant stopped at its particle cap grows on once it has room again (see grow()).
  void resumeCappedPlants();
  // The most particles one growth of an apex adds to its plant (max_particles is kept with it).
  size_t particlesPerGrowth(const Plant& pl) const;
  struct ApexUpdate;  // what an apex decided (growth.cpp)
  void decideApex(uint32_t i, const env::Environment& env, ApexUpdate& u) const;
  void applyApex(uint32_t i, const ApexUpdate& u, const env::Environment& env);
  void placeOnParent(uint32_t i);  // eq. 10, after the particle grew or turned
  void growLeaves();
  void attachLeavesOfLargePlants();
  void thicken();  // secondary growth
  void predict();
  void shapeMatch();
  void gatherMatchRest();          // shapeMatch()'s fixed part of a step
  void matchOne(uint32_t k);       // one particle's fit (piece order k)
  void matchFour(uint32_t k);      // the same for k … k + 3, one per SIMD lane
  void applyAnchors(const env::Environment& env);
  void collideObstacles(const env::Environment& env);
  void collideParticles();
  // Eq. 17–20, each particle's speed held to kMaxSpeed (speedLimited_ marks those held).
  void integrate();
  // Warns once per plant whose particles were held to kMaxSpeed (see integrate()).
  void reportSpeedLimit();
  void breakConnections();
  void updateRestingPieces(const env::Environment& env);
  // Broken-off particles this far (m) below the lowest obstacle and plant root have fallen off
  // the world (updateRestingPieces()).
  static constexpr float kFallenOffDepth = 10.0f;
  void buildOcclusion(const env::Environment& env);
  float occlusion(const Vec3& p, const Vec3& towardLight) const;
  // Stems of other branches within `radius` of particle i: their count and the sum of unit
  // vectors from them to i (from the last collision pass's spatial hash).
  Vec3 crowdAway(uint32_t i, float radius, int* count) const;

  WorldSettings settings_;
  std::vector<Plant> plants_;
  float time_ = 0.0f;
  uint32_t step_ = 0;
  size_t active_ = 0;
  StepTimings timings_;

  // Hot state, one slot per particle (structure of arrays).
  std::vector<Vec3> x_, xp_, v_, w_, xr_;
  std::vector<Quat> q_, qp_, qr_, groupRotation_;
  std::vector<float> a_, b_, m_, age_;
  std::vector<uint32_t> flags_, plant_, parent_, firstChild_, nextSibling_;
  // How far a particle's centre keeps off obstacles: its bark's clearance
  // (models::barkClearance) and a little more for rounding. Collisions push to it; anchors hold
  // at it.
  float contactDistance(uint32_t i) const;
  // Sets the anchor's point at the particle's contact distance off its support (anchor_ below);
  // an anchor without a normal keeps its point.
  void placeAnchor(uint32_t i);
  // Cold(er) per-particle state.
  std::vector<float> targetHalfLength_, restTime_;
  // Eq. 5's anchor: the point the particle's centre is pulled to (anchor_), set each step at its
  // bark's clearance (contactDistance) off the support point under it (anchorSupport_) along
  // the support's outward normal there (anchorNormal_), so that an anchored particle that
  // thickens is held where collisions keep it, not pulled into its support. A zero normal
  // keeps anchor_ where it was set (worlds saved before the support was kept).
  std::vector<Vec3> anchor_, anchorSupport_, anchorNormal_;
  std::vector<float> anchorPhi_;
  std::vector<uint32_t> branchIndex_;  // position along its branch (leaf step, phyllotaxis)
  std::vector<uint16_t> order_;        // branch order
  std::vector<uint16_t> leafShape_;
  std::vector<float> leafTarget_;      // leaf particles: full-grown blade length
  // Growth-Flow (seed 001) state of the internode a particle is, relative to still air: its
  // accumulated growth angle α (eq. 9; < 0 before the first windy internode), its length
  // factor (eq. 8, times the species' particle length) and the factors of eq. 17 and 16 its
  // leaves grow with; the radius (eq. 7) lives in b_. Successors and laterals inherit it,
  // times one step of wind. `turn` takes the internode's still-air orientation (the one its
  // tropisms steer) to the one it grows in: Algorithm 1's rotation by the whole of α about
  // b × w (identity for a lineage that never grew in wind).
  struct FlowState {
    float angle = -1.0f;
    float length = 1.0f;
    float leafSize = 1.0f;
    float leafThickness = 1.0f;
    Quat turn = Quat::Identity();
  };
  std::vector<FlowState> flow_;
  std::vector<uint32_t> freeList_;
  std::vector<Vec3> externalAcceleration_;
  std::vector<AttachedLeaf> leaves_;

  // Scratch for the parallel passes.
  std::vector<Vec3> goal_, correction_;
  std::vector<uint8_t> speedLimited_;  // integrate(): held to kMaxSpeed this step
  std::vector<uint8_t> speedWarned_;   // per plant: reportSpeedLimit() has warned
  // Obstacle collisions: what the last distance samples of each particle proved about the
  // field around it, valid while the obstacles stay where they were (see collideObstacles()).
  struct Clearance {
    Vec3 centre = Vec3::Zero(), axis = Vec3::Zero();  // where it was sampled
    float centreDistance = -std::numeric_limits<float>::infinity();  // field at the centre
    float distance = -std::numeric_limits<float>::infinity();        // lower bound at the three samples
  };
  struct ObstacleState {
    RigidTransform worldFromLocal;
    Bounds3 localBounds;
    size_t triangles = 0;
  };
  std::vector<Clearance> clearance_;
  std::vector<ObstacleState> clearanceObstacles_;
  const env::Environment* clearanceEnv_ = nullptr;
  uint64_t clearanceStems_ = 0;  // the environment's stemRevision() and whether stems were seen
  // Shape matching runs on copies of the particles in piece order: connected pieces one after
  // the other, each root first and breadth first, so that a particle's parent comes before it
  // and its children are contiguous. The order is rebuilt only when the topology changes.
  struct MatchNode {   // rewritten by every pass
    Vec3 x;            // predicted position x_p
    Quat q;            // predicted orientation q_p
    Quat rotation;     // its group's rotation R (warm start of the extraction)
    Quat frame;        // q_p q̄⁻¹: the particle's own rotation, its children's parent frame
    Mat3 moment;       // eq. 15's ellipsoid moment R_i · restMoment
  };
  struct MatchRest {   // fixed during a step
    Vec3 restOffset = Vec3::Zero();  // x̄ − c̄ of its own group
    Vec3 fromParent = Vec3::Zero();  // x̄ − x̄_parent
    Quat qr = Quat::Identity();
    Mat3 restMoment = Mat3::Zero();  // m/5 · diag(b², a², b²) R̄ᵀ
    float matchMass = 0, invGroupMass = 0;
    float ownWeight = 1, parentWeight = 0;  // eq. 4's weights of its own and its parent's group, normalised
    float stiffness = 1, phi = 0;           // §4.3 stiffness; eq. 5 anchor pull (0: none)
    Vec3 anchor = Vec3::Zero();
    uint32_t parent = kNone, childBegin = 0, childEnd = 0;  // in piece order
  };
  void buildPieceOrder(std::vector<uint32_t>& start, std::vector<uint32_t>& order, std::vector<uint32_t>& parent,
                       std::vector<uint32_t>& childBegin, std::vector<uint32_t>& childEnd) const;
  std::vector<uint32_t> pieceStart_, pieceOrder_;  // piece order: slot of each entry, pieces' starts
  std::vector<uint32_t> matchParent_, matchChildBegin_, matchChildEnd_;
  std::vector<MatchNode> matchNode_;
  std::vector<MatchRest> matchRest_;
  uint64_t topologyVersion_ = 0, pieceOrderVersion_ = ~uint64_t(0);  // links changed / order built for
  std::vector<uint32_t> hashParticles_, hashBucket_, hashStart_, hashEntries_;
  float hashInv_ = 0.0f;  // 1 / cell size of the spatial hash
  // Scratch of collideParticles(), rewritten before it is read in every step (not saved;
  // kept from step to step only to spare the allocation).
  struct HashPacked {
    Eigen::Vector3i cell;
    Vec3 x;
    float reach;
  };
  // What the contact itself reads of the particle, in the same table order: the ends of its
  // axis, its radius and mass, the two particles above it and whether it is held (anchored or a
  // root): one record in place of reads from eight arrays at the particle's slot.
  struct HashContact {
    Vec3 a, b;  // x_p ∓ q_p (0, a, 0)
    float radius, mass;
    uint32_t particle, parent, grandparent, held;
  };
  std::vector<uint32_t> hashFill_;
  std::vector<HashPacked> hashPacked_;
  std::vector<HashContact> hashContact_;
  std::vector<float> nextRadius_;  // scratch of grow()'s secondary growth (not saved)
  mutable std::vector<uint32_t> airIds_;  // airBodies()' list, rebuilt by each call (not saved)

  // Interaction.
  uint32_t dragParticle_ = kNone;
  Vec3 dragTarget_ = Vec3::Zero();
  float dragStrength_ = 0.0f;

  // Plant occlusion grid for phototropism (Fig. 11): leaf and branch area per cell.
  struct Occlusion {
    Vec3 origin = Vec3::Zero();
    float cell = 0.1f;
    Eigen::Vector3i dims = Eigen::Vector3i::Zero();
    std::vector<float> density;
  } occlusion_;
};

}  // namespace tendril::particles
