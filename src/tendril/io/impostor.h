// The impostor (issue 26 part 3): a plant's last level of detail as a slab billboard cloud.
//
// Three families of parallel quads, one family per axis of the plant's bounding box, K slabs
// (ImpostorSettings::slabs) per family. Each quad lies in the middle plane of its slab and is
// textured with what of the plant lies in that slab, seen orthographically along the slab's
// normal (near and far planes clip to the slab). From any view each family alone approximates
// the plant's projection. Where all three show everything, an oblique view sees three copies of
// each part, each displaced by up to half a slab's parallax, and their union overshoots the
// silhouette (by 20 % and more at 45° with four slabs); so alpha-tested leaves, flat blades,
// are drawn only into the families they face: into family f where |n_f| ≥ kImpostorLeafShare ·
// max_k |n_k| for the blade's face normal n. Bark and primitives, whose grazing parts make the
// silhouette of axis-aligned views, go into every family. The baker (ImpostorBaker) applies
// this rule; ImpostorSurface::alphaMask marks the leaves. The quads are double-sided,
// alpha-tested (MASK, cutoff 0.5), with a base colour and a normal texture: one atlas pair per
// plant. Normal map: glTF's convention, the surface normal in the quad's tangent frame
// (red +U = the TANGENT written for the quad, green = image up, blue = the quad's normal),
// each component c stored as (c + 1) / 2.
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
};

// What a baker returns per view: `color` the base colour (sRGB-encoded; alpha 255 where the
// plant covers the texel after alpha testing, else 0) and `normal` (the normal facing the
// viewer in the view's frame: u, −v, normal; (c + 1) / 2; alpha as colour's).
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
  int axis = 0;            // 0, 1, 2: the family (slab normal along x, y, z)
  int slab = 0;            // 0 .. slabs − 1, from the low end of the axis
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

// The slab views alone (for tests and the baker's callers): every non-empty slab's view, in
// order of axis then slab, with its axis and slab index in `quads`.
std::vector<ImpostorQuad> impostorLayout(const std::vector<ImpostorSurface>& surfaces,
                                         const ImpostorSettings& settings);

}  // namespace tendril::io
