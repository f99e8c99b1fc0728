// Textures named by plants ("builtin:ivy-0", image paths) gathered in one 2D array texture, one
// layer each, so that every leaf (or every branch) of every plant is drawn by a single
// instanced draw. Layers are loaded through io::loadTexture, resampled to a common square size
// and uploaded with their mipmaps; a texture that cannot be read is reported once (log) and
// drawn with the fallback instead, so a broken path never stops a studio frame.
#pragma once

#include "tendril/core/math.h"
#include "tendril/io/image.h"
#include "tendril/render/gl_util.h"

#include <string>
#include <unordered_map>
#include <vector>

namespace tendril::render {

// Mip chain of an RGBA8 image, level 0 first, each level half the size (at least 1 pixel).
// With `preserveCoverage`, alpha in each smaller level is rescaled so that the fraction of
// texels passing an alpha test at 0.5 matches level 0 (Castaño 2010, "Computing alpha
// mipmaps"): alpha-tested leaves keep their area in the distance instead of thinning out.
// Colour is averaged weighted by alpha, so transparent texels do not darken blade edges.
std::vector<io::Image> buildMipChain(const io::Image& image, bool preserveCoverage);

// Fraction of texels whose alpha is at least `threshold` (0..255).
double alphaCoverage(const io::Image& image, int threshold = 128);

// Bilinear resampling to width × height (texel centres aligned; edges clamped).
io::Image resampleImage(const io::Image& image, int width, int height);

class TextureLayers {
 public:
  // `fallback` is used for specs that fail to load; `alphaTested` turns on coverage-preserving
  // mipmaps.
  TextureLayers(std::string fallback, bool alphaTested);

  // The layer of `spec`, loading the image now if the spec is new (it reaches the GPU at the
  // next sync).
  float layer(const std::string& spec);
  // Mean linear colour of a layer's opaque texels.
  Vec3 meanColor(float layer) const;
  // Uploads the array texture again when layers were added since the last sync.
  void sync();
  GLuint texture() const { return texture_.get(); }

 private:
  struct Layer {
    std::string spec;
    io::Image image;  // as loaded, before resampling
    Vec3 mean = Vec3::Ones();
  };

  std::string fallback_;
  bool alphaTested_;
  std::vector<Layer> layers_;
  std::unordered_map<std::string, size_t> index_;
  size_t uploaded_ = 0;  // layers in the GL texture
  gl::Texture texture_;
};

}  // namespace tendril::render
