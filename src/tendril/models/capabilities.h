// What a growth model can do beyond growing, as interfaces a PlantSystem implements or not
// (PlantSystem::grip(), branchSeeding(), obstacleHold(), strainGauge(), liveSettings(), airCoupling(),
// growthGauge() return null for a model without that capability). The Session, the edits and the apps ask a plant's system for a
// capability; they never name a model's own types. A new model gets dragging or the air's push
// by implementing the interface.
#pragma once

#include "tendril/core/math.h"
#include "tendril/env/environment.h"
#include "tendril/plant/plant_model.h"

#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace tendril::models {

// A model's own id of a part of a plant that can be held (a particle, for particle plants).
// Handles stay valid while the part exists; they are what edit scripts call "particle".
inline constexpr uint32_t kNoHandle = std::numeric_limits<uint32_t>::max();

// Plants whose parts a user can take hold of and pull (seed 000 §5.1).
class Grip {
 public:
  virtual ~Grip() = default;
  // The handle of each node of the plant's snapshot, in node order (kNoHandle where a node has
  // none).
  virtual std::vector<uint32_t> nodeHandles(size_t plant) const = 0;
  // Throws Error(what, "/particle", …) unless `handle` is a live part of `plant` that can be held.
  virtual void requireHandle(size_t plant, uint32_t handle, const std::string& what) const = 0;
  // Pulls the part toward `target` through a soft constraint of the given strength (0–1),
  // replacing any earlier pull. A part that has broken off and gone is no longer pulled.
  virtual void setDrag(uint32_t handle, const Vec3& target, float strength) = 0;
  virtual void clearDrag() = 0;
};

// Plants that can grow a new branch where the user asks (seed 000 §5.1: "the user paints ...
// new branches sprout").
class BranchSeeding {
 public:
  virtual ~BranchSeeding() = default;
  // A new lateral shoot on the plant's part `handle`, growing along `direction`. Throws
  // Error(what, "/particle", …) for a part that cannot carry one.
  virtual void seedBranch(size_t plant, uint32_t handle, const Vec3& direction, const std::string& what) = 0;
  // An attracting stroke seeds a branch at the full-grown part closest to one of its points
  // (within its radius), toward that point; nothing happens when no part is that close.
  virtual void seedBranchNear(const env::Stroke& stroke) = 0;
};

// Plants that hold on to obstacles (seed 000 eq. 5's anchors): when the user moves an obstacle,
// what holds on to it moves with it (Fig. 9) instead of being left behind in the air.
class ObstacleHold {
 public:
  virtual ~ObstacleHold() = default;
  // Obstacle `obstacle` of `env`, as it stands before the move, is about to move rigidly by
  // `motion` (world to world): the parts held on it move and turn with it. Returns how many.
  virtual size_t obstacleMoving(const env::Environment& env, uint32_t obstacle, const RigidTransform& motion) = 0;
};

// Plants whose connections strain and can break (seed 000 §4.3).
class StrainGauge {
 public:
  virtual ~StrainGauge() = default;
  struct NodeStrain {
    uint32_t handle = kNoHandle;  // the part, or kNoHandle for a node that is not judged
    float strain = 0.0f;          // its connection's strain over the strain at which it breaks
  };
  // Per node of the plant's snapshot, in node order: the strain of its connection to its parent
  // as the breaking rule measures it, as a fraction of the strain at which it breaks (1 breaks;
  // for a species that never breaks, of the species' reference strain).
  virtual std::vector<NodeStrain> nodeStrain(size_t plant) const = 0;
};

// Plants whose model settings can change while they grow, one number at a time (the studio's
// species panel; the change itself is a set_species edit with the setting's key). Values are
// in file units (degrees for angles), keyed as in the plant's scene-file object.
class LiveSettings {
 public:
  virtual ~LiveSettings() = default;
  struct Setting {
    std::string key;    // the species key, e.g. "growth_rate"
    std::string label;  // with its unit, e.g. "growth rate (m/s)"
    std::string group;  // settings of one group are shown together, in order
    bool integer = false;
    double value = 0.0;
    double min = 0.0, max = 1.0;  // a slider's range (the reader's limits may be wider)
    int decimals = 3;             // shown with this many decimals
  };
  // What the settings are of, e.g. "Species ivy-particles".
  virtual std::string settingsTitle(size_t plant) const = 0;
  virtual std::vector<Setting> liveSettings(size_t plant) const = 0;
};

// The bodies of a system's plants that the simulated air pushes and is pushed by (seed 000
// §5.3): ellipsoids with half-axis `halfLength` along their local +Y and `radius` across.
// Arrays are indexed by body slot; `ids` lists the slots taking part, ascending.
struct AirBodies {
  std::span<const uint32_t> ids;
  std::span<const Vec3> position, velocity;
  std::span<const Quat> orientation;
  std::span<const float> halfLength, radius, mass;
  size_t slots = 0;  // length of the arrays
};

class AirCoupling {
 public:
  virtual ~AirCoupling() = default;
  // The bodies as they are now (valid until the system steps or changes).
  virtual AirBodies airBodies() const = 0;
  // Where the air puts its push back: one acceleration per body slot (m/s²), added to the
  // bodies' motion in their next step. The air resizes and overwrites it every frame.
  virtual std::vector<Vec3>& airAcceleration() = 0;
  // The system's physics step (s): the air steps with it.
  virtual float airTimeStep() const = 0;
};

// Plants whose growth can be measured against what their species grows unhindered: how the
// diagnostics (models/diagnosis.h) find a plant that stops in its first steps or stays far
// below its species' size, and what they say about why.
class GrowthGauge {
 public:
  virtual ~GrowthGauge() = default;
  struct Reading {
    bool growing = false;   // some tip of the plant still grows
    bool complete = false;  // it has reached the end its settings give it (a derivation's length)
    double grown = 0.0;     // what the plant has grown, in `unit`
    const char* unit = "m of stem";
    uint32_t steps = 0;       // growth steps since it was seeded
    uint32_t lastGrowth = 0;  // the step (since seeded) in which it last grew
    std::string cap;          // the cap that stopped it, e.g. "max_segments (500)"; empty if none
    // Why the seed's own tip died before its first segment, where the model knows.
    plant::TipEnd seedEnd = plant::TipEnd::Unknown;
    // A climber that dies without support: how near its shoot a surface must be (m; 0 = it
    // needs none), and how far a shoot grows without one before it dies (m).
    float supportReach = 0.0f;
    float unsupportedRun = 0.0f;
    bool lightDriven = false;   // its growth rate follows the light it gets
  };
  virtual Reading growthReading(size_t plant) const = 0;
  // What the plant's species grows in `steps` steps from its seed with nothing in its way (in
  // the reading's unit), or 0 where the model cannot say.
  virtual double unhinderedGrowth(size_t plant, uint32_t steps) const = 0;
};

}  // namespace tendril::models
