#include "tendril/io/image.h"

#include "tendril/core/error.h"
#include "tendril/io/atomic_file.h"

#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <cerrno>
#include <cstring>
#include <fstream>

namespace tendril::io {

Image makeImage(int width, int height, uint8_t r, uint8_t g, uint8_t b, uint8_t a) {
  Image img;
  img.width = width;
  img.height = height;
  img.rgba.resize(static_cast<size_t>(width) * height * 4);
  for (size_t i = 0; i < img.rgba.size(); i += 4) {
    img.rgba[i] = r;
    img.rgba[i + 1] = g;
    img.rgba[i + 2] = b;
    img.rgba[i + 3] = a;
  }
  return img;
}

std::vector<uint8_t> encodePng(const Image& image) {
  if (image.empty() || image.rgba.size() != static_cast<size_t>(image.width) * image.height * 4)
    throw Error("cannot encode PNG: image size and pixel data disagree");
  bool opaque = true;
  for (size_t i = 3; i < image.rgba.size() && opaque; i += 4) opaque = image.rgba[i] == 255;
  std::vector<uint8_t> rgb;
  const uint8_t* data = image.rgba.data();
  int components = 4;
  if (opaque) {
    rgb.resize(static_cast<size_t>(image.width) * image.height * 3);
    for (size_t i = 0, j = 0; i < image.rgba.size(); i += 4, j += 3) std::memcpy(&rgb[j], &image.rgba[i], 3);
    data = rgb.data();
    components = 3;
  }
  std::vector<uint8_t> out;
  auto sink = [](void* context, void* bytes, int size) {
    auto* v = static_cast<std::vector<uint8_t>*>(context);
    const auto* b = static_cast<const uint8_t*>(bytes);
    v->insert(v->end(), b, b + size);
  };
  if (!stbi_write_png_to_func(sink, &out, image.width, image.height, components, data, image.width * components))
    throw Error("cannot encode PNG");
  return out;
}

Image decodeImage(std::span<const uint8_t> bytes, const std::string& source) {
  if (bytes.empty()) throw Error(source, "", "cannot read image: the file is empty");
  if (bytes.size() > static_cast<size_t>(INT32_MAX)) throw Error(source, "", "cannot read image: the file is too large");
  int w = 0, h = 0, n = 0;
  stbi_uc* pixels = stbi_load_from_memory(bytes.data(), static_cast<int>(bytes.size()), &w, &h, &n, 4);
  if (!pixels) {
    const char* why = stbi_failure_reason();
    throw Error(source, "", std::string("cannot read image: ") + (why ? why : "unknown format"));
  }
  Image img;
  img.width = w;
  img.height = h;
  img.rgba.assign(pixels, pixels + static_cast<size_t>(w) * h * 4);
  stbi_image_free(pixels);
  return img;
}

std::vector<uint8_t> readFileBytes(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw Error(path.string(), "", "cannot read: it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string(), "", std::string("cannot open: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  std::streamoff size = in.tellg();
  if (size < 0) throw Error(path.string(), "", "cannot read: not a regular file");
  in.seekg(0);
  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), size))
    throw Error(path.string(), "", "cannot read: read failed");
  return bytes;
}

Image readImage(const std::filesystem::path& path) {
  std::vector<uint8_t> bytes;
  try {
    bytes = readFileBytes(path);
  } catch (const Error& e) {
    throw Error(path.string(), "", "cannot read image: " + e.message());
  }
  return decodeImage(bytes, path.string());
}

void writePng(const Image& image, const std::filesystem::path& path) {
  std::vector<uint8_t> png = encodePng(image);
  writeFileAtomic(path, png);
}

std::string imageMimeType(std::span<const uint8_t> b) {
  static const uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (b.size() >= 8 && std::memcmp(b.data(), kPng, 8) == 0) return "image/png";
  if (b.size() >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff) return "image/jpeg";
  return "";
}

}  // namespace tendril::io
