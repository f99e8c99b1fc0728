// Silhouette areas for the level-of-detail and impostor tests (issue 26): a plant's covered
// area seen orthographically along a view, counted on a grid, optionally cut out by a texture's
// alpha as an alpha-tested material is.
#pragma once

#include "tendril/core/math.h"
#include "tendril/core/triangle_mesh.h"
#include "tendril/io/image.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace tendril::test {

// The square of the view's image plane the grid covers.
struct ViewFrame {
  Vec3 u, v;       // the image plane's axes
  Vec2 centre;     // in (u, v)
  float half = 0;  // half the square's side
};

// A part to rasterise: its triangles, and where `texture` is set (mesh uvs, v up;
// nearest-sampled), only where the texture's alpha is at least `minAlpha`.
struct DrawnPart {
  const TriangleMesh* mesh = nullptr;
  const io::Image* texture = nullptr;
  bool alphaMask = false;
  int minAlpha = 128;
};

// The frame over the parts' projection along `view`: centred on it, its side `margin` × 2 times
// the projection's larger extent.
inline ViewFrame viewFrame(const std::vector<DrawnPart>& parts, const Vec3& view, float margin) {
  ViewFrame f;
  f.u = anyPerpendicular(view).normalized();
  f.v = view.cross(f.u).normalized();
  Vec2 lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  for (const DrawnPart& d : parts)
    for (uint32_t i : d.mesh->indices) {
      const Vec2 q(d.mesh->positions[i].dot(f.u), d.mesh->positions[i].dot(f.v));
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
  f.centre = 0.5f * (lo + hi);
  f.half = margin * (hi - lo).maxCoeff();
  return f;
}

inline bool opaqueAt(const io::Image& img, const Vec2& uv, int minAlpha) {
  const int x = std::clamp(int(std::floor(uv.x() * float(img.width))), 0, img.width - 1);
  const int y = std::clamp(int(std::floor((1.0f - uv.y()) * float(img.height))), 0, img.height - 1);
  return img.pixel(x, y)[3] >= minAlpha;
}

// Silhouette area seen along the frame's normal, orthographically: the cells of a res × res
// grid over the frame whose centres a triangle covers (where its texture, if alpha-tested, is
// opaque).
inline size_t silhouette(const std::vector<DrawnPart>& parts, const ViewFrame& f, int res = 400) {
  const float scale = float(res) / (2.0f * f.half);
  std::vector<uint8_t> cell(size_t(res) * size_t(res), 0);
  for (const DrawnPart& d : parts) {
    const TriangleMesh& m = *d.mesh;
    const bool textured = d.alphaMask && d.texture && m.uvs.size() == m.positions.size();
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      Vec2 p[3];
      for (int k = 0; k < 3; ++k) {
        const Vec3& q = m.positions[m.indices[t + size_t(k)]];
        p[k] = (Vec2(q.dot(f.u), q.dot(f.v)) - f.centre) * scale + Vec2::Constant(0.5f * float(res));
      }
      const float area2 = (p[1] - p[0]).x() * (p[2] - p[0]).y() - (p[1] - p[0]).y() * (p[2] - p[0]).x();
      if (area2 == 0.0f) continue;
      const int x0 = std::max(0, int(std::floor(std::min({p[0].x(), p[1].x(), p[2].x()}))));
      const int x1 = std::min(res - 1, int(std::ceil(std::max({p[0].x(), p[1].x(), p[2].x()}))));
      const int y0 = std::max(0, int(std::floor(std::min({p[0].y(), p[1].y(), p[2].y()}))));
      const int y1 = std::min(res - 1, int(std::ceil(std::max({p[0].y(), p[1].y(), p[2].y()}))));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          uint8_t& c = cell[size_t(y) * size_t(res) + size_t(x)];
          if (c) continue;
          const Vec2 centre(float(x) + 0.5f, float(y) + 0.5f);
          float w[3];
          for (int k = 0; k < 3; ++k) {
            const Vec2 a = p[(k + 1) % 3] - centre, b = p[(k + 2) % 3] - centre;
            w[k] = (a.x() * b.y() - a.y() * b.x()) / area2;
          }
          if (w[0] < 0 || w[1] < 0 || w[2] < 0) continue;
          if (textured) {
            const Vec2 uv = w[0] * m.uvs[m.indices[t]] + w[1] * m.uvs[m.indices[t + 1]] + w[2] * m.uvs[m.indices[t + 2]];
            if (!opaqueAt(*d.texture, uv, d.minAlpha)) continue;
          }
          c = 1;
        }
    }
  }
  size_t area = 0;
  for (uint8_t c : cell) area += c;
  return area;
}

}  // namespace tendril::test
