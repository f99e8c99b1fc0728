// The scene a single-plant command grows: `tendril lsys`, `tendril model` and the studio's
// L-system preview mean "this one plant in this scene (or in an empty one)", and grow it
// through a Session like any scene, so the same plant and seeds give the same plant whichever
// way it is grown (docs/cli.md).
#pragma once

#include "tendril/scene/scene.h"

#include <optional>

namespace tendril::scene {

// `base` (its environment, seed, step time and output settings) with `plant` as its only plant
// (at /plants/0), or a scene with nothing else when there is no base: no obstacles, seed 1,
// default output settings. `steps` is what the scene runs (`tendril grow`'s "steps").
Scene onePlantScene(models::PlantSpec plant, int steps, const std::optional<Scene>& base = std::nullopt);

}  // namespace tendril::scene
