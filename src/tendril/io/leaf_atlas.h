// Leaf atlases (ExportOptions::leafAtlas): the leaf textures of a plant packed into one image
// with stb_rect_pack, and its leaves (of every shape, on every level of detail) merged into one
// mesh whose UVs point into that image, so that they are one material and one draw call.
//
// Each texture keeps its pixels (no resampling) and gets a gutter of kLeafAtlasGutter pixels on
// every side, filled by extending its edge texels outwards (what clamp-to-edge sampling of the
// texture alone would see), so that bilinear filtering and the first mip levels do not bleed
// one leaf into another. Cells are sized in multiples of 4 pixels. When a plant's leaf shapes
// have different tints, each tint is multiplied into its texture's pixels (in linear space) and
// the material's factor is white; otherwise the common tint stays the material's factor and
// the atlas holds the textures' pixels unchanged. Plants whose atlases would be the same share
// one.
#pragma once

#include "tendril/core/math.h"
#include "tendril/io/export_scene.h"
#include "tendril/io/texture.h"
#include "tendril/mesh/plant_mesh.h"

#include <string>
#include <vector>

namespace tendril::io {

struct TexturePreload;

inline constexpr int kLeafAtlasGutter = 8;
// The leaf atlas material's KHR_materials_diffuse_transmission factor: a quarter of the diffuse
// light goes through a leaf (thin blades transmit 10-40 %), tinted by the leaf's own colour.
inline constexpr float kLeafDiffuseTransmission = 0.25f;

// One texture's place in an atlas: its pixels occupy [x, x + width) × [y, y + height), rows
// from the top of the atlas image.
struct LeafAtlasRect {
  std::string texture;  // the texture spec
  Vec3 tint = Vec3::Ones();  // multiplied into the pixels when the atlas bakes tints
  int x = 0, y = 0, width = 0, height = 0;
};

struct LeafAtlas {
  std::string spec;  // a name for the image: "leaf-atlas-<k>:<texture labels joined by +>"
  int width = 0, height = 0;
  std::vector<LeafAtlasRect> rects;
  bool bakedTints = false;
  Vec3 tint = Vec3::Ones();  // the material's colour factor
  EncodedImage image;        // PNG
};

// Where one plant's leaves go.
struct PlantLeafAtlas {
  int atlas = -1;               // index into LeafAtlases::atlases; -1: the plant has no leaves
  std::vector<int> shapeRect;   // per leaf shape id: its rectangle in the atlas (-1 if unused)
  uint32_t slot = 0;            // the leaf shape id whose mesh (and part) holds all the leaves
};

struct LeafAtlases {
  std::vector<PlantLeafAtlas> plants;  // one per scene plant
  std::vector<LeafAtlas> atlases;
};

// Lays out and draws the atlases of a scene's plants from the preloaded textures (a texture
// that failed to load is rethrown). Deterministic for any thread count.
LeafAtlases buildLeafAtlases(const ExportScene& scene, const TexturePreload& textures);

// The UV (mesh convention: v up, image rows from the top) in the atlas of `uv` in the texture
// of `rect`.
Vec2 atlasUv(const LeafAtlas& atlas, const LeafAtlasRect& rect, const Vec2& uv);

// Merges the leaf meshes of `mesh` (one level of a plant) into mesh.leaves[plant.slot], shape
// by shape in id order, with UVs remapped into the atlas; the other shapes' meshes are left
// empty. Does nothing for a plant without an atlas.
void applyLeafAtlas(const LeafAtlases& atlases, const PlantLeafAtlas& plant, mesh::PlantMesh& mesh);

}  // namespace tendril::io
