// What the renderer draws: a plain description built by the caller (the studio every frame,
// the CLI once), never the Session itself. Meshes and plants are referenced, not copied: they
// belong to the caller and must stay alive and unchanged during Renderer::render.
// Colours are linear RGB.
#pragma once

#include "tendril/core/math.h"
#include "tendril/core/triangle_mesh.h"
#include "tendril/env/environment.h"
#include "tendril/plant/plant_model.h"
#include "tendril/render/camera.h"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace tendril::render {

struct ObstacleView {
  const TriangleMesh* mesh = nullptr;  // local frame; only positions and indices are used
  RigidTransform worldFromLocal;
  Vec3 color = Vec3(0.6f, 0.6f, 0.6f);
  bool selected = false;
  // Identifies the mesh's content across frames so its GPU copy is reused: the same non-zero
  // key promises the same vertices and indices. 0 = hash the content every frame.
  uint64_t meshKey = 0;
};

// A range of skeleton nodes [first, first + count) (a selected branch, say).
struct NodeRange {
  uint32_t first = 0;
  uint32_t count = 0;
  bool contains(size_t node) const { return node >= first && node - first < count; }
};

struct PlantView {
  const plant::PlantModel* model = nullptr;
  // Empty, or one value in [0, 1] per node: branches are coloured from blue (0) to red (1)
  // instead of bark, as in seed 000 fig. 6 and 10.
  std::span<const float> stress;
  NodeRange selected;  // highlighted nodes, and the leaves on them
};

// A line drawn over the scene (wind emitters, axes, picking feedback), optionally with an
// arrow head at `end`.
struct GizmoLine {
  Vec3 start = Vec3::Zero();
  Vec3 end = Vec3::Zero();
  Vec3 color = Vec3(1.0f, 0.8f, 0.2f);
  bool arrow = false;
};

// Simulated air (SPH particles, docs/sph.md) drawn as streaks centred on each particle along
// its velocity, v·streakSeconds long (at least minLength), coloured by speed from blue (still)
// through green (maxSpeed / 2) to red (maxSpeed and faster). Not part of the scene's bounds.
struct AirView {
  std::vector<Vec3> positions, velocities;
  float streakSeconds = 0.04f;  // s
  float minLength = 0.01f;      // m; still air along +y
  float maxSpeed = 5.0f;        // m/s
};

struct GroundGrid {
  bool enabled = false;
  float height = 0.0f;   // y of the grid plane (m)
  float spacing = 0.5f;  // m between lines
  int halfLines = 10;    // lines each side of the origin, along x and along z
  Vec3 color = Vec3(0.25f, 0.25f, 0.25f);
};

struct RenderScene {
  std::vector<ObstacleView> obstacles;
  std::vector<PlantView> plants;
  // Lights as the environment defines them; an empty list gets one light from above and in
  // front. Intensities are relative weights: together the lights give a fixed irradiance
  // (sun-like, before exposure), point lights falling off as 1 / (1 + d²). The first
  // directional light casts shadows; up to 8 lights are used.
  std::vector<env::Light> lights;
  std::vector<env::Stroke> strokes;  // painted points: attract green-ish, repel red-ish
  std::vector<GizmoLine> gizmos;
  AirView air;
  Vec3 background = Vec3(0.62f, 0.72f, 0.84f);
  GroundGrid grid;
  // The part of the scene that matters (plants and their supports, say): the shadow map is
  // fitted to it and defaultCamera frames it. Empty = the bounds of everything.
  Bounds3 focus;
};

// Bounds of every obstacle (world), plant node, leaf, plant primitive and stroke point.
Bounds3 sceneBounds(const RenderScene& scene);
// scene.focus, or sceneBounds when it is empty.
Bounds3 focusBounds(const RenderScene& scene);

// The lights the renderer uses for `scene` (its own, or the default light when it has none).
std::vector<env::Light> effectiveLights(const RenderScene& scene);

// Quality and look. Checked by validateRenderSettings.
struct RenderSettings {
  int width = 1280;          // image size for offscreen rendering (pixels, 16..16384)
  int height = 720;
  int samples = 4;           // MSAA samples for offscreen rendering (1 = none; clamped to GL_MAX_SAMPLES)
  bool shadows = true;       // variance shadow map from the first directional light
  int shadowMapSize = 2048;  // texels per side (256..8192)
  int branchSides = 8;       // vertices around each branch ring (3..64)
  float exposure = 1.0f;     // multiplies the light before tone mapping (> 0)
  float lineWidth = 1.5f;    // gizmo and grid lines (pixels, 0.5..128)
};

inline RenderSettings defaultRenderSettings() { return {}; }

// Throws Error(source, "<field>", what was expected) for an out-of-range field.
void validateRenderSettings(const RenderSettings& settings, const std::string& source);

// The direction of the default 3/4 front view: from the front right and above, toward −Z
// (the side walls face, see env/primitives.h).
inline const Vec3 kDefaultViewDirection = Vec3(-0.45f, -0.32f, -1.0f);

// frameBounds(focusBounds(scene), kDefaultViewDirection, aspect, fovY).
Camera defaultCamera(const RenderScene& scene, float aspect, float fovY = radians(40.0f));

}  // namespace tendril::render
