// tendril-studio's application: one open Session, the camera, the active tool and the panels.
// A frame advances the simulation (when playing), rebuilds the viewport scene, lays out the
// panels, draws the 3D view through render::Renderer and the UI over it.
#pragma once

#include "options.h"
#include "picking.h"
#include "viewport_scene.h"
#include "window.h"

#include "tendril/render/camera.h"
#include "tendril/render/renderer.h"
#include "tendril/session/session.h"

#include <memory>
#include <string>

namespace tendril::studio {

enum class Tool { View, Seed, BranchSeed, Cut, Drag, PaintAttract, PaintRepel, MoveObstacle, Light, WindEmitter };

const char* toolName(Tool tool);

// Per-frame timing (ms).
struct FrameTiming {
  double simulation = 0.0;  // growth and dynamics steps
  double update = 0.0;      // plant snapshots, viewport scene, render instances and uploads
  double draw = 0.0;        // the renderer's passes and the UI, until the GPU is done
  double frame = 0.0;       // the whole frame
};

// Screen rectangle in window pixels, top-left origin.
struct Rect {
  float x = 0, y = 0, w = 0, h = 0;
  bool contains(float px, float py) const { return px >= x && py >= y && px < x + w && py < y + h; }
};

class Studio {
 public:
  explicit Studio(const StudioOptions& options);
  ~Studio();

  // Runs until the window closes (interactive) or the headless frames are done; returns the
  // exit code.
  int run();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tendril::studio
