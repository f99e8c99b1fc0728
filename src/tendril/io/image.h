// 8-bit RGBA images and their PNG/JPEG encoding (stb_image, stb_image_write). Rows are stored
// top to bottom, as in the files.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace tendril::io {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgba;  // width · height · 4 bytes, row-major from the top row

  bool empty() const { return width <= 0 || height <= 0; }
  uint8_t* pixel(int x, int y) { return &rgba[(static_cast<size_t>(y) * width + x) * 4]; }
  const uint8_t* pixel(int x, int y) const { return &rgba[(static_cast<size_t>(y) * width + x) * 4]; }
};

// An image of the given size filled with one colour.
Image makeImage(int width, int height, uint8_t r, uint8_t g, uint8_t b, uint8_t a);

// PNG bytes: RGB when every pixel is opaque, RGBA otherwise. Deterministic.
std::vector<uint8_t> encodePng(const Image& image);

// Decodes PNG, JPEG (and the other formats stb_image reads) to RGBA. A corrupt or
// unsupported image is an Error(source, "", "cannot read image: <reason>").
Image decodeImage(std::span<const uint8_t> bytes, const std::string& source);

// Whole file into memory; an unreadable file is an Error naming it.
std::vector<uint8_t> readFileBytes(const std::filesystem::path& path);

Image readImage(const std::filesystem::path& path);
// Atomic (see atomic_file.h).
void writePng(const Image& image, const std::filesystem::path& path);

// "image/png" or "image/jpeg" from the file signature; "" for anything else.
std::string imageMimeType(std::span<const uint8_t> bytes);

}  // namespace tendril::io
