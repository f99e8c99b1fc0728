// Plants as supports: every plant whose spec says `support` gives the environment its stems
// (round cones, env::StemTube) and its leaves (shade), so that climbing plants of the other
// models climb it as they climb obstacles (environment.h).
#include "tendril/models/plant_support.h"
#include "tendril/session/session.h"

#include <algorithm>

namespace tendril::session {

void Session::updateSupports(bool stepping) {
  systemHasSupports_.resize(systems_.size(), false);
  staleSystems_.resize(systems_.size(), 0);
  bool changed = false;
  for (size_t s = 0; s < systems_.size(); ++s) {
    bool any = false;
    for (size_t i = 0; i < plants_.size() && !any; ++i) any = plants_[i].system == s && specs_[i].spec.support;
    if (!any) {
      if (systemHasSupports_[s]) env_->setStems(uint32_t(s), {}), changed = true;
      systemHasSupports_[s] = false;
      continue;
    }
    // A finished system's plants change only by edits, which mark the supports stale; between
    // steps, only edits change any.
    if (systemHasSupports_[s] && !supportsStale_ && !staleSystems_[s] && (!stepping || systems_[s]->finished()))
      continue;
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
  std::fill(staleSystems_.begin(), staleSystems_.end(), 0);
  if (changed) env_->commit();
}

std::vector<std::pair<uint32_t, uint32_t>> Session::clingingTo(size_t host, const std::vector<bool>& removed) const {
  std::vector<std::pair<uint32_t, uint32_t>> out;
  if (host >= plants_.size() || !specs_[host].spec.support) return out;
  for (size_t p = 0; p < plants_.size(); ++p) {
    const size_t s = plants_[p].system;
    // Only climb and particle plants can be cut; plants of the host's own system never see it.
    if (p == host || s == plants_[host].system || (specs_[p].spec.model != "climb" && specs_[p].spec.model != "particles"))
      continue;
    const models::GrowthGauge* gauge = systems_[s]->growthGauge();
    const float stated = gauge ? gauge->growthReading(plants_[p].index).supportReach : 0.0f;
    const float reach = stated > 0.0f ? stated : 0.1f;
    const plant::PlantModel m = systems_[s]->snapshot(plants_[p].index);
    const std::vector<Attachment> at = attachments(p, m, reach);
    std::vector<bool> held(m.nodeCount(), false);
    for (size_t i = 0; i < m.nodeCount(); ++i)
      held[i] = at[i].plant == int32_t(host) && size_t(at[i].node) < removed.size() && removed[size_t(at[i].node)];
    // Parents come before children: a held node whose parent is held goes with the parent.
    std::vector<bool> gone(m.nodeCount(), false);
    for (size_t i = 0; i < m.nodeCount(); ++i) {
      const int32_t parent = m.parent[i];
      const bool parentGone = parent >= 0 && gone[size_t(parent)];
      gone[i] = parentGone || held[i];
      if (held[i] && !parentGone) out.emplace_back(uint32_t(p), uint32_t(i));
    }
  }
  return out;
}

}  // namespace tendril::session
