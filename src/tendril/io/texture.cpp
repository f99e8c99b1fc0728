#include "tendril/io/texture.h"

#include "tendril/core/error.h"
#include "tendril/core/math.h"
#include "tendril/core/parallel.h"
#include "tendril/core/random.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>

namespace tendril::io {
namespace {

constexpr std::array<std::string_view, 6> kBuiltinNames = {"ivy-0", "ivy-1", "ivy-2", "heart-0", "ovate-0", "bark"};

// ---------------------------------------------------------------------------------------------
// Noise. Value noise on an integer lattice that wraps with periods (px, py), so a texture
// sampled over [0, px) × [0, py) tiles; fractal sums of it (fBm). Lattice values come from
// the keyed hash, so every pixel is independent of evaluation order.

float latticeValue(int64_t ix, int64_t iy, uint64_t seed) {
  uint64_t h = mix64(seed ^ mix64(static_cast<uint64_t>(ix) * 0x9e3779b97f4a7c15ull + static_cast<uint64_t>(iy)));
  return static_cast<float>(h >> 40) * (1.0f / 16777216.0f);
}

float quintic(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }

float periodicNoise(float x, float y, int px, int py, uint64_t seed) {
  float fx = std::floor(x), fy = std::floor(y);
  auto wrap = [](int64_t i, int p) {
    int64_t m = i % p;
    return m < 0 ? m + p : m;
  };
  int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  int64_t x0 = wrap(ix, px), x1 = wrap(ix + 1, px), y0 = wrap(iy, py), y1 = wrap(iy + 1, py);
  float tx = quintic(x - fx), ty = quintic(y - fy);
  float a = latticeValue(x0, y0, seed), b = latticeValue(x1, y0, seed);
  float c = latticeValue(x0, y1, seed), d = latticeValue(x1, y1, seed);
  return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}

// Fractal sum in [0, 1]; (x, y) in [0, 1) tiles with `px` × `py` cells at the first octave.
float fbm(float x, float y, int px, int py, int octaves, uint64_t seed) {
  float sum = 0.0f, amp = 1.0f, norm = 0.0f;
  for (int o = 0; o < octaves; ++o) {
    int sx = px << o, sy = py << o;
    sum += amp * periodicNoise(x * sx, y * sy, sx, sy, seed + static_cast<uint64_t>(o) * 0x632be59bd9b4e019ull);
    norm += amp;
    amp *= 0.5f;
  }
  return sum / norm;
}

float clamp01(float v) { return std::min(1.0f, std::max(0.0f, v)); }
float smoothstep(float e0, float e1, float x) {
  float t = clamp01((x - e0) / (e1 - e0));
  return t * t * (3.0f - 2.0f * t);
}
Vec3 mix(const Vec3& a, const Vec3& b, float t) { return a + (b - a) * t; }

float segmentDistance(const Vec2& p, const Vec2& a, const Vec2& b, float* along) {
  Vec2 ab = b - a;
  float t = clamp01((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-12f));
  *along = t;
  return (p - (a + t * ab)).norm();
}

// ---------------------------------------------------------------------------------------------
// Leaves. Coordinates: x from the image's vertical centre line, y up from its bottom edge, both
// as fractions of the image size. The blade joins its petiole at `origin`; a short petiole stub
// runs from there to the bottom centre (0, 0), which is where the leaf quad's petiole ends.

// A pointed lobe of a palmate blade: radius `length` from the origin in direction `angle`
// (radians from +y toward +x), falling to 0 at `tipward` radians on its flank toward the leaf
// tip and at `baseward` radians on the flank toward the petiole; power < 1 gives broad lobes.
struct Lobe {
  float angle, length, tipward, baseward, power;
};

struct Vein {
  Vec2 a, b;
  float widthA, widthB;  // half widths (image fractions) at a and b
};

struct LeafDesign {
  bool palmate = true;
  Vec2 origin = Vec2(0.0f, 0.12f);
  // Palmate blades: the radius around the origin is a smooth maximum (p-norm with exponent
  // `sharpness`; larger = deeper sinuses) of the lobes and `body`. Scaled to fit the image.
  std::vector<Lobe> lobes;
  float body = 0.05f;
  float sharpness = 8.0f;
  std::vector<float> veinAngles;  // main veins radiating from the origin
  // Pinnate blades: half width along the midrib t in [0, 1] is
  // halfWidth · sin(pi · t^shapeA)^shapeB, the midrib running from origin up to tipY.
  float tipY = 0.97f, halfWidth = 0.3f, shapeA = 0.8f, shapeB = 1.0f;
  int teeth = 0;            // serrations along the margin
  float toothDepth = 0.0f;  // fraction of the radius / half width
  int secondaryVeins = 4;   // per side of each main vein
  float secondaryAngle = 0.75f;
  Vec3 base, vein, margin, petiole;  // sRGB 0..255
  float mottle = 0.08f;              // relative brightness variation
  float gloss = 0.10f;               // brightening toward the upper left
  uint64_t seed = 1;
};

float wrapAngle(float a) {
  while (a > kPi) a -= kTwoPi;
  while (a < -kPi) a += kTwoPi;
  return a;
}

float sawtooth(float t) { return t - std::floor(t); }

float palmateRadius(const LeafDesign& d, float phi, bool withTeeth = true) {
  float sum = std::pow(d.body, d.sharpness);
  for (const Lobe& l : d.lobes) {
    float delta = wrapAngle(phi - l.angle);
    // The flank toward the tip turns back toward angle 0.
    bool towardTip = l.angle == 0.0f || delta * l.angle < 0.0f;
    float x = std::abs(delta) / (towardTip ? l.tipward : l.baseward);
    if (x < 1.0f) sum += std::pow(l.length * std::pow(1.0f - x, l.power), d.sharpness);
  }
  float r = std::pow(sum, 1.0f / d.sharpness);
  if (withTeeth && d.teeth > 0) r *= 1.0f - d.toothDepth * sawtooth(phi * static_cast<float>(d.teeth) / kTwoPi);
  return r;
}

// Scales and moves a palmate design so that the blade fills the image with a small margin,
// the origin staying on the centre line.
void fitPalmate(LeafDesign& d) {
  constexpr float kMargin = 0.02f;
  float maxX = 0.0f, minY = 0.0f, maxY = 0.0f;
  for (int i = 0; i < 1440; ++i) {
    float phi = kTwoPi * static_cast<float>(i) / 1440.0f - kPi;
    Vec2 q = palmateRadius(d, phi, false) * Vec2(std::sin(phi), std::cos(phi));
    maxX = std::max(maxX, std::abs(q.x()));
    minY = std::min(minY, q.y());
    maxY = std::max(maxY, q.y());
  }
  float scale = std::min((0.5f - kMargin) / maxX, (1.0f - 2.0f * kMargin) / (maxY - minY));
  for (Lobe& l : d.lobes) l.length *= scale;
  d.body *= scale;
  d.origin = Vec2(0.0f, kMargin - scale * minY);
}

float pinnateHalfWidth(const LeafDesign& d, float t) {
  if (t <= 0.0f || t >= 1.0f) return 0.0f;
  float w = d.halfWidth * std::pow(std::sin(kPi * std::pow(t, d.shapeA)), d.shapeB);
  if (d.teeth > 0) w *= 1.0f - d.toothDepth * sawtooth(t * static_cast<float>(d.teeth));
  return w;
}

// Approximate distance inside the blade's margin (> 0 inside), in image fractions.
float bladeDistance(const LeafDesign& d, const Vec2& p) {
  Vec2 q = p - d.origin;
  if (d.palmate) {
    float r = q.norm();
    float phi = std::atan2(q.x(), q.y());
    return palmateRadius(d, phi) - r;
  }
  float length = d.tipY - d.origin.y();
  float t = q.y() / length;
  if (t <= 0.0f) return q.y() - std::abs(q.x());
  if (t >= 1.0f) return -(q.y() - length) - std::abs(q.x());
  return pinnateHalfWidth(d, t) - std::abs(q.x());
}

Vec2 direction(float angle) { return Vec2(std::sin(angle), std::cos(angle)); }

std::vector<Vein> leafVeins(const LeafDesign& d) {
  std::vector<Vein> veins;
  auto addBranch = [&](const Vec2& from, float angle, float length, float w0, float w1) {
    veins.push_back({from, from + length * direction(angle), w0, w1});
  };
  auto addMain = [&](float angle, float length, float w0) {
    Vec2 a = d.origin;
    Vec2 b = a + length * direction(angle);
    veins.push_back({a, b, w0, 0.25f * w0});
    for (int s = 1; s <= d.secondaryVeins; ++s) {
      float f = static_cast<float>(s) / static_cast<float>(d.secondaryVeins + 1);
      Vec2 at = a + f * (b - a);
      float len = length * 0.55f * (1.0f - 0.7f * f);
      for (float side : {-1.0f, 1.0f})
        addBranch(at, angle + side * d.secondaryAngle, len, 0.45f * w0 * (1.0f - 0.5f * f), 0.1f * w0);
    }
  };
  if (d.palmate) {
    for (float angle : d.veinAngles) {
      float length = 0.92f * palmateRadius(d, angle, false);
      addMain(angle, length, length > 0.35f ? 0.012f : 0.008f);
    }
  } else {
    addMain(0.0f, d.tipY - d.origin.y() - 0.01f, 0.012f);
  }
  return veins;
}

void drawLeaf(const LeafDesign& d, Image& img) {
  const int size = img.width;
  const float px = 1.0f / static_cast<float>(size);
  std::vector<Vein> veins = leafVeins(d);
  // Each vein's bounds and the square of a distance beyond which it cannot add to a pixel:
  // 2w for its widest w, plus a margin far above the rounding of the distance test.
  std::vector<Vec2> veinLo, veinHi;
  std::vector<float> veinReach2;
  for (const Vein& v : veins) {
    veinLo.push_back(v.a.cwiseMin(v.b));
    veinHi.push_back(v.a.cwiseMax(v.b));
    const float reach = 2.0f * std::max({v.widthA, v.widthB, 0.6f * px}) + 1e-4f;
    veinReach2.push_back(reach * reach);
  }
  parallelFor(0, static_cast<size_t>(size), [&](size_t row) {
    for (int col = 0; col < size; ++col) {
      // Pixel centre; image rows run top to bottom, y runs up.
      Vec2 p((static_cast<float>(col) + 0.5f) * px - 0.5f, 1.0f - (static_cast<float>(row) + 0.5f) * px);
      float dist = bladeDistance(d, p);
      float alpha = clamp01(dist * static_cast<float>(size) + 0.5f);
      Vec3 c = d.base;
      if (alpha > 0.0f) {
        float n = fbm(p.x() + 0.5f, p.y(), 6, 6, 3, d.seed);
        float fine = fbm(p.x() + 0.5f, p.y(), 32, 32, 2, d.seed + 7);
        c *= 1.0f + d.mottle * (2.0f * n - 1.0f) + 0.03f * (2.0f * fine - 1.0f);
        // A soft sheen toward the upper left, as on a glossy cuticle under sky light.
        float sheen = std::exp(-((p - Vec2(-0.15f, 0.62f)).squaredNorm()) / 0.06f);
        c *= 1.0f + d.gloss * sheen;
        float veinAmount = 0.0f;
        for (size_t k = 0; k < veins.size(); ++k) {
          // A vein whose reach (2w) cannot touch p adds nothing; most are far from a pixel.
          const Vec2 gap = (veinLo[k] - p).cwiseMax(p - veinHi[k]).cwiseMax(0.0f);
          if (gap.squaredNorm() > veinReach2[k]) continue;
          const Vein& v = veins[k];
          float t;
          float vd = segmentDistance(p, v.a, v.b, &t);
          float w = std::max(v.widthA + (v.widthB - v.widthA) * t, 0.6f * px);
          if (vd < 2.0f * w) veinAmount = std::max(veinAmount, 1.0f - smoothstep(0.4f * w, 1.5f * w, vd));
        }
        c = mix(c, d.vein, 0.75f * veinAmount);
        // The margin is a little darker (a thickened edge).
        c = mix(c, d.margin, 0.6f * (1.0f - smoothstep(0.0f, 0.02f, dist)));
      }
      // The petiole stub from the bottom centre to the blade.
      float t;
      float sd = segmentDistance(p, Vec2(0.0f, 0.0f), d.origin, &t);
      float stub = clamp01((0.011f - sd) * static_cast<float>(size) + 0.5f);
      if (stub > 0.0f) {
        c = mix(c, d.petiole, stub);
        alpha = std::max(alpha, stub);
      }
      uint8_t* o = img.pixel(col, static_cast<int>(row));
      for (int k = 0; k < 3; ++k) o[k] = static_cast<uint8_t>(std::lround(std::min(255.0f, std::max(0.0f, c[k]))));
      o[3] = static_cast<uint8_t>(std::lround(alpha * 255.0f));
      // Fully transparent pixels keep the base colour so filtering does not bleed a fringe.
      if (o[3] == 0)
        for (int k = 0; k < 3; ++k) o[k] = static_cast<uint8_t>(std::lround(d.base[k]));
    }
  }, 8);
}

LeafDesign ivyDesign(int variant) {
  LeafDesign d;
  d.palmate = true;
  d.petiole = Vec3(92, 104, 40);
  d.margin = Vec3(22, 52, 20);
  d.vein = Vec3(112, 146, 62);
  d.seed = purposeId("texture.ivy") + static_cast<uint64_t>(variant);
  switch (variant) {
    case 0:  // the textbook three-lobed blade with a cordate base
      d.lobes = {{0.0f, 0.76f, 1.2f, 1.2f, 0.55f}, {0.95f, 0.56f, 0.95f, 2.0f, 0.6f}, {-0.95f, 0.56f, 0.95f, 2.0f, 0.6f}};
      d.veinAngles = {0.0f, 0.95f, -0.95f, 2.1f, -2.1f};
      d.body = 0.06f;
      d.sharpness = 10.0f;
      d.teeth = 48;
      d.toothDepth = 0.025f;
      d.base = Vec3(36, 80, 30);
      break;
    case 1:  // deeply cut, narrow lobes
      d.lobes = {{0.0f, 0.8f, 0.9f, 0.9f, 0.7f}, {1.05f, 0.56f, 0.75f, 1.9f, 0.65f}, {-1.05f, 0.56f, 0.75f, 1.9f, 0.65f}};
      d.veinAngles = {0.0f, 1.05f, -1.05f, 2.2f, -2.2f};
      d.body = 0.05f;
      d.sharpness = 16.0f;
      d.teeth = 60;
      d.toothDepth = 0.03f;
      d.base = Vec3(30, 72, 28);
      d.secondaryAngle = 0.65f;
      break;
    default:  // a young, shallowly lobed blade, lighter and glossier, with a reddish petiole
      d.lobes = {{0.0f, 0.76f, 1.35f, 1.35f, 0.5f}, {0.9f, 0.55f, 1.2f, 2.1f, 0.5f}, {-0.9f, 0.55f, 1.2f, 2.1f, 0.5f}};
      d.veinAngles = {0.0f, 0.9f, -0.9f, 2.05f, -2.05f};
      d.body = 0.08f;
      d.sharpness = 6.0f;
      d.teeth = 40;
      d.toothDepth = 0.02f;
      d.base = Vec3(48, 98, 34);
      d.gloss = 0.16f;
      d.petiole = Vec3(120, 70, 40);
      break;
  }
  fitPalmate(d);
  return d;
}

LeafDesign heartDesign() {
  LeafDesign d;
  d.palmate = true;
  d.lobes = {{0.0f, 0.75f, 2.3f, 2.3f, 0.75f}, {1.9f, 0.47f, 1.9f, 1.25f, 0.45f}, {-1.9f, 0.47f, 1.9f, 1.25f, 0.45f}};
  d.veinAngles = {0.0f, 0.9f, -0.9f, 2.1f, -2.1f};
  d.body = 0.08f;
  d.sharpness = 4.0f;
  d.secondaryVeins = 5;
  d.secondaryAngle = 0.6f;
  d.base = Vec3(44, 96, 36);
  d.vein = Vec3(120, 156, 70);
  d.margin = Vec3(28, 62, 24);
  d.petiole = Vec3(80, 110, 45);
  d.seed = purposeId("texture.heart");
  fitPalmate(d);
  return d;
}

LeafDesign ovateDesign() {
  LeafDesign d;
  d.palmate = false;
  d.origin = Vec2(0.0f, 0.05f);
  d.tipY = 0.97f;
  d.halfWidth = 0.3f;
  d.shapeA = 0.7f;
  d.shapeB = 0.8f;
  d.teeth = 30;
  d.toothDepth = 0.03f;
  d.secondaryVeins = 7;
  d.secondaryAngle = 0.9f;
  d.base = Vec3(52, 104, 38);
  d.vein = Vec3(126, 160, 74);
  d.margin = Vec3(32, 70, 26);
  d.petiole = Vec3(86, 112, 48);
  d.seed = purposeId("texture.ovate");
  return d;
}

// ---------------------------------------------------------------------------------------------
// Bark: ridges and furrows running along the branch (image up = v = along the chain), tiling
// in both directions because every noise term has integer periods over the image.

void drawBark(Image& img) {
  const int size = img.width;
  const uint64_t seed = purposeId("texture.bark");
  const Vec3 dark(52, 38, 27), mid(98, 74, 53), light(138, 110, 82);
  parallelFor(0, static_cast<size_t>(size), [&](size_t row) {
    for (int col = 0; col < size; ++col) {
      float u = (static_cast<float>(col) + 0.5f) / static_cast<float>(size);
      float v = (static_cast<float>(row) + 0.5f) / static_cast<float>(size);
      // Plates and furrows: noise stretched along v (10 cells around, 2 along); furrows where
      // it crosses 1/2. Fine fibres on top, and broad blotches of lighter bark.
      float streak = fbm(u, v, 10, 2, 4, seed);
      float ridge = 1.0f - std::abs(2.0f * streak - 1.0f);
      float blotch = fbm(u, v, 3, 3, 2, seed + 11);
      float fibre = fbm(u, v, 64, 4, 2, seed + 23);
      Vec3 c = mix(mid, light, smoothstep(0.35f, 0.9f, ridge) * 0.7f + 0.3f * blotch);
      c = mix(c, dark, 1.0f - smoothstep(0.08f, 0.32f, ridge));
      c *= 0.86f + 0.28f * fibre;
      uint8_t* o = img.pixel(col, static_cast<int>(row));
      for (int k = 0; k < 3; ++k) o[k] = static_cast<uint8_t>(std::lround(std::min(255.0f, std::max(0.0f, c[k]))));
      o[3] = 255;
    }
  }, 8);
}

// The same terms drawBark colours with.
float barkRelief(float u, float v, uint64_t seed) {
  const float streak = fbm(u, v, 10, 2, 4, seed);
  const float ridge = 1.0f - std::abs(2.0f * streak - 1.0f);
  const float fibre = fbm(u, v, 64, 4, 2, seed + 23);
  return 0.85f * smoothstep(0.08f, 0.32f, ridge) * (0.7f + 0.3f * smoothstep(0.35f, 0.9f, ridge)) + 0.15f * fibre;
}

std::string knownNames() {
  std::string s;
  for (std::string_view n : kBuiltinNames) s += fmt::format("{}builtin:{}", s.empty() ? "" : ", ", n);
  return s;
}

std::string_view builtinName(std::string_view spec) { return spec.substr(kBuiltinPrefix.size()); }

}  // namespace

std::span<const std::string_view> builtinTextureNames() { return kBuiltinNames; }

float builtinBarkHeight(float u, float v) { return barkRelief(u, v, purposeId("texture.bark")); }

bool isBuiltinTexture(std::string_view spec) { return spec.substr(0, kBuiltinPrefix.size()) == kBuiltinPrefix; }

Image generateBuiltinTexture(std::string_view name, int size) {
  if (size < 16 || size > 4096)
    throw Error(fmt::format("builtin:{}", name), "", fmt::format("texture size must be in [16, 4096], got {}", size));
  Image img = makeImage(size, size, 0, 0, 0, 0);
  if (name == "ivy-0") drawLeaf(ivyDesign(0), img);
  else if (name == "ivy-1") drawLeaf(ivyDesign(1), img);
  else if (name == "ivy-2") drawLeaf(ivyDesign(2), img);
  else if (name == "heart-0") drawLeaf(heartDesign(), img);
  else if (name == "ovate-0") drawLeaf(ovateDesign(), img);
  else if (name == "bark") drawBark(img);
  else
    throw Error(fmt::format("builtin:{}", name), "", fmt::format("unknown built-in texture; known: {}", knownNames()));
  return img;
}

Image loadTexture(const std::string& spec) {
  if (isBuiltinTexture(spec)) return generateBuiltinTexture(builtinName(spec));
  if (spec.empty()) throw Error("texture", "", "empty texture path");
  return readImage(spec);
}

EncodedImage loadEncodedTexture(const std::string& spec) {
  if (isBuiltinTexture(spec)) {
    // Encoding costs milliseconds and every export needs the same few images.
    static std::mutex mutex;
    static std::map<std::string, std::shared_ptr<const EncodedImage>, std::less<>> cache;
    {
      std::lock_guard lock(mutex);
      auto it = cache.find(spec);
      if (it != cache.end()) return *it->second;
    }
    Image img = generateBuiltinTexture(builtinName(spec));
    auto encoded = std::make_shared<EncodedImage>(EncodedImage{"image/png", encodePng(img), img.width, img.height});
    std::lock_guard lock(mutex);
    cache.emplace(spec, encoded);
    return *encoded;
  }
  if (spec.empty()) throw Error("texture", "", "empty texture path");
  std::vector<uint8_t> bytes;
  try {
    bytes = readFileBytes(spec);
  } catch (const Error& e) {
    throw Error(spec, "", "cannot read image: " + e.message());
  }
  Image img = decodeImage(bytes, spec);  // rejects corrupt files
  std::string mime = imageMimeType(bytes);
  if (mime.empty()) return {"image/png", encodePng(img), img.width, img.height};
  return {mime, std::move(bytes), img.width, img.height};
}

void writeBuiltinTextures(const std::filesystem::path& dir, int size) {
  for (std::string_view name : kBuiltinNames)
    writePng(generateBuiltinTexture(name, size), dir / (std::string(name) + ".png"));
}

}  // namespace tendril::io
