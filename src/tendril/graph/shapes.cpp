#include "tendril/graph/shapes.h"

#include "tendril/io/texture.h"
#include "tendril/core/curve.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

namespace tendril::graph {

namespace {

constexpr float kTiny = 1e-7f;

// Appends a vertex and returns its index.
uint32_t vertex(TriangleMesh& m, const Vec3& p, const Vec3& n, const Vec2& uv) {
  m.positions.push_back(p);
  m.normals.push_back(n);
  m.uvs.push_back(uv);
  return uint32_t(m.positions.size() - 1);
}

void triangle(TriangleMesh& m, uint32_t a, uint32_t b, uint32_t c) { m.indices.insert(m.indices.end(), {a, b, c}); }

// A grid of (rows + 1) × (columns + 1) vertices already in the mesh from `base`, row-major;
// quads wound counter-clockwise when rows run along +v and columns along +u.
void gridTriangles(TriangleMesh& m, uint32_t base, int rows, int columns) {
  uint32_t stride = uint32_t(columns + 1);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      uint32_t a = base + uint32_t(r) * stride + uint32_t(c), b = a + 1, d = a + stride, e = d + 1;
      triangle(m, a, b, e);
      triangle(m, a, e, d);
    }
}

// A closed fan around `centre` over ring vertices [first, first + count), facing `normal`.
void fan(TriangleMesh& m, const Vec3& centre, std::span<const Vec3> ring, const Vec3& normal, bool flip) {
  uint32_t c = vertex(m, centre, normal, Vec2(0.5f, 0.5f));
  uint32_t first = uint32_t(m.positions.size());
  Vec3 u = anyPerpendicular(normal);
  Vec3 w = normal.cross(u);
  float extent = 1e-12f;
  for (const Vec3& p : ring) extent = std::max(extent, (p - centre).norm());
  for (const Vec3& p : ring) {
    Vec3 d = (p - centre) / extent;
    vertex(m, p, normal, Vec2(0.5f + 0.5f * d.dot(u), 0.5f + 0.5f * d.dot(w)));
  }
  uint32_t n = uint32_t(ring.size());
  for (uint32_t k = 0; k < n; ++k) {
    uint32_t a = first + k, b = first + (k + 1) % n;
    if (flip)
      triangle(m, c, b, a);
    else
      triangle(m, c, a, b);
  }
}

TriangleMesh cube(const Vec3& s) {
  TriangleMesh m;
  Vec3 lo(-0.5f * s.x(), 0.0f, -0.5f * s.z()), hi(0.5f * s.x(), s.y(), 0.5f * s.z());
  // Each face: normal, and two edge directions u, v with u × v = normal.
  const Vec3 normals[6] = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
  for (const Vec3& n : normals) {
    Vec3 u = anyPerpendicular(n);
    Vec3 v = n.cross(u);
    uint32_t base = uint32_t(m.positions.size());
    const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (const auto& c : corners) {
      Vec3 dir = n + c[0] * u + c[1] * v;  // a corner of the unit cube [-1, 1]^3
      Vec3 p(dir.x() < 0 ? lo.x() : hi.x(), dir.y() < 0 ? lo.y() : hi.y(), dir.z() < 0 ? lo.z() : hi.z());
      vertex(m, p, n, Vec2(0.5f * (c[0] + 1.0f), 0.5f * (c[1] + 1.0f)));
    }
    triangle(m, base, base + 1, base + 2);
    triangle(m, base, base + 2, base + 3);
  }
  return m;
}

TriangleMesh ellipsoid(const Vec3& s, int segments) {
  TriangleMesh m;
  Vec3 r = 0.5f * s;
  Vec3 centre(0.0f, r.y(), 0.0f);
  int rings = std::max(2, segments / 2);
  for (int i = 0; i <= rings; ++i) {
    float theta = kPi * float(i) / float(rings);  // from the top pole
    for (int j = 0; j <= segments; ++j) {
      float phi = kTwoPi * float(j) / float(segments);
      Vec3 unit(std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi));
      Vec3 p = centre + unit.cwiseProduct(r);
      Vec3 n = unit.cwiseQuotient(r.cwiseMax(kTiny)).normalized();
      vertex(m, p, n, Vec2(float(j) / float(segments), 1.0f - float(i) / float(rings)));
    }
  }
  uint32_t stride = uint32_t(segments + 1);
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      uint32_t a = uint32_t(i) * stride + uint32_t(j), b = a + 1, d = a + stride, e = d + 1;
      // Rows run downward (from the pole); u runs counter-clockwise seen from +Y.
      if (i > 0) triangle(m, a, d, b);
      if (i + 1 < rings) triangle(m, b, d, e);
    }
  return m;
}

// Cylinder (top = 1) or cone (top = 0) of height sy along +Y.
TriangleMesh frustum(const Vec3& s, int segments, float top) {
  TriangleMesh m;
  float rx = 0.5f * s.x(), rz = 0.5f * s.z(), h = s.y();
  float slope = rx > 0.0f ? (1.0f - top) * rx / std::max(h, kTiny) : 0.0f;  // radius lost per height
  for (int k = 0; k <= 1; ++k) {
    float f = k == 0 ? 1.0f : top;
    for (int j = 0; j <= segments; ++j) {
      float phi = kTwoPi * float(j) / float(segments);
      Vec3 dir(std::cos(phi), 0.0f, -std::sin(phi));
      Vec3 p(f * rx * dir.x(), float(k) * h, f * rz * dir.z());
      Vec3 n = Vec3(dir.x() / std::max(rx, kTiny), slope / std::max(rx, kTiny), dir.z() / std::max(rz, kTiny)).normalized();
      vertex(m, p, n, Vec2(float(j) / float(segments), float(k)));
    }
  }
  uint32_t stride = uint32_t(segments + 1);
  for (int j = 0; j < segments; ++j) {
    uint32_t a = uint32_t(j), b = a + 1, d = a + stride, e = d + 1;
    triangle(m, a, b, e);
    if (top > 0.0f) triangle(m, a, e, d);
  }
  std::vector<Vec3> ring;
  for (int j = 0; j < segments; ++j) {
    float phi = kTwoPi * float(j) / float(segments);
    ring.push_back(Vec3(rx * std::cos(phi), 0.0f, -rz * std::sin(phi)));
  }
  fan(m, Vec3::Zero(), ring, -Vec3::UnitY(), true);
  if (top > 0.0f) {
    for (Vec3& p : ring) p = Vec3(top * p.x(), h, top * p.z());
    fan(m, Vec3(0.0f, h, 0.0f), ring, Vec3::UnitY(), false);
  }
  return m;
}

TriangleMesh disc(const Vec3& s, int segments) {
  TriangleMesh m;
  std::vector<Vec3> ring;
  for (int j = 0; j < segments; ++j) {
    float phi = kTwoPi * float(j) / float(segments);
    ring.push_back(Vec3(0.5f * s.x() * std::cos(phi), 0.0f, -0.5f * s.z() * std::sin(phi)));
  }
  fan(m, Vec3::Zero(), ring, Vec3::UnitY(), false);
  makeDoubleSided(m);
  return m;
}

// Points of a 2D polyline or Catmull-Rom spline through `points`, `samples` per span.
std::vector<Vec2> sampleCurve(const std::vector<Vec2>& points, bool spline, int samples) {
  std::vector<Vec2> out;
  if (!spline || points.size() < 3) {
    for (size_t k = 0; k < points.size(); ++k) {
      if (k > 0)
        for (int j = 1; j < samples; ++j) {
          float f = float(j) / float(samples);
          out.push_back(points[k - 1] + f * (points[k] - points[k - 1]));
        }
      out.push_back(points[k]);
    }
    return out;
  }
  auto lift = [](const Vec2& p) { return Vec3(p.x(), p.y(), 0.0f); };
  for (size_t k = 0; k + 1 < points.size(); ++k) {
    Vec3 p1 = lift(points[k]), p2 = lift(points[k + 1]);
    Vec3 p0 = k > 0 ? lift(points[k - 1]) : Vec3(2.0f * p1 - p2);
    Vec3 p3 = k + 2 < points.size() ? lift(points[k + 2]) : Vec3(2.0f * p2 - p1);
    if ((p2 - p1).norm() < 1e-9f) continue;
    CurveSegment seg = centripetalCatmullRom(p0, p1, p2, p3);
    for (int j = 0; j < samples; ++j) {
      Vec3 q = j == 0 ? p1 : seg.point(float(j) / float(samples));
      out.push_back(Vec2(q.x(), q.y()));
    }
  }
  out.push_back(points.back());
  return out;
}

// Half width of the blade at position y from the outline points (a function of y: cubic
// Hermite with Catmull-Rom tangents over the non-uniform positions, or linear).
float outlineWidth(const std::vector<Vec2>& o, bool spline, float y) {
  if (y <= o.front().x()) return o.front().y();
  if (y >= o.back().x()) return o.back().y();
  size_t k = 0;
  while (k + 2 < o.size() && o[k + 1].x() < y) ++k;
  float y0 = o[k].x(), y1 = o[k + 1].x(), w0 = o[k].y(), w1 = o[k + 1].y();
  float h = y1 - y0;
  float t = (y - y0) / h;
  if (!spline || o.size() < 3) return w0 + t * (w1 - w0);
  auto slope = [&](size_t i) {
    size_t a = i > 0 ? i - 1 : i, b = i + 1 < o.size() ? i + 1 : i;
    return (o[b].y() - o[a].y()) / (o[b].x() - o[a].x());
  };
  float m0 = slope(k) * h, m1 = slope(k + 1) * h;
  float t2 = t * t, t3 = t2 * t;
  float w = (2 * t3 - 3 * t2 + 1) * w0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * w1 + (t3 - t2) * m1;
  return std::max(w, 0.0f);
}

}  // namespace

void makeDoubleSided(TriangleMesh& m) {
  size_t nv = m.positions.size(), ni = m.indices.size();
  m.positions.reserve(2 * nv);
  m.normals.reserve(2 * nv);
  m.uvs.reserve(2 * nv);
  for (size_t k = 0; k < nv; ++k) {
    m.positions.push_back(m.positions[k]);
    m.normals.push_back(-m.normals[k]);
    m.uvs.push_back(m.uvs[k]);
  }
  m.indices.reserve(2 * ni);
  for (size_t t = 0; t + 2 < ni; t += 3) {
    uint32_t a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
    m.indices.insert(m.indices.end(), {uint32_t(a + nv), uint32_t(c + nv), uint32_t(b + nv)});
  }
}

TriangleMesh solidMesh(Shape shape, const Vec3& size, int segments) {
  segments = std::max(segments, 3);
  bool flat = size.x() < kTiny || size.z() < kTiny;
  switch (shape) {
    case Shape::Cube:
      return flat || size.y() < kTiny ? TriangleMesh() : cube(size);
    case Shape::Sphere:
      return flat || size.y() < kTiny ? TriangleMesh() : ellipsoid(size, segments);
    case Shape::Cylinder:
      return flat || size.y() < kTiny ? TriangleMesh() : frustum(size, segments, 1.0f);
    case Shape::Cone:
      return flat || size.y() < kTiny ? TriangleMesh() : frustum(size, segments, 0.0f);
    case Shape::Disc:
      return flat ? TriangleMesh() : disc(size, segments);
    case Shape::Area:
    case Shape::Tube: return TriangleMesh();
  }
  return TriangleMesh();
}

TriangleMesh revoMesh(const RevoParams& p, int samples, int segments) {
  std::vector<Vec2> profile = sampleCurve(p.profile, p.spline, samples);
  // Consecutive duplicates make zero-area quads.
  profile.erase(std::unique(profile.begin(), profile.end(),
                            [](const Vec2& a, const Vec2& b) { return (a - b).norm() < 1e-7f; }),
                profile.end());
  TriangleMesh m;
  if (profile.size() < 2) return m;
  std::vector<float> arc(profile.size(), 0.0f);
  for (size_t k = 1; k < profile.size(); ++k) arc[k] = arc[k - 1] + (profile[k] - profile[k - 1]).norm();
  float total = std::max(arc.back(), kTiny);
  for (size_t k = 0; k < profile.size(); ++k)
    for (int j = 0; j <= segments; ++j) {
      float phi = kTwoPi * float(j) / float(segments);
      Vec3 dir(std::cos(phi), 0.0f, -std::sin(phi));
      vertex(m, Vec3(profile[k].x() * dir.x(), profile[k].y(), profile[k].x() * dir.z()), Vec3::UnitY(),
             Vec2(float(j) / float(segments), arc[k] / total));
    }
  uint32_t stride = uint32_t(segments + 1);
  for (size_t k = 0; k + 1 < profile.size(); ++k)
    for (int j = 0; j < segments; ++j) {
      uint32_t a = uint32_t(k) * stride + uint32_t(j), b = a + 1, d = a + stride, e = d + 1;
      // A quad collapses to a triangle where the profile touches the axis.
      if (profile[k].x() > kTiny) triangle(m, a, b, e);
      if (profile[k + 1].x() > kTiny) triangle(m, a, e, d);
    }
  m.computeNormals();
  if (p.caps) {
    auto cap = [&](const Vec2& q, bool top) {
      if (q.x() <= kTiny) return;
      std::vector<Vec3> ring;
      for (int j = 0; j < segments; ++j) {
        float phi = kTwoPi * float(j) / float(segments);
        ring.push_back(Vec3(q.x() * std::cos(phi), q.y(), -q.x() * std::sin(phi)));
      }
      fan(m, Vec3(0.0f, q.y(), 0.0f), ring, top ? Vec3::UnitY() : Vec3(-Vec3::UnitY()), !top);
    };
    cap(profile.front(), profile.front().y() > profile.back().y());
    cap(profile.back(), profile.back().y() >= profile.front().y());
  }
  makeDoubleSided(m);
  return m;
}

TriangleMesh sectionSweepMesh(std::span<const Ring> rings, const std::vector<Vec2>& section) {
  TriangleMesh m;
  if (rings.size() < 2 || section.size() < 3) return m;
  size_t count = section.size();
  std::vector<float> arc(count + 1, 0.0f);
  for (size_t k = 1; k <= count; ++k) arc[k] = arc[k - 1] + (section[k % count] - section[k - 1]).norm();
  float along = 0.0f;
  for (size_t r = 0; r < rings.size(); ++r) {
    if (r > 0) along += (rings[r].frame.position - rings[r - 1].frame.position).norm();
    for (size_t k = 0; k <= count; ++k) {
      const Vec2& q = section[k % count];
      Vec3 p = rings[r].frame.position + rings[r].frame.rotation * Vec3(rings[r].radius * q.x(), 0.0f, rings[r].radius * q.y());
      vertex(m, p, Vec3::UnitY(), Vec2(arc[k] / std::max(arc[count], kTiny), along));
    }
  }
  gridTriangles(m, 0, int(rings.size()) - 1, int(count));
  // The winding above faces outward for sections counter-clockwise seen from +Y; flip the
  // triangles otherwise (signed area of the section, with z pointing toward the viewer's -y).
  float signedArea = 0.0f;
  for (size_t k = 0; k < count; ++k) {
    const Vec2& a = section[k];
    const Vec2& b = section[(k + 1) % count];
    signedArea += a.x() * b.y() - b.x() * a.y();
  }
  if (signedArea > 0.0f)
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) std::swap(m.indices[t + 1], m.indices[t + 2]);
  m.computeNormals();
  for (int end = 0; end < 2; ++end) {
    const Ring& ring = end == 0 ? rings.front() : rings.back();
    std::vector<Vec3> pts;
    Vec3 centre = Vec3::Zero();
    for (const Vec2& q : section) {
      pts.push_back(ring.frame.position + ring.frame.rotation * Vec3(ring.radius * q.x(), 0.0f, ring.radius * q.y()));
      centre += pts.back();
    }
    centre /= float(count);
    Vec3 axis = ring.frame.rotation * Vec3::UnitY();
    Vec3 facing = end == 0 ? Vec3(-axis) : axis;
    bool flip = (end == 0) != (signedArea > 0.0f);
    fan(m, centre, pts, facing, flip);
  }
  return m;
}

TriangleMesh bladeMesh(const BladeSpec& s) {
  TriangleMesh m;
  int rows = std::max(1, s.rows), columns = std::max(1, s.columns);
  float y0 = 0.0f, y1 = 1.0f;
  if (!s.outline.empty()) {
    y0 = s.outline.front().x();
    y1 = s.outline.back().x();
  }
  // A blade never narrows to nothing: a zero width would make zero-area triangles.
  constexpr float kMinHalfWidth = 2e-3f;
  auto halfWidth = [&](float y) {
    float w;
    if (!s.outline.empty()) {
      w = outlineWidth(s.outline, s.outlineSpline, y);
    } else if (s.profile.size() >= 2) {
      float f = std::clamp(y, 0.0f, 1.0f) * float(s.profile.size() - 1);
      size_t k = std::min(size_t(f), s.profile.size() - 2);
      float t = f - float(k);
      w = s.aspect * (s.profile[k] + t * (s.profile[k + 1] - s.profile[k]));
    } else {
      w = 0.5f * s.aspect;
    }
    return std::max(w, kMinHalfWidth);
  };
  // Longitudinal bending: the midrib is an arc turning by `curvature` over the blade.
  float kappa = s.curvature;
  auto midrib = [&](float y) {
    if (std::abs(kappa) < 1e-6f) return Vec3(0.0f, y, 0.0f);
    return Vec3(0.0f, std::sin(kappa * y) / kappa, (std::cos(kappa * y) - 1.0f) / kappa);
  };
  for (int r = 0; r <= rows; ++r) {
    float y = y0 + (y1 - y0) * float(r) / float(rows);
    float w = halfWidth(y);
    Vec3 c = midrib(y);
    float theta = kappa * y;
    Vec3 up(0.0f, std::sin(theta), std::cos(theta));  // upper-side normal of the midrib
    // Lateral curvature: the cross-section is an arc whose edges rise by `fold`.
    float k = s.fold / w;
    for (int col = 0; col <= columns; ++col) {
      float u = w * (-1.0f + 2.0f * float(col) / float(columns));
      float across = std::abs(k) < 1e-6f ? u : std::sin(k * u) / k;
      float lift = std::abs(k) < 1e-6f ? 0.0f : (1.0f - std::cos(k * u)) / k;
      Vec3 p = c + across * Vec3::UnitX() + lift * up;
      vertex(m, p, up, Vec2(0.5f + u / s.aspect, y));
    }
  }
  gridTriangles(m, 0, rows, columns);
  m.computeNormals();
  makeDoubleSided(m);
  return m;
}

std::vector<float> textureHalfWidths(const std::string& spec, int samples) {
  static std::mutex mutex;
  static std::map<std::pair<std::string, int>, std::vector<float>> cache;
  {
    std::lock_guard lock(mutex);
    auto it = cache.find({spec, samples});
    if (it != cache.end()) return it->second;
  }
  io::Image img = io::loadTexture(spec);
  std::vector<float> widths(size_t(samples), 0.0f);
  float centre = 0.5f * float(img.width - 1);
  for (int k = 0; k < samples; ++k) {
    // Row k of `samples` from the bottom (v = 0) to the top (v = 1); image rows run downward.
    int y = img.height - 1 - int(std::lround(float(k) / float(samples - 1) * float(img.height - 1)));
    float extent = 0.0f;
    for (int x = 0; x < img.width; ++x)
      if (img.pixel(x, y)[3] >= 128) extent = std::max(extent, std::abs(float(x) - centre) + 0.5f);
    widths[size_t(k)] = extent / float(img.width);
  }
  std::lock_guard lock(mutex);
  cache.emplace(std::make_pair(spec, samples), widths);
  return widths;
}

TriangleMesh pointSetStrip(std::span<const Vec3> a, std::span<const Vec3> b, bool closed, float v0, float v1) {
  TriangleMesh m;
  size_t n = a.size();
  if (n < 2 || b.size() != n) return m;
  size_t columns = closed ? n : n - 1;
  for (int side = 0; side < 2; ++side) {
    std::span<const Vec3> pts = side == 0 ? a : b;
    for (size_t k = 0; k <= columns; ++k)
      vertex(m, pts[k % n], Vec3::UnitY(), Vec2(float(k) / float(columns), side == 0 ? v0 : v1));
  }
  gridTriangles(m, 0, 1, int(columns));
  // Drop quads whose sides coincide (zero area); keep the rest.
  std::vector<uint32_t> kept;
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    const Vec3& p = m.positions[m.indices[t]];
    Vec3 n2 = (m.positions[m.indices[t + 1]] - p).cross(m.positions[m.indices[t + 2]] - p);
    if (n2.norm() > 1e-12f) kept.insert(kept.end(), {m.indices[t], m.indices[t + 1], m.indices[t + 2]});
  }
  m.indices = std::move(kept);
  m.computeNormals();
  makeDoubleSided(m);
  return m;
}

TriangleMesh pointSetCap(std::span<const Vec3> ring) {
  TriangleMesh m;
  if (ring.size() < 3) return m;
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : ring) centre += p;
  centre /= float(ring.size());
  // Newell's normal of the ring.
  Vec3 normal = Vec3::Zero();
  for (size_t k = 0; k < ring.size(); ++k) normal += ring[k].cross(ring[(k + 1) % ring.size()]);
  if (normal.norm() < 1e-12f) return m;
  fan(m, centre, ring, normal.normalized(), false);
  makeDoubleSided(m);
  return m;
}

}  // namespace tendril::graph
