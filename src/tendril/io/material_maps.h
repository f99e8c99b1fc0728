// Normal and roughness maps made with a plant's textures (issue 26 part 2; docs/export.md
// "Normal and roughness maps"): the bark's tangent-space normal map and its roughness map, and
// a leaf texture's normal map (its veins raised).
//
// A map is made from a height field over the colour texture's pixels: builtin:bark's own relief
// (io/texture.h builtinBarkHeight: the same noise that colours it, so furrows in the normal map
// lie under the dark furrows of the colour), any other texture's luminance (lighter is higher:
// a leaf's pale veins, a photo's lit bark plates). Normals follow glTF's convention (OpenGL's):
// tangent space, +X along the image's columns (+U), +Y up the image, +Z out of the surface,
// stored as (n + 1) / 2 in RGB; slopes by central differences, wrapping for a repeating texture
// and clamped at the edges otherwise. Roughness maps follow glTF's metallicRoughnessTexture:
// roughness in G (multiplied by the material's roughnessFactor), metalness 0 in B, R unused
// (255). Deterministic.
#pragma once

#include "tendril/core/math.h"
#include "tendril/core/triangle_mesh.h"
#include "tendril/io/image.h"

#include <vector>

namespace tendril::io {

// How deep a map's relief is, in pixels of the image: the height field's full range (0 → 1)
// is this many pixels' widths deep; bark's deep furrows, a leaf's low veins.
inline constexpr float kBarkReliefPixels = 8.0f;
inline constexpr float kLeafReliefPixels = 2.0f;

// A height field over an image's pixels, in [0, 1]: h(x, y) for column x, row y (row 0 on top).
struct HeightField {
  int width = 0, height = 0;
  std::vector<float> h;  // row-major from the top row
  float at(int x, int y) const { return h[size_t(y) * size_t(width) + size_t(x)]; }
};

// builtin:bark's relief sampled at the pixel centres of a size × size image, as drawBark samples.
HeightField barkHeightField(int size);
// An image's luminance (Rec. 709 weights on the sRGB bytes, / 255) as height; 0 where alpha <
// 128 (cut-out texels, never seen).
HeightField luminanceHeightField(const Image& image);

// The unit normal the map stores at pixel (x, y), before 8-bit quantisation: normalize(−d·∂h/∂x,
// d·∂h/∂row, 1) with d = reliefPixels, slopes per pixel (∂h/∂row: down the image, so +Y up gets
// its minus).
Vec3 heightFieldNormal(const HeightField& field, int x, int y, float reliefPixels, bool repeat);

Image normalMap(const HeightField& field, float reliefPixels, bool repeat);

// Per vertex the tangent space a normal map needs (glTF TANGENT): xyz the unit direction of
// increasing u in the surface, orthogonal to the normal; w = ±1 so that cross(normal, xyz)·w
// points along increasing v (the mesh convention: v up the image, the map's +Y). From each
// triangle's UV gradients, area-weighted; a vertex without usable UVs gets any tangent
// orthogonal to its normal. Needs normals and uvs.
std::vector<Vec4> computeTangents(const TriangleMesh& mesh);
// Roughness in G: from `smooth` on the highest relief to 1 in the lowest; B 0, R 255.
Image roughnessMap(const HeightField& field, float smooth = 0.7f);

}  // namespace tendril::io
