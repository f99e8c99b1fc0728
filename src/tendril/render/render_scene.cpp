#include "tendril/render/render_scene.h"

#include "tendril/core/error.h"
#include "tendril/mesh/primitive_mesh.h"

#include <fmt/format.h>

namespace tendril::render {

Bounds3 sceneBounds(const RenderScene& scene) {
  Bounds3 b;
  for (const ObstacleView& o : scene.obstacles) {
    if (!o.mesh) continue;
    for (const Vec3& p : o.mesh->positions) b.extend(o.worldFromLocal.applyPoint(p));
  }
  for (const PlantView& v : scene.plants) {
    if (!v.model) continue;
    const plant::PlantModel& m = *v.model;
    for (size_t i = 0; i < m.nodeCount(); ++i) {
      b.extend(m.position[i]);
      b.extend(m.tip(i));
    }
    for (size_t i = 0; i < m.leafCount(); ++i) {
      Vec3 base = m.leafWorldPosition(i);
      b.extend(base);
      b.extend(base + (m.leafPetiole[i] + m.leafSize[i]) * (m.leafWorldRotation(i) * Vec3::UnitY()));
    }
    for (const plant::Primitive& p : m.primitives) {
      Bounds3 local = m.meshes[p.mesh].mesh.bounds();
      if (local.empty()) continue;
      Mat4 world = mesh::worldFromNode(m, p.node) * p.nodeFromPrimitive;
      for (int k = 0; k < 8; ++k) {
        Vec4 corner((k & 1) ? local.max.x() : local.min.x(), (k & 2) ? local.max.y() : local.min.y(),
                    (k & 4) ? local.max.z() : local.min.z(), 1.0f);
        b.extend(Vec3((world * corner).head<3>()));
      }
    }
  }
  for (const env::Stroke& s : scene.strokes)
    for (const Vec3& p : s.points) b.extend(p);
  return b;
}

Bounds3 focusBounds(const RenderScene& scene) { return scene.focus.empty() ? sceneBounds(scene) : scene.focus; }

std::vector<env::Light> effectiveLights(const RenderScene& scene) {
  if (!scene.lights.empty()) return scene.lights;
  env::Light sun;
  sun.type = env::Light::Type::Directional;
  sun.direction = Vec3(-0.3f, -1.0f, -0.6f).normalized();
  sun.intensity = 1.0f;
  return {sun};
}

void validateRenderSettings(const RenderSettings& s, const std::string& source) {
  auto range = [&](const char* field, int value, int lo, int hi) {
    if (value < lo || value > hi)
      throw Error(source, field, fmt::format("must be between {} and {} (got {})", lo, hi, value));
  };
  range("width", s.width, 16, 16384);
  range("height", s.height, 16, 16384);
  range("samples", s.samples, 1, 64);
  range("shadowMapSize", s.shadowMapSize, 256, 8192);
  range("branchSides", s.branchSides, 3, 64);
  if (!(s.exposure > 0.0f) || !isFinite(s.exposure))
    throw Error(source, "exposure", fmt::format("must be a positive number (got {})", s.exposure));
  if (!(s.lineWidth >= 0.5f && s.lineWidth <= 128.0f))
    throw Error(source, "lineWidth", fmt::format("must be between 0.5 and 128 pixels (got {})", s.lineWidth));
}

Camera defaultCamera(const RenderScene& scene, float aspect, float fovY) {
  return frameBounds(focusBounds(scene), kDefaultViewDirection, aspect, fovY);
}

}  // namespace tendril::render
