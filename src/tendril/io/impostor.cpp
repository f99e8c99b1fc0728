#include "tendril/io/impostor.h"

#include "tendril/core/error.h"
#include "tendril/core/parallel.h"
#include "tendril/io/rect_pack.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <mutex>

#include <Eigen/Eigenvalues>

namespace tendril::io {
namespace {

std::mutex gBakerMutex;
std::shared_ptr<ImpostorBaker> gBaker;

// Per family: the slab normal and the image's right and up directions (right × up = normal).
struct Frame {
  Vec3 normal, right, up;
};
Frame frameOf(int axis) {
  switch (axis) {
    case 0: return {Vec3::UnitX(), -Vec3::UnitZ(), Vec3::UnitY()};
    case 1: return {Vec3::UnitY(), Vec3::UnitX(), -Vec3::UnitZ()};
    default: return {Vec3::UnitZ(), Vec3::UnitX(), Vec3::UnitY()};
  }
}

constexpr int kGutter = 2;  // texels round each quad's cell in the atlas

Bounds3 surfaceBounds(const std::vector<ImpostorSurface>& surfaces) {
  Bounds3 b;
  for (const ImpostorSurface& s : surfaces)
    for (uint32_t i : s.mesh->indices) b.extend(s.mesh->positions[i]);
  return b;
}

// The (right, up) bounds of what of the surfaces lies in each slab of `axis`, and the depth its
// quad is placed at: the mean depth along the axis of what the slab's bake shows, weighted by
// the area it covers seen along the axis (leaves only where they face the family, as baked).
// A stem in a slab then sits on its quad and does not shift sideways when seen obliquely.
struct Rect2 {
  Vec2 min = Vec2::Constant(INFINITY), max = Vec2::Constant(-INFINITY);
  double depthSum = 0.0, weight = 0.0;
  bool empty() const { return !(min.x() <= max.x()); }
  void extend(const Vec2& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
};

std::vector<Rect2> slabRects(const std::vector<ImpostorSurface>& surfaces, const Frame& f, int axis,
                             const std::vector<float>& edges) {
  const int k = int(edges.size()) - 1;
  std::vector<Rect2> rects(static_cast<size_t>(k), Rect2{});
  const float first = edges.front(), thickness = (edges.back() - edges.front()) / float(k);
  auto flat = [&](const Vec3& p) { return Vec2(p.dot(f.right), p.dot(f.up)); };
  // Area seen along the axis, and that area times its mean depth, of a convex polygon (a fan).
  auto addDepth = [&](Rect2& r, const Vec3* q, int n) {
    for (int i = 1; i + 1 < n; ++i) {
      const double seen = 0.5 * std::abs(double((q[i] - q[0]).cross(q[i + 1] - q[0])[axis]));
      r.weight += seen;
      r.depthSum += seen * (double(q[0][axis]) + double(q[i][axis]) + double(q[i + 1][axis])) / 3.0;
    }
  };
  for (const ImpostorSurface& s : surfaces) {
    if (!inFamily(s, f.normal)) continue;
    const TriangleMesh& m = *s.mesh;
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      const Vec3 p[3] = {m.positions[m.indices[t]], m.positions[m.indices[t + 1]], m.positions[m.indices[t + 2]]};
      const float d[3] = {p[0][axis], p[1][axis], p[2][axis]};
      const float dmin = std::min({d[0], d[1], d[2]}), dmax = std::max({d[0], d[1], d[2]});
      const int j0 = std::clamp(int(std::floor((dmin - first) / thickness)), 0, k - 1);
      const int j1 = std::clamp(int(std::floor((dmax - first) / thickness)), 0, k - 1);
      // Whether the bake draws this triangle into the family (the baker's rule for leaves).
      bool shown = true;
      if (s.alphaMask) {
        const Vec3 a = (p[1] - p[0]).cross(p[2] - p[0]).cwiseAbs();
        shown = a[axis] >= kImpostorLeafShare * a.maxCoeff();
      }
      for (int j = j0; j <= j1; ++j) {
        const float lo = edges[size_t(j)], hi = edges[size_t(j) + 1];
        if (dmax < lo || dmin > hi) continue;
        if (dmin >= lo && dmax <= hi) {
          for (const Vec3& q : p) rects[size_t(j)].extend(flat(q));
          if (shown) addDepth(rects[size_t(j)], p, 3);
          continue;
        }
        // Clip the triangle to lo <= d <= hi (Sutherland-Hodgman, two planes).
        std::array<Vec3, 9> a{}, b{};
        int na = 3;
        for (int i = 0; i < 3; ++i) a[size_t(i)] = p[i];
        for (int side = 0; side < 2; ++side) {
          auto inside = [&](const Vec3& q) { return side == 0 ? q[axis] >= lo : q[axis] <= hi; };
          const float plane = side == 0 ? lo : hi;
          int nb = 0;
          for (int i = 0; i < na; ++i) {
            const Vec3& c = a[size_t(i)];
            const Vec3& n = a[size_t((i + 1) % na)];
            if (inside(c)) b[size_t(nb++)] = c;
            if (inside(c) != inside(n)) {
              const float s = (plane - c[axis]) / (n[axis] - c[axis]);
              b[size_t(nb++)] = c + s * (n - c);
            }
          }
          a = b;
          na = nb;
        }
        for (int i = 0; i < na; ++i) rects[size_t(j)].extend(flat(a[size_t(i)]));
        if (shown) addDepth(rects[size_t(j)], a.data(), na);
      }
    }
  }
  return rects;
}

// The plane that fits a set of triangles best: area, area-weighted mean, and the axes of their
// exact area-weighted second moments, least spread first (the plane's normal).
struct PlaneFit {
  double area = 0.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
};
PlaneFit fitPlane(const TriangleMesh& m, const std::vector<uint32_t>& triangles) {
  PlaneFit fit;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  for (uint32_t t : triangles) {
    const Eigen::Vector3d p0 = m.positions[m.indices[t]].cast<double>(), p1 = m.positions[m.indices[t + 1]].cast<double>(),
                          p2 = m.positions[m.indices[t + 2]].cast<double>();
    const double a = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    const Eigen::Vector3d sum = p0 + p1 + p2;
    fit.area += a;
    first += a / 3.0 * sum;
    second += a / 12.0 * (sum * sum.transpose() + p0 * p0.transpose() + p1 * p1.transpose() + p2 * p2.transpose());
  }
  if (fit.area <= 0.0) return fit;
  fit.mean = first / fit.area;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(second / fit.area - fit.mean * fit.mean.transpose());
  fit.axes = solver.eigenvectors();
  // A sign that does not depend on the solver: the normal's largest coordinate positive.
  Eigen::Index big = 0;
  fit.axes.col(0).cwiseAbs().maxCoeff(&big);
  if (fit.axes(big, 0) < 0) fit.axes.col(0) = -fit.axes.col(0);
  return fit;
}

// A connected piece of a primitive surface (triangles joined by vertices at the same position)
// large and flat enough for a quad of its own.
struct FlatPart {
  size_t surface = 0;
  std::vector<std::vector<uint32_t>> planes;  // per quad the first index of each triangle, in mesh order
  double area = 0.0;
};

std::vector<FlatPart> findFlatParts(const std::vector<ImpostorSurface>& surfaces, float longest) {
  std::vector<FlatPart> parts;
  const double minArea = double(kImpostorFlatSize * longest) * double(kImpostorFlatSize * longest);
  for (size_t si = 0; si < surfaces.size(); ++si) {
    const ImpostorSurface& s = surfaces[si];
    if (s.alphaMask || s.ownQuad || !s.primitive) continue;
    const TriangleMesh& m = *s.mesh;
    // Weld vertices by position, then join each triangle's corners.
    std::map<std::array<float, 3>, uint32_t> welded;
    std::vector<uint32_t> weld(m.positions.size());
    for (size_t v = 0; v < m.positions.size(); ++v) {
      const Vec3& p = m.positions[v];
      weld[v] = welded.emplace(std::array<float, 3>{p.x(), p.y(), p.z()}, uint32_t(welded.size())).first->second;
    }
    std::vector<uint32_t> parent(welded.size());
    for (size_t k = 0; k < parent.size(); ++k) parent[k] = uint32_t(k);
    auto root = [&](uint32_t a) {
      while (parent[a] != a) a = parent[a] = parent[parent[a]];
      return a;
    };
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3)
      for (size_t k = 1; k < 3; ++k) {
        const uint32_t a = root(weld[m.indices[t]]), b = root(weld[m.indices[t + k]]);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    std::map<uint32_t, std::vector<uint32_t>> pieces;  // by root, the piece's smallest welded vertex
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) pieces[root(weld[m.indices[t]])].push_back(uint32_t(t));
    // Flat: every corner within kImpostorFlatness of the triangles' narrower extent in their
    // plane from that plane (a stem, as thick as it is wide, is not).
    auto flat = [&](const std::vector<uint32_t>& triangles) {
      const PlaneFit fit = fitPlane(m, triangles);
      double off = 0.0;
      Eigen::Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
      for (uint32_t t : triangles)
        for (uint32_t k = 0; k < 3; ++k) {
          const Eigen::Vector3d d = m.positions[m.indices[t + k]].cast<double>() - fit.mean;
          off = std::max(off, std::abs(d.dot(fit.axes.col(0))));
          const Eigen::Vector2d q(d.dot(fit.axes.col(1)), d.dot(fit.axes.col(2)));
          lo = lo.cwiseMin(q);
          hi = hi.cwiseMax(q);
        }
      return off <= double(kImpostorFlatness) * (hi - lo).minCoeff();
    };
    for (auto& [r, triangles] : pieces) {
      const PlaneFit fit = fitPlane(m, triangles);
      if (fit.area < minArea) continue;
      if (flat(triangles)) {
        parts.push_back({si, {std::move(triangles)}, fit.area});
        continue;
      }
      // A blade bent along its length: its base and tip halves (either side of the middle of its
      // longest axis), each flat enough, get a quad each.
      std::vector<uint32_t> half[2];
      for (uint32_t t : triangles) {
        const Eigen::Vector3d c = (m.positions[m.indices[t]] + m.positions[m.indices[t + 1]] + m.positions[m.indices[t + 2]])
                                      .cast<double>() / 3.0;
        half[(c - fit.mean).dot(fit.axes.col(2)) < 0.0 ? 0 : 1].push_back(t);
      }
      if (half[0].empty() || half[1].empty() || !flat(half[0]) || !flat(half[1])) continue;
      parts.push_back({si, {std::move(half[0]), std::move(half[1])}, fit.area});
    }
  }
  // The largest first (ties: surface, then triangle order), at most kImpostorFlatQuads quads.
  std::stable_sort(parts.begin(), parts.end(), [](const FlatPart& a, const FlatPart& b) { return a.area > b.area; });
  size_t quads = 0, keep = 0;
  while (keep < parts.size() && quads + parts[keep].planes.size() <= size_t(kImpostorFlatQuads))
    quads += parts[keep++].planes.size();
  parts.resize(keep);
  return parts;
}

// A TriangleMesh of the given triangles of `m` (the vertices they use, in order of first use).
std::unique_ptr<TriangleMesh> subMesh(const TriangleMesh& m, const std::vector<uint32_t>& triangles) {
  auto out = std::make_unique<TriangleMesh>();
  std::vector<uint32_t> remap(m.positions.size(), UINT32_MAX);
  for (uint32_t t : triangles)
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = m.indices[t + k];
      if (remap[v] == UINT32_MAX) {
        remap[v] = uint32_t(out->positions.size());
        out->positions.push_back(m.positions[v]);
        if (m.normals.size() == m.positions.size()) out->normals.push_back(m.normals[v]);
        if (m.uvs.size() == m.positions.size()) out->uvs.push_back(m.uvs[v]);
      }
      out->indices.push_back(remap[v]);
    }
  return out;
}

// Packs the quads' cells (gutter included) into the squarest atlas (io/rect_pack.h); returns the
// atlas size.
void packCells(std::vector<ImpostorQuad>& quads, int& width, int& height) {
  std::vector<std::array<int, 2>> sizes;
  for (const ImpostorQuad& q : quads) sizes.push_back({q.view.width + 2 * kGutter, q.view.height + 2 * kGutter});
  const PackedRects packed = packRects(sizes, PackGoal::Squarest, 128, 1);
  width = packed.width;
  height = packed.height;
  for (size_t i = 0; i < quads.size(); ++i) {
    quads[i].atlasX = packed.corners[i][0] + kGutter;
    quads[i].atlasY = packed.corners[i][1] + kGutter;
  }
}

// Spreads covered texels' colours into the transparent texels next to them (alpha stays 0), so
// that filtering and mipmaps do not bleed black into the edges.
void dilate(Image& color, Image& normal, int passes) {
  const int W = color.width, H = color.height;
  std::vector<uint8_t> filled(size_t(W) * size_t(H));
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) filled[size_t(y) * size_t(W) + size_t(x)] = color.pixel(x, y)[3] > 0;
  for (int pass = 0; pass < passes; ++pass) {
    std::vector<uint8_t> next = filled;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        if (filled[size_t(y) * size_t(W) + size_t(x)]) continue;
        int sum[2][3] = {}, count = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= W || yy >= H || !filled[size_t(yy) * size_t(W) + size_t(xx)]) continue;
            for (int c = 0; c < 3; ++c) {
              sum[0][c] += color.pixel(xx, yy)[c];
              sum[1][c] += normal.pixel(xx, yy)[c];
            }
            ++count;
          }
        if (count == 0) continue;
        for (int c = 0; c < 3; ++c) {
          color.pixel(x, y)[c] = uint8_t((sum[0][c] + count / 2) / count);
          normal.pixel(x, y)[c] = uint8_t((sum[1][c] + count / 2) / count);
        }
        next[size_t(y) * size_t(W) + size_t(x)] = 1;
      }
    filled.swap(next);
  }
}

}  // namespace

void validateImpostorSettings(const ImpostorSettings& s, const std::string& source) {
  if (s.slabs < 1 || s.slabs > 16)
    throw Error(source, "impostor", fmt::format("slabs must be between 1 and 16, got {}", s.slabs));
  if (s.resolution < 16 || s.resolution > 2048)
    throw Error(source, "impostor", fmt::format("resolution must be between 16 and 2048 texels, got {}", s.resolution));
}

void installImpostorBaker(std::shared_ptr<ImpostorBaker> baker) {
  std::lock_guard lock(gBakerMutex);
  gBaker = std::move(baker);
}

std::shared_ptr<ImpostorBaker> installedImpostorBaker() {
  std::lock_guard lock(gBakerMutex);
  return gBaker;
}

ImpostorParts splitFlatParts(const std::vector<ImpostorSurface>& surfaces) {
  ImpostorParts out;
  const Bounds3 bounds = surfaceBounds(surfaces);
  if (bounds.empty()) {
    out.surfaces = surfaces;
    return out;
  }
  const std::vector<FlatPart> flat = findFlatParts(surfaces, std::max(bounds.size().maxCoeff(), 1e-4f));
  // Surfaces in order, each followed by nothing; the flat parts after them all, largest first.
  std::vector<std::vector<uint8_t>> taken(surfaces.size());
  for (const FlatPart& f : flat) {
    std::vector<uint8_t>& t = taken[f.surface];
    if (t.empty()) t.assign(surfaces[f.surface].mesh->indices.size() / 3, 0);
    for (const std::vector<uint32_t>& plane : f.planes)
      for (uint32_t tri : plane) t[tri / 3] = 1;
  }
  for (size_t i = 0; i < surfaces.size(); ++i) {
    if (taken[i].empty()) {
      out.surfaces.push_back(surfaces[i]);
      continue;
    }
    const TriangleMesh& m = *surfaces[i].mesh;
    std::vector<uint32_t> rest;
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3)
      if (!taken[i][t / 3]) rest.push_back(uint32_t(t));
    if (rest.empty()) continue;
    out.meshes.push_back(subMesh(m, rest));
    out.surfaces.push_back(surfaces[i]);
    out.surfaces.back().mesh = out.meshes.back().get();
  }
  for (const FlatPart& f : flat)
    for (const std::vector<uint32_t>& plane : f.planes) {
      out.meshes.push_back(subMesh(*surfaces[f.surface].mesh, plane));
      out.surfaces.push_back(surfaces[f.surface]);
      out.surfaces.back().mesh = out.meshes.back().get();
      out.surfaces.back().ownQuad = true;
      std::vector<uint32_t> all;
      for (size_t t = 0; t < out.meshes.back()->indices.size(); t += 3) all.push_back(uint32_t(t));
      out.surfaces.back().ownNormal = fitPlane(*out.meshes.back(), all).axes.col(0).cast<float>().normalized();
    }
  return out;
}

std::vector<ImpostorQuad> impostorLayout(const std::vector<ImpostorSurface>& surfaces,
                                         const ImpostorSettings& settings) {
  std::vector<ImpostorQuad> quads;
  const Bounds3 bounds = surfaceBounds(surfaces);
  if (bounds.empty()) return quads;
  const float longest = std::max(bounds.size().maxCoeff(), 1e-4f);
  const float texel = longest / float(settings.resolution);
  std::array<std::vector<ImpostorQuad>, 3> perAxis;
  parallelFor(0, 3, [&](size_t a) {
    const int axis = int(a);
    const Frame f = frameOf(axis);
    const float extent = bounds.size()[axis];
    // A plant flat along this axis (a leaf facing it) gets one slab, a texel thick.
    const int k = extent < texel ? 1 : settings.slabs;
    const float pad = 1e-4f * longest;
    const float lo = bounds.min[axis] - (extent < texel ? texel : pad);
    const float hi = bounds.max[axis] + (extent < texel ? texel : pad);
    std::vector<float> edges(size_t(k) + 1);
    for (int j = 0; j <= k; ++j) edges[size_t(j)] = lo + (hi - lo) * float(j) / float(k);
    const std::vector<Rect2> rects = slabRects(surfaces, f, axis, edges);
    for (int j = 0; j < k; ++j) {
      const Rect2& r = rects[size_t(j)];
      if (r.empty()) continue;
      ImpostorQuad q;
      q.axis = axis;
      q.slab = j;
      // Whole texels, one more on each side than the geometry needs, centred on it.
      const Vec2 size = r.max - r.min;
      const int w = int(std::ceil(size.x() / texel)) + 2, h = int(std::ceil(size.y() / texel)) + 2;
      const Vec2 centre = 0.5f * (r.min + r.max);
      const float left = centre.x() - 0.5f * float(w) * texel, top = centre.y() + 0.5f * float(h) * texel;
      // The quad's plane: what the slab shows, on average (its middle if it shows nothing
      // seen along the axis, e.g. only blades edge-on).
      float mid = 0.5f * (edges[size_t(j)] + edges[size_t(j) + 1]);
      if (r.weight > 0.0)
        mid = std::clamp(float(r.depthSum / r.weight), edges[size_t(j)], edges[size_t(j) + 1]);
      q.view.corner = left * f.right + top * f.up + mid * f.normal;
      q.view.u = f.right * (float(w) * texel);
      q.view.v = -f.up * (float(h) * texel);
      q.view.normal = f.normal;
      q.view.lo = edges[size_t(j)] - mid;
      q.view.hi = edges[size_t(j) + 1] - mid;
      q.view.width = w;
      q.view.height = h;
      perAxis[a].push_back(q);
    }
  }, 1);
  for (const auto& v : perAxis) quads.insert(quads.end(), v.begin(), v.end());
  // A flat part's own quad: in its plane, through its mean, a texel of depth beyond it each side.
  for (size_t i = 0; i < surfaces.size(); ++i) {
    if (!surfaces[i].ownQuad || surfaces[i].mesh->empty()) continue;
    const TriangleMesh& m = *surfaces[i].mesh;
    std::vector<uint32_t> all;
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) all.push_back(uint32_t(t));
    const PlaneFit fit = fitPlane(m, all);
    const Vec3 n = surfaces[i].ownNormal;
    const Vec3 right = anyPerpendicular(n).normalized(), up = n.cross(right);
    const Vec3 mean = fit.mean.cast<float>();
    Rect2 r;
    float dlo = INFINITY, dhi = -INFINITY;
    for (uint32_t v : m.indices) {
      const Vec3 d = m.positions[v] - mean;
      r.extend(Vec2(m.positions[v].dot(right), m.positions[v].dot(up)));
      dlo = std::min(dlo, d.dot(n));
      dhi = std::max(dhi, d.dot(n));
    }
    ImpostorQuad q;
    q.axis = 3;
    q.slab = int(i);
    const Vec2 size = r.max - r.min;
    const int w = int(std::ceil(size.x() / texel)) + 2, h = int(std::ceil(size.y() / texel)) + 2;
    const Vec2 centre = 0.5f * (r.min + r.max);
    const float left = centre.x() - 0.5f * float(w) * texel, top = centre.y() + 0.5f * float(h) * texel;
    q.view.corner = left * right + top * up + mean.dot(n) * n;
    q.view.u = right * (float(w) * texel);
    q.view.v = -up * (float(h) * texel);
    q.view.normal = n;
    q.view.lo = dlo - texel;
    q.view.hi = dhi + texel;
    q.view.width = w;
    q.view.height = h;
    q.view.surface = int(i);
    quads.push_back(q);
  }
  return quads;
}

Impostor buildImpostor(const std::vector<ImpostorSurface>& surfaces, const ImpostorSettings& settings,
                       ImpostorBaker& baker, const std::string& source) {
  validateImpostorSettings(settings, source);
  Impostor out;
  const ImpostorParts parts = splitFlatParts(surfaces);
  out.quads = impostorLayout(parts.surfaces, settings);
  if (out.quads.empty()) return out;
  std::vector<ImpostorView> views;
  for (const ImpostorQuad& q : out.quads) views.push_back(q.view);
  std::vector<ImpostorImages> baked = baker.bake(parts.surfaces, views);
  if (baked.size() != views.size())
    throw Error(source, "impostor", fmt::format("the baker returned {} images for {} views", baked.size(), views.size()));
  for (size_t i = 0; i < views.size(); ++i)
    for (const Image* img : {&baked[i].color, &baked[i].normal})
      if (img->width != views[i].width || img->height != views[i].height)
        throw Error(source, "impostor", fmt::format("the baker returned a {} x {} image for a {} x {} view",
                                                    img->width, img->height, views[i].width, views[i].height));

  // Quads whose slab held only leaves facing other families bake empty: none for them.
  {
    std::vector<ImpostorQuad> kept;
    std::vector<ImpostorImages> keptImages;
    for (size_t i = 0; i < out.quads.size(); ++i) {
      const std::vector<uint8_t>& px = baked[i].color.rgba;
      bool any = false;
      for (size_t k = 3; k < px.size() && !any; k += 4) any = px[k] != 0;
      if (!any) continue;
      kept.push_back(out.quads[i]);
      keptImages.push_back(std::move(baked[i]));
    }
    out.quads = std::move(kept);
    baked = std::move(keptImages);
  }
  if (out.quads.empty()) return out;

  int W = 0, H = 0;
  packCells(out.quads, W, H);
  out.color = makeImage(W, H, 0, 0, 0, 0);
  out.normal = makeImage(W, H, 128, 128, 255, 0);
  for (size_t i = 0; i < out.quads.size(); ++i) {
    const ImpostorQuad& q = out.quads[i];
    for (int y = 0; y < q.view.height; ++y)
      for (int x = 0; x < q.view.width; ++x) {
        std::copy_n(baked[i].color.pixel(x, y), 4, out.color.pixel(q.atlasX + x, q.atlasY + y));
        std::copy_n(baked[i].normal.pixel(x, y), 4, out.normal.pixel(q.atlasX + x, q.atlasY + y));
      }
  }
  dilate(out.color, out.normal, kGutter + 2);

  // The quads: corners top-left, top-right, bottom-right, bottom-left; counter-clockwise seen
  // from the side the normal points to.
  TriangleMesh& m = out.mesh;
  for (const ImpostorQuad& q : out.quads) {
    const uint32_t base = uint32_t(m.positions.size());
    const Vec3& c = q.view.corner;
    m.positions.insert(m.positions.end(), {c, c + q.view.u, c + q.view.u + q.view.v, c + q.view.v});
    const float u0 = float(q.atlasX) / float(W), u1 = float(q.atlasX + q.view.width) / float(W);
    const float v0 = 1.0f - float(q.atlasY) / float(H), v1 = 1.0f - float(q.atlasY + q.view.height) / float(H);
    m.uvs.insert(m.uvs.end(), {Vec2(u0, v0), Vec2(u1, v0), Vec2(u1, v1), Vec2(u0, v1)});
    const Vec3 t = q.view.u.normalized();
    for (int k = 0; k < 4; ++k) {
      m.normals.push_back(q.view.normal);
      out.tangents.push_back(Vec4(t.x(), t.y(), t.z(), 1.0f));  // bitangent = normal × tangent = image up
    }
    m.indices.insert(m.indices.end(), {base + 3, base + 2, base + 1, base + 3, base + 1, base + 0});
  }
  return out;
}

}  // namespace tendril::io
