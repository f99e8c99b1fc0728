// Rendering a Session's current state to an image: what `tendril render` does, and what other
// commands reuse for a `--preview out.png`.
#pragma once

#include "tendril/io/image.h"
#include "tendril/render/camera.h"
#include "tendril/render/render_scene.h"
#include "tendril/session/session.h"

#include <filesystem>
#include <optional>
#include <vector>

namespace tendril::render {

// A RenderScene made from a Session, owning copies of everything it points to (plant
// snapshots, obstacle meshes). Its focus is the plants and every obstacle but ground planes,
// so the default camera and the shadow map frame what grows rather than the whole ground.
class SessionScene {
 public:
  // With `air`, the session's simulated air too (airView).
  explicit SessionScene(const session::Session& session, bool air = false);
  SessionScene(const SessionScene&) = delete;
  SessionScene& operator=(const SessionScene&) = delete;

  const RenderScene& scene() const { return scene_; }
  // Adjustable (background, grid, gizmos); the plant and obstacle pointers must stay as made.
  RenderScene& scene() { return scene_; }
  const std::vector<plant::PlantModel>& plants() const { return plants_; }

 private:
  std::vector<plant::PlantModel> plants_;
  std::vector<TriangleMesh> meshes_;
  RenderScene scene_;
};

// The session's simulated air (wind mode "sph") as streaks: the fastest wind the scene sets
// (prevailing or emitter) is mid-scale and draws streaks 3/4 of the air's spacing long. Empty
// without air.
AirView airView(const session::Session& session);

// Renders the session at settings.width × settings.height, from `camera` or by default from
// defaultCamera(). Creates (and ends) its own offscreen OpenGL context; throws Error when none
// can be made.
io::Image renderSessionImage(const session::Session& session, const RenderSettings& settings,
                             const std::optional<Camera>& camera = std::nullopt);

// The same, written to `png` atomically (a temporary file renamed over it once complete).
void renderScenePng(const session::Session& session, const RenderSettings& settings, const std::filesystem::path& png,
                    const std::optional<Camera>& camera = std::nullopt);

// A preview picture: the session from the default 3/4 view, framed on what grows (40° field of
// view), written to `png` atomically. What `tendril edit --preview` and the Python module's
// Session.render write.
void writePreview(const session::Session& session, const std::filesystem::path& png, int width = 960,
                  int height = 540);

}  // namespace tendril::render
