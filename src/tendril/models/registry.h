// What a growth model provides ("model" of a scene plant): a reader for its own keys of a
// plant in a scene file and a PlantSystem that grows all plants of its kind in a Session, with
// the capabilities it has beyond growing (models/capabilities.h). The table of models is
// scene/model_types.h; adding a model is one entry there.
#pragma once

#include "tendril/core/archive.h"
#include "tendril/core/json_reader.h"
#include "tendril/env/environment.h"
#include "tendril/models/capabilities.h"
#include "tendril/plant/plant_model.h"
#include "tendril/models/plant_spec.h"
#include "tendril/plant/growth_flow.h"

#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace tendril::models {

// Every plant of one model in a Session, grown together (e.g. climbing plants see each
// other's crowding; particle plants share one particle world).
class PlantSystem {
 public:
  virtual ~PlantSystem();
  // Adds a plant. Throws Error for bad settings (the Session names the file and pointer).
  virtual void addPlant(const models::PlantSpec& spec, const env::Environment& env) = 0;
  // One step of every plant of this model.
  virtual void step(const env::Environment& env) = 0;
  // True when no plant of this model changes any more.
  virtual bool finished() const = 0;
  virtual size_t plantCount() const = 0;
  // The plant with the given index (in the order added) as a PlantModel.
  virtual plant::PlantModel snapshot(size_t plant) const = 0;
  // Every plant as a PlantModel, in the order added (a model may do it in one pass).
  virtual std::vector<plant::PlantModel> snapshots() const;
  // Skeleton segments of all plants (progress reports).
  virtual size_t segmentCount() const = 0;
  // The plant's Growth-Flow constants (seed 001): how its growth and motion answer the wind.
  virtual plant::GrowthFlowSpecies growthFlow(size_t /*plant*/) const { return {}; }

  // --- sessions (session/session.h) ---
  // Everything that decides this system's future steps. loadState is called on a system that
  // was given the same plants (same specs, in the same order) and overwrites their state, so
  // that stepping on is bit-identical to never having saved. Model settings that come from
  // the plant specs (species, grammars, graphs) are not written: the Session keeps the specs.
  // Damaged input throws Error (from the reader); the system may then be left half-loaded
  // (the Session discards it).
  virtual void saveState(ArchiveWriter& out) const = 0;
  virtual void loadState(ArchiveReader& in) = 0;
  // Live parameter edits: replaces the plant's model settings with spec.params (same model).
  virtual void setParams(size_t plant, const models::PlantSpec& spec);
  // Live edits of a whole plant: replaces its settings with `spec` (same model) and grows it
  // again from its seed to the step it had reached, asking `env` as growth does. Models that
  // cannot regrow change their parameters in place (setParams).
  virtual void regrow(size_t plant, const models::PlantSpec& spec, const env::Environment& /*env*/) {
    setParams(plant, spec);
  }
  // Removes the node's segment and everything beyond it (interactive cuts, seed 000 §5.1): a
  // piece that can fall (particle plants) falls unless `remove` (pruning: it is gone at once).
  // Throws Error for a model that cannot be cut or a node out of range.
  virtual void cut(size_t plant, uint32_t node, bool remove = false);

  // --- capabilities (models/capabilities.h): null where the model does not have one ---
  virtual const Grip* grip() const { return nullptr; }
  virtual const BranchSeeding* branchSeeding() const { return nullptr; }
  virtual const ObstacleHold* obstacleHold() const { return nullptr; }
  virtual const StrainGauge* strainGauge() const { return nullptr; }
  virtual const LiveSettings* liveSettings() const { return nullptr; }
  virtual const AirCoupling* airCoupling() const { return nullptr; }
  virtual const GrowthGauge* growthGauge() const { return nullptr; }
  Grip* grip() { return const_cast<Grip*>(std::as_const(*this).grip()); }
  BranchSeeding* branchSeeding() { return const_cast<BranchSeeding*>(std::as_const(*this).branchSeeding()); }
  ObstacleHold* obstacleHold() { return const_cast<ObstacleHold*>(std::as_const(*this).obstacleHold()); }
  StrainGauge* strainGauge() { return const_cast<StrainGauge*>(std::as_const(*this).strainGauge()); }
  LiveSettings* liveSettings() { return const_cast<LiveSettings*>(std::as_const(*this).liveSettings()); }
  AirCoupling* airCoupling() { return const_cast<AirCoupling*>(std::as_const(*this).airCoupling()); }
};

struct SystemContext {
  uint64_t sceneSeed = 1;
  float stepTime = 1.0f;  // plant age per growth step (s)
};

struct ModelType {
  std::string name;
  std::string description;
  // Reads the model's own keys of a scene plant object (the shared keys are already read;
  // the caller calls finish()). `baseDir` resolves relative paths.
  std::function<std::shared_ptr<const models::ModelParams>(JsonObject& plant, const std::filesystem::path& baseDir)>
      read;
  std::function<std::unique_ptr<PlantSystem>(const SystemContext& context)> createSystem;
  // The scene-plant key that names the plant's model settings (a species preset or file, a
  // grammar, a graph): what seed_plant's "species" fills in.
  std::string settingsKey = "species";
};

}  // namespace tendril::models
