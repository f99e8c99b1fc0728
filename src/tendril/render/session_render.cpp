#include "tendril/render/session_render.h"

#include "tendril/io/atomic_file.h"
#include "tendril/render/offscreen.h"
#include "tendril/wind/sph.h"

#include <algorithm>

namespace tendril::render {

AirView airView(const session::Session& session) {
  AirView view;
  const wind::SphAir* air = session.air();
  if (!air) return view;
  view.positions = air->positions();
  view.velocities = air->velocities();
  // The scene's wind mid-scale (green), the air it speeds up toward red, its lees blue; at the
  // scene's wind a streak is 3/4 of the particle spacing long.
  const env::WindSettings& w = session.environment().windField().settings();
  float wind = std::max(0.5f, w.velocity.norm());
  for (const env::WindEmitter& e : w.emitters) wind = std::max(wind, e.speed);
  const float spacing = air->settings().spacing;
  view.maxSpeed = 2.0f * wind;
  view.streakSeconds = 0.75f * spacing / wind;
  view.minLength = 0.2f * spacing;
  return view;
}

SessionScene::SessionScene(const session::Session& session, bool air) : plants_(session.plants()) {
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
  if (air) scene_.air = airView(session);
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

void writePreview(const session::Session& session, const std::filesystem::path& png, int width, int height) {
  io::checkOutputPath(png);
  SessionScene view(session);
  RenderSettings settings;
  settings.width = width;
  settings.height = height;
  const Camera camera =
      frameBounds(focusBounds(view.scene()), kDefaultViewDirection, float(width) / float(height), radians(40.0f));
  OffscreenRenderer renderer;
  io::writeFileAtomic(png, io::encodePng(renderer.render(view.scene(), camera, settings)));
}

}  // namespace tendril::render
