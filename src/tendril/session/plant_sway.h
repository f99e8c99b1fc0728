// Plants that grow and move in the wind at once (seed 001): the Growth-Flow motion
// (wind/motion.h) of a Session's plants, kept from frame to frame while they grow and are
// edited. Each frame takes the plants as Session::plants() gives them; a plant that changed
// since the last frame (it grew, was cut or dragged) carries on swaying from where it was
// (WindMotion::setRest), so growing does not restart its sway. A climber's nodes that cling to a
// support plant (Session::attachments, looked up again whenever the climber changes) are carried
// by their host's sway, and its free shoots with them (wind::carryWithHosts), as in the clip. Plants the simulated air moves
// itself (models::AirCoupling in wind mode "sph") are left as they are. The studio's viewport
// and the growth-and-motion benchmark run this.
#pragma once

#include "tendril/plant/plant_model.h"
#include "tendril/wind/motion.h"

#include <memory>
#include <vector>

namespace tendril::session {

class Session;

class PlantSway {
 public:
  // Poses `plants` (the session's plants, in its order) in the session's wind at time t (s),
  // integrating eq. 1 over dt. Plants in parallel; the result does not depend on the thread
  // count. Calm air: the plants stay as they are and every motion is forgotten.
  void pose(const Session& session, std::vector<plant::PlantModel>& plants, float t, float dt);
  // Forgets every plant's motion (sway turned off, or another session opened).
  void clear() {
    motions_.clear();
    hosts_.clear();
  }
  // The plant's motion, if it sways.
  const wind::WindMotion* motion(size_t plant) const {
    return plant < motions_.size() ? motions_[plant].get() : nullptr;
  }

 private:
  std::vector<std::unique_ptr<wind::WindMotion>> motions_;
  std::vector<plant::PlantModel> posed_;
  // Per plant: the host plant and node of each node (empty for a plant that clings to nothing),
  // and each node's carrier (wind::clingingCarriers).
  struct Hosts {
    std::vector<int32_t> plant, node, carriers;
  };
  std::vector<Hosts> hosts_;
};

}  // namespace tendril::session
