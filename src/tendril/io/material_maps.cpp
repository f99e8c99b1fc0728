#include "tendril/io/material_maps.h"

#include "tendril/core/parallel.h"
#include "tendril/io/texture.h"

#include <algorithm>
#include <cmath>

namespace tendril::io {

HeightField barkHeightField(int size) {
  HeightField f{size, size, std::vector<float>(size_t(size) * size_t(size))};
  parallelFor(0, size_t(size), [&](size_t row) {
    for (int col = 0; col < size; ++col)
      f.h[row * size_t(size) + size_t(col)] = builtinBarkHeight((float(col) + 0.5f) / float(size),
                                                                (float(row) + 0.5f) / float(size));
  }, 8);
  return f;
}

HeightField luminanceHeightField(const Image& image) {
  HeightField f{image.width, image.height, std::vector<float>(size_t(image.width) * size_t(image.height))};
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const uint8_t* p = image.pixel(x, y);
      f.h[size_t(y) * size_t(image.width) + size_t(x)] =
          p[3] < 128 ? 0.0f : (0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2]) / 255.0f;
    }
  return f;
}

Vec3 heightFieldNormal(const HeightField& field, int x, int y, float reliefPixels, bool repeat) {
  auto sample = [&](int px, int py) {
    if (repeat) {
      px = ((px % field.width) + field.width) % field.width;
      py = ((py % field.height) + field.height) % field.height;
    } else {
      px = std::clamp(px, 0, field.width - 1);
      py = std::clamp(py, 0, field.height - 1);
    }
    return field.at(px, py);
  };
  // Central differences (one-sided at a clamped edge: the clamp repeats the edge texel).
  const float dx = (sample(x + 1, y) - sample(x - 1, y)) * 0.5f;
  const float drow = (sample(x, y + 1) - sample(x, y - 1)) * 0.5f;
  const float s = reliefPixels;
  return Vec3(-s * dx, s * drow, 1.0f).normalized();
}

Image normalMap(const HeightField& field, float reliefPixels, bool repeat) {
  Image img = makeImage(field.width, field.height, 128, 128, 255, 255);
  parallelFor(0, size_t(field.height), [&](size_t row) {
    for (int x = 0; x < field.width; ++x) {
      const Vec3 n = heightFieldNormal(field, x, int(row), reliefPixels, repeat);
      uint8_t* o = img.pixel(x, int(row));
      for (int k = 0; k < 3; ++k) o[k] = uint8_t(std::lround(std::clamp((n[k] * 0.5f + 0.5f) * 255.0f, 0.0f, 255.0f)));
    }
  }, 8);
  return img;
}

std::vector<Vec4> computeTangents(const TriangleMesh& m) {
  const size_t n = m.vertexCount();
  std::vector<Vec3> t(n, Vec3::Zero()), b(n, Vec3::Zero());
  if (m.uvs.size() == n)
    for (size_t k = 0; k + 2 < m.indices.size(); k += 3) {
      const uint32_t i0 = m.indices[k], i1 = m.indices[k + 1], i2 = m.indices[k + 2];
      const Vec3 e1 = m.positions[i1] - m.positions[i0], e2 = m.positions[i2] - m.positions[i0];
      const Vec2 d1 = m.uvs[i1] - m.uvs[i0], d2 = m.uvs[i2] - m.uvs[i0];
      const float r = d1.x() * d2.y() - d2.x() * d1.y();
      if (!(std::abs(r) > 1e-12f)) continue;
      // Weighted by the triangle's area: |e1 × e2| / |r| times the unnormalised gradients · r.
      const float w = e1.cross(e2).norm() / std::abs(r);
      const Vec3 tu = (e1 * d2.y() - e2 * d1.y()) / r, tv = (e2 * d1.x() - e1 * d2.x()) / r;
      const float lt = tu.norm(), lv = tv.norm();
      for (uint32_t i : {i0, i1, i2}) {
        if (lt > 0.0f) t[i] += w * tu / lt;
        if (lv > 0.0f) b[i] += w * tv / lv;
      }
    }
  std::vector<Vec4> out(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3 nrm = i < m.normals.size() ? m.normals[i] : Vec3::UnitY();
    Vec3 tan = t[i] - nrm * nrm.dot(t[i]);
    if (!(tan.squaredNorm() > 1e-20f)) {  // no UV gradient here: any direction in the surface
      tan = nrm.cross(std::abs(nrm.x()) < 0.9f ? Vec3::UnitX() : Vec3::UnitY());
    }
    tan.normalize();
    const float w = nrm.cross(tan).dot(b[i]) < 0.0f ? -1.0f : 1.0f;
    out[i] = Vec4(tan.x(), tan.y(), tan.z(), w);
  }
  return out;
}

Image roughnessMap(const HeightField& field, float smooth) {
  Image img = makeImage(field.width, field.height, 255, 255, 0, 255);
  for (int y = 0; y < field.height; ++y)
    for (int x = 0; x < field.width; ++x) {
      const float r = smooth + (1.0f - smooth) * (1.0f - std::clamp(field.at(x, y), 0.0f, 1.0f));
      img.pixel(x, y)[1] = uint8_t(std::lround(r * 255.0f));
    }
  return img;
}

}  // namespace tendril::io
