// The impostor (issue 26 part 3): a plant's last level of detail as a billboard cloud.
//
// Three families of parallel quads, one family per axis of the plant's bounding box, K slabs
// (ImpostorSettings::slabs) per family. Each quad is textured with what of the plant lies in its
// slab, seen orthographically along the slab's normal (near and far planes clip to the slab),
// and lies at the mean depth of what its slab shows (weighted by the area seen along the axis),
// so a stem in a slab lies on its quad and does not shift when seen obliquely. From any view
// each family alone approximates the plant's projection. Where all three show everything, an
// oblique view sees three copies of each part, each displaced by parallax within its slab, and
// their union overshoots the silhouette (by 20 % and more at 45° with four slabs); so
// alpha-tested leaves, flat blades, are drawn only into the families they face: into family f
// where |n_f| ≥ kImpostorLeafShare · max_k |n_k| for the blade's face normal n. Bark and small
// primitives, whose grazing parts make the silhouette of axis-aligned views, go into every
// family. Large flat primitives (a sunflower's head, leaves and petals: a piece whose area is at
// least (kImpostorFlatSize · the plant's longest side)² and whose corners lie within
// kImpostorFlatness of its narrower extent from its best-fitting plane — or a bent blade whose
// base and tip halves each do, a quad each) get a quad of their own in that plane instead, at most
// kImpostorFlatQuads of them, largest first: in the families they would be either missing from
// views that see them obliquely or copied, displaced, into each. Such a quad vanishes seen
// edge-on, and with it the blade's curl, so a piece nearly edge-on to a family (|n · n_f| <
// kImpostorFlatEdgeOn) is drawn into that family as well. The baker
// (ImpostorBaker) applies the leaves' rule; ImpostorSurface::alphaMask marks the leaves. The
// quads are double-sided, alpha-tested (MASK, cutoff 0.5), with a base colour and a normal
// texture: one atlas pair per plant. Normal map: glTF's convention, the surface normal in the
// quad's tangent frame (red +U = the TANGENT written for the quad, green = image up, blue = the
// quad's normal), each component c stored as (c + 1) / 2. The normal texture's alpha marks what
// each texel shows: 255 a leaf (an alpha-tested surface), 128 anything else, 0 nothing — a leaf
// mask for engines' translucency and for measuring leaf coverage (glTF reads only RGB of a
// normal texture).
//
// Baking needs a renderer, which is not a part of the library (docs/architecture.md,
// "Layers"): the library lays out the slabs, packs the atlas and builds the quads; an
// ImpostorBaker (render/impostor_baker.h) renders the views. Entry points that link the
// renderer install one (installImpostorBaker); asking for an impostor without one is an Error.
#pragma once

#include "tendril/core/math.h"
#include "tendril/core/triangle_mesh.h"
#include "tendril/io/image.h"

#include <memory>
#include <string>
#include <vector>

namespace tendril::io {

// Leaves share (see above): 0 would draw them into every family, 1 only into the one they face most.
inline constexpr float kImpostorLeafShare = 0.8f;
// Flat primitives on quads of their own (see above); chosen on the test plants
// (tests/io/impostor_test.cpp): the sunflower's silhouette within 10 % from the eight views.
inline constexpr float kImpostorFlatSize = 0.02f;
inline constexpr float kImpostorFlatness = 0.1f;
inline constexpr int kImpostorFlatQuads = 96;
inline constexpr float kImpostorFlatEdgeOn = 0.1f;

struct ImpostorSettings {
  bool enabled = false;
  int slabs = 8;          // quads per axis family (1..16)
  int resolution = 256;   // texels across the plant's largest bounding-box side (16..2048)
};
// Throws Error(source, "impostor", ...) for settings out of range.
void validateImpostorSettings(const ImpostorSettings& settings, const std::string& source);

// One part of the plant the baker draws: triangles with normals (and uvs with a texture), a
// linear base colour factor, and whether the texture's alpha cuts it out (< 0.5).
struct ImpostorSurface {
  const TriangleMesh* mesh = nullptr;
  Vec4 baseColor = Vec4::Ones();
  const Image* texture = nullptr;  // sRGB-encoded RGBA (or none)
  bool repeat = false;             // texture wraps (else clamps to edge)
  bool alphaMask = false;
  bool primitive = false;  // a component graph's primitive group: its pieces may get quads of their own
  // Set by buildImpostor on a large flat piece: baked alone onto a quad of its own, in the plane
  // with this unit normal, and into the families it is nearly edge-on to (see above).
  bool ownQuad = false;
  Vec3 ownNormal = Vec3::Zero();
};

// One orthographic view: the image's pixel (x, y) (x right, y down, centre at +0.5) shows the
// plant along −normal at corner + (x + 0.5) / width · u + (y + 0.5) / height · v, keeping only
// what lies at lo ≤ (p − corner) · normal ≤ hi (the slab; the camera is on its +normal side).
struct ImpostorView {
  Vec3 corner = Vec3::Zero();
  Vec3 u = Vec3::UnitX();  // the image's whole width, in world space
  Vec3 v = Vec3::UnitY();  // its whole height (downward in the image)
  Vec3 normal = Vec3::UnitZ();  // unit, u × −v along it; the camera looks along −normal
  float lo = -1.0f, hi = 1.0f;
  int width = 1, height = 1;
  // −1: a family's slab, showing every surface not on its own quad (leaves by the rule above);
  // else the index of the one surface it shows, all of it.
  int surface = -1;
};

// What a baker returns per view: `color` the base colour (sRGB-encoded; alpha 255 where the
// plant covers the texel after alpha testing, else 0) and `normal` (the normal facing the
// viewer in the view's frame: u, −v, normal; (c + 1) / 2; alpha 255 where a leaf covers the
// texel, 128 where something else does, 0 where nothing does).
struct ImpostorImages {
  Image color, normal;
};

class ImpostorBaker {
 public:
  virtual ~ImpostorBaker() = default;
  // Renders every view of the surfaces; throws Error when it cannot. Called from any thread,
  // one call at a time per baker is not assumed (implementations serialise as they need).
  virtual std::vector<ImpostorImages> bake(const std::vector<ImpostorSurface>& surfaces,
                                           const std::vector<ImpostorView>& views) = 0;
};

// The process's baker (none until an entry point installs one; null uninstalls).
void installImpostorBaker(std::shared_ptr<ImpostorBaker> baker);
std::shared_ptr<ImpostorBaker> installedImpostorBaker();

// One quad of the impostor and its place in the atlas.
struct ImpostorQuad {
  int axis = 0;            // 0, 1, 2: the family (slab normal along x, y, z); 3: a flat part's own
  int slab = 0;            // 0 .. slabs − 1, from the low end of the axis; own quads: the surface
  ImpostorView view;       // what was baked for it
  int atlasX = 0, atlasY = 0;  // its texels' top-left corner in the atlas
};

struct Impostor {
  // Four vertices and two triangles per quad; positions, normals (the slab's normal), uvs into
  // the atlas (mesh convention: v up), and `tangents` (xyz +U, w the bitangent's sign).
  TriangleMesh mesh;
  std::vector<Vec4> tangents;
  Image color, normal;  // the atlas pair
  std::vector<ImpostorQuad> quads;
};

// Lays out the slabs of the surfaces' bounding box, has `baker` render them and packs the
// results into one atlas pair. Slabs with nothing in them, or whose bake came out empty (only
// leaves facing other families), get no quad; no geometry, no quads.
// `source` names the plant in errors.
Impostor buildImpostor(const std::vector<ImpostorSurface>& surfaces, const ImpostorSettings& settings,
                       ImpostorBaker& baker, const std::string& source);

// The surfaces as baked: each large flat primitive split off its surface into one of its own
// (ownQuad), the rest of that surface kept (the meshes are owned here).
struct ImpostorParts {
  std::vector<std::unique_ptr<TriangleMesh>> meshes;
  std::vector<ImpostorSurface> surfaces;
};
ImpostorParts splitFlatParts(const std::vector<ImpostorSurface>& surfaces);
// Whether a family's slabs (normal `familyNormal`) show surface `s`: all but those on quads of
// their own, unless nearly edge-on to the family (see above).
inline bool inFamily(const ImpostorSurface& s, const Vec3& familyNormal) {
  return !s.ownQuad || std::abs(s.ownNormal.dot(familyNormal)) < kImpostorFlatEdgeOn;
}

// The views alone (for tests and the baker's callers): every non-empty slab's view, in order of
// axis then slab, then one per surface on its own quad, with its axis and slab (or surface)
// index in `quads`.
std::vector<ImpostorQuad> impostorLayout(const std::vector<ImpostorSurface>& surfaces,
                                         const ImpostorSettings& settings);

}  // namespace tendril::io
