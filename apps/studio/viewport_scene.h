// The RenderScene the viewport draws, rebuilt from the Session every frame: plant snapshots
// (they change every step), obstacles at their current transforms (meshes kept until the
// obstacles change), lights, strokes, wind emitters, the simulated air and the selection. Unlike
// render::SessionScene it keeps obstacle meshes across frames, so a frame costs the plant
// snapshots and nothing else.
#pragma once

#include "tendril/render/render_scene.h"
#include "tendril/session/plant_sway.h"
#include "tendril/session/session.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace tendril::studio {

struct Selection {
  enum class Kind { None, Plant, Obstacle, Light, Stroke, Emitter };
  Kind kind = Kind::None;
  uint32_t index = 0;
  std::optional<uint32_t> node;  // Plant: the picked segment
  bool is(Kind k, uint32_t i) const { return kind == k && index == i; }
};

class ViewportScene {
 public:
  // Rebuilds the scene from the session. `meshesChanged` forces the obstacle meshes to be
  // fetched again (an obstacle was added, imported or rescaled).
  // With `air`, the session's simulated air too (render::airView).
  void update(const session::Session& session, const Selection& selection, bool meshesChanged, bool air = false);
  // Per-node stress in [0, 1] for a plant (empty = bark colours); applyStress hands the
  // current values to the scene's plant views.
  void setStress(uint32_t plant, std::vector<float> stress);
  // Growth-Flow motion (session/plant_sway.h) of the plants as the last update() took them, at
  // time t (s) with frame length dt: branches sway and leaves move in the scene's wind while
  // the plants grow and are edited.
  void sway(const session::Session& session, float t, float dt);
  // Forgets every plant's motion (sway turned off, or another session opened).
  void stopSway() { sway_.clear(); }
  void applyStress();

  const render::RenderScene& scene() const { return scene_; }
  // For this frame's previews (gesture feedback); rebuilt by the next update().
  render::RenderScene& mutableScene() { return scene_; }
  const std::vector<plant::PlantModel>& plants() const { return plants_; }
  double snapshotMs() const { return snapshotMs_; }

 private:
  std::vector<plant::PlantModel> plants_;
  session::PlantSway sway_;
  std::vector<std::vector<float>> stress_;
  std::vector<TriangleMesh> meshes_;
  std::vector<uint64_t> meshKeys_;
  uint64_t nextKey_ = 1;
  render::RenderScene scene_;
  double snapshotMs_ = 0.0;
};

}  // namespace tendril::studio
