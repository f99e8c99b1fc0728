// Saving and restoring a ParticleWorld exactly (sessions, undo): every field that decides
// future steps, listed once in visitState().
#include "tendril/particles/world.h"

#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"

#include <fmt/format.h>

#include <cmath>

namespace tendril::particles {

namespace {

constexpr uint32_t kWorldTag = 0x57505433;          // "3TPW"
constexpr uint32_t kWorldTagNoSupport = 0x57505432;  // "2TPW": anchors without the support under them
constexpr uint32_t kWorldTagBefore = 0x57505431;     // "1TPW": and Growth-Flow records without their turn

}  // namespace

// The one list of the world's state. Per-particle arrays and records (AttachedLeaf, FlowState,
// the shape-matching and hash caches) go in as raw blocks, so a field added to such a record is
// covered; a new member of ParticleWorld must be added here, except per-step scratch that is
// rewritten before it is read (hashFill_, hashPacked_, hashContact_, nextRadius_). The caches
// are written too (it is cheaper than proving that rebuilding them gives the same bits); only the
// obstacle-clearance proof is dropped on load (clearanceEnv_), which is exact: it only skips
// distance samples that could not push a particle (collideObstacles()). The support under each
// anchor (anchorSupport_, anchorNormal_) follows this list in the archive, so that worlds saved
// before it was kept still load.
template <class Self, class Visit>
void ParticleWorld::visitState(Self& w, Visit&& v) {
  v(w.settings_);
  v(w.time_), v(w.step_), v(w.active_);
  v(w.x_), v(w.xp_), v(w.v_), v(w.w_), v(w.xr_);
  v(w.q_), v(w.qp_), v(w.qr_), v(w.groupRotation_);
  v(w.a_), v(w.b_), v(w.m_), v(w.age_);
  v(w.flags_), v(w.plant_), v(w.parent_), v(w.firstChild_), v(w.nextSibling_);
  v(w.targetHalfLength_), v(w.restTime_), v(w.anchor_), v(w.anchorPhi_);
  v(w.branchIndex_), v(w.order_), v(w.leafShape_), v(w.leafTarget_), v(w.flow_);
  v(w.freeList_), v(w.externalAcceleration_), v(w.leaves_);
  v(w.goal_), v(w.correction_);
  v(w.clearance_), v(w.clearanceObstacles_);
  v(w.pieceStart_), v(w.pieceOrder_), v(w.matchParent_), v(w.matchChildBegin_), v(w.matchChildEnd_);
  v(w.matchNode_), v(w.matchRest_);
  v(w.topologyVersion_), v(w.pieceOrderVersion_);
  v(w.hashParticles_), v(w.hashBucket_), v(w.hashStart_), v(w.hashEntries_), v(w.hashInv_);
  v(w.dragParticle_), v(w.dragTarget_), v(w.dragStrength_);
  v(w.occlusion_.origin), v(w.occlusion_.cell), v(w.occlusion_.dims), v(w.occlusion_.density);
}

namespace {

struct SaveField {
  ArchiveWriter& out;
  template <class T>
  void operator()(const std::vector<T>& v) const {
    out.vector(v);
  }
  template <ArchivePlain T>
  void operator()(const T& v) const {
    out.value(v);
  }
};

struct LoadField {
  ArchiveReader& in;
  bool flowWithoutTurn = false;  // a world saved as "1TPW"
  template <class T>
  void operator()(std::vector<T>& v) const {
    if constexpr (requires(T f) { f.turn; f.leafThickness; }) {
      if (flowWithoutTurn) {
        // The Growth-Flow records before they carried their turn: the four factors. Their
        // lineages go on from the orientation they have (no turn recorded).
        struct Before {
          float angle, length, leafSize, leafThickness;
        };
        std::vector<Before> before;
        in.vector(before);
        v.assign(before.size(), T{});
        for (size_t k = 0; k < before.size(); ++k) {
          v[k].angle = before[k].angle;
          v[k].length = before[k].length;
          v[k].leafSize = before[k].leafSize;
          v[k].leafThickness = before[k].leafThickness;
        }
        return;
      }
    }
    in.vector(v);
  }
  template <ArchivePlain T>
  void operator()(T& v) const {
    in.value(v);
  }
};

}  // namespace

void ParticleWorld::saveState(ArchiveWriter& out) const {
  out.tag(kWorldTag);
  out.u64(plants_.size());
  for (const Plant& p : plants_) {
    out.string(p.name);
    out.u64(p.seed);
    out.u32(p.root);
    out.u64(p.particles);
    out.boolean(p.capped);
  }
  visitState(*this, SaveField{out});
  out.vector(anchorSupport_);
  out.vector(anchorNormal_);
}

void ParticleWorld::loadState(ArchiveReader& in) {
  const size_t tagAt = in.position();
  const uint32_t tag = in.u32();
  if (tag != kWorldTag && tag != kWorldTagNoSupport && tag != kWorldTagBefore)
    in.fail(tagAt, "expected the start of a particle world (the data is damaged)");
  const size_t at = in.position();
  const uint64_t n = in.u64();
  if (n != plants_.size())
    in.fail(at, fmt::format("the saved particle world has {} plants, the session {}", n, plants_.size()));
  for (Plant& p : plants_) {
    p.name = in.string();
    p.seed = in.u64();
    p.root = in.u32();
    p.particles = size_t(in.u64());
    p.capped = in.boolean();
  }
  visitState(*this, LoadField{in, tag == kWorldTagBefore});
  if (tag == kWorldTag) {
    in.vector(anchorSupport_);
    in.vector(anchorNormal_);
  } else {
    // Anchors saved without their support stay where they were set (a zero normal).
    anchorSupport_ = anchor_;
    anchorNormal_.assign(anchor_.size(), Vec3::Zero());
  }
  // Every per-particle array must have one slot per particle, and links must stay in range:
  // damaged input is an Error here, not a crash in the next step.
  const size_t cap = flags_.size();
  const size_t sizes[] = {x_.size(), xp_.size(), v_.size(), w_.size(), xr_.size(), q_.size(), qp_.size(),
                          qr_.size(), groupRotation_.size(), a_.size(), b_.size(), m_.size(), age_.size(),
                          plant_.size(), parent_.size(), firstChild_.size(), nextSibling_.size(),
                          targetHalfLength_.size(), restTime_.size(), anchor_.size(), anchorSupport_.size(),
                          anchorNormal_.size(), anchorPhi_.size(),
                          branchIndex_.size(), order_.size(), leafShape_.size(), leafTarget_.size(), flow_.size()};
  for (size_t s : sizes)
    if (s != cap) in.fail("the particle arrays of the saved world differ in length");
  auto link = [&](uint32_t i) { return i == kNone || i < cap; };
  for (size_t i = 0; i < cap; ++i)
    if (!link(parent_[i]) || !link(firstChild_[i]) || !link(nextSibling_[i]) ||
        ((flags_[i] & kActive) && plant_[i] >= plants_.size()))
      in.fail(fmt::format("particle {} of the saved world links outside the world", i));
  for (const Plant& p : plants_)
    if (!link(p.root)) in.fail("a plant root of the saved world lies outside the world");
  for (const AttachedLeaf& l : leaves_)
    if (l.particle >= cap) in.fail("a leaf of the saved world hangs from no particle");
  for (uint32_t f : freeList_)
    if (f >= cap) in.fail("the free list of the saved world lies outside the world");
  if (!link(dragParticle_)) in.fail("the dragged particle of the saved world lies outside the world");
  // The links form a forest: every child list ends and names children whose parent is its
  // owner, and no particle is its own ancestor (a cycle would loop the next step for ever).
  for (size_t i = 0; i < cap; ++i) {
    size_t children = 0;
    for (uint32_t c = firstChild_[i]; c != kNone; c = nextSibling_[c])
      if (++children > cap || parent_[c] != i)
        in.fail(fmt::format("the children of particle {} of the saved world are not linked back to it", i));
  }
  {
    std::vector<uint8_t> state(cap, 0);  // 1: on the path being walked, 2: known to reach a root
    std::vector<uint32_t> path;
    for (size_t i = 0; i < cap; ++i) {
      path.clear();
      uint32_t j = uint32_t(i);
      while (j != kNone && state[j] != 2) {
        if (state[j] == 1) in.fail(fmt::format("particle {} of the saved world is its own ancestor", j));
        state[j] = 1;
        path.push_back(j);
        j = parent_[j];
      }
      for (uint32_t k : path) state[k] = 2;
    }
  }
  // Values the next step turns into cell indices or divides by: finite and within reach for
  // every particle in use (a kilometre of ivy is far beyond any scene).
  constexpr float kFar = float(JsonObject::kWorldExtent);  // the readers' world
  auto finite = [&](const Vec3& p) { return isFinite(p) && p.cwiseAbs().maxCoeff() <= kFar; };
  auto unit = [](const Quat& q) { return std::isfinite(q.squaredNorm()) && std::abs(q.squaredNorm() - 1.0f) < 1e-2f; };
  for (size_t i = 0; i < cap; ++i) {
    if (!(flags_[i] & kActive)) continue;
    if (!finite(x_[i]) || !finite(xp_[i]) || !finite(v_[i]) || !finite(w_[i]) || !finite(xr_[i]) || !unit(q_[i]) ||
        !unit(qp_[i]) || !unit(qr_[i]) || !(a_[i] >= 0.0f && a_[i] <= kFar) || !(b_[i] >= 0.0f && b_[i] <= kFar) ||
        !(m_[i] > 0.0f && m_[i] <= kFar) || !std::isfinite(age_[i]))
      in.fail(fmt::format("particle {} of the saved world holds a value out of range", i));
  }
  // The caches: the spatial hash of the last collision pass (a power-of-two table, ascending
  // starts, entries in the world), and the light occlusion grid (as many cells as its size).
  if (!hashStart_.empty()) {
    const size_t table = hashStart_.size() - 1;
    bool ok = table >= 1 && (table & (table - 1)) == 0 && hashStart_.front() == 0 &&
              hashStart_.back() == hashEntries_.size() && hashInv_ > 0.0f && hashInv_ <= 1e4f;
    for (size_t t = 0; ok && t < table; ++t) ok = hashStart_[t] <= hashStart_[t + 1];
    for (size_t e = 0; ok && e < hashEntries_.size(); ++e) ok = hashEntries_[e] < cap;
    if (!ok) in.fail("the spatial hash of the saved world is damaged");
  } else if (!hashEntries_.empty()) {
    in.fail("the spatial hash of the saved world is damaged");
  }
  if (!occlusion_.density.empty()) {
    const Eigen::Vector3i d = occlusion_.dims;
    if ((d.array() < 1).any() || double(d.x()) * d.y() * d.z() != double(occlusion_.density.size()) ||
        !finite(occlusion_.origin) || !(occlusion_.cell >= 1e-3f && occlusion_.cell <= kFar))
      in.fail("the light occlusion grid of the saved world is damaged");
  }
  // The order in which shape matching visits the pieces follows from the links: when it is
  // marked current, it must be what they give (it is indexed without further checks).
  if (pieceOrderVersion_ == topologyVersion_) {
    std::vector<uint32_t> start, order, parent, begin, end;
    buildPieceOrder(start, order, parent, begin, end);
    if (start != pieceStart_ || order != pieceOrder_ || parent != matchParent_ || begin != matchChildBegin_ ||
        end != matchChildEnd_)
      in.fail("the shape-matching order of the saved world does not follow its links");
  }
  clearanceEnv_ = nullptr;
}

std::vector<uint32_t> ParticleWorld::snapshotParticles(uint32_t plantId) const {
  // The same walk as snapshot(): the plant's tree depth first, children in creation order,
  // then its detached pieces in slot order; leaf particles are not nodes.
  const Plant& pl = plants_.at(plantId);
  std::vector<uint32_t> out;
  auto addTree = [&](uint32_t root) {
    std::vector<uint32_t> stack = {root};
    while (!stack.empty()) {
      uint32_t i = stack.back();
      stack.pop_back();
      if (flags_[i] & kLeaf) continue;
      out.push_back(i);
      std::vector<uint32_t> kids;
      for (uint32_t c = firstChild_[i]; c != kNone; c = nextSibling_[c]) kids.push_back(c);
      for (auto it = kids.rbegin(); it != kids.rend(); ++it) stack.push_back(*it);
    }
  };
  if (pl.root != kNone && (flags_[pl.root] & kActive)) addTree(pl.root);
  for (uint32_t i = 0; i < capacity(); ++i)
    if ((flags_[i] & kActive) && plant_[i] == plantId && (flags_[i] & kDetached) && parent_[i] == kNone &&
        !(flags_[i] & kLeaf))
      addTree(i);
  return out;
}

}  // namespace tendril::particles
