// Viewport geometry the library's picking (session/edit.h: pickNode, pickSurface) does not
// cover: where a dragged point goes as the cursor moves.
#pragma once

#include "tendril/render/camera.h"

namespace tendril::studio {

// The point where the ray through `pixel` meets the plane through `point` facing the camera
// (a dragged particle or obstacle stays at its depth).
Vec3 dragPoint(const render::Camera& camera, int width, int height, const Vec2& pixel, const Vec3& point);

}  // namespace tendril::studio
