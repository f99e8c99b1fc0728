// Climbers on plants: which of a plant's nodes cling to the stems of support plants (the hosts
// the wind clip skins them to, wind/gltf_animation.h).
#include "tendril/core/parallel.h"
#include "tendril/session/session.h"

namespace tendril::session {

std::vector<Session::Attachment> Session::attachments(size_t plant, const plant::PlantModel& snapshot,
                                                      float reach) const {
  std::vector<Attachment> out(snapshot.nodeCount());
  if (specs_.at(plant).spec.support || env_->stemCount() == 0 || !(reach > 0.0f)) return out;
  viewingAs(plants_.at(plant).system, [&] {
    if (!env_->seesStems()) return;
    parallelFor(size_t(0), out.size(), [&](size_t i) {
      const std::optional<env::SurfacePoint> sp = env_->closestPoint(snapshot.position[i], reach);
      if (!sp || !sp->onStem()) return;
      const env::StemTube& tube = env_->stem(sp->stem());
      out[i] = {int32_t(tube.plant), int32_t(tube.node)};
    });
  });
  return out;
}

}  // namespace tendril::session
