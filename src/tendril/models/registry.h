// The growth models a scene can use ("model" of a scene plant): each reads its own keys of a
// plant from the scene file and grows all plants of its kind in a Session. Adding a model is
// one entry in models/builtin_models.cpp.
#pragma once

#include "tendril/core/archive.h"
#include "tendril/core/json_reader.h"
#include "tendril/env/environment.h"
#include "tendril/plant/plant_model.h"
#include "tendril/scene/plant_spec.h"
#include "tendril/wind/growth_flow.h"

#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace tendril::models {

// Every plant of one model in a Session, grown together (e.g. climbing plants see each
// other's crowding; particle plants share one particle world).
class PlantSystem {
 public:
  virtual ~PlantSystem() = default;
  // Adds a plant. Throws Error for bad settings (the Session names the file and pointer).
  virtual void addPlant(const scene::PlantSpec& spec, const env::Environment& env) = 0;
  // One step of every plant of this model.
  virtual void step(const env::Environment& env) = 0;
  // True when no plant of this model changes any more.
  virtual bool finished() const = 0;
  virtual size_t plantCount() const = 0;
  // The plant with the given index (in the order added) as a PlantModel.
  virtual plant::PlantModel snapshot(size_t plant) const = 0;
  // Every plant as a PlantModel, in the order added (a model may do it in one pass).
  virtual std::vector<plant::PlantModel> snapshots() const {
    std::vector<plant::PlantModel> out;
    out.reserve(plantCount());
    for (size_t i = 0; i < plantCount(); ++i) out.push_back(snapshot(i));
    return out;
  }
  // Skeleton segments of all plants (progress reports).
  virtual size_t segmentCount() const = 0;
  // The plant's Growth-Flow constants (seed 001): how its growth and motion answer the wind.
  virtual wind::GrowthFlowSpecies growthFlow(size_t /*plant*/) const { return {}; }

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
  virtual void setParams(size_t /*plant*/, const scene::PlantSpec& spec) {
    throw Error("", "", "plants of model \"" + spec.model + "\" cannot change their settings while growing");
  }
  // Live edits of a whole plant: replaces its settings with `spec` (same model) and grows it
  // again from its seed to the step it had reached, asking `env` as growth does. Models that
  // cannot regrow change their parameters in place (setParams).
  virtual void regrow(size_t plant, const scene::PlantSpec& spec, const env::Environment& /*env*/) {
    setParams(plant, spec);
  }
  // Removes the node's segment and everything beyond it (interactive cuts, seed 000 §5.1).
  // Throws Error for a model that cannot be cut or a node out of range.
  virtual void cut(size_t /*plant*/, uint32_t /*node*/) {
    throw Error("", "", "plants of this model cannot be cut");
  }
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
  std::function<std::shared_ptr<const scene::ModelParams>(JsonObject& plant, const std::filesystem::path& baseDir)>
      read;
  std::function<std::unique_ptr<PlantSystem>(const SystemContext& context)> createSystem;
};

std::span<const ModelType> modelTypes();
const ModelType* findModelType(std::string_view name);

}  // namespace tendril::models
