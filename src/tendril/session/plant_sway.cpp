#include "tendril/session/plant_sway.h"

#include "tendril/core/parallel_largest_first.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session.h"

#include <algorithm>

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
    clear();
    return;
  }
  const std::vector<plant::GrowthFlowSpecies> species = session.growthFlow();
  const bool air = wind.settings().mode == env::WindMode::Sph;
  motions_.resize(plants.size());
  posed_.resize(plants.size());
  hosts_.resize(plants.size());
  std::vector<uint8_t> changed(plants.size(), 0);  // a new rest plant: its hosts looked up again
  // Plants of very unequal size, each posed on one thread: the largest first.
  std::vector<size_t> size(plants.size());
  for (size_t p = 0; p < plants.size(); ++p) size[p] = plants[p].nodeCount() + plants[p].leafCount();
  parallelForLargestFirst(size, [&](size_t p) {
    std::unique_ptr<wind::WindMotion>& motion = motions_[p];
    if ((air && session.system(p).airCoupling()) || plants[p].nodeCount() == 0) {
      motion.reset();
      changed[p] = 1;
      return;
    }
    if (!motion) {
      changed[p] = 1;
      wind::MotionSettings settings;
      settings.seed = session.scene().seed + p;
      motion = std::make_unique<wind::WindMotion>(plants[p], species.at(p), settings);
    } else if (!samePlant(motion->rest(), plants[p])) {
      changed[p] = 1;
      motion->setRest(plants[p]);
    }
    motion->step(t, dt, wind, posed_[p]);
    // The posed plant is handed over whole. What is left in posed_[p] has no nodes, so the
    // next step writes every field of it anew, as it does after setRest().
    std::swap(plants[p], posed_[p]);
    posed_[p].position.clear();
  });
  // Climbers on swaying hosts (the queries one plant at a time: they set the stems' viewer).
  for (size_t p = 0; p < plants.size(); ++p) {
    if (!changed[p]) continue;
    Hosts& h = hosts_[p];
    h = Hosts{};
    if (!motions_[p]) continue;
    const std::vector<Session::Attachment> at = session.attachments(p, motions_[p]->rest(), kClingReach);
    if (std::none_of(at.begin(), at.end(), [](const Session::Attachment& a) { return a.plant >= 0; })) continue;
    for (const Session::Attachment& a : at) h.plant.push_back(a.plant), h.node.push_back(a.node);
    h.carriers = wind::clingingCarriers(motions_[p]->rest(), h.plant);
  }
  for (size_t p = 0; p < plants.size(); ++p) {
    const Hosts& h = hosts_[p];
    if (h.plant.empty() || !motions_[p]) continue;
    wind::carryWithHosts(plants[p], *motions_[p], h.carriers, h.plant, h.node, [&](size_t host) {
      // A host that is a climber itself, or moved by the air, carries nothing.
      if (host >= plants.size() || !motions_[host] || !hosts_[host].plant.empty()) return wind::HostPose{};
      return wind::HostPose{motions_[host].get(), &plants[host]};
    });
  }
}

}  // namespace tendril::session
