#include "tendril/env/primitives.h"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <cmath>

namespace tendril::env {
namespace {

// Adds a quad a-b-c-d (counter-clockwise seen from the front) as two triangles.
void addQuad(TriangleMesh& m, uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
  m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
}

uint32_t addVertex(TriangleMesh& m, const Vec3& p) {
  m.positions.push_back(p);
  return static_cast<uint32_t>(m.positions.size() - 1);
}

}  // namespace

TriangleMesh makeBox(const Vec3& size) {
  TriangleMesh m;
  Vec3 h = 0.5f * size;
  for (int i = 0; i < 8; ++i)
    addVertex(m, Vec3((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z()));
  // Corner index bits: x = 1, y = 2, z = 4. Faces wound counter-clockwise seen from outside.
  addQuad(m, 1, 3, 7, 5);  // +x
  addQuad(m, 0, 4, 6, 2);  // -x
  addQuad(m, 2, 6, 7, 3);  // +y
  addQuad(m, 0, 1, 5, 4);  // -y
  addQuad(m, 4, 5, 7, 6);  // +z
  addQuad(m, 0, 2, 3, 1);  // -z
  return m;
}

TriangleMesh makePlane(const Vec2& sizeXZ, float thickness) {
  TriangleMesh m = makeBox(Vec3(sizeXZ.x(), thickness, sizeXZ.y()));
  for (Vec3& p : m.positions) p.y() -= 0.5f * thickness;
  return m;
}

TriangleMesh makeSphere(float radius, int subdivisions) {
  // Icosahedron, then each triangle split in four with midpoints pushed to the sphere.
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (Vec3& p : v) p.normalize();
  std::vector<uint32_t> f = {0, 11, 5, 0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                             4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9,  4,  3,  4,  2, 3, 2, 6, 3,
                             6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6, 2,  10, 8,  6, 7, 9, 8, 1};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      uint32_t id = static_cast<uint32_t>(v.size() - 1);
      mid.emplace(key, id);
      return id;
    };
    std::vector<uint32_t> next;
    next.reserve(f.size() * 4);
    for (size_t i = 0; i < f.size(); i += 3) {
      uint32_t a = f[i], b = f[i + 1], c = f[i + 2];
      uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    f.swap(next);
  }
  TriangleMesh m;
  m.positions.reserve(v.size());
  for (const Vec3& p : v) m.positions.push_back(p * radius);
  m.indices = std::move(f);
  return m;
}

TriangleMesh makeCylinder(float radius, float height, int segments) {
  TriangleMesh m;
  float h = 0.5f * height;
  for (int i = 0; i < segments; ++i) {
    float a = kTwoPi * static_cast<float>(i) / static_cast<float>(segments);
    float x = radius * std::cos(a), z = -radius * std::sin(a);
    addVertex(m, Vec3(x, -h, z));
    addVertex(m, Vec3(x, h, z));
  }
  uint32_t bottom = addVertex(m, Vec3(0, -h, 0));
  uint32_t top = addVertex(m, Vec3(0, h, 0));
  for (int i = 0; i < segments; ++i) {
    uint32_t j = static_cast<uint32_t>((i + 1) % segments);
    uint32_t b0 = 2 * i, t0 = 2 * i + 1, b1 = 2 * j, t1 = 2 * j + 1;
    // Angle increases counter-clockwise seen from +y (x toward -z), so b0-b1-t1-t0 faces out.
    addQuad(m, b0, b1, t1, t0);
    m.indices.insert(m.indices.end(), {top, t0, t1});
    m.indices.insert(m.indices.end(), {bottom, b1, b0});
  }
  return m;
}

std::string checkWallOpenings(const Vec3& size, const std::vector<WallOpening>& openings) {
  const float w = size.x(), h = size.y();
  for (size_t i = 0; i < openings.size(); ++i) {
    const WallOpening& o = openings[i];
    float x0 = o.center.x() - 0.5f * o.size.x(), x1 = o.center.x() + 0.5f * o.size.x();
    float y0 = o.center.y() - 0.5f * o.size.y(), y1 = o.center.y() + 0.5f * o.size.y();
    if (!(o.size.x() > 0 && o.size.y() > 0))
      return fmt::format("opening {} must have a positive size", i);
    if (!(x0 > -0.5f * w && x1 < 0.5f * w && y0 > 0.0f && y1 < h))
      return fmt::format(
          "opening {} (x {:.3g}..{:.3g}, y {:.3g}..{:.3g}) must lie strictly inside the wall "
          "(x {:.3g}..{:.3g}, y 0..{:.3g})",
          i, x0, x1, y0, y1, -0.5f * w, 0.5f * w, h);
    for (size_t j = 0; j < i; ++j) {
      const WallOpening& p = openings[j];
      bool apartX = std::abs(o.center.x() - p.center.x()) >= 0.5f * (o.size.x() + p.size.x());
      bool apartY = std::abs(o.center.y() - p.center.y()) >= 0.5f * (o.size.y() + p.size.y());
      if (!apartX && !apartY) return fmt::format("opening {} overlaps opening {}", i, j);
    }
  }
  return {};
}

TriangleMesh makeWall(const Vec3& size, const std::vector<WallOpening>& openings) {
  const float w = size.x(), h = size.y(), t = size.z();
  // The grid of every opening edge: each cell is either solid or part of one opening.
  std::vector<float> xs = {-0.5f * w, 0.5f * w}, ys = {0.0f, h};
  for (const WallOpening& o : openings) {
    xs.push_back(o.center.x() - 0.5f * o.size.x());
    xs.push_back(o.center.x() + 0.5f * o.size.x());
    ys.push_back(o.center.y() - 0.5f * o.size.y());
    ys.push_back(o.center.y() + 0.5f * o.size.y());
  }
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
  std::sort(ys.begin(), ys.end());
  ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
  const int nx = static_cast<int>(xs.size()) - 1, ny = static_cast<int>(ys.size()) - 1;

  auto solid = [&](int i, int j) {
    if (i < 0 || j < 0 || i >= nx || j >= ny) return false;
    float cx = 0.5f * (xs[i] + xs[i + 1]), cy = 0.5f * (ys[j] + ys[j + 1]);
    for (const WallOpening& o : openings)
      if (std::abs(cx - o.center.x()) < 0.5f * o.size.x() && std::abs(cy - o.center.y()) < 0.5f * o.size.y())
        return false;
    return true;
  };

  TriangleMesh m;
  // Grid vertices on both faces: front (z = +t/2) and back (z = -t/2).
  auto vid = [&](int i, int j, int side) { return static_cast<uint32_t>((j * (nx + 1) + i) * 2 + side); };
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      addVertex(m, Vec3(xs[i], ys[j], 0.5f * t));
      addVertex(m, Vec3(xs[i], ys[j], -0.5f * t));
    }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (!solid(i, j)) continue;
      addQuad(m, vid(i, j, 0), vid(i + 1, j, 0), vid(i + 1, j + 1, 0), vid(i, j + 1, 0));  // front
      addQuad(m, vid(i + 1, j, 1), vid(i, j, 1), vid(i, j + 1, 1), vid(i + 1, j + 1, 1));  // back
      // Side faces where the neighbour is empty (outside or an opening).
      if (!solid(i + 1, j))
        addQuad(m, vid(i + 1, j, 0), vid(i + 1, j, 1), vid(i + 1, j + 1, 1), vid(i + 1, j + 1, 0));
      if (!solid(i - 1, j))
        addQuad(m, vid(i, j, 1), vid(i, j, 0), vid(i, j + 1, 0), vid(i, j + 1, 1));
      if (!solid(i, j + 1))
        addQuad(m, vid(i, j + 1, 0), vid(i + 1, j + 1, 0), vid(i + 1, j + 1, 1), vid(i, j + 1, 1));
      if (!solid(i, j - 1))
        addQuad(m, vid(i, j, 1), vid(i + 1, j, 1), vid(i + 1, j, 0), vid(i, j, 0));
    }
  // Drop grid vertices that no face uses.
  std::vector<uint32_t> remap(m.positions.size(), UINT32_MAX);
  std::vector<Vec3> used;
  for (uint32_t& idx : m.indices) {
    if (remap[idx] == UINT32_MAX) {
      remap[idx] = static_cast<uint32_t>(used.size());
      used.push_back(m.positions[idx]);
    }
    idx = remap[idx];
  }
  m.positions = std::move(used);
  return m;
}

}  // namespace tendril::env
