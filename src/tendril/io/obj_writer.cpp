#include "tendril/io/obj_writer.h"

#include "tendril/core/error.h"
#include "tendril/core/parallel.h"
#include "tendril/io/atomic_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstring>

namespace tendril::io {
namespace {

// OBJ and MTL names end at whitespace.
std::string safeName(const std::string& name) {
  std::string s = name.empty() ? std::string("unnamed") : name;
  for (char& c : s)
    if (std::isspace(static_cast<unsigned char>(c)) || c == '#') c = '_';
  return s;
}

// Builds one text line in a fixed buffer (numbers by std::to_chars; floats in their shortest
// exact form) and appends it to a string in one go.
class LineWriter {
 public:
  explicit LineWriter(std::string& out) : out_(out) {}
  void text(std::string_view s) {
    std::memcpy(end_, s.data(), s.size());
    end_ += s.size();
  }
  void number(float v) { end_ = std::to_chars(end_, line_ + kMax, v == 0.0f ? 0.0f : v).ptr; }  // no "-0"
  void integer(uint64_t v) { end_ = std::to_chars(end_, line_ + kMax, v).ptr; }
  void vec(std::string_view tag, const float* v, int n) {
    text(tag);
    for (int i = 0; i < n; ++i) {
      *end_++ = ' ';
      number(v[i]);
    }
    endLine();
  }
  void endLine() {
    *end_++ = '\n';
    out_.append(line_, end_);
    end_ = line_;
  }

 private:
  static constexpr size_t kMax = 192;  // "f" + 3 × (3 × 20 digits + 2 slashes + space)
  std::string& out_;
  char line_[kMax];
  char* end_ = line_;
};

// Formats items [0, count) with `format(i, LineWriter&)` in parallel chunks and writes them
// in order, a bounded batch of chunks at a time.
template <class F>
void writeFormatted(AtomicFileWriter& file, size_t count, F&& format) {
  constexpr size_t kChunk = size_t(1) << 14;
  constexpr size_t kBatch = 64;
  size_t chunks = (count + kChunk - 1) / kChunk;
  std::vector<std::string> text(std::min(chunks, kBatch));
  for (size_t first = 0; first < chunks; first += kBatch) {
    size_t n = std::min(kBatch, chunks - first);
    parallelFor(0, n, [&](size_t k) {
      std::string& s = text[k];
      s.clear();
      s.reserve(kChunk * 48);
      LineWriter w(s);
      size_t begin = (first + k) * kChunk, end = std::min(count, begin + kChunk);
      for (size_t i = begin; i < end; ++i) format(i, w);
    }, 1);
    for (size_t k = 0; k < n; ++k) file.write(text[k]);
  }
}

std::string extensionFor(const std::string& mime) { return mime == "image/jpeg" ? ".jpg" : ".png"; }

// Level `level` of every object that has it, in one .obj using the materials of `mtlName`.
// OBJ indices are 1-based and global over the file.
void writeObjGeometry(const ExportModel& model, size_t level, const std::string& mtlName,
                      const std::filesystem::path& path) {
  AtomicFileWriter obj(path);
  obj.write(fmt::format("# Tendril {}\nmtllib {}\n", TENDRIL_VERSION, mtlName));
  uint64_t base = 1;
  for (const ExportObject& object : model.objects) {
    if (level >= object.levels()) continue;
    const std::string name = safeName(levelName(object, level));
    obj.write(fmt::format("o {}\n", name));
    for (const ExportPart& part : object.partsOf(level)) {
      const TriangleMesh& m = *part.mesh;
      obj.write(fmt::format("g {}_{}\nusemtl {}\n", name, safeName(part.name),
                            safeName(model.materials[part.material].name)));
      writeFormatted(obj, m.positions.size(), [&](size_t i, LineWriter& w) { w.vec("v", m.positions[i].data(), 3); });
      writeFormatted(obj, m.uvs.size(), [&](size_t i, LineWriter& w) { w.vec("vt", m.uvs[i].data(), 2); });
      writeFormatted(obj, m.normals.size(), [&](size_t i, LineWriter& w) { w.vec("vn", m.normals[i].data(), 3); });
      bool uvs = !m.uvs.empty();
      writeFormatted(obj, m.triangleCount(), [&](size_t t, LineWriter& w) {
        w.text("f");
        for (int k = 0; k < 3; ++k) {
          uint64_t v = base + m.indices[3 * t + k];
          w.text(" ");
          w.integer(v);
          w.text(uvs ? "/" : "//");
          if (uvs) {
            w.integer(v);
            w.text("/");
          }
          w.integer(v);
        }
        w.endLine();
      });
      base += m.positions.size();
    }
  }
  obj.commit();
}

}  // namespace

std::filesystem::path objLodPath(const std::filesystem::path& path, size_t level) {
  return path.parent_path() / fmt::format("{}_LOD{}{}", path.stem().string(), level, path.extension().string());
}

void writeObj(const ExportModel& model, const std::filesystem::path& path) {
  std::filesystem::path dir = path.parent_path();
  std::string stem = path.stem().string();
  checkOutputPath(path);

  // File names of the images, by the role of the first material using them.
  std::vector<std::string> imageFile(model.images.size());
  int barkCount = 0, leafCount = 0, otherCount = 0, impostorCount = 0;
  for (const ExportMaterial& m : model.materials) {
    if (m.texture < 0) continue;
    int image = model.textures[m.texture].image;
    if (!imageFile[image].empty()) continue;
    std::string role;
    switch (m.kind) {
      case ExportMaterial::Kind::Bark:
        role = barkCount++ == 0 ? std::string("bark") : fmt::format("bark{}", barkCount - 1);
        break;
      case ExportMaterial::Kind::Leaf:
        role = fmt::format("leaf{}", leafCount++);
        break;
      case ExportMaterial::Kind::Plain:
        role = fmt::format("tex{}", otherCount++);
        break;
      case ExportMaterial::Kind::Impostor:
        role = fmt::format("impostor{}", impostorCount++);
        break;
    }
    imageFile[image] = safeName(stem) + "_" + role + extensionFor(model.images[image].image.mimeType);
  }
  // Impostors' normal maps: <stem>_impostor<k>_normal.png.
  for (const ExportMaterial& m : model.materials) {
    if (m.normalTexture < 0 || m.texture < 0) continue;
    const int image = model.textures[m.normalTexture].image;
    if (!imageFile[image].empty()) continue;
    const std::string& colour = imageFile[model.textures[m.texture].image];
    imageFile[image] = colour.substr(0, colour.rfind('.')) + "_normal.png";
  }
  // Bark roughness maps (output.maps): <stem>_bark_roughness.png.
  for (const ExportMaterial& m : model.materials) {
    if (m.roughnessTexture < 0 || m.texture < 0) continue;
    const int image = model.textures[m.roughnessTexture].image;
    if (!imageFile[image].empty()) continue;
    const std::string& colour = imageFile[model.textures[m.texture].image];
    imageFile[image] = colour.substr(0, colour.rfind('.')) + "_roughness.png";
  }
  for (size_t i = 0; i < model.images.size(); ++i)
    if (!imageFile[i].empty()) writeFileAtomic(dir / imageFile[i], model.images[i].image.bytes);

  // Materials.
  std::string mtlName = stem + ".mtl";
  std::string mtl = fmt::format("# Tendril {}\n", TENDRIL_VERSION);
  for (const ExportMaterial& m : model.materials) {
    mtl += fmt::format("\nnewmtl {}\n", safeName(m.name));
    mtl += fmt::format("Kd {} {} {}\n", m.baseColor.x(), m.baseColor.y(), m.baseColor.z());
    mtl += "Ka 0 0 0\nKs 0.04 0.04 0.04\n";
    // Phong exponent from roughness (Blinn-Phong ~ 2 / alpha^2 - 2 with alpha = roughness²),
    // and the PBR extension's Pr for importers that read it.
    float alpha = std::max(m.roughness * m.roughness, 0.03f);
    mtl += fmt::format("Ns {}\nPr {}\nd 1\nillum 2\n", std::min(1000.0f, 2.0f / (alpha * alpha) - 2.0f), m.roughness);
    if (m.texture >= 0) {
      const std::string& file = imageFile[model.textures[m.texture].image];
      mtl += fmt::format("map_Kd {}\n", file);
      if (m.alphaMask) mtl += fmt::format("map_d {}\n", file);
    }
    // A tangent-space normal map (the impostor's; glTF's convention, docs/export.md).
    if (m.normalTexture >= 0) mtl += fmt::format("norm {}\n", imageFile[model.textures[m.normalTexture].image]);
    // Roughness in G (glTF's layout); map_Pr readers take one channel: -imfchan g.
    if (m.roughnessTexture >= 0)
      mtl += fmt::format("map_Pr -imfchan g {}\n", imageFile[model.textures[m.roughnessTexture].image]);
  }
  writeFileAtomic(dir / mtlName, mtl);

  // Geometry: LOD0 (every object) in <stem>.obj, each lower level of detail of the plants that
  // have one in <stem>_LOD<k>.obj.
  size_t levels = 1;
  for (const ExportObject& object : model.objects) levels = std::max(levels, object.levels());
  for (size_t level = 0; level < levels; ++level)
    writeObjGeometry(model, level, mtlName, level == 0 ? path : objLodPath(path, level));
}

void writeObj(const ExportScene& scene, const std::filesystem::path& path, const ExportOptions& options) {
  checkOutputPath(path);
  writeObj(buildExportModel(scene, options), path);
}

}  // namespace tendril::io
