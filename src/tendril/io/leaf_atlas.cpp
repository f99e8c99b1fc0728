#include "tendril/io/leaf_atlas.h"

#include "tendril/core/error.h"
#include "tendril/core/parallel.h"
#include "tendril/io/export_model.h"
#include "tendril/io/rect_pack.h"
#include "tendril/mesh/leaf_mesh.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <exception>
#include <filesystem>

namespace tendril::io {
namespace {

constexpr int kMaxAtlasSize = 16384;

int roundUp4(int v) { return (v + 3) & ~3; }

// A cell: the texture, its gutter, rounded up to 4 pixels.
int cellSize(int textureSize) { return roundUp4(textureSize + 2 * kLeafAtlasGutter); }

std::string textureLabel(const std::string& spec) {
  if (isBuiltinTexture(spec)) return spec.substr(kBuiltinPrefix.size());
  return std::filesystem::path(spec).stem().string();
}

// Places the cells of `rects` with the least atlas area (io/rect_pack.h).
void pack(LeafAtlas& atlas, const std::string& plantName) {
  std::vector<std::array<int, 2>> sizes;
  for (const LeafAtlasRect& r : atlas.rects) sizes.push_back({cellSize(r.width), cellSize(r.height)});
  const PackedRects packed = packRects(sizes, PackGoal::SmallestArea, 256, 4);
  if (packed.corners.empty() || packed.width > kMaxAtlasSize || packed.height > kMaxAtlasSize)
    throw Error(plantName, "leaf atlas",
                fmt::format("the leaf textures do not fit in a {0} x {0} atlas (they need {1} x {2} pixels)",
                            kMaxAtlasSize, packed.width, packed.height));
  atlas.width = packed.width;
  atlas.height = packed.height;
  for (size_t i = 0; i < atlas.rects.size(); ++i) {
    atlas.rects[i].x = packed.corners[i][0] + kLeafAtlasGutter;
    atlas.rects[i].y = packed.corners[i][1] + kLeafAtlasGutter;
  }
}

float srgbToLinear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }
float linearToSrgb(float c) { return c <= 0.0031308f ? c * 12.92f : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f; }

// Draws the cells of an atlas: each texture at its place, its edge texels extended over the
// rest of its cell. Outside every cell the atlas is transparent black.
Image drawAtlas(const LeafAtlas& atlas, const std::vector<const Image*>& sources) {
  Image out = makeImage(atlas.width, atlas.height, 0, 0, 0, 0);
  for (size_t k = 0; k < atlas.rects.size(); ++k) {
    const LeafAtlasRect& r = atlas.rects[k];
    const Image& src = *sources[k];
    uint8_t lut[3][256];
    for (int c = 0; c < 3; ++c)
      for (int v = 0; v < 256; ++v) {
        const float t = atlas.bakedTints ? std::clamp(r.tint[c], 0.0f, 1.0f) : 1.0f;
        lut[c][v] = atlas.bakedTints
                        ? uint8_t(std::lround(255.0f * linearToSrgb(srgbToLinear(float(v) / 255.0f) * t)))
                        : uint8_t(v);
      }
    const int x0 = r.x - kLeafAtlasGutter, y0 = r.y - kLeafAtlasGutter;
    const int cw = cellSize(r.width), ch = cellSize(r.height);
    for (int y = y0; y < y0 + ch; ++y) {
      const int sy = std::clamp(y - r.y, 0, r.height - 1);
      for (int x = x0; x < x0 + cw; ++x) {
        const int sx = std::clamp(x - r.x, 0, r.width - 1);
        const uint8_t* s = src.pixel(sx, sy);
        uint8_t* d = out.pixel(x, y);
        d[0] = lut[0][s[0]];
        d[1] = lut[1][s[1]];
        d[2] = lut[2][s[2]];
        d[3] = s[3];
      }
    }
  }
  return out;
}

}  // namespace

Vec2 atlasUv(const LeafAtlas& atlas, const LeafAtlasRect& rect, const Vec2& uv) {
  const float W = float(atlas.width), H = float(atlas.height);
  const float x = float(rect.x) + uv.x() * float(rect.width);
  const float y = float(rect.y) + (1.0f - uv.y()) * float(rect.height);  // from the top
  return Vec2(x / W, 1.0f - y / H);
}

LeafAtlases buildLeafAtlases(const ExportScene& scene, const TexturePreload& textures) {
  LeafAtlases out;
  out.plants.resize(scene.plants.size());
  std::vector<std::string> keys;  // per atlas: what makes two plants' atlases the same
  for (size_t i = 0; i < scene.plants.size(); ++i) {
    const plant::PlantModel& p = scene.plants[i];
    const std::string plantName = p.name.empty() ? fmt::format("plant-{}", i) : p.name;
    const size_t shapes = mesh::leafShapeCount(p);
    std::vector<uint8_t> used(shapes, 0);
    for (uint16_t s : p.leafShape) used[s] = 1;
    std::vector<plant::LeafShape> shape(shapes);
    bool any = false, sameTint = true;
    for (size_t s = 0; s < shapes; ++s) {
      if (!used[s]) continue;
      shape[s] = mesh::leafShapeFor(p, s);
      for (size_t t = 0; t < s && sameTint; ++t)
        if (used[t] && shape[t].tint != shape[s].tint) sameTint = false;
      any = true;
    }
    if (!any) continue;
    LeafAtlas atlas;
    atlas.bakedTints = !sameTint;
    PlantLeafAtlas& pa = out.plants[i];
    pa.shapeRect.assign(shapes, -1);
    bool slotSet = false;
    std::string key = atlas.bakedTints ? "baked" : "plain";
    for (size_t s = 0; s < shapes; ++s) {
      if (!used[s]) continue;
      if (!slotSet) {
        pa.slot = uint32_t(s);
        slotSet = true;
        if (!atlas.bakedTints) {
          if (!isFinite(shape[s].tint))
            throw Error(plantName, fmt::format("leaf shape {}", s), "colour must be finite");
          atlas.tint = shape[s].tint.cwiseMax(0.0f).cwiseMin(1.0f);
        }
      }
      if (atlas.bakedTints && !isFinite(shape[s].tint))
        throw Error(plantName, fmt::format("leaf shape {}", s), "colour must be finite");
      int rect = -1;
      for (size_t k = 0; k < atlas.rects.size(); ++k)
        if (atlas.rects[k].texture == shape[s].texture && (!atlas.bakedTints || atlas.rects[k].tint == shape[s].tint))
          rect = int(k);
      if (rect < 0) {
        LeafAtlasRect r;
        r.texture = shape[s].texture;
        r.tint = atlas.bakedTints ? shape[s].tint : Vec3::Ones();
        atlas.rects.push_back(r);
        rect = int(atlas.rects.size() - 1);
        key += fmt::format("|{}|{},{},{}", r.texture, r.tint.x(), r.tint.y(), r.tint.z());
      }
      pa.shapeRect[s] = rect;
    }
    key += fmt::format("|{},{},{}", atlas.tint.x(), atlas.tint.y(), atlas.tint.z());
    auto same = std::find(keys.begin(), keys.end(), key);
    if (same != keys.end()) {
      pa.atlas = int(same - keys.begin());
      continue;
    }
    // Texture sizes, from the preloaded images.
    for (LeafAtlasRect& r : atlas.rects) {
      auto it = std::find(textures.specs.begin(), textures.specs.end(), r.texture);
      if (it == textures.specs.end()) throw Error(plantName, "leaf atlas", "texture " + r.texture + " was not loaded");
      const size_t k = size_t(it - textures.specs.begin());
      if (textures.failed[k]) std::rethrow_exception(textures.failed[k]);
      r.width = textures.loaded[k].width;
      r.height = textures.loaded[k].height;
    }
    pack(atlas, plantName);
    std::string labels;
    for (const LeafAtlasRect& r : atlas.rects) {
      if (!labels.empty()) labels += '+';
      labels += textureLabel(r.texture);
    }
    atlas.spec = fmt::format("leaf-atlas-{}:{}", out.atlases.size(), labels);
    keys.push_back(std::move(key));
    pa.atlas = int(out.atlases.size());
    out.atlases.push_back(std::move(atlas));
  }

  // Pixels: each texture decoded once, each atlas drawn and encoded, in parallel.
  std::vector<std::string> specs;
  for (const LeafAtlas& a : out.atlases)
    for (const LeafAtlasRect& r : a.rects)
      if (std::find(specs.begin(), specs.end(), r.texture) == specs.end()) specs.push_back(r.texture);
  std::vector<Image> decoded(specs.size());
  parallelFor(0, specs.size(), [&](size_t i) {
    const size_t k = size_t(std::find(textures.specs.begin(), textures.specs.end(), specs[i]) - textures.specs.begin());
    decoded[i] = decodeImage(textures.loaded[k].bytes, specs[i]);
  }, 1);
  parallelFor(0, out.atlases.size(), [&](size_t a) {
    LeafAtlas& atlas = out.atlases[a];
    std::vector<const Image*> sources;
    for (const LeafAtlasRect& r : atlas.rects)
      sources.push_back(&decoded[size_t(std::find(specs.begin(), specs.end(), r.texture) - specs.begin())]);
    const Image image = drawAtlas(atlas, sources);
    atlas.image = {"image/png", encodePng(image), image.width, image.height};
  }, 1);
  return out;
}

void applyLeafAtlas(const LeafAtlases& atlases, const PlantLeafAtlas& plant, mesh::PlantMesh& mesh) {
  if (plant.atlas < 0) return;
  const LeafAtlas& atlas = atlases.atlases[size_t(plant.atlas)];
  TriangleMesh merged;
  for (size_t s = 0; s < mesh.leaves.size(); ++s) {
    TriangleMesh& m = mesh.leaves[s];
    if (m.empty()) continue;
    const int rect = s < plant.shapeRect.size() ? plant.shapeRect[s] : -1;
    if (rect < 0) throw Error("leaf atlas", "", fmt::format("leaf shape {} has no place in the atlas (internal error)", s));
    const LeafAtlasRect& r = atlas.rects[size_t(rect)];
    for (Vec2& uv : m.uvs) uv = atlasUv(atlas, r, uv);
    merged.append(m);
    m.clear();
  }
  if (plant.slot >= mesh.leaves.size()) mesh.leaves.resize(plant.slot + 1);
  mesh.leaves[plant.slot] = std::move(merged);
}

}  // namespace tendril::io
