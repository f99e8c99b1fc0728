#include "tendril/render/session_render.h"

#include "tendril/io/atomic_file.h"
#include "tendril/render/offscreen.h"

namespace tendril::render {

SessionScene::SessionScene(const session::Session& session) : plants_(session.plants()) {
  const env::Environment& env = session.environment();
  const std::string source = session.scene().path.empty() ? std::string("session") : session.scene().path.string();
  meshes_.reserve(env.obstacleCount());
  Bounds3 focus;
  for (uint32_t id = 0; id < env.obstacleCount(); ++id) {
    const env::ObstacleInfo& info = env.obstacle(id);
    meshes_.push_back(env.obstacleMesh(id));
    ObstacleView view;
    view.mesh = &meshes_.back();
    view.worldFromLocal = info.worldFromLocal;
    view.color = info.color;
    scene_.obstacles.push_back(view);
    if (info.kind != env::ObstacleKind::Plane) focus.extend(info.worldBounds);
  }
  for (const plant::PlantModel& p : plants_) {
    plant::validate(p, source);
    PlantView view;
    view.model = &p;
    scene_.plants.push_back(view);
  }
  scene_.lights = env.lights();
  scene_.strokes = env.strokes();
  RenderScene plantsOnly;
  plantsOnly.plants = scene_.plants;
  Bounds3 plantBounds = sceneBounds(plantsOnly);
  if (!plantBounds.empty()) focus.extend(plantBounds);
  scene_.focus = focus;
}

io::Image renderSessionImage(const session::Session& session, const RenderSettings& settings,
                             const std::optional<Camera>& camera) {
  validateRenderSettings(settings, "render settings");
  SessionScene scene(session);
  OffscreenRenderer renderer;
  Camera cam = camera ? *camera : defaultCamera(scene.scene(), float(settings.width) / float(settings.height));
  return renderer.render(scene.scene(), cam, settings);
}

void renderScenePng(const session::Session& session, const RenderSettings& settings, const std::filesystem::path& png,
                    const std::optional<Camera>& camera) {
  io::Image image = renderSessionImage(session, settings, camera);
  io::writeFileAtomic(png, io::encodePng(image));
}

}  // namespace tendril::render
