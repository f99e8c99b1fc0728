#include "tendril/io/gltf_writer.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/parallel.h"
#include "tendril/io/atomic_file.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <sstream>

namespace tendril::io {
namespace {

constexpr int kArrayBuffer = TINYGLTF_TARGET_ARRAY_BUFFER;
constexpr int kElementArrayBuffer = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;

// Mesh arrays are written as they are in memory; GLB is little-endian.
static_assert(std::endian::native == std::endian::little, "the .glb writer assumes a little-endian host");

// The content of one buffer view; views are written in offset order.
struct CopyJob {
  enum class Kind { Bytes, FlipUv, Index16, NodeId, WindColor, WindPivot, WindAxis, PivotUv, Zeros };
  Kind kind = Kind::Bytes;
  const void* source = nullptr;
  // bytes (Bytes, Zeros), uvs (FlipUv), indices (Index16) or node ids (NodeId, Wind*, PivotUv)
  size_t count = 0;
  size_t offset = 0;  // in the buffer
  // Wind*: the plant's engine wind table (by node id) and whether the part is leaves.
  const WindVertexNode* wind = nullptr;
  size_t windNodes = 0;
  bool leaf = false;
  // PivotUv: the plant's Pivot Painter textures (per node id its pixel's UV; io/pivot_painter.h).
  PivotPainterGrid grid = {};
};

// Bytes per vertex of a wind view: COLOR_0 (float RGBA), _WIND_PIVOT and _WIND_AXIS (float VEC3).
size_t windBytes(CopyJob::Kind kind) { return kind == CopyJob::Kind::WindColor ? 4 * sizeof(float) : sizeof(Vec3); }

// The bytes a copy job writes.
size_t jobBytes(const CopyJob& job) {
  switch (job.kind) {
    case CopyJob::Kind::FlipUv:
    case CopyJob::Kind::PivotUv: return job.count * sizeof(Vec2);
    case CopyJob::Kind::Index16: return job.count * sizeof(uint16_t);
    case CopyJob::Kind::NodeId: return job.count * sizeof(float);
    case CopyJob::Kind::WindColor:
    case CopyJob::Kind::WindPivot:
    case CopyJob::Kind::WindAxis: return job.count * windBytes(job.kind);
    case CopyJob::Kind::Bytes:
    case CopyJob::Kind::Zeros: return job.count;
  }
  return job.count;
}

// Node ids are written as floats (glTF forbids unsigned int for application-specific
// attributes), exact integers below 2^24.
constexpr uint32_t kMaxNodeId = (uint32_t(1) << 24) - 1;

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
    case CopyJob::Kind::NodeId: {
      const uint32_t* id = static_cast<const uint32_t*>(job.source);
      for (size_t b = 0; b < job.count; b += kBlock) {
        size_t n = std::min(kBlock, job.count - b);
        float* f = reinterpret_cast<float*>(scratch.data());
        for (size_t i = 0; i < n; ++i) {
          if (id[b + i] > kMaxNodeId)
            throw Error(out.path().string(), "", fmt::format("cannot write .glb: node id {} does not fit _NODE_ID "
                                                             "(a float, exact up to {})", id[b + i], kMaxNodeId));
          f[i] = static_cast<float>(id[b + i]);
        }
        out.write(scratch.data(), n * sizeof(float));
      }
      return;
    }
    case CopyJob::Kind::Zeros: {
      std::fill(scratch.begin(), scratch.end(), uint8_t(0));
      for (size_t b = 0; b < job.count; b += kScratchBytes) out.write(scratch.data(), std::min(kScratchBytes, job.count - b));
      return;
    }
    case CopyJob::Kind::PivotUv: {
      // Per vertex its element's (its node's) pixel centre (io/pivot_painter.h).
      const uint32_t* id = static_cast<const uint32_t*>(job.source);
      for (size_t b = 0; b < job.count; b += kBlock) {
        size_t n = std::min(kBlock, job.count - b);
        float* f = reinterpret_cast<float*>(scratch.data());
        for (size_t i = 0; i < n; ++i) {
          if (id[b + i] >= job.grid.elements)
            throw Error(out.path().string(), "", fmt::format("cannot write .glb: node id {} has no Pivot Painter "
                                                             "element (the plant has {} nodes)", id[b + i], job.grid.elements));
          const Vec2 uv = pivotPainterUv(id[b + i], job.grid);
          f[2 * i] = uv.x(), f[2 * i + 1] = uv.y();
        }
        out.write(scratch.data(), n * sizeof(Vec2));
      }
      return;
    }
    case CopyJob::Kind::WindColor:
    case CopyJob::Kind::WindPivot:
    case CopyJob::Kind::WindAxis: {
      // Per vertex its node's record (docs/engine-wind.md); a block of at most kScratchBytes.
      const uint32_t* id = static_cast<const uint32_t*>(job.source);
      const size_t bytes = windBytes(job.kind), block = kScratchBytes / bytes;
      for (size_t b = 0; b < job.count; b += block) {
        size_t n = std::min(block, job.count - b);
        float* f = reinterpret_cast<float*>(scratch.data());
        for (size_t i = 0; i < n; ++i) {
          if (id[b + i] >= job.windNodes)
            throw Error(out.path().string(), "", fmt::format("cannot write .glb: node id {} has no wind data (the "
                                                             "plant has {} nodes)", id[b + i], job.windNodes));
          const WindVertexNode& w = job.wind[id[b + i]];
          if (job.kind == CopyJob::Kind::WindColor) {
            f[4 * i] = w.level, f[4 * i + 1] = w.phase, f[4 * i + 2] = w.period, f[4 * i + 3] = job.leaf ? 1.0f : 0.0f;
          } else {
            const Vec3& v = job.kind == CopyJob::Kind::WindPivot ? w.pivot : w.lever;
            f[3 * i] = v.x(), f[3 * i + 1] = v.y(), f[3 * i + 2] = v.z();
          }
        }
        out.write(scratch.data(), n * bytes);
      }
      return;
    }
  }
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

// What the JSON says of a part's arrays.
struct PartGeometry {
  size_t vertices = 0, indices = 0;
  bool normals = false, uvs = false;
  Bounds3 bounds;
  bool nodeIds = false;
  bool wind = false;  // engine wind data: COLOR_0, _WIND_PIVOT, _WIND_AXIS
  bool pivot = false;  // Pivot Painter UVs: TEXCOORD_1 (and a TEXCOORD_0 of zeros where the part has no uvs)
};

// `wind`: the part's plant has a wind table; `pivot`: Pivot Painter textures (each written
// where the part has node ids).
PartGeometry geometryOf(const TriangleMesh& m, bool wind = false, bool pivot = false) {
  return {m.positions.size(), m.indices.size(), !m.normals.empty(), !m.uvs.empty(), parallelBounds(m.positions),
          !m.nodeIds.empty(), wind && !m.nodeIds.empty(), pivot && !m.nodeIds.empty()};
}

// A plant's wind table, or none.
const std::vector<WindVertexNode>* windTableOf(const WindTables* tables, size_t object) {
  return tables && object < tables->size() && !(*tables)[object].empty() ? &(*tables)[object] : nullptr;
}

// A plant's Pivot Painter texture grid, or none.
const PivotPainterGrid* pivotGridOf(const PivotPainterGrids* grids, size_t object) {
  return grids && object < grids->size() && (*grids)[object].width > 0 ? &(*grids)[object] : nullptr;
}

// uint16 indices when they fit; 65535 itself is the primitive-restart value and not allowed.
bool smallIndices(size_t vertices) { return vertices < 65536; }

// The part's views and accessors, in the order its bytes are written: positions, normals,
// uvs, node ids, wind data (COLOR_0, _WIND_PIVOT, _WIND_AXIS), Pivot Painter UVs (TEXCOORD_0
// of zeros where the part has no uvs, TEXCOORD_1), indices. With `mesh`, the copy jobs that
// write them (the wind data from `wind`, the plant's table; the UVs from `pivot`, its grid).
tinygltf::Primitive addPart(const ExportPart& part, const PartGeometry& g, GlbBuilder& b, tinygltf::Model& gltf,
                            const TriangleMesh* mesh, std::vector<CopyJob>* jobs,
                            const std::vector<WindVertexNode>* wind = nullptr, const PivotPainterGrid* pivot = nullptr) {
  const size_t n = g.vertices;
  tinygltf::Primitive prim;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  prim.material = part.material;

  int pv = b.view(n * sizeof(Vec3), kArrayBuffer);
  int pa = b.accessor(pv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n);
  gltf.accessors[pa].minValues = {g.bounds.min.x(), g.bounds.min.y(), g.bounds.min.z()};
  gltf.accessors[pa].maxValues = {g.bounds.max.x(), g.bounds.max.y(), g.bounds.max.z()};
  if (mesh) jobs->push_back({CopyJob::Kind::Bytes, mesh->positions.data(), n * sizeof(Vec3), b.offsetOf(pv)});
  prim.attributes["POSITION"] = pa;

  if (g.normals) {
    int nv = b.view(n * sizeof(Vec3), kArrayBuffer);
    prim.attributes["NORMAL"] = b.accessor(nv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n);
    if (mesh) jobs->push_back({CopyJob::Kind::Bytes, mesh->normals.data(), n * sizeof(Vec3), b.offsetOf(nv)});
  }
  if (part.tangents && part.tangents->size() == n) {  // impostor quads (io/impostor.h)
    int tv = b.view(n * sizeof(Vec4), kArrayBuffer);
    prim.attributes["TANGENT"] = b.accessor(tv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, n);
    if (mesh) jobs->push_back({CopyJob::Kind::Bytes, part.tangents->data(), n * sizeof(Vec4), b.offsetOf(tv)});
  }
  if (g.uvs) {
    int tv = b.view(n * sizeof(Vec2), kArrayBuffer);
    prim.attributes["TEXCOORD_0"] = b.accessor(tv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, n);
    if (mesh) jobs->push_back({CopyJob::Kind::FlipUv, mesh->uvs.data(), n, b.offsetOf(tv)});
  }
  if (g.nodeIds) {
    int iv = b.view(n * sizeof(float), kArrayBuffer);
    prim.attributes["_NODE_ID"] = b.accessor(iv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, n);
    if (mesh) jobs->push_back({CopyJob::Kind::NodeId, mesh->nodeIds.data(), n, b.offsetOf(iv)});
  }
  if (g.wind) {
    const std::pair<const char*, CopyJob::Kind> views[3] = {
        {"COLOR_0", CopyJob::Kind::WindColor}, {"_WIND_PIVOT", CopyJob::Kind::WindPivot}, {"_WIND_AXIS", CopyJob::Kind::WindAxis}};
    for (const auto& [name, kind] : views) {
      int wv = b.view(n * windBytes(kind), kArrayBuffer);
      prim.attributes[name] = b.accessor(wv, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                         kind == CopyJob::Kind::WindColor ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3, n);
      if (mesh) {
        if (!wind) throw Error("", "", "cannot write .glb: a part with wind data has no wind table (internal error)");
        jobs->push_back({kind, mesh->nodeIds.data(), n, b.offsetOf(wv), wind->data(), wind->size(),
                         part.source == PartSource::Leaves});
      }
    }
  }
  if (g.pivot) {
    if (!g.uvs) {  // TEXCOORD_1 needs a TEXCOORD_0 (glTF's sets are numbered from 0 without gaps)
      int zv = b.view(n * sizeof(Vec2), kArrayBuffer);
      prim.attributes["TEXCOORD_0"] = b.accessor(zv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, n);
      if (mesh) jobs->push_back({CopyJob::Kind::Zeros, nullptr, n * sizeof(Vec2), b.offsetOf(zv)});
    }
    int pv = b.view(n * sizeof(Vec2), kArrayBuffer);
    prim.attributes["TEXCOORD_1"] = b.accessor(pv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, n);
    if (mesh) {
      if (!pivot) throw Error("", "", "cannot write .glb: a part with Pivot Painter UVs has no grid (internal error)");
      CopyJob job{CopyJob::Kind::PivotUv, mesh->nodeIds.data(), n, b.offsetOf(pv)};
      job.grid = *pivot;
      jobs->push_back(job);
    }
  }
  const bool small = smallIndices(n);
  const size_t ni = g.indices;
  int iv = b.view(ni * (small ? 2 : 4), kElementArrayBuffer);
  prim.indices = b.accessor(iv, small ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT : TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                            TINYGLTF_TYPE_SCALAR, ni);
  if (mesh) {
    if (small)
      jobs->push_back({CopyJob::Kind::Index16, mesh->indices.data(), ni, b.offsetOf(iv)});
    else
      jobs->push_back({CopyJob::Kind::Bytes, mesh->indices.data(), ni * sizeof(uint32_t), b.offsetOf(iv)});
  }
  return prim;
}

// What the JSON says of an instanced shape (io/instancing.h): its mesh's arrays and its copies.
struct InstanceGeometry {
  PartGeometry shape;
  size_t instances = 0;
  bool nodeIds = false;
  bool wind = false;  // per copy: _WIND_COLOR, _WIND_PIVOT, _WIND_AXIS
};

InstanceGeometry instanceGeometryOf(const InstancedShape& s, bool wind) {
  return {geometryOf(s.shape), s.instances(), !s.nodeIds.empty(), wind && !s.nodeIds.empty()};
}

// The node of an instanced shape (named `name`): its mesh of one primitive, laid out as addPart
// lays out a part, then its instance attributes in the order their bytes are written:
// TRANSLATION, ROTATION, SCALE, _NODE_ID, and with wind data _WIND_COLOR (what COLOR_0 holds
// for a baked vertex), _WIND_PIVOT, _WIND_AXIS. With `shape`, the copy jobs that write them.
tinygltf::Node addInstanced(const ExportInstanced& inst, const std::string& name, const InstanceGeometry& g,
                            GlbBuilder& b, tinygltf::Model& gltf, const InstancedShape* shape,
                            std::vector<CopyJob>* jobs, const std::vector<WindVertexNode>* wind) {
  const ExportPart part{inst.name, nullptr, inst.material, PartSource::Primitive, inst.group};
  tinygltf::Mesh mesh;
  mesh.name = name;
  mesh.primitives.push_back(addPart(part, g.shape, b, gltf, shape ? &shape->shape : nullptr, jobs));
  gltf.meshes.push_back(std::move(mesh));
  tinygltf::Node node;
  node.name = name;
  node.mesh = static_cast<int>(gltf.meshes.size() - 1);
  const size_t n = g.instances;
  tinygltf::Value::Object attributes;
  auto add = [&](const char* semantic, int type, size_t bytes, CopyJob job) {
    const int v = b.view(n * bytes, 0);
    attributes[semantic] = tinygltf::Value(b.accessor(v, TINYGLTF_COMPONENT_TYPE_FLOAT, type, n));
    if (shape) {
      job.offset = b.offsetOf(v);
      jobs->push_back(job);
    }
  };
  const bool data = shape != nullptr;
  add("TRANSLATION", TINYGLTF_TYPE_VEC3, sizeof(Vec3),
      {CopyJob::Kind::Bytes, data ? shape->translation.data() : nullptr, n * sizeof(Vec3)});
  add("ROTATION", TINYGLTF_TYPE_VEC4, sizeof(Vec4),
      {CopyJob::Kind::Bytes, data ? shape->rotation.data() : nullptr, n * sizeof(Vec4)});
  add("SCALE", TINYGLTF_TYPE_VEC3, sizeof(Vec3), {CopyJob::Kind::Bytes, data ? shape->scale.data() : nullptr, n * sizeof(Vec3)});
  if (g.nodeIds)
    add("_NODE_ID", TINYGLTF_TYPE_SCALAR, sizeof(float),
        {CopyJob::Kind::NodeId, data ? shape->nodeIds.data() : nullptr, n});
  if (g.wind) {
    if (data && !wind) throw Error("", "", "cannot write .glb: instances with wind data have no wind table (internal error)");
    const std::pair<const char*, CopyJob::Kind> views[3] = {{"_WIND_COLOR", CopyJob::Kind::WindColor},
                                                            {"_WIND_PIVOT", CopyJob::Kind::WindPivot},
                                                            {"_WIND_AXIS", CopyJob::Kind::WindAxis}};
    for (const auto& [semantic, kind] : views)
      add(semantic, kind == CopyJob::Kind::WindColor ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3, windBytes(kind),
          {kind, data ? shape->nodeIds.data() : nullptr, n, 0, data ? wind->data() : nullptr, data ? wind->size() : 0,
           false});
  }
  tinygltf::Value::Object ext;
  ext["attributes"] = tinygltf::Value(std::move(attributes));
  node.extensions["EXT_mesh_gpu_instancing"] = tinygltf::Value(std::move(ext));
  return node;
}

// The mesh the .glb bakes of a part (io/instancing.h: a primitive group's non-instanced rest).
const TriangleMesh* bakedMesh(const ExportPart& part) { return part.instancing == 1 ? part.rest : part.mesh; }

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
    if (m.normalTexture >= 0) g.normalTexture.index = m.normalTexture;  // impostors; bark and leaf maps
    if (m.roughnessTexture >= 0) g.pbrMetallicRoughness.metallicRoughnessTexture.index = m.roughnessTexture;
    if (m.alphaMask) {
      g.alphaMode = "MASK";
      g.alphaCutoff = 0.5;
    }
    g.doubleSided = m.doubleSided;
    if (m.diffuseTransmission > 0.0f) {
      // Translucent leaves: light from behind shows through, in the texture's colour.
      tinygltf::Value::Object transmission, colour;
      transmission["diffuseTransmissionFactor"] = tinygltf::Value(double(m.diffuseTransmission));
      if (m.texture >= 0) {
        colour["index"] = tinygltf::Value(m.texture);
        transmission["diffuseTransmissionColorTexture"] = tinygltf::Value(std::move(colour));
      }
      g.extensions["KHR_materials_diffuse_transmission"] = tinygltf::Value(std::move(transmission));
      const std::string name = "KHR_materials_diffuse_transmission";
      if (std::find(gltf.extensionsUsed.begin(), gltf.extensionsUsed.end(), name) == gltf.extensionsUsed.end())
        gltf.extensionsUsed.push_back(name);
    }
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

namespace {

// The glTF of a model (everything but the bytes): nodes, meshes and their parts' views and
// accessors, materials, textures, images. geometry(o, p) describes part p of object o;
// imageBytes[i] is the encoded size of image i. Views are laid out in the order the bytes are
// written: every part in object order, then the images. With `jobs`, the copy jobs that write
// them (every part then needs its mesh; plant o's wind data comes from windTableOf(wind, o)).
// instanceGeometry(o, k) describes instanced shape k of object o (its nodes follow the object's
// levels, children of LOD0's node; their bytes follow the object's parts).
template <class Geometry, class InstGeometry>
void describe(const ExportModel& model, Geometry&& geometry, InstGeometry&& instanceGeometry,
              const std::vector<size_t>& imageBytes, GlbBuilder& builder, tinygltf::Model& gltf,
              std::vector<CopyJob>* jobs, const WindTables* wind, const PivotPainterGrids* pivot) {
  gltf.asset.version = "2.0";
  gltf.asset.generator = "Tendril " TENDRIL_VERSION;
  tinygltf::Scene scene;
  scene.name = "Tendril";  // also keeps an empty scene an object rather than null
  for (size_t o = 0; o < model.objects.size(); ++o) {
    const ExportObject& object = model.objects[o];
    // One node per level of detail, LOD0 first; only LOD0 is in the scene, and lists the others
    // (MSFT_lod), so that a reader without the extension shows LOD0 alone.
    const int first = static_cast<int>(gltf.nodes.size());
    for (size_t level = 0; level < object.levels(); ++level) {
      tinygltf::Node node;
      node.name = levelName(object, level);
      tinygltf::Mesh mesh;
      mesh.name = node.name;
      for (const ExportPart& part : object.partsOf(level))
        if (part.instancing != 2)  // a primitive group all of whose copies are instances has no baked part
          mesh.primitives.push_back(addPart(part, geometry(o, part), builder, gltf, jobs ? bakedMesh(part) : nullptr,
                                            jobs, windTableOf(wind, o), pivotGridOf(pivot, o)));
      if (!mesh.primitives.empty()) {
        gltf.meshes.push_back(std::move(mesh));
        node.mesh = static_cast<int>(gltf.meshes.size() - 1);
      }
      gltf.nodes.push_back(std::move(node));
    }
    if (object.levels() > 1) {
      tinygltf::Value::Array ids, coverage;
      for (size_t level = 1; level < object.levels(); ++level) ids.emplace_back(first + static_cast<int>(level));
      for (float c : object.screenCoverage) coverage.emplace_back(std::round(double(c) * 1e4) / 1e4);
      tinygltf::Value::Object lod, extras;
      lod["ids"] = tinygltf::Value(std::move(ids));
      extras["MSFT_screencoverage"] = tinygltf::Value(std::move(coverage));
      gltf.nodes[size_t(first)].extensions["MSFT_lod"] = tinygltf::Value(std::move(lod));
      gltf.nodes[size_t(first)].extras = tinygltf::Value(std::move(extras));
      if (std::find(gltf.extensionsUsed.begin(), gltf.extensionsUsed.end(), "MSFT_lod") == gltf.extensionsUsed.end())
        gltf.extensionsUsed.push_back("MSFT_lod");
    }
    // Instanced shapes: children of LOD0's node. Required: a reader without the extension would
    // draw one copy of each shape, at the plant's origin (docs/export.md).
    for (size_t k = 0; k < object.instanced.size(); ++k) {
      const ExportInstanced& inst = object.instanced[k];
      const std::string name = fmt::format("{}-{}", levelName(object, 0), inst.name);
      gltf.nodes.push_back(addInstanced(inst, name, instanceGeometry(o, k), builder, gltf,
                                        jobs ? inst.shape : nullptr, jobs, windTableOf(wind, o)));
      gltf.nodes[size_t(first)].children.push_back(static_cast<int>(gltf.nodes.size() - 1));
      const std::string ext = "EXT_mesh_gpu_instancing";
      if (std::find(gltf.extensionsUsed.begin(), gltf.extensionsUsed.end(), ext) == gltf.extensionsUsed.end()) {
        gltf.extensionsUsed.push_back(ext);
        gltf.extensionsRequired.push_back(ext);
      }
    }
    scene.nodes.push_back(first);
  }
  gltf.scenes.push_back(std::move(scene));
  gltf.defaultScene = 0;

  appendMaterialsAndTextures(model, gltf);
  for (size_t i = 0; i < model.images.size(); ++i) {
    const ExportImage& img = model.images[i];
    tinygltf::Image image;
    image.name = std::filesystem::path(img.spec).filename().string();
    image.mimeType = img.image.mimeType;
    image.bufferView = builder.view(imageBytes[i], 0);
    if (jobs)
      jobs->push_back({CopyJob::Kind::Bytes, img.image.bytes.data(), imageBytes[i], builder.offsetOf(image.bufferView)});
    gltf.images.push_back(std::move(image));
  }
}

std::vector<size_t> imageSizes(const ExportModel& model) {
  std::vector<size_t> sizes;
  for (const ExportImage& img : model.images) sizes.push_back(img.image.bytes.size());
  return sizes;
}

// The JSON chunk's text (unpadded): tinygltf serialises the glTF; the one buffer (the GLB's BIN
// chunk, `binBytes` long) is added here, as the container is written by us.
std::string glbJson(tinygltf::Model& gltf, size_t binBytes, const std::filesystem::path& path) {
  std::ostringstream text;
  tinygltf::TinyGLTF tiny;
  if (!tiny.WriteGltfSceneToStream(&gltf, text, false, false))
    throw Error(path.string(), "", "cannot write .glb: tinygltf could not serialise the scene");
  nlohmann::json json = nlohmann::json::parse(text.str());
  if (binBytes > 0) json["buffers"] = nlohmann::json::array({{{"byteLength", binBytes}}});
  return json.dump();
}

void appendU32(std::string& s, uint64_t v) {
  for (int k = 0; k < 4; ++k) s.push_back(static_cast<char>(uint8_t(v >> (8 * k))));  // little-endian
}

// The GLB header and the JSON chunk's header, for `jsonBytes` (padded, a multiple of 4) of
// JSON followed by a BIN chunk of `binBytes` (none when 0).
std::string glbHeader(size_t jsonBytes, size_t binBytes, const std::filesystem::path& path) {
  uint64_t total = 12 + 8 + jsonBytes + (binBytes > 0 ? 8 + binBytes : 0);
  if (total > std::numeric_limits<uint32_t>::max())
    throw Error(path.string(), "", "cannot write .glb: more than the format's 4 GiB; lower radialSegments or "
                                   "subdivisions");
  std::string h = "glTF";
  appendU32(h, 2);
  appendU32(h, total);
  appendU32(h, jsonBytes);
  h += "JSON";
  return h;
}

std::string binHeader(size_t binBytes) {
  std::string h;
  appendU32(h, binBytes);
  h.append("BIN\0", 4);
  return h;
}

const uint8_t kZeros[4] = {0, 0, 0, 0};

}  // namespace

void writeGlb(const ExportModel& model, const std::filesystem::path& path, const WindTables* wind,
              const PivotPainterGrids* pivot) {
  for (size_t o = 0; o < model.objects.size(); ++o)
    if (pivotGridOf(pivot, o) && !model.objects[o].instanced.empty())
      throw Error(path.string(), "output.pivot_painter",
                  "Pivot Painter textures cannot go with GPU instancing (an instanced copy has no vertices to carry "
                  "its element's UV): turn output.instancing off");
  tinygltf::Model gltf;
  GlbBuilder builder(gltf);
  std::vector<CopyJob> jobs;
  describe(
      model,
      [&](size_t o, const ExportPart& part) {
        return geometryOf(*bakedMesh(part), windTableOf(wind, o) != nullptr, pivotGridOf(pivot, o) != nullptr);
      },
      [&](size_t o, size_t k) {
        return instanceGeometryOf(*model.objects[o].instanced[k].shape, windTableOf(wind, o) != nullptr);
      },
      imageSizes(model), builder, gltf, &jobs, wind, pivot);
  // Every view is streamed from the meshes into the file, so that the geometry is never copied
  // into a second in-memory buffer (hundreds of MB for a large plant).
  const size_t binBytes = builder.size();
  std::string content = glbJson(gltf, binBytes, path);
  content.resize(align4(content.size()), ' ');  // the JSON chunk is padded with spaces
  const std::string header = glbHeader(content.size(), binBytes, path);

  AtomicFileWriter out(path);
  out.write(header);
  out.write(content);
  if (binBytes > 0) {
    out.write(binHeader(binBytes));
    std::vector<uint8_t> scratch(kScratchBytes);
    uint64_t at = 0;
    for (const CopyJob& job : jobs) {  // in offset order
      out.write(kZeros, job.offset - at);
      writeJob(job, out, scratch);
      at = job.offset + jobBytes(job);
    }
    out.write(kZeros, binBytes - at);
  }
  out.commit();
}

namespace {

// An upper bound on the JSON chunk of a scene's .glb, from what is known before meshing. Each
// item's allowance is its JSON with every number at its longest (ten digits for a count, size
// or index; 24 characters for a float) and every optional field present, plus its name with
// every byte escaped (×6): a part (its primitive, five accessors, five views) 1,294 bytes, a
// material 381, an image with its texture and sampler 194, a node with its mesh 69. Parts are
// counted as if every one were non-empty, materials once per distinct look. With `levels` of
// detail, a plant's node, mesh and parts come once per level (its names 5 bytes longer), and
// LOD0's node lists the others (MSFT_lod: ten digits per id, 24 characters per coverage).
size_t jsonAllowance(const ExportScene& scene, size_t levels, bool leafAtlas, bool instancing, bool maps = false) {
  constexpr size_t kPart = 1300, kMaterial = 400, kImage = 200, kObject = 80, kEscape = 6;
  // Engine wind data: three more accessors and views per plant part (COLOR_0, _WIND_PIVOT,
  // _WIND_AXIS); Pivot Painter UVs: two more (TEXCOORD_0 where the part has none, TEXCOORD_1).
  const size_t windPart = (scene.wind.empty() ? 0 : 800) + (scene.pivotPainter.empty() ? 0 : 540);
  size_t bytes = 1024;  // asset, scene, buffer, separators
  std::vector<std::string> images, materials;
  auto image = [&](const std::string& spec) {
    if (!spec.empty() && std::find(images.begin(), images.end(), spec) == images.end()) {
      images.push_back(spec);
      bytes += (maps ? 3 : 1) * (kImage + kEscape * (spec.size() + 10));  // with maps: normal and roughness too
    }
  };
  auto material = [&](std::string look, size_t nameLength) {
    if (std::find(materials.begin(), materials.end(), look) == materials.end()) {
      materials.push_back(std::move(look));
      bytes += kMaterial + kEscape * (nameLength + 16) + (maps ? 120 : 0);  // the name made unique; map indices
    }
  };
  auto colour = [](const Vec3& c) { return fmt::format("{},{},{}", c.x(), c.y(), c.z()); };
  // Primitive and mesh materials are named after the first mesh of their look: the longest name.
  size_t longest = 0;
  for (const plant::PlantModel& p : scene.plants)
    for (const plant::PrimitiveMesh& m : p.meshes) longest = std::max(longest, m.name.size());
  for (const NamedMesh& m : scene.meshes) longest = std::max(longest, m.name.size());
  if (levels > 1) bytes += 64;  // extensionsUsed
  if (leafAtlas) bytes += 64;    // KHR_materials_diffuse_transmission in extensionsUsed
  for (size_t i = 0; i < scene.plants.size(); ++i) {
    const plant::PlantModel& p = scene.plants[i];
    size_t partCount = 0;
    if (p.nodeCount() > 0) {
      ++partCount;
      image(p.bark.texture);
      material(fmt::format("bark|{}|{}|{}", p.bark.texture, colour(p.bark.color), p.bark.roughness), 4);
    }
    std::vector<uint8_t> used(mesh::leafShapeCount(p), 0);
    for (uint16_t s : p.leafShape) used[s] = 1;
    for (size_t s = 0; s < used.size(); ++s)
      if (used[s]) {
        const plant::LeafShape shape = mesh::leafShapeFor(p, s);
        ++partCount;
        image(shape.texture);
        material(fmt::format("leaf|{}|{}", shape.texture, colour(shape.tint)), 5 + shape.texture.size());
        if (leafAtlas)  // its share of the atlas (and of its normal map)
          bytes += (maps ? 2 : 1) * kImage + kMaterial + kEscape * (shape.texture.size() + 64);
      }
    for (const plant::PrimitiveMesh& m : p.meshes) {
      ++partCount;
      image(m.texture);
      material(fmt::format("primitive|{}|{}", m.texture, colour(m.color)), longest);
    }
    const size_t names = levels > 1 ? 5 : 0;  // "_LOD<k>"
    // node and mesh names
    bytes += levels * (kObject + 2 * kEscape * (std::max<size_t>(p.name.size(), 16) + names) + (kPart + windPart) * partCount);
    if (levels > 1) bytes += 96 + 40 * levels;
    // Instancing: per primitive mesh, a node with a mesh of one part and up to seven instance
    // accessors and views (named after the plant's LOD0 and the mesh).
    // Only a mesh placed more than once can be.
    if (instancing) {
      std::vector<uint32_t> uses(p.meshes.size(), 0);
      for (const plant::Primitive& pr : p.primitives)
        if (pr.mesh < uses.size()) ++uses[pr.mesh];
      for (size_t k = 0; k < p.meshes.size(); ++k)
        if (uses[k] > 1)
          bytes += 128 + kObject + kPart + windPart + 1500 +
                   2 * kEscape * (std::max<size_t>(p.name.size(), 16) + 5 + p.meshes[k].name.size() + 1);
    }
  }
  for (const NamedMesh& m : scene.meshes) {
    bytes += kObject + kPart + 2 * kEscape * std::max<size_t>(m.name.size(), 16);
    material(fmt::format("mesh|{}", colour(m.color)), longest);
  }
  return align4(bytes);
}

// Writes one part's arrays at the end of the binary chunk (`at` bytes so far), each view
// 4-byte aligned as GlbBuilder lays them out; the wind data (where the part has node ids) from
// the plant's table `wind`, `leaf` for a leaf part.
void writePart(const TriangleMesh& m, AtomicFileWriter& out, uint64_t& at, std::vector<uint8_t>& scratch,
               const std::vector<WindVertexNode>* wind = nullptr, bool leaf = false,
               const PivotPainterGrid* pivot = nullptr) {
  auto view = [&](CopyJob::Kind kind, const void* source, size_t count, size_t bytes) {
    out.write(kZeros, align4(at) - at);
    at = align4(at);
    writeJob({kind, source, count, at}, out, scratch);
    at += bytes;
  };
  const size_t n = m.positions.size(), ni = m.indices.size();
  view(CopyJob::Kind::Bytes, m.positions.data(), n * sizeof(Vec3), n * sizeof(Vec3));
  if (!m.normals.empty()) view(CopyJob::Kind::Bytes, m.normals.data(), n * sizeof(Vec3), n * sizeof(Vec3));
  if (!m.uvs.empty()) view(CopyJob::Kind::FlipUv, m.uvs.data(), n, n * sizeof(Vec2));
  if (!m.nodeIds.empty()) view(CopyJob::Kind::NodeId, m.nodeIds.data(), n, n * sizeof(float));
  if (wind && !m.nodeIds.empty())
    for (CopyJob::Kind kind : {CopyJob::Kind::WindColor, CopyJob::Kind::WindPivot, CopyJob::Kind::WindAxis}) {
      out.write(kZeros, align4(at) - at);
      at = align4(at);
      writeJob({kind, m.nodeIds.data(), n, at, wind->data(), wind->size(), leaf}, out, scratch);
      at += n * windBytes(kind);
    }
  if (pivot && !m.nodeIds.empty()) {
    if (m.uvs.empty()) view(CopyJob::Kind::Zeros, nullptr, n * sizeof(Vec2), n * sizeof(Vec2));
    out.write(kZeros, align4(at) - at);
    at = align4(at);
    CopyJob job{CopyJob::Kind::PivotUv, m.nodeIds.data(), n, at};
    job.grid = *pivot;
    writeJob(job, out, scratch);
    at += n * sizeof(Vec2);
  }
  if (smallIndices(n))
    view(CopyJob::Kind::Index16, m.indices.data(), ni, ni * sizeof(uint16_t));
  else
    view(CopyJob::Kind::Bytes, m.indices.data(), ni * sizeof(uint32_t), ni * sizeof(uint32_t));
}

// Writes an instanced shape's arrays as addInstanced lays them out: its mesh, then per copy
// translation, rotation, scale, node id and (with `wind`) the wind data.
void writeInstances(const InstancedShape& s, AtomicFileWriter& out, uint64_t& at, std::vector<uint8_t>& scratch,
                    const std::vector<WindVertexNode>* wind) {
  writePart(s.shape, out, at, scratch);
  const size_t n = s.instances();
  auto view = [&](CopyJob job, size_t bytes) {
    out.write(kZeros, align4(at) - at);
    at = align4(at);
    job.offset = at;
    writeJob(job, out, scratch);
    at += bytes;
  };
  view({CopyJob::Kind::Bytes, s.translation.data(), n * sizeof(Vec3)}, n * sizeof(Vec3));
  view({CopyJob::Kind::Bytes, s.rotation.data(), n * sizeof(Vec4)}, n * sizeof(Vec4));
  view({CopyJob::Kind::Bytes, s.scale.data(), n * sizeof(Vec3)}, n * sizeof(Vec3));
  if (s.nodeIds.empty()) return;
  view({CopyJob::Kind::NodeId, s.nodeIds.data(), n}, n * sizeof(float));
  if (wind)
    for (CopyJob::Kind kind : {CopyJob::Kind::WindColor, CopyJob::Kind::WindPivot, CopyJob::Kind::WindAxis})
      view({kind, s.nodeIds.data(), n, 0, wind->data(), wind->size(), false}, n * windBytes(kind));
}

// Whether `m`, one of `pm`'s part meshes, is a leaf part.
bool isLeafPart(const mesh::PlantMesh& pm, const TriangleMesh& m) {
  return std::any_of(pm.leaves.begin(), pm.leaves.end(), [&](const TriangleMesh& l) { return &l == &m; });
}

// A plant's non-empty part meshes in the order assembleExportModel makes its parts: bark,
// leaves by shape id, primitive groups.
template <class F>
void forPlantParts(const mesh::PlantMesh& pm, F&& f) {
  if (!pm.bark.empty()) f(pm.bark);
  for (const TriangleMesh& m : pm.leaves)
    if (!m.empty()) f(m);
  for (const mesh::PrimitiveGroup& g : pm.primitives)
    if (!g.mesh.empty()) f(g.mesh);
}

}  // namespace

// The scene's .glb in one pass with little memory: plants are meshed a few at a time (in
// parallel, into meshes reused from plant to plant) and each one's arrays are written as soon
// as the plants before it are. The binary chunk goes after room reserved for the JSON chunk,
// which is written last, when every part's size and bounds are known, and padded with spaces to
// the reserved size (a JSON chunk may end in spaces). A large scene thus never holds all its
// meshes at once, and the memory its meshes use is touched once, not once per plant (fresh
// pages are what made the export slow). Should the JSON outgrow its room (the allowance is
// generous, so it should not), the scene is written again the simple way.
void writeGlb(const ExportScene& scene, const std::filesystem::path& path, const ExportOptions& options) {
  checkOutputPath(path);
  // Bad plants and options are reported before anything is written: the first bad plant by
  // index, as when they were meshed in order.
  mesh::validateMeshOptions(options.mesh, "mesh options");
  mesh::validateLodSettings(options.lods, "export options");
  if (options.instancing && std::any_of(scene.pivotPainter.begin(), scene.pivotPainter.end(),
                                        [](const PivotPainterGrid& g) { return g.width > 0; }))
    throw Error(path.string(), "output.pivot_painter",
                "Pivot Painter textures cannot go with GPU instancing (an instanced copy has no vertices to carry "
                "its element's UV): turn output.instancing off");
  {
    const size_t n = scene.plants.size();
    std::vector<std::exception_ptr> failed(n);
    parallelFor(0, n, [&](size_t i) {
      try {
        mesh::checkMeshable(scene.plants[i], options.mesh);
      } catch (...) {
        failed[i] = std::current_exception();
      }
    }, 16);
    for (const std::exception_ptr& e : failed)
      if (e) std::rethrow_exception(e);
  }
  if (scene.plants.empty()) return writeGlb(buildExportModel(scene, options), path, &scene.wind, &scene.pivotPainter);
  // An impostor is baked from the whole LOD0 of its plant: from one model, not streamed.
  if (options.impostor.enabled) return writeGlb(buildExportModel(scene, options), path, &scene.wind, &scene.pivotPainter);
  // Normal maps need each part's tangents, computed from the whole part: from one model too.
  if (options.maps) return writeGlb(buildExportModel(scene, options), path, &scene.wind, &scene.pivotPainter);

  const size_t reserve =
      jsonAllowance(scene, size_t(options.lods.levels), options.leafAtlas, options.instancing, options.maps);
  std::optional<AtomicFileWriter> out(std::in_place, path);
  out->write(std::string(20 + reserve + 8, ' '));  // header, JSON chunk, BIN chunk header: written last
  // Textures load while the plants are meshed and written.
  TexturePreload textures;
  std::vector<PlantParts> parts(scene.plants.size());
  std::vector<PartGeometry> written;  // every plant part's, in file order
  std::vector<std::vector<InstanceGeometry>> writtenInstances(scene.plants.size());  // per plant, its instanced shapes'
  std::vector<std::string> warnings;  // levels of detail over their budget, in plant order
  uint64_t at = 0;                    // bytes of the binary chunk so far
  std::vector<uint8_t> scratch(kScratchBytes);
  tbb::task_group loading;
  loading.run([&] { textures = preloadTextures(scene); });
  // A leaf atlas remaps the UVs of the meshes: its layout (from the textures' sizes) comes first.
  LeafAtlases atlases;
  if (options.leafAtlas) {
    loading.wait();
    atlases = buildLeafAtlases(scene, textures);
  }
  try {
    const size_t tokens = size_t(std::max(2, 2 * tbb::this_task_arena::max_concurrency()));
    std::vector<mesh::PlantMesh> slots(tokens);
    std::vector<std::vector<mesh::LodLevel>> slotLods(tokens);  // the plant's lower levels of detail
    std::vector<std::vector<PartGeometry>> slotGeometry(tokens);
    std::vector<PlantInstancing> slotInstancing(tokens);  // the plant's instanced primitives
    size_t next = 0;
    // At most `tokens` plants are in flight, and consecutive ones (the first and last stages
    // keep plant order): plant i owns slot i % tokens.
    auto input = [&](tbb::flow_control& fc) -> size_t {
      if (next == scene.plants.size()) {
        fc.stop();
        return 0;
      }
      return next++;
    };
    auto meshPlant = [&](size_t i) {
      mesh::PlantMesh& pm = slots[i % tokens];
      std::vector<mesh::LodLevel>& lods = slotLods[i % tokens];
      meshPlantLevels(scene.plants[i], options, pm, lods);
      if (options.leafAtlas) {
        applyLeafAtlas(atlases, atlases.plants[i], pm);
        for (mesh::LodLevel& level : lods) applyLeafAtlas(atlases, atlases.plants[i], level.mesh);
      }
      // Instancing: the parts are those of the plant's whole meshes; the .glb bakes each
      // instanced group's rest, swapped in for its mesh (an empty one is not written).
      PlantInstancing& inst = slotInstancing[i % tokens];
      inst = plantInstancing(scene, i, options, pm);
      parts[i] = plantParts(pm, lods);
      addInstancing(parts[i], inst);
      for (size_t k = 0; k < inst.instanced.size() && k < pm.primitives.size(); ++k)
        if (inst.instanced[k]) std::swap(pm.primitives[k].mesh, inst.rest[k]);
      std::vector<PartGeometry>& g = slotGeometry[i % tokens];
      g.clear();
      const bool wind = windTableOf(&scene.wind, i) != nullptr;
      const bool pivot = pivotGridOf(&scene.pivotPainter, i) != nullptr;
      writtenInstances[i].clear();
      for (const InstancedShape& shape : inst.shapes) writtenInstances[i].push_back(instanceGeometryOf(shape, wind));
      forPlantParts(pm, [&](const TriangleMesh& m) { g.push_back(geometryOf(m, wind, pivot)); });
      for (const mesh::LodLevel& level : lods)
        forPlantParts(level.mesh, [&](const TriangleMesh& m) { g.push_back(geometryOf(m, wind, pivot)); });
      return i;
    };
    auto writePlant = [&](size_t i) {
      const mesh::PlantMesh& pm = slots[i % tokens];
      const std::vector<mesh::LodLevel>& lods = slotLods[i % tokens];
      for (std::string& w : lodBudgetWarnings(scene.plants[i], i, lods)) warnings.push_back(std::move(w));
      const std::vector<WindVertexNode>* wind = windTableOf(&scene.wind, i);
      const PivotPainterGrid* pivot = pivotGridOf(&scene.pivotPainter, i);
      forPlantParts(pm, [&](const TriangleMesh& m) { writePart(m, *out, at, scratch, wind, isLeafPart(pm, m), pivot); });
      for (const mesh::LodLevel& level : lods)
        forPlantParts(level.mesh, [&](const TriangleMesh& m) {
          writePart(m, *out, at, scratch, wind, isLeafPart(level.mesh, m), pivot);
        });
      for (const InstancedShape& shape : slotInstancing[i % tokens].shapes) writeInstances(shape, *out, at, scratch, wind);
      written.insert(written.end(), slotGeometry[i % tokens].begin(), slotGeometry[i % tokens].end());
    };
    tbb::parallel_pipeline(tokens, tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order, input) &
                                       tbb::make_filter<size_t, size_t>(tbb::filter_mode::parallel, meshPlant) &
                                       tbb::make_filter<size_t, void>(tbb::filter_mode::serial_in_order, writePlant));
  } catch (...) {
    loading.wait();
    throw;
  }
  loading.wait();
  for (const std::string& w : warnings) log::warn("{}", w);

  ExportModel model = assembleExportModel(scene, parts, textures, options.leafAtlas ? &atlases : nullptr, options.maps);
  for (size_t o = scene.plants.size(); o < model.objects.size(); ++o)
    for (const ExportPart& part : model.objects[o].parts) writePart(*part.mesh, *out, at, scratch);
  for (const ExportImage& img : model.images) {
    out->write(kZeros, align4(at) - at);
    at = align4(at);
    out->write(img.image.bytes.data(), img.image.bytes.size());
    at += img.image.bytes.size();
  }
  out->write(kZeros, align4(at) - at);
  at = align4(at);

  tinygltf::Model gltf;
  GlbBuilder builder(gltf);
  size_t plantPart = 0;
  describe(
      model,
      [&](size_t o, const ExportPart& part) {
        if (o < scene.plants.size()) return written[plantPart++];
        return geometryOf(*part.mesh);
      },
      [&](size_t o, size_t k) { return writtenInstances[o].at(k); }, imageSizes(model), builder, gltf, nullptr,
      &scene.wind, &scene.pivotPainter);
  const size_t binBytes = builder.size();
  if (plantPart != written.size() || binBytes != at)
    throw Error(path.string(), "", "cannot write .glb: the streamed parts do not match the model (internal error)");
  std::string content = glbJson(gltf, binBytes, path);
  if (content.size() > reserve || binBytes == 0) {
    out.reset();  // removes the temporary
    return writeGlb(buildExportModel(scene, options), path, &scene.wind, &scene.pivotPainter);
  }
  content.resize(reserve, ' ');
  const std::string header = glbHeader(reserve, binBytes, path);
  out->writeAt(0, header.data(), header.size());
  out->writeAt(header.size(), content.data(), content.size());
  const std::string bin = binHeader(binBytes);
  out->writeAt(header.size() + reserve, bin.data(), bin.size());
  out->commit();
}

}  // namespace tendril::io
