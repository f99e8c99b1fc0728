// The oriented-particle model ("model": "particles") as seen by scenes and Sessions.
#pragma once

#include "tendril/models/registry.h"
#include "tendril/particles/species.h"
#include "tendril/particles/world.h"

namespace tendril::particles {

struct ParticleParams : scene::ModelParams {
  ParticleSpecies species;
};

models::ModelType particleModelType();

// A particle species by built-in name (examples/species/<name>.json with "model":
// "particles") or .json path; errors are located at (source, pointer).
ParticleSpecies loadSpecies(const std::string& nameOrPath, const std::filesystem::path& baseDir,
                            const std::string& source = "species", const std::string& pointer = "");

// The Session-facing system: all particle plants of a scene in one ParticleWorld.
class ParticlePlantSystem final : public models::PlantSystem {
 public:
  explicit ParticlePlantSystem(const models::SystemContext& context);
  void addPlant(const scene::PlantSpec& spec, const env::Environment& env) override;
  void step(const env::Environment& env) override;
  bool finished() const override { return false; }  // a particle world never stops moving
  size_t plantCount() const override { return world_.plantCount(); }
  plant::PlantModel snapshot(size_t plant) const override { return world_.snapshot(uint32_t(plant)); }
  std::vector<plant::PlantModel> snapshots() const override { return world_.snapshots(); }
  size_t segmentCount() const override { return world_.particleCount(); }
  wind::GrowthFlowSpecies growthFlow(size_t plant) const override { return world_.species(uint32_t(plant)).growthFlow; }
  void saveState(ArchiveWriter& out) const override { world_.saveState(out); }
  void loadState(ArchiveReader& in) override { world_.loadState(in); }
  void setParams(size_t plant, const scene::PlantSpec& spec) override;
  // The node's particle and everything beyond it fall and disappear (ParticleWorld::cut).
  void cut(size_t plant, uint32_t node) override;
  ParticleWorld& world() { return world_; }
  const ParticleWorld& world() const { return world_; }

 private:
  ParticleWorld world_;
};

}  // namespace tendril::particles
