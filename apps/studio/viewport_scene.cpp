#include "viewport_scene.h"

#include "tendril/core/timer.h"
#include "tendril/render/session_render.h"

namespace tendril::studio {
namespace {

// The picked node and the nodes after it that descend from it: the branch a cut there takes
// away (its whole subtree when the plant lists nodes depth first, as particle plants do).
render::NodeRange subtree(const plant::PlantModel& m, uint32_t node) {
  if (node >= m.nodeCount()) return {};
  uint32_t end = node + 1;
  while (end < m.nodeCount()) {
    int32_t a = m.parent[end];
    while (a > int32_t(node)) a = m.parent[size_t(a)];
    if (a != int32_t(node)) break;
    ++end;
  }
  return {node, end - node};
}

}  // namespace

void ViewportScene::sway(const session::Session& session, float t, float dt) { sway_.pose(session, plants_, t, dt); }

void ViewportScene::setStress(uint32_t plant, std::vector<float> stress) {
  if (stress_.size() <= plant) stress_.resize(plant + 1);
  stress_[plant] = std::move(stress);
}

void ViewportScene::applyStress() {
  for (size_t p = 0; p < scene_.plants.size() && p < stress_.size(); ++p)
    scene_.plants[p].stress = stress_[p].size() == plants_[p].nodeCount() ? std::span<const float>(stress_[p])
                                                                          : std::span<const float>();
}

void ViewportScene::update(const session::Session& session, const Selection& selection, bool meshesChanged,
                           bool air) {
  const env::Environment& env = session.environment();
  Timer timer;
  plants_ = session.plants();
  snapshotMs_ = timer.milliseconds();

  if (meshesChanged || meshes_.size() != env.obstacleCount()) {
    meshes_.clear();
    meshKeys_.clear();
    meshes_.reserve(env.obstacleCount());
    for (uint32_t id = 0; id < env.obstacleCount(); ++id) {
      meshes_.push_back(env.obstacleMesh(id));
      meshKeys_.push_back(nextKey_++);
    }
  }

  scene_ = render::RenderScene();
  Bounds3 focus;
  for (uint32_t id = 0; id < env.obstacleCount(); ++id) {
    const env::ObstacleInfo& info = env.obstacle(id);
    render::ObstacleView view;
    view.mesh = &meshes_[id];
    view.worldFromLocal = info.worldFromLocal;
    view.color = info.color;
    view.selected = selection.is(Selection::Kind::Obstacle, id);
    view.meshKey = meshKeys_[id];
    scene_.obstacles.push_back(view);
    if (info.kind != env::ObstacleKind::Plane) focus.extend(info.worldBounds);
  }
  stress_.resize(std::max(stress_.size(), plants_.size()));
  for (uint32_t p = 0; p < plants_.size(); ++p) {
    render::PlantView view;
    view.model = &plants_[p];
    if (selection.is(Selection::Kind::Plant, p) && selection.node) view.selected = subtree(plants_[p], *selection.node);
    scene_.plants.push_back(view);
  }
  scene_.lights = env.lights();
  scene_.strokes = env.strokes();
  if (air) scene_.air = render::airView(session);
  for (const env::WindEmitter& e : env.windField().settings().emitters) {
    render::GizmoLine line;
    line.start = e.position;
    line.end = e.position + e.direction.normalized() * std::min(e.reach, 2.0f);
    line.arrow = true;
    line.color = Vec3(0.3f, 0.8f, 1.0f);
    scene_.gizmos.push_back(line);
  }
  if (selection.kind == Selection::Kind::Light && selection.index < scene_.lights.size()) {
    const env::Light& l = scene_.lights[selection.index];
    render::GizmoLine line;
    Vec3 c = focus.empty() ? Vec3::Zero() : focus.center();
    line.end = l.type == env::Light::Type::Point ? l.position : c;
    line.start = l.type == env::Light::Type::Point ? Vec3(l.position + Vec3(0, 0.3f, 0)) : Vec3(c - l.direction * 2.0f);
    line.arrow = true;
    line.color = Vec3(1.0f, 0.9f, 0.3f);
    scene_.gizmos.push_back(line);
  }
  scene_.grid.enabled = true;
  render::RenderScene plantsOnly;
  plantsOnly.plants = scene_.plants;
  Bounds3 plantBounds = render::sceneBounds(plantsOnly);
  if (!plantBounds.empty()) focus.extend(plantBounds);
  scene_.focus = focus;
}

}  // namespace tendril::studio
