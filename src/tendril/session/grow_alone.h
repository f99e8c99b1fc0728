// One plant grown on its own as a Session's scene would grow it — the scene's seed and step
// time, the session's environment as it is now — without adding it to the session: the
// studio's previews (an edited grammar beside its plant). A Session of a one-plant scene
// (scene/one_plant_scene.h) gives the same plant in the same environment.
#pragma once

#include "tendril/models/registry.h"
#include "tendril/session/session.h"

#include <functional>
#include <memory>

namespace tendril::session {

// Seeds `plant` (any model; an Error for a seed inside an obstacle and other bad settings, as
// Session::addPlant) and steps it up to `steps` times, until it has finished or `more(system)`
// says no. Returns its system: the plant is its plant 0.
std::unique_ptr<models::PlantSystem> growAlone(const Session& session, const models::PlantSpec& plant, uint32_t steps,
                                               const std::function<bool(const models::PlantSystem&)>& more = {});

}  // namespace tendril::session
