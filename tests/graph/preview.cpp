#include "preview.h"

#include "tendril/io/texture.h"
#include "tendril/mesh/plant_mesh.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace tendril::graphtest {

namespace {

struct Material {
  Vec3 color = Vec3(0.8f, 0.8f, 0.8f);
  const io::Image* texture = nullptr;
  bool alphaTest = false;
  bool repeat = false;
};

Bounds3 meshBounds(const mesh::PlantMesh& m) {
  Bounds3 b = m.bark.bounds();
  for (const TriangleMesh& l : m.leaves) b.extend(l.bounds());
  for (const mesh::PrimitiveGroup& g : m.primitives) b.extend(g.mesh.bounds());
  return b;
}

Vec4 sample(const io::Image& img, Vec2 uv, bool repeat) {
  float u = repeat ? uv.x() - std::floor(uv.x()) : std::clamp(uv.x(), 0.0f, 1.0f);
  float v = repeat ? uv.y() - std::floor(uv.y()) : std::clamp(uv.y(), 0.0f, 1.0f);
  int x = std::clamp(int(u * float(img.width)), 0, img.width - 1);
  int y = std::clamp(int((1.0f - v) * float(img.height)), 0, img.height - 1);  // v points up the image
  const uint8_t* p = img.pixel(x, y);
  return Vec4(p[0], p[1], p[2], p[3]) / 255.0f;
}

// sRGB-ish output of a linear colour.
uint8_t encode(float c) { return uint8_t(std::clamp(std::pow(std::max(c, 0.0f), 1.0f / 2.2f), 0.0f, 1.0f) * 255.0f + 0.5f); }

}  // namespace

PreviewCamera frameBounds(const plant::PlantModel& plant, float fov) {
  mesh::PlantMesh m = mesh::buildPlantMesh(plant);
  Bounds3 b = meshBounds(m);
  PreviewCamera c;
  c.fov = fov;
  if (b.empty()) return c;
  Vec3 centre = b.center();
  float radius = std::max(0.5f * b.size().norm(), 1e-3f);
  float distance = 1.15f * radius / std::sin(0.5f * radians(fov));
  c.target = centre;
  c.eye = centre + distance * Vec3(0.55f, 0.3f, 1.0f).normalized();
  return c;
}

io::Image renderPreview(const plant::PlantModel& plant, const PreviewCamera& camera, int width, int height,
                        const Vec3& lightDirection) {
  mesh::PlantMesh pm = mesh::buildPlantMesh(plant);
  const int ss = 2;
  const int w = width * ss, h = height * ss;
  std::vector<float> depth(size_t(w) * size_t(h), std::numeric_limits<float>::infinity());
  std::vector<Vec3> color(size_t(w) * size_t(h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float t = float(y) / float(h - 1);
      color[size_t(y) * size_t(w) + size_t(x)] = (1.0f - t) * Vec3(0.45f, 0.62f, 0.85f) + t * Vec3(0.85f, 0.88f, 0.9f);
    }

  // Camera basis (right-handed, looking down -Z of the camera).
  Vec3 forward = (camera.target - camera.eye).normalized();
  Vec3 up0 = std::abs(forward.y()) > 0.99f ? Vec3::UnitZ() : Vec3::UnitY();
  Vec3 right = forward.cross(up0).normalized();
  Vec3 up = right.cross(forward);
  float f = 1.0f / std::tan(0.5f * radians(camera.fov));
  float aspect = float(w) / float(h);
  Vec3 light = -lightDirection.normalized();

  std::map<std::string, io::Image> textures;
  auto texture = [&](const std::string& spec) -> const io::Image* {
    if (spec.empty()) return nullptr;
    auto it = textures.find(spec);
    if (it == textures.end()) it = textures.emplace(spec, io::loadTexture(spec)).first;
    return &it->second;
  };

  auto draw = [&](const TriangleMesh& m, const Material& mat) {
    size_t nv = m.positions.size();
    std::vector<Vec3> screen(nv);  // pixel x, pixel y, view depth
    for (size_t i = 0; i < nv; ++i) {
      Vec3 d = m.positions[i] - camera.eye;
      float z = d.dot(forward);
      float px = d.dot(right) / z * f / aspect, py = d.dot(up) / z * f;
      screen[i] = Vec3((px * 0.5f + 0.5f) * float(w), (0.5f - py * 0.5f) * float(h), z);
    }
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      uint32_t ia = m.indices[t], ib = m.indices[t + 1], ic = m.indices[t + 2];
      const Vec3 &a = screen[ia], &b = screen[ib], &c = screen[ic];
      if (a.z() < 1e-3f || b.z() < 1e-3f || c.z() < 1e-3f) continue;
      float area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
      if (std::abs(area) < 1e-12f) continue;
      int x0 = std::max(0, int(std::floor(std::min({a.x(), b.x(), c.x()}))));
      int x1 = std::min(w - 1, int(std::ceil(std::max({a.x(), b.x(), c.x()}))));
      int y0 = std::max(0, int(std::floor(std::min({a.y(), b.y(), c.y()}))));
      int y1 = std::min(h - 1, int(std::ceil(std::max({a.y(), b.y(), c.y()}))));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          float px = float(x) + 0.5f, py = float(y) + 0.5f;
          float wa = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
          float wb = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
          float wc = 1.0f - wa - wb;
          if (wa < 0.0f || wb < 0.0f || wc < 0.0f) continue;
          float z = wa * a.z() + wb * b.z() + wc * c.z();
          size_t k = size_t(y) * size_t(w) + size_t(x);
          if (z >= depth[k]) continue;
          Vec3 base = mat.color;
          if (mat.texture && !m.uvs.empty()) {
            Vec2 uv = wa * m.uvs[ia] + wb * m.uvs[ib] + wc * m.uvs[ic];
            Vec4 s = sample(*mat.texture, uv, mat.repeat);
            if (mat.alphaTest && s.w() < 0.5f) continue;
            base = base.cwiseProduct(Vec3(std::pow(s.x(), 2.2f), std::pow(s.y(), 2.2f), std::pow(s.z(), 2.2f)));
          }
          Vec3 n = m.normals.empty() ? Vec3::UnitY() : Vec3(wa * m.normals[ia] + wb * m.normals[ib] + wc * m.normals[ic]);
          n.normalize();
          // Face the viewer (leaves are two-sided), then light.
          Vec3 toEye = (camera.eye - (wa * m.positions[ia] + wb * m.positions[ib] + wc * m.positions[ic])).normalized();
          if (n.dot(toEye) < 0.0f) n = -n;
          float lambert = std::max(0.0f, n.dot(light));
          depth[k] = z;
          color[k] = base * (0.3f + 0.75f * lambert);
        }
    }
  };

  Material bark;
  bark.color = plant.bark.texture.empty() ? plant.bark.color : Vec3::Ones();
  bark.texture = texture(plant.bark.texture);
  bark.repeat = true;
  draw(pm.bark, bark);
  for (size_t s = 0; s < pm.leaves.size(); ++s) {
    plant::LeafShape shape = mesh::leafShapeFor(plant, s);
    Material leaf;
    leaf.color = shape.tint;
    leaf.texture = texture(shape.texture);
    leaf.alphaTest = true;
    draw(pm.leaves[s], leaf);
  }
  for (const mesh::PrimitiveGroup& g : pm.primitives) {
    Material prim;
    prim.color = g.color;
    prim.texture = texture(g.texture);
    prim.repeat = true;
    draw(g.mesh, prim);
  }

  io::Image img = io::makeImage(width, height, 0, 0, 0, 255);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      Vec3 sum = Vec3::Zero();
      for (int dy = 0; dy < ss; ++dy)
        for (int dx = 0; dx < ss; ++dx) sum += color[size_t(y * ss + dy) * size_t(w) + size_t(x * ss + dx)];
      sum /= float(ss * ss);
      uint8_t* p = img.pixel(x, y);
      p[0] = encode(sum.x());
      p[1] = encode(sum.y());
      p[2] = encode(sum.z());
      p[3] = 255;
    }
  return img;
}

}  // namespace tendril::graphtest
