// Triangle meshes of the geometry-producing components other than tube stems (those become
// skeleton chains swept by mesh/): Simple solids, Revo surfaces of revolution, Horns with a
// cross-section, curved Leaf blades and the strips between consecutive point sets.
//
// Every mesh has unit normals and uvs. Open surfaces (discs, revolution surfaces, blades,
// strips) are double-sided: each face is emitted twice with opposite winding, because glTF
// materials of primitives are single-sided.
#pragma once

#include "tendril/core/triangle_mesh.h"
#include "tendril/graph/components.h"
#include "tendril/graph/expand.h"

#include <span>
#include <vector>

namespace tendril::graph {

// A Simple solid standing on the origin: cube [-sx/2, sx/2] × [0, sy] × [-sz/2, sz/2]; sphere
// (an ellipsoid) in the same box; cylinder and cone of diameters sx, sz and height sy along +Y;
// disc of diameters sx, sz in the XZ plane. `segments` tessellates round shapes. Returns an
// empty mesh when a needed dimension is zero.
TriangleMesh solidMesh(Shape shape, const Vec3& size, int segments);

// Surface of revolution about +Y of the [radius, height] profile (seed 004 sidebar, Revo).
TriangleMesh revoMesh(const RevoParams& params, int samples, int segments);

// A generalised cylinder through `rings` (world frames; the section lies in each ring's XZ
// plane, scaled by the ring's radius), closed at both ends (seed 004 sidebar, Horn, Fig. B).
// World space.
TriangleMesh sectionSweepMesh(std::span<const Ring> rings, const std::vector<Vec2>& section);

// A leaf blade of length 1 starting at the origin along +Y, upper side +Z (seed 004 sidebar,
// Leaf): half widths along the blade from `outline` ([position, half width], in blade lengths)
// or from `profile` (half widths sampled evenly over [0, 1]); longitudinal `curvature` (radians
// over the blade; positive bends the tip toward -Z) and lateral `fold` (radians the edges rise
// toward +Z). UVs project the texture as a card of width `aspect` would show it.
struct BladeSpec {
  float aspect = 1.0f;
  float curvature = 0.0f;
  float fold = 0.0f;
  int rows = 8, columns = 4;
  std::vector<Vec2> outline;
  bool outlineSpline = true;
  std::vector<float> profile;  // used when outline is empty (>= 2 samples); else a rectangle of width aspect
};
TriangleMesh bladeMesh(const BladeSpec& spec);

// Half widths (in units of the image width) of the opaque part of a leaf texture, `samples`
// rows from its bottom (petiole) to its top: the outline of a textured blade.
std::vector<float> textureHalfWidths(const std::string& textureSpec, int samples);

// The strip joining two point sets with the same number of points (closed: also the last to
// the first), v running from v0 (a) to v1 (b). World space, double-sided.
TriangleMesh pointSetStrip(std::span<const Vec3> a, std::span<const Vec3> b, bool closed, float v0, float v1);
// A fan closing a ring of points, double-sided.
TriangleMesh pointSetCap(std::span<const Vec3> ring);

// Appends the back faces: every triangle again with reversed winding and negated normals.
void makeDoubleSided(TriangleMesh& mesh);

}  // namespace tendril::graph
