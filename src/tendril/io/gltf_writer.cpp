#include "tendril/io/gltf_writer.h"

#include "tendril/core/error.h"
#include "tendril/core/parallel.h"
#include "tendril/io/atomic_file.h"

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>
#include <sstream>

namespace tendril::io {
namespace {

constexpr int kArrayBuffer = TINYGLTF_TARGET_ARRAY_BUFFER;
constexpr int kElementArrayBuffer = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;

// Mesh arrays are written as they are in memory; GLB is little-endian.
static_assert(std::endian::native == std::endian::little, "the .glb writer assumes a little-endian host");

// The content of one buffer view; views are written in offset order.
struct CopyJob {
  enum class Kind { Bytes, FlipUv, Index16 };
  Kind kind = Kind::Bytes;
  const void* source = nullptr;
  size_t count = 0;   // bytes (Bytes), uvs (FlipUv) or indices (Index16)
  size_t offset = 0;  // in the buffer
};

size_t align4(size_t n) { return (n + 3) & ~size_t(3); }

// Converted views are written this many elements at a time.
constexpr size_t kBlock = size_t(1) << 15;
// Scratch bytes for one block of the largest converted element (a uv).
constexpr size_t kScratchBytes = kBlock * sizeof(Vec2);

// Writes one buffer view's bytes: straight from the mesh arrays, or converted a block at a
// time (glTF uvs, 16-bit indices) so that no copy of the whole binary chunk is ever made.
// `scratch` holds kScratchBytes: sized once, since resizing it between uvs and indices
// zero-filled it again for every part.
void writeJob(const CopyJob& job, AtomicFileWriter& out, std::vector<uint8_t>& scratch) {
  switch (job.kind) {
    case CopyJob::Kind::Bytes:
      out.write(job.source, job.count);
      return;
    case CopyJob::Kind::FlipUv: {
      const Vec2* uv = static_cast<const Vec2*>(job.source);
      for (size_t b = 0; b < job.count; b += kBlock) {
        size_t n = std::min(kBlock, job.count - b);
        float* f = reinterpret_cast<float*>(scratch.data());
        for (size_t i = 0; i < n; ++i) {
          f[2 * i] = uv[b + i].x();
          f[2 * i + 1] = 1.0f - uv[b + i].y();
        }
        out.write(scratch.data(), n * sizeof(Vec2));
      }
      return;
    }
    case CopyJob::Kind::Index16: {
      const uint32_t* idx = static_cast<const uint32_t*>(job.source);
      for (size_t b = 0; b < job.count; b += kBlock) {
        size_t n = std::min(kBlock, job.count - b);
        uint16_t* o = reinterpret_cast<uint16_t*>(scratch.data());
        for (size_t i = 0; i < n; ++i) o[i] = static_cast<uint16_t>(idx[b + i]);
        out.write(scratch.data(), n * sizeof(uint16_t));
      }
      return;
    }
  }
}

void writeU32(AtomicFileWriter& out, uint32_t v) {
  uint8_t b[4] = {uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16), uint8_t(v >> 24)};  // little-endian
  out.write(b, 4);
}

Bounds3 parallelBounds(const std::vector<Vec3>& points) {
  constexpr size_t kChunk = size_t(1) << 15;
  size_t chunks = (points.size() + kChunk - 1) / kChunk;
  std::vector<Bounds3> partial(chunks);
  parallelFor(0, chunks, [&](size_t c) {
    size_t end = std::min(points.size(), (c + 1) * kChunk);
    for (size_t i = c * kChunk; i < end; ++i) partial[c].extend(points[i]);
  }, 1);
  Bounds3 b;
  for (const Bounds3& p : partial) b.extend(p);  // min/max: exact in any order
  return b;
}

class GlbBuilder {
 public:
  explicit GlbBuilder(tinygltf::Model& gltf) : gltf_(gltf) {}

  // Reserves `bytes` in the binary chunk (4-byte aligned) and returns its buffer view.
  int view(size_t bytes, int target) {
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = size_;
    v.byteLength = bytes;
    v.target = target;
    size_ = align4(size_ + bytes);
    gltf_.bufferViews.push_back(v);
    return static_cast<int>(gltf_.bufferViews.size() - 1);
  }

  int accessor(int view, int componentType, int type, size_t count) {
    tinygltf::Accessor a;
    a.bufferView = view;
    a.byteOffset = 0;
    a.componentType = componentType;
    a.type = type;
    a.count = count;
    gltf_.accessors.push_back(a);
    return static_cast<int>(gltf_.accessors.size() - 1);
  }

  size_t size() const { return size_; }
  size_t offsetOf(int view) const { return gltf_.bufferViews[view].byteOffset; }

 private:
  tinygltf::Model& gltf_;
  size_t size_ = 0;
};

tinygltf::Primitive addPart(const ExportPart& part, GlbBuilder& b, tinygltf::Model& gltf, std::vector<CopyJob>& jobs) {
  const TriangleMesh& m = *part.mesh;
  size_t n = m.positions.size();
  tinygltf::Primitive prim;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  prim.material = part.material;

  int pv = b.view(n * sizeof(Vec3), kArrayBuffer);
  int pa = b.accessor(pv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n);
  Bounds3 bounds = parallelBounds(m.positions);
  gltf.accessors[pa].minValues = {bounds.min.x(), bounds.min.y(), bounds.min.z()};
  gltf.accessors[pa].maxValues = {bounds.max.x(), bounds.max.y(), bounds.max.z()};
  jobs.push_back({CopyJob::Kind::Bytes, m.positions.data(), n * sizeof(Vec3), b.offsetOf(pv)});
  prim.attributes["POSITION"] = pa;

  if (!m.normals.empty()) {
    int nv = b.view(n * sizeof(Vec3), kArrayBuffer);
    prim.attributes["NORMAL"] = b.accessor(nv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n);
    jobs.push_back({CopyJob::Kind::Bytes, m.normals.data(), n * sizeof(Vec3), b.offsetOf(nv)});
  }
  if (!m.uvs.empty()) {
    int tv = b.view(n * sizeof(Vec2), kArrayBuffer);
    prim.attributes["TEXCOORD_0"] = b.accessor(tv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, n);
    jobs.push_back({CopyJob::Kind::FlipUv, m.uvs.data(), n, b.offsetOf(tv)});
  }
  // uint16 indices when they fit; 65535 itself is the primitive-restart value and not allowed.
  bool small = n < 65536;
  size_t ni = m.indices.size();
  int iv = b.view(ni * (small ? 2 : 4), kElementArrayBuffer);
  prim.indices = b.accessor(iv, small ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT : TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                            TINYGLTF_TYPE_SCALAR, ni);
  if (small)
    jobs.push_back({CopyJob::Kind::Index16, m.indices.data(), ni, b.offsetOf(iv)});
  else
    jobs.push_back({CopyJob::Kind::Bytes, m.indices.data(), ni * sizeof(uint32_t), b.offsetOf(iv)});
  return prim;
}

std::vector<double> toDoubles(const Vec4& v) { return {v.x(), v.y(), v.z(), v.w()}; }

}  // namespace

void appendMaterialsAndTextures(const ExportModel& model, tinygltf::Model& gltf) {
  for (const ExportMaterial& m : model.materials) {
    tinygltf::Material g;
    g.name = m.name;
    g.pbrMetallicRoughness.baseColorFactor = toDoubles(m.baseColor);
    g.pbrMetallicRoughness.metallicFactor = m.metallic;
    g.pbrMetallicRoughness.roughnessFactor = m.roughness;
    g.pbrMetallicRoughness.baseColorTexture.index = m.texture;
    if (m.alphaMask) {
      g.alphaMode = "MASK";
      g.alphaCutoff = 0.5;
    }
    g.doubleSided = m.doubleSided;
    gltf.materials.push_back(std::move(g));
  }

  // Samplers only for the wrap modes in use.
  int samplerOf[2] = {-1, -1};
  for (const ExportTexture& t : model.textures) {
    int& s = samplerOf[t.repeat ? 1 : 0];
    if (s < 0) {
      tinygltf::Sampler sampler;
      sampler.name = t.repeat ? "repeat" : "clamp";
      sampler.magFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
      sampler.minFilter = TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR;
      sampler.wrapS = sampler.wrapT = t.repeat ? TINYGLTF_TEXTURE_WRAP_REPEAT : TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
      gltf.samplers.push_back(sampler);
      s = static_cast<int>(gltf.samplers.size() - 1);
    }
    tinygltf::Texture texture;
    texture.sampler = s;
    texture.source = t.image;
    gltf.textures.push_back(texture);
  }
}

void writeGlb(const ExportModel& model, const std::filesystem::path& path) {
  tinygltf::Model gltf;
  gltf.asset.version = "2.0";
  gltf.asset.generator = "Tendril " TENDRIL_VERSION;
  GlbBuilder builder(gltf);
  std::vector<CopyJob> jobs;

  tinygltf::Scene scene;
  scene.name = "Tendril";  // also keeps an empty scene an object rather than null
  for (const ExportObject& object : model.objects) {
    tinygltf::Node node;
    node.name = object.name;
    if (!object.parts.empty()) {
      tinygltf::Mesh mesh;
      mesh.name = object.name;
      for (const ExportPart& part : object.parts) mesh.primitives.push_back(addPart(part, builder, gltf, jobs));
      gltf.meshes.push_back(std::move(mesh));
      node.mesh = static_cast<int>(gltf.meshes.size() - 1);
    }
    gltf.nodes.push_back(std::move(node));
    scene.nodes.push_back(static_cast<int>(gltf.nodes.size() - 1));
  }
  gltf.scenes.push_back(std::move(scene));
  gltf.defaultScene = 0;

  appendMaterialsAndTextures(model, gltf);
  for (const ExportImage& img : model.images) {
    tinygltf::Image image;
    image.name = std::filesystem::path(img.spec).filename().string();
    image.mimeType = img.image.mimeType;
    image.bufferView = builder.view(img.image.bytes.size(), 0);
    jobs.push_back({CopyJob::Kind::Bytes, img.image.bytes.data(), img.image.bytes.size(),
                    builder.offsetOf(image.bufferView)});
    gltf.images.push_back(std::move(image));
  }

  // tinygltf serialises the glTF JSON; the one buffer (the GLB's BIN chunk) is added here
  // and the container written directly, streaming every view from the meshes, so that the
  // geometry is never copied into a second in-memory buffer (hundreds of MB for a large plant).
  std::ostringstream text;
  tinygltf::TinyGLTF tiny;
  if (!tiny.WriteGltfSceneToStream(&gltf, text, false, false))
    throw Error(path.string(), "", "cannot write .glb: tinygltf could not serialise the scene");
  nlohmann::json json = nlohmann::json::parse(text.str());
  size_t binBytes = builder.size();
  if (binBytes > 0) json["buffers"] = nlohmann::json::array({{{"byteLength", binBytes}}});
  std::string content = json.dump();
  content.resize(align4(content.size()), ' ');  // the JSON chunk is padded with spaces
  uint64_t total = 12 + 8 + content.size() + (binBytes > 0 ? 8 + binBytes : 0);
  if (total > std::numeric_limits<uint32_t>::max())
    throw Error(path.string(), "", "cannot write .glb: more than the format's 4 GiB; lower radialSegments or "
                                   "subdivisions");

  AtomicFileWriter out(path);
  out.write("glTF", 4);
  writeU32(out, 2);
  writeU32(out, static_cast<uint32_t>(total));
  writeU32(out, static_cast<uint32_t>(content.size()));
  out.write("JSON", 4);
  out.write(content);
  if (binBytes > 0) {
    writeU32(out, static_cast<uint32_t>(binBytes));
    out.write("BIN\0", 4);
    std::vector<uint8_t> scratch(kScratchBytes);
    static const uint8_t kZeros[4] = {0, 0, 0, 0};
    uint64_t at = 0;
    for (const CopyJob& job : jobs) {  // in offset order
      out.write(kZeros, job.offset - at);
      writeJob(job, out, scratch);
      at = job.offset + (job.kind == CopyJob::Kind::FlipUv    ? job.count * sizeof(Vec2)
                         : job.kind == CopyJob::Kind::Index16 ? job.count * sizeof(uint16_t)
                                                              : job.count);
    }
    out.write(kZeros, binBytes - at);
  }
  out.commit();
}

void writeGlb(const ExportScene& scene, const std::filesystem::path& path, const ExportOptions& options) {
  checkOutputPath(path);
  writeGlb(buildExportModel(scene, options), path);
}

}  // namespace tendril::io
