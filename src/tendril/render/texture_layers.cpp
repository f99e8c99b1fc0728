#include "tendril/render/texture_layers.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/io/texture.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace tendril::render {
namespace {

constexpr int kMinLayerSize = 16;
constexpr int kMaxLayerSize = 1024;

float srgbToLinear(uint8_t v) {
  float c = float(v) / 255.0f;
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// Alpha of `image` scaled by `scale` (rounded, clamped to 255): the level that passes the test
// as often as wanted.
double scaledCoverage(const io::Image& image, float scale, int threshold) {
  size_t pass = 0, n = size_t(image.width) * size_t(image.height);
  for (size_t i = 0; i < n; ++i) pass += std::min(255.0f, std::round(image.rgba[4 * i + 3] * scale)) >= float(threshold);
  return n ? double(pass) / double(n) : 0.0;
}

io::Image halve(const io::Image& src) {
  io::Image dst;
  dst.width = std::max(1, src.width / 2);
  dst.height = std::max(1, src.height / 2);
  dst.rgba.resize(size_t(dst.width) * size_t(dst.height) * 4);
  for (int y = 0; y < dst.height; ++y)
    for (int x = 0; x < dst.width; ++x) {
      std::array<float, 4> sum{};
      float weight = 0.0f;
      int count = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          int sx = std::min(src.width - 1, 2 * x + dx), sy = std::min(src.height - 1, 2 * y + dy);
          const uint8_t* p = src.pixel(sx, sy);
          float a = p[3];
          for (int k = 0; k < 3; ++k) sum[k] += a * p[k];
          sum[3] += a;
          weight += a;
          ++count;
        }
      uint8_t* o = dst.pixel(x, y);
      if (weight > 0.0f) {
        for (int k = 0; k < 3; ++k) o[k] = uint8_t(std::lround(sum[k] / weight));
      } else {
        // Fully transparent: keep the plain average so filtering toward it stays neutral.
        std::array<int, 3> plain{};
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const uint8_t* p = src.pixel(std::min(src.width - 1, 2 * x + dx), std::min(src.height - 1, 2 * y + dy));
            for (int k = 0; k < 3; ++k) plain[k] += p[k];
          }
        for (int k = 0; k < 3; ++k) o[k] = uint8_t((plain[k] + 2) / 4);
      }
      o[3] = uint8_t(std::lround(sum[3] / float(count)));
    }
  return dst;
}

}  // namespace

double alphaCoverage(const io::Image& image, int threshold) { return scaledCoverage(image, 1.0f, threshold); }

io::Image resampleImage(const io::Image& src, int width, int height) {
  if (src.width == width && src.height == height) return src;
  io::Image dst;
  dst.width = width;
  dst.height = height;
  dst.rgba.resize(size_t(width) * size_t(height) * 4);
  float sx = float(src.width) / float(width), sy = float(src.height) / float(height);
  for (int y = 0; y < height; ++y) {
    float fy = std::clamp((float(y) + 0.5f) * sy - 0.5f, 0.0f, float(src.height - 1));
    int y0 = int(fy), y1 = std::min(y0 + 1, src.height - 1);
    float ty = fy - float(y0);
    for (int x = 0; x < width; ++x) {
      float fx = std::clamp((float(x) + 0.5f) * sx - 0.5f, 0.0f, float(src.width - 1));
      int x0 = int(fx), x1 = std::min(x0 + 1, src.width - 1);
      float tx = fx - float(x0);
      uint8_t* o = dst.pixel(x, y);
      for (int k = 0; k < 4; ++k) {
        float top = (1.0f - tx) * src.pixel(x0, y0)[k] + tx * src.pixel(x1, y0)[k];
        float bottom = (1.0f - tx) * src.pixel(x0, y1)[k] + tx * src.pixel(x1, y1)[k];
        o[k] = uint8_t(std::lround((1.0f - ty) * top + ty * bottom));
      }
    }
  }
  return dst;
}

std::vector<io::Image> buildMipChain(const io::Image& image, bool preserveCoverage) {
  std::vector<io::Image> levels{image};
  const double target = alphaCoverage(image);
  while (levels.back().width > 1 || levels.back().height > 1) {
    io::Image next = halve(levels.back());
    if (preserveCoverage && target > 0.0) {
      // Bisection for the alpha scale whose coverage matches level 0 (coverage grows with it).
      float lo = 0.0f, hi = 8.0f;
      for (int i = 0; i < 16; ++i) {
        float mid = 0.5f * (lo + hi);
        (scaledCoverage(next, mid, 128) < target ? lo : hi) = mid;
      }
      // Coverage is a step function of the scale: take whichever side lands closer.
      float scale = std::abs(scaledCoverage(next, lo, 128) - target) < std::abs(scaledCoverage(next, hi, 128) - target)
                        ? lo
                        : hi;
      for (size_t i = 3; i < next.rgba.size(); i += 4)
        next.rgba[i] = uint8_t(std::min(255.0f, std::round(next.rgba[i] * scale)));
    }
    levels.push_back(std::move(next));
  }
  return levels;
}

TextureLayers::TextureLayers(std::string fallback, bool alphaTested)
    : fallback_(std::move(fallback)), alphaTested_(alphaTested) {}

float TextureLayers::layer(const std::string& spec) {
  auto found = index_.find(spec);
  if (found != index_.end()) return float(found->second);
  Layer l;
  l.spec = spec;
  try {
    l.image = io::loadTexture(spec);
  } catch (const Error& e) {
    log::warn("render: {} (drawing {} instead)", e.what(), fallback_);
    l.image = io::loadTexture(fallback_);
  }
  // Mean linear colour of the opaque part: branches divide their colour by it so that the
  // texture adds detail without changing the material's average colour.
  Vec3 sum = Vec3::Zero();
  double weight = 0.0;
  for (size_t i = 0; i + 3 < l.image.rgba.size(); i += 4) {
    float a = float(l.image.rgba[i + 3]) / 255.0f;
    sum += a * Vec3(srgbToLinear(l.image.rgba[i]), srgbToLinear(l.image.rgba[i + 1]), srgbToLinear(l.image.rgba[i + 2]));
    weight += a;
  }
  if (weight > 0.0) l.mean = (sum / float(weight)).cwiseMax(Vec3::Constant(1e-3f));
  index_.emplace(spec, layers_.size());
  layers_.push_back(std::move(l));
  return float(layers_.size() - 1);
}

Vec3 TextureLayers::meanColor(float layer) const { return layers_.at(size_t(layer)).mean; }

void TextureLayers::sync() {
  if (uploaded_ == layers_.size() && texture_) return;
  if (layers_.empty()) layer(fallback_);
  int size = kMinLayerSize;
  for (const Layer& l : layers_) size = std::max({size, l.image.width, l.image.height});
  int pow2 = kMinLayerSize;
  while (pow2 < std::min(size, kMaxLayerSize)) pow2 *= 2;
  size = pow2;

  std::vector<std::vector<io::Image>> chains;
  chains.reserve(layers_.size());
  for (const Layer& l : layers_) chains.push_back(buildMipChain(resampleImage(l.image, size, size), alphaTested_));
  const int levels = int(chains.front().size());
  const int count = int(layers_.size());

  texture_ = gl::makeTexture();
  glBindTexture(GL_TEXTURE_2D_ARRAY, texture_.get());
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  for (int level = 0; level < levels; ++level) {
    const int w = chains.front()[size_t(level)].width, h = chains.front()[size_t(level)].height;
    std::vector<uint8_t> data;
    data.reserve(size_t(w) * size_t(h) * 4 * size_t(count));
    for (const auto& chain : chains) {
      const auto& px = chain[size_t(level)].rgba;
      data.insert(data.end(), px.begin(), px.end());
    }
    glTexImage3D(GL_TEXTURE_2D_ARRAY, level, GL_SRGB8_ALPHA8, w, h, count, 0, GL_RGBA, GL_UNSIGNED_BYTE, data.data());
  }
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAX_LEVEL, levels - 1);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  GLint wrap = alphaTested_ ? GL_CLAMP_TO_EDGE : GL_REPEAT;
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, wrap);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, wrap);
  uploaded_ = layers_.size();
}

}  // namespace tendril::render
