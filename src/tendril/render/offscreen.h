// Headless rendering: an OpenGL 4.1+ core context through EGL with no window and no X server
// (Mesa's llvmpipe on CI machines, the GPU driver elsewhere), a multisampled framebuffer, and
// read-back to an io::Image. The same Renderer draws here and in the studio's window.
#pragma once

#include "tendril/io/image.h"
#include "tendril/render/camera.h"
#include "tendril/render/render_scene.h"
#include "tendril/render/renderer.h"

#include <memory>
#include <string>

namespace tendril::render {

// An EGL display and an OpenGL core context, current on the constructing thread. Tries, in
// order: the Mesa surfaceless platform, each EGL device (EGL_EXT_platform_device), then the
// default display with a 16×16 pbuffer; on each, a 4.6 → 4.1 core context. Throws
// Error("OpenGL", "", ...) listing what was tried and why each failed when none works.
class OffscreenContext {
 public:
  OffscreenContext();
  ~OffscreenContext();
  OffscreenContext(const OffscreenContext&) = delete;
  OffscreenContext& operator=(const OffscreenContext&) = delete;

  void makeCurrent() const;
  // How the context was made: "EGL surfaceless (Mesa), OpenGL 4.5 core".
  const std::string& description() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A colour + depth framebuffer of a fixed image size with anti-aliasing, and its read-back.
// Needs the context current.
//
// `samples` > 1 anti-aliases with multisampling (clamped to GL_MAX_SAMPLES) and a resolve
// blit, except on Mesa's software rasterisers (llvmpipe, softpipe): their multisampling costs
// grow with the triangle count (a 25k-node plant took 30× longer with 4× MSAA than without),
// so there the target supersamples instead, rendering k × k times larger (k = ceil(√samples),
// at most 4) and averaging each k × k block in linear light. That also smooths alpha-tested
// leaf edges, which multisampling does not.
class OffscreenTarget {
 public:
  OffscreenTarget(int width, int height, int samples);
  ~OffscreenTarget();
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;

  // The image size.
  int width() const;
  int height() const;
  // The framebuffer's size (larger than the image when supersampling): what to render at.
  int framebufferWidth() const;
  int framebufferHeight() const;
  // Samples per pixel actually used, and how.
  int samples() const;
  bool supersampled() const;
  // Binds the framebuffer for drawing (GL_FRAMEBUFFER) and sets the viewport to all of it.
  void bind() const;
  // Resolves the samples, reads the pixels back and flips them to top-to-bottom rows.
  io::Image read() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Context, renderer and target together: what `tendril render` and tests use.
class OffscreenRenderer {
 public:
  OffscreenRenderer();  // throws Error when no OpenGL context can be created
  ~OffscreenRenderer();

  // Renders at settings.width × settings.height with settings.samples and returns the image.
  io::Image render(const RenderScene& scene, const Camera& camera, const RenderSettings& settings);

  Renderer& renderer() { return *renderer_; }
  const OffscreenContext& context() const { return *context_; }
  // Wall time of the last render() call including the GPU's work and the read-back (ms).
  double lastRenderMs() const { return lastRenderMs_; }

 private:
  std::unique_ptr<OffscreenContext> context_;
  std::unique_ptr<Renderer> renderer_;
  std::unique_ptr<OffscreenTarget> target_;
  int targetSamples_ = 0;  // as requested (the target may have clamped it)
  double lastRenderMs_ = 0.0;
};

}  // namespace tendril::render
