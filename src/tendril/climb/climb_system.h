// Climbing growth after seed 003 ("Procedural generation of climbing plants using
// L-systems"): tips extend their branch by one internode segment per step and rules from
// Program 1 / Table 1 turn, shrink, branch, leaf and kill them. The Environment answers every
// geometric question (Embree BVH), which keeps growth nearly flat in the triangle count.
//
// All climbing plants of a scene grow together so that they see each other's crowding. Tips
// are processed in parallel; each writes only its own outcome and draws random numbers keyed
// by (seed, plant, tip, step, purpose), and outcomes are merged in tip order — so the result
// is bit-identical for any thread count.
#pragma once

#include "tendril/climb/occupancy.h"
#include "tendril/climb/species.h"
#include "tendril/core/archive.h"
#include "tendril/core/random.h"
#include "tendril/env/environment.h"
#include "tendril/models/capabilities.h"
#include "tendril/plant/plant_model.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tendril::climb {

struct ClimbPlantDef {
  std::string name;
  ClimbSpecies species;
  Vec3 position = Vec3::Zero();        // seed point (m), must lie outside every obstacle
  Vec3 direction = Vec3::UnitY();      // initial growth direction
  uint64_t seed = 1;                   // the plant's own random seed
};

struct ClimbStats {
  size_t segments = 0;
  size_t leaves = 0;
  size_t aliveTips = 0;
  size_t climbingSegments = 0;
};

class ClimbSystem {
 public:
  // stepTime: seconds of plant age per growth step (node ages in the PlantModel).
  explicit ClimbSystem(uint64_t sceneSeed = 1, float stepTime = 1.0f);
  ~ClimbSystem();
  ClimbSystem(ClimbSystem&&) noexcept;
  ClimbSystem& operator=(ClimbSystem&&) noexcept;

  // Throws Error when the seed lies inside an obstacle (env::seedInsideObstacle).
  uint32_t addPlant(const ClimbPlantDef& def, const env::Environment& env);
  size_t plantCount() const { return plants_.size(); }
  const ClimbPlantDef& plantDef(uint32_t id) const { return plants_[id]->def; }

  // One growth step of every plant (Program 1 for every live tip).
  void step(const env::Environment& env);
  uint32_t stepCount() const { return step_; }
  // True when no plant has a live tip left.
  bool finished() const;

  // The plant as a PlantModel (ages filled in, pipe model applied if the species asks).
  plant::PlantModel snapshot(uint32_t plant) const;
  ClimbStats stats() const;
  ClimbStats stats(uint32_t plant) const;
  // The plant's growth against its species' unhindered main stem (models/diagnosis.h).
  models::GrowthGauge::Reading growthReading(uint32_t plant) const;
  // The length of stem its species' first shoot grows in `steps` steps with nothing in its way.
  double unhinderedGrowth(uint32_t plant, uint32_t steps) const;

  // Obstacle `obstacle` of `env`, as it stands before the move, is about to move by `motion`: a
  // plant seeded on it (its first node's nearest surface) moves with it whole, tips and their
  // supports too. Plants seeded elsewhere keep their nodes where they grew, also those on the
  // obstacle. Returns how many plants moved.
  size_t carryWithObstacle(const env::Environment& env, uint32_t obstacle, const RigidTransform& motion);

  // Removes node `node` of the plant, everything beyond it, their leaves and their tips
  // (interactive cuts); the parent becomes a dead end if nothing else grows from it.
  // Throws Error for a node out of range.
  // A plant that reached max_segments keeps its tips; a cut that leaves it room for a twentieth
  // of the cap again lets them grow on.
  void cut(uint32_t plant, uint32_t node);

  // Every field that decides future steps (sessions, undo). loadState expects the same plants,
  // added with the same definitions; the crowding grid is rebuilt from the segment ends (its
  // answers do not depend on the order of insertion).
  void saveState(ArchiveWriter& out) const;
  void loadState(ArchiveReader& in);

 private:
  struct Tip {
    uint64_t id = 0;
    int32_t lastNode = -1;  // node this tip's next segment hangs from
    Vec3 position = Vec3::Zero();
    Vec3 dir = Vec3::UnitY();
    Vec3 normal = Vec3::UnitZ();  // frame hint: away from the support surface
    float length = 0, radius = 0, leafSize = 0;
    float leafThickness = 0;
    float windAngle = -1.0f;  // Growth-Flow's accumulated growth angle α (eq. 9); < 0: not yet in wind
    float windLength = 1.0f;  // Growth-Flow's eq. 8 factor so far: the shoot's internodes relative to still air
    Vec3 shootStart = Vec3::Zero();  // (radius, length, leaf size) at the shoot's base
    uint32_t segments = 0;
    uint32_t unsupported = 0;  // segments in a row grown without support
    // The closest surface within the adhesion distance of `position` (unfiltered), if any:
    // computed when the previous segment ended there.
    std::optional<env::SurfacePoint> support;
    uint16_t order = 0;
    bool startsBranch = false;
  };
  struct Plant {
    ClimbPlantDef def;
    uint32_t id = 0;
    plant::PlantModel model;
    std::vector<uint32_t> birthStep;
    std::vector<Vec3> nodeEnd;  // where each node's segment ends (its crowding-grid point)
    std::vector<Tip> tips;
    std::vector<Tip> nextTips;  // scratch for the merge
    uint64_t nextTipId = 0;
    bool capped = false;
    // Why the seed's own tip died before its first segment (diagnostics only; not saved: a
    // loaded session finds the cause again from the scene).
    plant::TipEnd seedEnd = plant::TipEnd::Unknown;
  };
  struct Outcome;
  static std::vector<Tip> savedTips(const std::vector<Tip>& tips);  // climb_state.cpp
  struct TipRef {
    uint32_t plant;
    uint32_t tip;
  };

  void growTip(const Plant& plant, const Tip& tip, const env::Environment& env, Outcome& out) const;
  struct Segment {
    Vec3 end, dir;
    std::optional<env::SurfacePoint> endSupport;
  };
  std::optional<Segment> placeSegment(const ClimbSpecies& s, Tip& t, const Vec3& growDir, bool climbing, Rng hold,
                                      const env::Environment& env) const;
  // The PlaceLeaf rule on the segment growTip has just added (out.node, ending at out.end).
  void placeLeaves(const ClimbSpecies& s, const Tip& t, const Vec3& dir,
                   const std::optional<env::SurfacePoint>& endSupport, Rng lr, const env::Environment& env,
                   Outcome& out) const;
  // Applies the plant's outcomes, which start at outcomes_[first]: new nodes, leaves and tips.
  void mergePlant(Plant& plant, size_t first);
  void resumeCappedPlants();
  void rebuildOccupancy();

  uint64_t sceneSeed_;
  float stepTime_;
  uint32_t step_ = 0;
  std::vector<std::unique_ptr<Plant>> plants_;
  OccupancyGrid occupancy_;
  // Per-step scratch, kept to avoid reallocating every step.
  std::vector<TipRef> refs_;
  std::vector<uint32_t> firstOutcome_;  // per plant, + the total
  std::vector<Outcome> outcomes_;
};

}  // namespace tendril::climb
