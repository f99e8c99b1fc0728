// The impostor baker of the renderer (io/impostor.h): renders each slab view of a plant with
// Tendril's OpenGL stack, headless (an EGL offscreen context, offscreen.h; llvmpipe on CI).
// One orthographic pass per view into a colour and a normal attachment, the near and far
// planes at the slab's faces, leaves alpha-tested at 0.5 as the exporters' materials are; no
// anti-aliasing, so a texel is covered exactly where the alpha test keeps the surface at its
// centre. llvmpipe's rasteriser is deterministic: the same views give the same bytes for any
// thread count.
#pragma once

#include "tendril/io/impostor.h"

#include <memory>
#include <mutex>

namespace tendril::render {

class RendererImpostorBaker final : public io::ImpostorBaker {
 public:
  // Each bake() call renders on a thread of its own with an OpenGL context of its own (so that a
  // caller with a context current, the studio, keeps it); calls are serialised.
  std::vector<io::ImpostorImages> bake(const std::vector<io::ImpostorSurface>& surfaces,
                                       const std::vector<io::ImpostorView>& views) override;

 private:
  std::mutex mutex_;
};

// Installs a RendererImpostorBaker as the process's baker (io::installImpostorBaker): what
// every entry point that links the renderer (CLI, studio, Python module) calls at start.
void installRendererImpostorBaker();

}  // namespace tendril::render
