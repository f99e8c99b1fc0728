// Plants as supports: every plant whose spec says `support` gives the environment its stems
// (round cones, env::StemTube) and its leaves (shade), so that climbing plants of the other
// models climb it as they climb obstacles (environment.h).
#include "tendril/models/plant_support.h"
#include "tendril/session/session.h"

namespace tendril::session {

void Session::updateSupports() {
  systemHasSupports_.resize(systems_.size(), false);
  bool changed = false;
  for (size_t s = 0; s < systems_.size(); ++s) {
    bool any = false;
    for (size_t i = 0; i < plants_.size() && !any; ++i) any = plants_[i].system == s && specs_[i].spec.support;
    if (!any) {
      if (systemHasSupports_[s]) env_->setStems(uint32_t(s), {}), changed = true;
      systemHasSupports_[s] = false;
      continue;
    }
    // A finished system's plants change only by edits, which mark the supports stale.
    if (systemHasSupports_[s] && !supportsStale_ && systems_[s]->finished()) continue;
    std::vector<env::StemTube> tubes;
    std::vector<env::ShadeTriangle> shade;
    for (size_t i = 0; i < plants_.size(); ++i)
      if (plants_[i].system == s && specs_[i].spec.support)
        models::appendSupport(systems_[s]->snapshot(plants_[i].index), uint32_t(i), tubes, shade);
    env_->setStems(uint32_t(s), std::move(tubes), std::move(shade));
    systemHasSupports_[s] = true;
    changed = true;
  }
  supportsStale_ = false;
  if (changed) env_->commit();
}

}  // namespace tendril::session
