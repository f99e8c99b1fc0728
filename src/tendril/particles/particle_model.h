// The oriented-particle model ("model": "particles") as seen by scenes and Sessions.
#pragma once

#include "tendril/models/registry.h"
#include "tendril/particles/species.h"
#include "tendril/particles/world.h"

namespace tendril::particles {

struct ParticleParams : models::ModelParams {
  ParticleSpecies species;
};

models::ModelType particleModelType();

// A particle species by built-in name (examples/species/<name>.json with "model":
// "particles") or .json path; errors are located at (source, pointer).
ParticleSpecies loadSpecies(const std::string& nameOrPath, const std::filesystem::path& baseDir,
                            const std::string& source = "species", const std::string& pointer = "");

// The Session-facing system: all particle plants of a scene in one ParticleWorld. Particles
// can be held and pulled, carry new branches and report their strain (handles are particle
// ids), and the world takes the air's push.
class ParticlePlantSystem final : public models::PlantSystem,
                                  public models::Grip,
                                  public models::BranchSeeding,
                                  public models::ObstacleHold,
                                  public models::StrainGauge,
                                  public models::LiveSettings,
                                  public models::GrowthGauge {
 public:
  explicit ParticlePlantSystem(const models::SystemContext& context);
  void addPlant(const models::PlantSpec& spec, const env::Environment& env) override;
  void step(const env::Environment& env) override;
  bool finished() const override { return false; }  // a particle world never stops moving
  size_t plantCount() const override { return world_.plantCount(); }
  plant::PlantModel snapshot(size_t plant) const override { return world_.snapshot(uint32_t(plant)); }
  std::vector<plant::PlantModel> snapshots() const override { return world_.snapshots(); }
  size_t segmentCount() const override { return world_.particleCount(); }
  plant::GrowthFlowSpecies growthFlow(size_t plant) const override { return world_.species(uint32_t(plant)).growthFlow; }
  void saveState(ArchiveWriter& out) const override { world_.saveState(out); }
  void loadState(ArchiveReader& in) override { world_.loadState(in); }
  void setParams(size_t plant, const models::PlantSpec& spec) override;
  // The node's particle and everything beyond it fall and disappear (ParticleWorld::cut).
  void cut(size_t plant, uint32_t node, bool remove) override;

  const models::Grip* grip() const override { return this; }
  const models::BranchSeeding* branchSeeding() const override { return this; }
  const models::ObstacleHold* obstacleHold() const override { return this; }
  const models::StrainGauge* strainGauge() const override { return this; }
  const models::LiveSettings* liveSettings() const override { return this; }
  const models::AirCoupling* airCoupling() const override { return &world_; }
  const models::GrowthGauge* growthGauge() const override { return this; }
  Reading growthReading(size_t plant) const override { return world_.growthReading(uint32_t(plant)); }
  double unhinderedGrowth(size_t plant, uint32_t steps) const override {
    return world_.unhinderedGrowth(uint32_t(plant), steps);
  }
  using models::PlantSystem::airCoupling, models::PlantSystem::branchSeeding, models::PlantSystem::grip,
      models::PlantSystem::liveSettings, models::PlantSystem::obstacleHold, models::PlantSystem::strainGauge;

  // Grip
  std::vector<uint32_t> nodeHandles(size_t plant) const override { return world_.snapshotParticles(uint32_t(plant)); }
  void requireHandle(size_t plant, uint32_t handle, const std::string& what) const override;
  void setDrag(uint32_t handle, const Vec3& target, float strength) override { world_.setDrag(handle, target, strength); }
  void clearDrag() override { world_.clearDrag(); }
  // BranchSeeding
  void seedBranch(size_t plant, uint32_t handle, const Vec3& direction, const std::string& what) override;
  void seedBranchNear(const env::Stroke& stroke) override;
  // ObstacleHold: the particles anchored on the obstacle, and roots seeded on it, move with it.
  size_t obstacleMoving(const env::Environment& env, uint32_t obstacle, const RigidTransform& motion) override {
    return world_.carryWithObstacle(env, obstacle, motion);
  }
  // StrainGauge: branch particles that are not growing apices are judged (particles/dynamics.cpp).
  std::vector<NodeStrain> nodeStrain(size_t plant) const override;
  // LiveSettings: Table 2 of seed 000 and the growth and mechanics settings beside it.
  std::string settingsTitle(size_t plant) const override;
  std::vector<Setting> liveSettings(size_t plant) const override;

  ParticleWorld& world() { return world_; }
  const ParticleWorld& world() const { return world_; }

 private:
  ParticleWorld world_;
};

}  // namespace tendril::particles
