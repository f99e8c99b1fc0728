#include "tendril/io/impostor.h"

#include "tendril/core/error.h"
#include "tendril/core/parallel.h"
#include "tendril/io/rect_pack.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>

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

// The (right, up) bounds of what of the surfaces lies in each slab of `axis`.
struct Rect2 {
  Vec2 min = Vec2::Constant(INFINITY), max = Vec2::Constant(-INFINITY);
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
  for (const ImpostorSurface& s : surfaces) {
    const TriangleMesh& m = *s.mesh;
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      const Vec3 p[3] = {m.positions[m.indices[t]], m.positions[m.indices[t + 1]], m.positions[m.indices[t + 2]]};
      const float d[3] = {p[0][axis], p[1][axis], p[2][axis]};
      const float dmin = std::min({d[0], d[1], d[2]}), dmax = std::max({d[0], d[1], d[2]});
      const int j0 = std::clamp(int(std::floor((dmin - first) / thickness)), 0, k - 1);
      const int j1 = std::clamp(int(std::floor((dmax - first) / thickness)), 0, k - 1);
      for (int j = j0; j <= j1; ++j) {
        const float lo = edges[size_t(j)], hi = edges[size_t(j) + 1];
        if (dmax < lo || dmin > hi) continue;
        if (dmin >= lo && dmax <= hi) {
          for (const Vec3& q : p) rects[size_t(j)].extend(flat(q));
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
      }
    }
  }
  return rects;
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
      const float mid = 0.5f * (edges[size_t(j)] + edges[size_t(j) + 1]);
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
  return quads;
}

Impostor buildImpostor(const std::vector<ImpostorSurface>& surfaces, const ImpostorSettings& settings,
                       ImpostorBaker& baker, const std::string& source) {
  validateImpostorSettings(settings, source);
  Impostor out;
  out.quads = impostorLayout(surfaces, settings);
  if (out.quads.empty()) return out;
  std::vector<ImpostorView> views;
  for (const ImpostorQuad& q : out.quads) views.push_back(q.view);
  std::vector<ImpostorImages> baked = baker.bake(surfaces, views);
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
