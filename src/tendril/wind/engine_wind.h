// Engine wind data (issue 26 part 4, docs/engine-wind.md): per skeleton node, what a game
// engine's vertex shader needs to sway a plant the way WindMotion does, and that shader's
// displacement written once here, so that the documented GLSL and the test cannot drift.
//
// For a small steady wind w = s ŵ, WindMotion bends every node j by θ_j = τ_j / k_j about its
// base p_j (eq. 1 settled: its spring k_j against the drag's moment τ_j of everything it
// carries), and a vertex x on node i moves by Σ_j θ_j × (x − p_j) over the path j from the root
// to i (small rotations add). The drag grows as s², so θ_j = s² M_j ŵ for a 3 × 3 matrix M_j,
// read off WindMotion's own torques for unit winds along x, y and z; its skew part is
// M_j ŵ ≈ L_j × ŵ, L_j the node's lever (the drag's lever arm over k). With L = Σ_j L_j, its
// direction Â and λ_j = L_j · Â, the vertex's motion is, to first order, one rotation
//     d(x) = s² (L × ŵ) × (x − P),   P = Σ_j λ_j p_j / Σ_j λ_j,
// exact when the levers along the path are parallel (the larger they differ, the larger the
// error: the test states it). L goes to _WIND_AXIS, P to _WIND_PIVOT.
#pragma once

#include "tendril/core/math.h"
#include "tendril/io/wind_attributes.h"
#include "tendril/plant/growth_flow.h"
#include "tendril/plant/plant_model.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace tendril::wind {

// The wind tables of a plant: one record per node (WindMotion's sway in unit winds).
std::vector<io::WindVertexNode> engineWindNodes(const plant::PlantModel& plant, const plant::GrowthFlowSpecies& species);
// ... of every plant (species[i] for plant i; the default species where there is none).
io::WindTables engineWindTables(const std::vector<plant::PlantModel>& plants,
                                const std::vector<plant::GrowthFlowSpecies>& species);

// COLOR_0.b back to the natural period (s), and the period's range.
inline constexpr float kEngineMinPeriod = 0.4f, kEngineMaxPeriod = 6.0f;
inline float enginePeriod(float encoded) { return kEngineMinPeriod + (kEngineMaxPeriod - kEngineMinPeriod) * encoded; }

// The shader's uniforms.
struct EngineWindUniforms {
  Vec3 wind = Vec3::Zero();  // m/s, world (the glTF's frame)
  float time = 0.0f;         // s
  float gust = 0.0f;         // relative swing about the steady bend (0: steady wind)
  float maxAngle = 0.35f;    // rad, the bend's limit
};

// The displacement docs/engine-wind.md's vertex shader gives a vertex at `position` with
// attributes pivot (_WIND_PIVOT), lever (_WIND_AXIS) and color (COLOR_0): a rotation about
// the pivot by the rotation vector s² (L × ŵ) (= |w| (L × w)), swung by `gust` at the branch's
// natural period and phase. Line for line the GLSL of the doc.
inline Vec3 engineWindDisplacement(const Vec3& position, const Vec3& pivot, const Vec3& lever, const Vec4& color,
                                   const EngineWindUniforms& u) {
  const float speed = u.wind.norm();
  const float period = enginePeriod(color.z());
  const float swing = 1.0f + u.gust * std::sin(kTwoPi * (u.time / period + color.y()));
  const Vec3 bend = speed * swing * lever.cross(u.wind);  // rotation vector
  const float angle = std::min(bend.norm(), u.maxAngle);
  if (!(angle > 0.0f)) return Vec3::Zero();
  const Vec3 k = bend.normalized();
  const Vec3 r = position - pivot;
  // Rodrigues: r cos a + (k × r) sin a + k (k · r)(1 − cos a).
  const Vec3 rotated = r * std::cos(angle) + k.cross(r) * std::sin(angle) + k * (k.dot(r) * (1.0f - std::cos(angle)));
  return rotated - r;
}

}  // namespace tendril::wind
