// The OpenGL renderer shared by the studio window and headless rendering (offscreen.h).
//
// A frame (seed 000 §6):
//  1. Plants become instance data: one generalised-cylinder instance per skeleton node and one
//     curved-blade instance per leaf (plant_instances.h). All plants share two instance
//     buffers, re-filled every frame by orphaning + glBufferSubData, so a growing or swaying
//     plant costs one upload and two instanced draws however many nodes it has.
//  2. Shadow pass: the first directional light renders the first two moments of depth into a
//     variance shadow map fitted to the scene's focus bounds (Donnelly & Lauritzen 2006);
//     branches, obstacles and alpha-tested leaves cast. A separable Gaussian blur pre-filters
//     the map, which is what gives soft edges without aliasing.
//  3. Main pass into the caller's framebuffer: obstacles and plant primitives (flat normals,
//     primitives instanced per distinct mesh), branches (bark
//     texture, or blue→red stress colours), leaves (alpha-tested at 0.5, textured, double-
//     sided with translucency), stroke points, ground grid and gizmo lines. Lighting is
//     Blinn-Phong with hemispheric ambient, tone-mapped (ACES) and written sRGB-encoded.
#pragma once

#include "tendril/render/camera.h"
#include "tendril/render/render_scene.h"

#include <cstddef>
#include <memory>
#include <string>

namespace tendril::render {

struct FrameStats {
  size_t branchInstances = 0;
  size_t leafInstances = 0;
  size_t primitiveInstances = 0;
  size_t obstacleTriangles = 0;
  size_t drawCalls = 0;
  double buildMs = 0.0;   // CPU: instance arrays from the plants (and textures seen for the first time)
  double uploadMs = 0.0;  // CPU: buffer and texture uploads
  double drawMs = 0.0;    // CPU: issuing the shadow and main passes (the GPU may still be busy)
};

class Renderer {
 public:
  // Needs a current OpenGL 4.1+ core profile context; throws Error naming the version found
  // otherwise. Every call, the destructor included, must be made with that context current.
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Draws `scene` seen by `camera` into the framebuffer bound to GL_DRAW_FRAMEBUFFER, over the
  // viewport (0, 0, width, height), clearing it to the scene's background first. The draw
  // framebuffer and viewport are restored afterwards; other GL state (depth test, culling,
  // bound program and vertex array) is left as the renderer last set it. settings.width,
  // settings.height and settings.samples are not used here (they describe offscreen images).
  void render(const RenderScene& scene, const Camera& camera, const RenderSettings& settings, int width, int height);

  const FrameStats& lastFrame() const;
  // "OpenGL 4.5 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6, 256 bits)".
  std::string glDescription() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tendril::render
