#include "tendril/io/pivot_painter.h"

#include "tendril/core/error.h"
#include "tendril/io/atomic_file.h"
#include "tendril/io/image.h"

#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfRgbaFile.h>
#include <Imath/half.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <exception>

namespace tendril::io {

namespace {

// An OpenEXR output stream into memory, so that the file is written atomically in one go.
class MemoryStream : public Imf::OStream {
 public:
  MemoryStream() : Imf::OStream("memory") {}
  void write(const char c[], int n) override {
    if (pos_ + size_t(n) > bytes_.size()) bytes_.resize(pos_ + size_t(n));
    std::memcpy(bytes_.data() + pos_, c, size_t(n));
    pos_ += size_t(n);
  }
  uint64_t tellp() override { return pos_; }
  void seekp(uint64_t pos) override { pos_ = size_t(pos); }
  const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
  size_t pos_ = 0;
};

std::string safeFileName(const std::string& name) {
  std::string s = name.empty() ? std::string("plant") : name;
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-') c = '_';
  return s;
}

uint16_t halfBits(float v) { return half(v).bits(); }

uint8_t unitToByte(float v) { return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); }

}  // namespace

PivotPainterGrid pivotPainterGrid(size_t elements, const std::string& source, const std::string& plant) {
  if (elements > kPivotPainterMaxElements)
    throw Error(source, plant.empty() ? std::string("output.pivot_painter") : fmt::format("plant \"{}\"", plant),
                fmt::format("{} nodes do not fit Pivot Painter textures (at most {}: the parent index is a half "
                            "float); leave output.pivot_painter off for this plant's scene",
                            elements, kPivotPainterMaxElements));
  PivotPainterGrid g;
  if (elements == 0) return g;
  g.elements = uint32_t(elements);
  g.width = uint32_t(std::ceil(std::sqrt(double(elements))));
  while (size_t(g.width) * g.width < elements) ++g.width;  // ⌈√n⌉ exactly, whatever the rounding
  while (g.width > 1 && size_t(g.width - 1) * (g.width - 1) >= elements) --g.width;
  g.height = uint32_t((elements + g.width - 1) / g.width);
  return g;
}

Vec2 pivotPainterUv(uint32_t element, const PivotPainterGrid& grid) {
  return Vec2((float(element % grid.width) + 0.5f) / float(grid.width),
              (float(element / grid.width) + 0.5f) / float(grid.height));
}

uint8_t encodePivotPainterExtent(float metres) {
  const float units = std::clamp(metres * kPivotPainterCmPerMetre / 8.0f, 1.0f, 256.0f);
  return unitToByte(units / 256.0f);
}

std::vector<float> branchLengths(const plant::PlantModel& plant) {
  const size_t n = plant.nodeCount();
  std::vector<uint32_t> branch(n);
  std::vector<double> total(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    const int32_t q = plant.parent[i];
    branch[i] = q >= 0 && plant.order[size_t(q)] == plant.order[i] ? branch[size_t(q)] : uint32_t(i);
    total[branch[i]] += double(plant.length[i]);
  }
  std::vector<float> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = float(total[branch[i]]);
  return out;
}

PivotPainterTextures pivotPainterTextures(const plant::PlantModel& plant, const std::vector<WindVertexNode>& wind,
                                          const std::string& source) {
  const size_t n = plant.nodeCount();
  if (wind.size() != n)
    throw Error(source, fmt::format("plant \"{}\"", plant.name),
                fmt::format("cannot make Pivot Painter textures: the wind table has {} records for {} nodes "
                            "(internal error)", wind.size(), n));
  PivotPainterTextures t;
  t.grid = pivotPainterGrid(n, source, plant.name);
  if (n == 0) return t;
  const size_t pixels = size_t(t.grid.width) * t.grid.height;
  // Pixels past the last element: pivot 0, their own index as parent (roots), axis 0, extent 0.
  t.pivot.resize(pixels);
  t.xaxis.assign(pixels, {128, 128, 128, 0});
  for (size_t i = 0; i < pixels; ++i) {
    const uint16_t zero = halfBits(0.0f);
    t.pivot[i] = {zero, zero, zero, packPivotPainterIndex(uint32_t(std::min(i, size_t(kPivotPainterMaxElements - 1))))};
  }
  const std::vector<float> lengths = branchLengths(plant);
  for (size_t i = 0; i < n; ++i) {
    const Vec3 p = unrealPoint(wind[i].pivot);
    const int32_t q = plant.parent[i];
    t.pivot[i] = {halfBits(p.x()), halfBits(p.y()), halfBits(p.z()), packPivotPainterIndex(q >= 0 ? uint32_t(q) : uint32_t(i))};
    const float length = wind[i].lever.norm();
    const Vec3 d = length > 0.0f ? unrealDirection(wind[i].lever / length) : Vec3::Zero();
    t.xaxis[i] = {unitToByte(0.5f * (d.x() + 1.0f)), unitToByte(0.5f * (d.y() + 1.0f)), unitToByte(0.5f * (d.z() + 1.0f)),
                  encodePivotPainterExtent(lengths[i])};
  }
  return t;
}

std::filesystem::path pivotPainterPivotPath(const std::filesystem::path& dir, const std::string& stem,
                                            const std::string& name) {
  return dir / (stem + "-" + safeFileName(name) + "-pp-pivot.exr");
}

std::filesystem::path pivotPainterXAxisPath(const std::filesystem::path& dir, const std::string& stem,
                                            const std::string& name) {
  return dir / (stem + "-" + safeFileName(name) + "-pp-xaxis.png");
}

void writePivotPainterTextures(const PivotPainterTextures& textures, const std::filesystem::path& pivotExr,
                               const std::filesystem::path& xaxisPng) {
  const PivotPainterGrid& g = textures.grid;
  const size_t pixels = size_t(g.width) * g.height;
  if (g.width == 0 || textures.pivot.size() != pixels || textures.xaxis.size() != pixels)
    throw Error(pivotExr.string(), "", "cannot write Pivot Painter textures: no elements or sizes that disagree");
  checkOutputPath(pivotExr);
  checkOutputPath(xaxisPng);
  MemoryStream exr;
  try {
    std::vector<Imf::Rgba> rgba(pixels);
    for (size_t i = 0; i < pixels; ++i) {
      rgba[i].r.setBits(textures.pivot[i][0]);
      rgba[i].g.setBits(textures.pivot[i][1]);
      rgba[i].b.setBits(textures.pivot[i][2]);
      rgba[i].a.setBits(textures.pivot[i][3]);
    }
    Imf::Header header(int(g.width), int(g.height));
    header.compression() = Imf::ZIP_COMPRESSION;
    // One thread: the bytes do not depend on the machine.
    Imf::RgbaOutputFile file(exr, header, Imf::WRITE_RGBA, 0);
    file.setFrameBuffer(rgba.data(), 1, g.width);
    file.writePixels(int(g.height));
  } catch (const std::exception& e) {
    throw Error(pivotExr.string(), "", fmt::format("cannot write OpenEXR: {}", e.what()));
  }
  Image png;
  png.width = int(g.width);
  png.height = int(g.height);
  png.rgba.resize(pixels * 4);
  for (size_t i = 0; i < pixels; ++i) std::memcpy(&png.rgba[4 * i], textures.xaxis[i].data(), 4);
  writeFileAtomic(pivotExr, exr.bytes());
  writePng(png, xaxisPng);
}

}  // namespace tendril::io
