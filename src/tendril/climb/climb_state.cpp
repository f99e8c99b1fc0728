// Saving, restoring and cutting climbing plants (sessions, undo, interactive cuts).
#include "tendril/climb/climb_system.h"

#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"
#include "tendril/plant/plant_archive.h"

#include <fmt/format.h>

#include <cmath>

namespace tendril::climb {

namespace {

constexpr uint32_t kClimbTag = 0x4d4c4332;    // "2CLM" (2: tips carry Growth-Flow's length factor)
constexpr uint32_t kClimbTagV1 = 0x4d4c4331;  // "1CLM": states saved before that

// A tip as "1CLM" saved it: ClimbSystem::Tip without windLength, member for member.
struct TipV1 {
  uint64_t id = 0;
  int32_t lastNode = -1;
  Vec3 position = Vec3::Zero();
  Vec3 dir = Vec3::UnitY();
  Vec3 normal = Vec3::UnitZ();
  float length = 0, radius = 0, leafSize = 0;
  float leafThickness = 0;
  float windAngle = -1.0f;
  Vec3 shootStart = Vec3::Zero();
  uint32_t segments = 0;
  uint32_t unsupported = 0;
  std::optional<env::SurfacePoint> support;
  uint16_t order = 0;
  bool startsBranch = false;
};

}  // namespace

void ClimbSystem::rebuildOccupancy() {
  OccupancyGrid grid(occupancy_.cell());
  for (const auto& p : plants_)
    for (const Vec3& e : p->nodeEnd) grid.insert(e);
  occupancy_ = std::move(grid);
}

// Tips are saved as their bytes. Copied member by member into value-initialised records, their
// padding and an empty support's storage are zero: the same state always saves the same bytes
// (a copied Tip carries whatever bytes its padding held).
std::vector<ClimbSystem::Tip> ClimbSystem::savedTips(const std::vector<Tip>& tips) {
  static_assert(sizeof(Tip) == 152, "a member added to ClimbSystem::Tip must be copied here");
  std::vector<Tip> out(tips.size());
  for (size_t i = 0; i < tips.size(); ++i) {
    const Tip& t = tips[i];
    Tip& c = out[i];
    c.id = t.id;
    c.lastNode = t.lastNode;
    c.position = t.position;
    c.dir = t.dir;
    c.normal = t.normal;
    c.length = t.length, c.radius = t.radius, c.leafSize = t.leafSize;
    c.leafThickness = t.leafThickness;
    c.windAngle = t.windAngle;
    c.windLength = t.windLength;
    c.shootStart = t.shootStart;
    c.segments = t.segments;
    c.unsupported = t.unsupported;
    if (t.support) c.support.emplace(*t.support);
    c.order = t.order;
    c.startsBranch = t.startsBranch;
  }
  return out;
}

void ClimbSystem::saveState(ArchiveWriter& out) const {
  out.tag(kClimbTag);
  out.u32(step_);
  out.u64(plants_.size());
  for (const auto& p : plants_) {
    plant::savePlantModel(out, p->model);
    out.vector(p->birthStep);
    out.vector(p->nodeEnd);
    out.vector(savedTips(p->tips));
    out.u64(p->nextTipId);
    out.boolean(p->capped);
  }
}

void ClimbSystem::loadState(ArchiveReader& in) {
  const size_t tagAt = in.position();
  const uint32_t tag = in.u32();
  if (tag != kClimbTag && tag != kClimbTagV1) in.fail(tagAt, "expected the start of climbing plants (the data is damaged)");
  step_ = in.u32();
  const size_t at = in.position();
  const uint64_t n = in.u64();
  if (n != plants_.size())
    in.fail(at, fmt::format("the saved climbing plants are {}, the session has {}", n, plants_.size()));
  for (auto& p : plants_) {
    plant::loadPlantModel(in, p->model);
    in.vector(p->birthStep);
    in.vector(p->nodeEnd);
    if (tag == kClimbTagV1) {
      // Saved before tips carried Growth-Flow's length factor: taken as grown in still air.
      std::vector<TipV1> old;
      in.vector(old);
      p->tips.resize(old.size());
      for (size_t k = 0; k < old.size(); ++k) {
        const TipV1& o = old[k];
        Tip& t = p->tips[k];
        t = Tip{};
        t.id = o.id, t.lastNode = o.lastNode, t.position = o.position, t.dir = o.dir, t.normal = o.normal;
        t.length = o.length, t.radius = o.radius, t.leafSize = o.leafSize, t.leafThickness = o.leafThickness;
        t.windAngle = o.windAngle, t.shootStart = o.shootStart, t.segments = o.segments;
        t.unsupported = o.unsupported, t.support = o.support, t.order = o.order, t.startsBranch = o.startsBranch;
      }
    } else {
      in.vector(p->tips);
    }
    p->nextTipId = in.u64();
    p->capped = in.boolean();
    const size_t nodes = p->model.nodeCount();
    if (p->birthStep.size() != nodes || p->nodeEnd.size() != nodes)
      in.fail("the node records of a saved climbing plant differ in length");
    for (uint32_t b : p->birthStep)
      if (b > step_) in.fail("a node of a saved climbing plant was born after the saved step");
    for (const Tip& t : p->tips)
      if (t.lastNode < -1 || t.lastNode >= int32_t(nodes)) in.fail("a tip of a saved climbing plant has no node");
    // Positions the occupancy grid turns into cell indices and tips grow from: finite and
    // within the world (100 km of the origin).
    constexpr float kFar = float(JsonObject::kWorldExtent);  // the readers' world
    auto near = [](const Vec3& v) { return isFinite(v) && v.cwiseAbs().maxCoeff() <= kFar; };
    for (const Vec3& e : p->nodeEnd)
      if (!near(e)) in.fail("a node of a saved climbing plant ends out of range");
    for (const Tip& t : p->tips)
      if (!near(t.position) || !near(t.dir) || !near(t.normal) || !near(t.shootStart) || !std::isfinite(t.length) ||
          !std::isfinite(t.radius) || !std::isfinite(t.leafSize) || !std::isfinite(t.leafThickness) ||
          !std::isfinite(t.windAngle) || !(t.windLength > 0.0f && t.windLength <= 1.0f) ||
          (t.support && (!near(t.support->point) || !near(t.support->normal) || !near(t.support->away))))
        in.fail("a tip of a saved climbing plant holds a value out of range");
  }
  rebuildOccupancy();
}

size_t ClimbSystem::carryWithObstacle(const env::Environment& env, uint32_t obstacle, const RigidTransform& motion) {
  if (obstacle >= env.obstacleCount()) return 0;
  const Quat turn = motion.rotation;
  auto moveSupport = [&](std::optional<env::SurfacePoint>& sp) {
    if (!sp) return;
    if (sp->onStem() || sp->obstacle != obstacle) {
      sp.reset();  // a surface the plant has left: the next step looks again
      return;
    }
    sp->point = motion.applyPoint(sp->point);
    sp->normal = turn * sp->normal;
    sp->away = turn * sp->away;
  };
  size_t moved = 0;
  for (auto& pp : plants_) {
    Plant& p = *pp;
    const ClimbSpecies& s = p.def.species;
    // Where the plant is held: its first node, or its seed's tip before it grew.
    if (p.model.nodeCount() == 0 && p.tips.empty()) continue;
    const Vec3 base = p.model.nodeCount() > 0 ? p.model.position[0] : p.tips[0].position;
    const std::optional<env::SurfacePoint> sp = env.closestPoint(base, s.surfaceOffset + s.radius + 0.01f);
    if (!sp || sp->onStem() || sp->obstacle != obstacle) continue;
    for (size_t i = 0; i < p.model.nodeCount(); ++i) {
      p.model.position[i] = motion.applyPoint(p.model.position[i]);
      p.model.orientation[i] = (turn * p.model.orientation[i]).normalized();
    }
    for (Vec3& e : p.nodeEnd) e = motion.applyPoint(e);
    for (Tip& t : p.tips) {
      t.position = motion.applyPoint(t.position);
      t.dir = turn * t.dir;
      t.normal = turn * t.normal;
      moveSupport(t.support);
    }
    ++moved;
  }
  if (moved) rebuildOccupancy();
  return moved;
}

void ClimbSystem::cut(uint32_t plantId, uint32_t node) {
  if (plantId >= plants_.size()) throw Error("", "", fmt::format("there is no climbing plant {}", plantId));
  Plant& p = *plants_[plantId];
  plant::PlantModel& m = p.model;
  const size_t n = m.nodeCount();
  if (node >= n) throw Error("", "", fmt::format("plant \"{}\" has no node {} (it has {})", p.def.name, node, n));
  // Parents come before children: one forward pass marks the whole subtree.
  std::vector<char> gone(n, 0);
  gone[node] = 1;
  for (size_t i = node + 1; i < n; ++i)
    if (m.parent[i] >= 0 && gone[m.parent[i]]) gone[i] = 1;
  std::vector<int32_t> remap(n, -1);
  plant::PlantModel kept = m;
  kept.position.clear(), kept.orientation.clear(), kept.length.clear(), kept.radius.clear();
  kept.parent.clear(), kept.age.clear(), kept.order.clear(), kept.flags.clear();
  kept.leafNode.clear(), kept.leafOffset.clear(), kept.leafRotation.clear(), kept.leafSize.clear();
  kept.leafThickness.clear(), kept.leafPetiole.clear(), kept.leafShape.clear(), kept.leafMotion.clear();
  std::vector<uint32_t> birth;
  std::vector<Vec3> ends;
  for (size_t i = 0; i < n; ++i) {
    if (gone[i]) continue;
    remap[i] = int32_t(kept.position.size());
    kept.position.push_back(m.position[i]);
    kept.orientation.push_back(m.orientation[i]);
    kept.length.push_back(m.length[i]);
    kept.radius.push_back(m.radius[i]);
    kept.parent.push_back(m.parent[i] < 0 ? -1 : remap[m.parent[i]]);
    kept.age.push_back(m.age[i]);
    kept.order.push_back(m.order[i]);
    kept.flags.push_back(m.flags[i]);
    birth.push_back(p.birthStep[i]);
    ends.push_back(p.nodeEnd[i]);
  }
  for (size_t l = 0; l < m.leafCount(); ++l) {
    if (gone[m.leafNode[l]]) continue;
    kept.leafNode.push_back(remap[m.leafNode[l]]);
    kept.leafOffset.push_back(m.leafOffset[l]);
    kept.leafRotation.push_back(m.leafRotation[l]);
    kept.leafSize.push_back(m.leafSize[l]);
    kept.leafThickness.push_back(m.leafThickness[l]);
    kept.leafPetiole.push_back(m.leafPetiole[l]);
    kept.leafShape.push_back(m.leafShape[l]);
    kept.leafMotion.push_back(m.leafMotion[l]);
  }
  std::vector<Tip> tips;
  for (Tip t : p.tips) {
    if (t.lastNode >= 0 && gone[t.lastNode]) continue;
    if (t.lastNode >= 0) t.lastNode = remap[t.lastNode];
    tips.push_back(t);
  }
  // The cut end stops growing: the parent is a dead end unless a tip or another child goes on.
  const int32_t parent = m.parent[node] < 0 ? -1 : remap[m.parent[node]];
  if (parent >= 0) {
    bool continues = false;
    for (const Tip& t : tips) continues |= t.lastNode == parent;
    for (int32_t q : kept.parent) continues |= q == parent;
    if (!continues) kept.flags[parent] |= plant::kNodeDead;
  }
  m = std::move(kept);
  p.birthStep = std::move(birth);
  p.nodeEnd = std::move(ends);
  p.tips = std::move(tips);
  rebuildOccupancy();
}

}  // namespace tendril::climb
