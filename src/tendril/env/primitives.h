// Built-in obstacle shapes as closed, outward-wound triangle meshes in their local frame.
// Frames: box, sphere and cylinder are centred on their origin (cylinder axis +Y); the plane's
// top surface is at y = 0 (it is a slab reaching `thickness` below, so "below ground" is
// inside); a wall stands on its origin: x across [-w/2, w/2], y up [0, h], z through
// [-t/2, t/2], front face at +z.
#pragma once

#include "tendril/core/triangle_mesh.h"

#include <string>
#include <vector>

namespace tendril::env {

TriangleMesh makeBox(const Vec3& size);
TriangleMesh makePlane(const Vec2& sizeXZ, float thickness);
// Icosphere: 20·4^subdivisions triangles.
TriangleMesh makeSphere(float radius, int subdivisions);
TriangleMesh makeCylinder(float radius, float height, int segments);

// A rectangular opening in a wall, in the wall's x (across) / y (up) coordinates (m).
struct WallOpening {
  Vec2 center = Vec2::Zero();
  Vec2 size = Vec2::Zero();
};
// Empty when the openings fit: each strictly inside the wall face and none overlapping.
// Otherwise a message naming the first bad opening by index.
std::string checkWallOpenings(const Vec3& size, const std::vector<WallOpening>& openings);
// A wall of size (width, height, thickness) with rectangular openings through it (windows,
// doors that stop short of the base). Built on the grid of all opening edges so the mesh is
// closed and manifold, with no T-junctions. Openings must pass checkWallOpenings.
TriangleMesh makeWall(const Vec3& size, const std::vector<WallOpening>& openings);

}  // namespace tendril::env
