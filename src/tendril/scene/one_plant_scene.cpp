#include "tendril/scene/one_plant_scene.h"

namespace tendril::scene {

Scene onePlantScene(models::PlantSpec plant, int steps, const std::optional<Scene>& base) {
  Scene scene = base ? *base : Scene{};
  plant.pointer = "/plants/0";
  scene.plants.clear();
  scene.plants.push_back(std::move(plant));
  scene.steps = steps;
  return scene;
}

}  // namespace tendril::scene
