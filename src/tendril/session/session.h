// A Session owns one open scene: its Environment, every plant of every model, and the clock.
// Apps (CLI, studio) drive a Session; they never reach around it.
#pragma once

#include "tendril/env/environment.h"
#include "tendril/models/registry.h"
#include "tendril/plant/plant_model.h"
#include "tendril/scene/scene.h"
#include "tendril/wind/sph.h"

#include <functional>
#include <memory>
#include <vector>

namespace tendril::session {

class Session {
 public:
  // Builds the environment and seeds every plant. Throws Error for seeds inside obstacles and
  // other bad plant settings, naming the scene file and the plant's JSON pointer.
  explicit Session(scene::Scene scene);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  const scene::Scene& scene() const { return scene_; }
  env::Environment& environment() { return *env_; }
  const env::Environment& environment() const { return *env_; }

  // One growth step of every plant.
  void step();
  // Up to `steps` steps, stopping early when nothing grows any more. `onStep(done)` is called
  // after each step (progress reports).
  void run(uint32_t steps, const std::function<void(uint32_t)>& onStep = {});
  uint32_t stepCount() const { return steps_; }
  bool finished() const;

  // Snapshots of every plant, in scene order.
  std::vector<plant::PlantModel> plants() const;
  // The Growth-Flow constants of every plant, in scene order.
  std::vector<wind::GrowthFlowSpecies> growthFlow() const;
  size_t segmentCount() const;

 private:
  struct PlantRef {
    size_t system;  // index into systems_
    size_t index;   // plant index within that system
  };

  scene::Scene scene_;
  std::unique_ptr<env::Environment> env_;
  std::vector<std::unique_ptr<models::PlantSystem>> systems_;  // one per model in use
  std::vector<std::string> systemModels_;
  std::vector<PlantRef> plants_;  // per scene plant
  std::unique_ptr<wind::SphAir> air_;  // simulated air (wind mode sph)
  uint32_t steps_ = 0;
};

}  // namespace tendril::session
