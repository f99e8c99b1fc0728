#include "tendril/session/plant_sway.h"

#include "tendril/core/parallel.h"
#include "tendril/session/session.h"

namespace tendril::session {
namespace {

// Whether `now` is the plant `rest` was: same nodes where they were, same leaves.
bool samePlant(const plant::PlantModel& rest, const plant::PlantModel& now) {
  return rest.nodeCount() == now.nodeCount() && rest.leafCount() == now.leafCount() && rest.position == now.position &&
         rest.orientation == now.orientation && rest.radius == now.radius && rest.length == now.length &&
         rest.leafRotation == now.leafRotation && rest.leafSize == now.leafSize;
}

}  // namespace

void PlantSway::pose(const Session& session, std::vector<plant::PlantModel>& plants, float t, float dt) {
  const env::WindField& wind = session.environment().windField();
  if (wind.settings().calm()) {
    motions_.clear();
    return;
  }
  const std::vector<plant::GrowthFlowSpecies> species = session.growthFlow();
  const bool air = wind.settings().mode == env::WindMode::Sph;
  motions_.resize(plants.size());
  posed_.resize(plants.size());
  parallelFor(size_t(0), plants.size(), [&](size_t p) {
    std::unique_ptr<wind::WindMotion>& motion = motions_[p];
    if ((air && session.system(p).airCoupling()) || plants[p].nodeCount() == 0) {
      motion.reset();
      return;
    }
    if (!motion) {
      wind::MotionSettings settings;
      settings.seed = session.scene().seed + p;
      motion = std::make_unique<wind::WindMotion>(plants[p], species.at(p), settings);
    } else if (!samePlant(motion->rest(), plants[p])) {
      motion->setRest(plants[p]);
    }
    motion->step(t, dt, wind, posed_[p]);
    plants[p] = posed_[p];
  }, 1);
}

}  // namespace tendril::session
