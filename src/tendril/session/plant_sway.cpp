#include "tendril/session/plant_sway.h"

#include "tendril/core/parallel_largest_first.h"
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
  // Plants of very unequal size, each posed on one thread: the largest first.
  std::vector<size_t> size(plants.size());
  for (size_t p = 0; p < plants.size(); ++p) size[p] = plants[p].nodeCount() + plants[p].leafCount();
  parallelForLargestFirst(size, [&](size_t p) {
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
    // The posed plant is handed over whole. What is left in posed_[p] has no nodes, so the
    // next step writes every field of it anew, as it does after setRest().
    std::swap(plants[p], posed_[p]);
    posed_[p].position.clear();
  });
}

}  // namespace tendril::session
