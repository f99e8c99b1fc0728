#include "tendril/io/texture.h"

#include "support/gltf_validator.h"
#include "tendril/core/error.h"
#include "tendril/io/atomic_file.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

namespace tendril::io {
namespace {

namespace fs = std::filesystem;

int alphaAt(const Image& img, float x, float y) {  // x, y in [0, 1], y = 0 at the bottom
  int px = std::min(img.width - 1, static_cast<int>(x * img.width));
  int py = std::min(img.height - 1, static_cast<int>((1.0f - y) * img.height));
  return img.pixel(px, py)[3];
}

TEST(TextureBuiltin, LeavesAreCutOutBladesStandingOnTheirPetiole) {
  for (std::string_view name : builtinTextureNames()) {
    if (name == "bark") continue;
    SCOPED_TRACE(std::string(name));
    Image img = generateBuiltinTexture(name);
    ASSERT_EQ(img.width, kBuiltinTextureSize);
    ASSERT_EQ(img.height, kBuiltinTextureSize);
    // Transparent corners, an opaque blade in the middle, and the petiole at the bottom centre.
    for (auto [x, y] : {std::pair{0.01f, 0.01f}, {0.99f, 0.01f}, {0.01f, 0.99f}, {0.99f, 0.99f}})
      EXPECT_EQ(alphaAt(img, x, y), 0) << x << "," << y;
    EXPECT_EQ(alphaAt(img, 0.5f, 0.5f), 255);
    EXPECT_EQ(alphaAt(img, 0.5f, 0.002f), 255);
    // The tip is at the top: the top rows hold blade pixels only near the centre line.
    int opaqueTop = 0;
    for (int x = 0; x < img.width; ++x) opaqueTop += img.pixel(x, img.height / 16)[3] > 127;
    EXPECT_GT(opaqueTop, 0);
    EXPECT_LT(opaqueTop, img.width / 3);
    // Green: the blade's mean colour has more green than red or blue.
    double r = 0, g = 0, b = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x)
        if (img.pixel(x, y)[3] == 255) {
          r += img.pixel(x, y)[0];
          g += img.pixel(x, y)[1];
          b += img.pixel(x, y)[2];
        }
    EXPECT_GT(g, 1.3 * r);
    EXPECT_GT(g, 1.3 * b);
  }
}

TEST(TextureBuiltin, IvyLeavesHaveThreeLobes) {
  // Some row crosses three separate runs of blade: the two side lobes and the middle lobe.
  for (std::string_view name : {"ivy-0", "ivy-1"}) {
    Image img = generateBuiltinTexture(name);
    int best = 0;
    for (int row = 0; row < img.height; ++row) {
      int runs = 0;
      bool inside = false;
      for (int x = 0; x < img.width; ++x) {
        bool opaque = img.pixel(x, row)[3] > 127;
        if (opaque && !inside) ++runs;
        inside = opaque;
      }
      best = std::max(best, runs);
    }
    EXPECT_GE(best, 3) << name;
  }
}

TEST(TextureBuiltin, BarkIsOpaqueBrownAndTiles) {
  Image img = generateBuiltinTexture("bark");
  double jumpAcrossSeam = 0, jumpInside = 0;
  double r = 0, g = 0, b = 0;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      ASSERT_EQ(img.pixel(x, y)[3], 255);
      r += img.pixel(x, y)[0];
      g += img.pixel(x, y)[1];
      b += img.pixel(x, y)[2];
    }
    for (int c = 0; c < 3; ++c) {
      jumpAcrossSeam += std::abs(img.pixel(img.width - 1, y)[c] - img.pixel(0, y)[c]);
      jumpInside += std::abs(img.pixel(img.width / 2, y)[c] - img.pixel(img.width / 2 - 1, y)[c]);
    }
  }
  EXPECT_GT(r, g);
  EXPECT_GT(g, b);
  // Wrapping around u is no rougher than any other step between neighbouring columns.
  EXPECT_LT(jumpAcrossSeam, 2.0 * jumpInside + img.height);
  // The same along v.
  double seamV = 0, insideV = 0;
  for (int x = 0; x < img.width; ++x)
    for (int c = 0; c < 3; ++c) {
      seamV += std::abs(img.pixel(x, img.height - 1)[c] - img.pixel(x, 0)[c]);
      insideV += std::abs(img.pixel(x, img.height / 2)[c] - img.pixel(x, img.height / 2 - 1)[c]);
    }
  EXPECT_LT(seamV, 2.0 * insideV + img.width);
}

TEST(TextureBuiltin, DeterministicAndSized) {
  Image a = generateBuiltinTexture("ivy-2", 64);
  Image b = generateBuiltinTexture("ivy-2", 64);
  EXPECT_EQ(a.width, 64);
  EXPECT_EQ(a.rgba, b.rgba);
  EXPECT_NE(generateBuiltinTexture("ivy-0", 64).rgba, a.rgba);
  EXPECT_THROW(generateBuiltinTexture("ivy-0", 4), Error);
}

TEST(TextureBuiltin, UnknownNameListsTheKnownOnes) {
  try {
    loadTexture("builtin:ivvy-0");
    FAIL();
  } catch (const Error& e) {
    std::string what = e.what();
    EXPECT_NE(what.find("builtin:ivvy-0"), std::string::npos) << what;
    EXPECT_NE(what.find("builtin:ivy-0"), std::string::npos) << what;
    EXPECT_NE(what.find("builtin:bark"), std::string::npos) << what;
  }
}

TEST(TextureFiles, LoadsPngAndJpegAndRejectsBadFiles) {
  fs::path dir = meshtest::exportTestDir();
  Image img = generateBuiltinTexture("ovate-0", 32);
  writePng(img, dir / "leaf.png");
  Image back = loadTexture((dir / "leaf.png").string());
  EXPECT_EQ(back.rgba, img.rgba);
  EncodedImage enc = loadEncodedTexture((dir / "leaf.png").string());
  EXPECT_EQ(enc.mimeType, "image/png");
  EXPECT_EQ(enc.bytes, readFileBytes(dir / "leaf.png"));  // passed through unchanged
  EXPECT_EQ(enc.width, 32);

  // A missing file and a corrupt one are Errors naming the path.
  for (const char* name : {"missing.png", "corrupt.png"}) {
    if (std::string(name) == "corrupt.png") writeFileAtomic(dir / name, std::string_view("\x89PNG\r\n\x1a\nnot really"));
    std::string path = (dir / name).string();
    try {
      loadTexture(path);
      FAIL() << name;
    } catch (const Error& e) {
      EXPECT_EQ(e.source(), path);
      EXPECT_NE(e.message().find("cannot read image"), std::string::npos) << e.what();
    }
    EXPECT_THROW(loadEncodedTexture(path), Error);
  }
}

TEST(ImagePng, RoundTripsOpaqueAndTransparentImages) {
  Image rgba = makeImage(5, 3, 10, 20, 30, 40);
  rgba.pixel(4, 2)[0] = 200;
  Image back = decodeImage(encodePng(rgba), "mem");
  EXPECT_EQ(back.width, 5);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(back.rgba, rgba.rgba);
  Image opaque = makeImage(4, 4, 1, 2, 3, 255);
  std::vector<uint8_t> png = encodePng(opaque);
  EXPECT_EQ(imageMimeType(png), "image/png");
  EXPECT_EQ(decodeImage(png, "mem").rgba, opaque.rgba);
  EXPECT_THROW(decodeImage(std::vector<uint8_t>{1, 2, 3}, "mem"), Error);
}

// examples/textures holds the built-in textures as generated, small enough to keep in git.
// TENDRIL_UPDATE_TEXTURES=1 rewrites them after a change to the generator.
TEST(TextureExamples, MatchTheGenerator) {
  fs::path dir = fs::path(TENDRIL_SOURCE_DIR) / "examples" / "textures";
  if (const char* update = std::getenv("TENDRIL_UPDATE_TEXTURES"); update && std::string(update) == "1")
    writeBuiltinTextures(dir);
  for (std::string_view name : builtinTextureNames()) {
    fs::path file = dir / (std::string(name) + ".png");
    SCOPED_TRACE(file.string());
    ASSERT_TRUE(fs::exists(file)) << "run with TENDRIL_UPDATE_TEXTURES=1 to create it";
    EXPECT_LT(fs::file_size(file), 100u * 1024u);
    Image stored = readImage(file);
    Image generated = generateBuiltinTexture(name);
    ASSERT_EQ(stored.width, generated.width);
    ASSERT_EQ(stored.height, generated.height);
    // Equal up to a rounding step (another libm may round a few pixels differently).
    size_t off = 0;
    for (size_t i = 0; i < stored.rgba.size(); ++i) off += std::abs(int(stored.rgba[i]) - int(generated.rgba[i])) > 2;
    EXPECT_LT(off, stored.rgba.size() / 1000) << "regenerate with TENDRIL_UPDATE_TEXTURES=1";
  }
}

}  // namespace
}  // namespace tendril::io
