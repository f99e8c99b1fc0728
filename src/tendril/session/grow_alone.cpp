#include "tendril/session/grow_alone.h"

#include "tendril/core/error.h"
#include "tendril/scene/model_types.h"

#include <fmt/format.h>

namespace tendril::session {

std::unique_ptr<models::PlantSystem> growAlone(const Session& session, const models::PlantSpec& plant, uint32_t steps,
                                               const std::function<bool(const models::PlantSystem&)>& more) {
  const models::ModelType* type = scene::findModelType(plant.model);
  if (!type) throw Error("", "/model", fmt::format("unknown model \"{}\"", plant.model));
  const scene::Scene& scene = session.scene();
  std::unique_ptr<models::PlantSystem> system = type->createSystem(models::SystemContext{scene.seed, scene.stepTime});
  const env::Environment& env = session.environment();
  system->addPlant(plant, env);
  for (uint32_t i = 0; i < steps && !system->finished() && (!more || more(*system)); ++i) system->step(env);
  return system;
}

}  // namespace tendril::session
