#include "tendril/io/skeleton_writer.h"

#include "tendril/core/parallel.h"
#include "tendril/io/atomic_file.h"
#include "tendril/mesh/branch_sweep.h"
#include "tendril/mesh/primitive_mesh.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>

namespace tendril::io {
namespace {

// nlohmann's JSON with keys in the order they are set and numbers kept as 32-bit floats, so that
// dump() writes each float's own shortest form (0.02, not the double 0.019999999552965164).
using SkeletonJson = nlohmann::basic_json<nlohmann::ordered_map, std::vector, std::string, bool, std::int64_t,
                                          std::uint64_t, float>;

constexpr uint32_t kNamedFlags = (1u << std::size(kNodeFlagNames)) - 1;

SkeletonJson vec3(const Vec3& v) { return SkeletonJson::array({v.x(), v.y(), v.z()}); }
SkeletonJson quat(const Quat& q) { return SkeletonJson::array({q.x(), q.y(), q.z(), q.w()}); }

// Writes records [0, count) as dump() lines joined by ",\n": built in parallel a batch of chunks
// at a time (so a large plant's text is never held whole) and written in order.
template <class Record>
void writeRecords(size_t count, Record&& record, AtomicFileWriter& out) {
  constexpr size_t kChunk = 1024, kBatch = 64;
  const size_t chunks = (count + kChunk - 1) / kChunk;
  std::vector<std::string> text(std::min(chunks, kBatch));
  for (size_t first = 0; first < chunks; first += kBatch) {
    const size_t batch = std::min(kBatch, chunks - first);
    parallelFor(0, batch, [&](size_t b) {
      const size_t begin = (first + b) * kChunk, end = std::min(count, begin + kChunk);
      text[b].clear();
      for (size_t i = begin; i < end; ++i) {
        if (i > 0) text[b] += ",\n";
        text[b] += record(i).dump();
      }
    }, 1);
    for (size_t b = 0; b < batch; ++b) out.write(text[b]);
  }
}

// An object's dump() without its closing brace, so that arrays written line by line can follow.
std::string openObject(const SkeletonJson& object) {
  std::string s = object.dump();
  s.pop_back();
  return s;
}

const char* tipEndName(plant::TipEnd end) {
  switch (end) {
    case plant::TipEnd::NoSupport: return "no_support";
    case plant::TipEnd::Blocked: return "blocked";
    case plant::TipEnd::Crowded: return "crowded";
    case plant::TipEnd::Capped: return "capped";
    case plant::TipEnd::Shortened: return "shortened";
    case plant::TipEnd::Rule: return "rule";
    case plant::TipEnd::Unknown: break;
  }
  return "unknown";
}

void writePlant(const plant::PlantModel& p, AtomicFileWriter& out) {
  const size_t n = p.nodeCount();
  // Edges as an MTG has them: "<" continues the parent's axis (the bark sweep's chains,
  // mesh/branch_sweep.h), "+" starts a branch on it.
  std::vector<uint8_t> startsAxis(n, 0);
  const mesh::BranchChains chains = mesh::buildBranchChains(p);
  for (size_t c = 0; c < chains.size(); ++c)
    if (!chains.chain(c).empty()) startsAxis[size_t(chains.chain(c).front())] = 1;

  SkeletonJson head = SkeletonJson::object();
  head["name"] = p.name;
  head["species"] = p.species;
  SkeletonJson shapes = SkeletonJson::array();
  for (size_t s = 0; s < p.leafShapes.size(); ++s)
    shapes.push_back({{"id", s}, {"texture", p.leafShapes[s].texture}, {"aspect", p.leafShapes[s].aspect}});
  head["leaf_shapes"] = std::move(shapes);
  out.write(openObject(head));

  out.write(",\"nodes\":[\n");
  writeRecords(n, [&](size_t i) {
    SkeletonJson r = SkeletonJson::object();
    r["id"] = i;
    r["kind"] = "internode";
    r["parent"] = p.parent[i];
    r["edge"] = p.parent[i] < 0 ? SkeletonJson(nullptr) : SkeletonJson(startsAxis[i] ? "+" : "<");
    r["position"] = vec3(p.position[i]);
    r["orientation"] = quat(p.orientation[i]);
    r["length"] = p.length[i];
    r["radius"] = p.radius[i];
    r["age"] = p.age[i];
    r["order"] = p.order[i];
    SkeletonJson flags = SkeletonJson::array();
    for (size_t b = 0; b < std::size(kNodeFlagNames); ++b)
      if (p.flags[i] & (1u << b)) flags.push_back(kNodeFlagNames[b]);
    r["flags"] = std::move(flags);
    // A dead tip's recorded end (plant::TipEnd: why it stopped, models/diagnosis.h).
    if (const plant::TipEnd end = plant::tipEnd(p.flags[i]); end != plant::TipEnd::Unknown)
      r["tip_end"] = tipEndName(end);
    const uint32_t other = p.flags[i] & ~(kNamedFlags | plant::kNodeTipEndMask);
    if (other) r["other_flags"] = other;
    return r;
  }, out);

  out.write("\n],\"leaves\":[\n");
  writeRecords(p.leafCount(), [&](size_t i) {
    SkeletonJson r = SkeletonJson::object();
    r["id"] = i;
    r["kind"] = "leaf";
    r["node"] = p.leafNode[i];
    r["position"] = vec3(p.leafWorldPosition(i));
    r["rotation"] = quat(p.leafWorldRotation(i));
    r["size"] = p.leafSize[i];
    r["petiole"] = p.leafPetiole[i];
    r["shape"] = p.leafShape[i];
    return r;
  }, out);

  out.write("\n],\"primitives\":[\n");
  writeRecords(p.primitives.size(), [&](size_t i) {
    const plant::Primitive& pr = p.primitives[i];
    const Mat4 world = mesh::worldFromNode(p, pr.node) * pr.nodeFromPrimitive;
    SkeletonJson matrix = SkeletonJson::array();
    for (int k = 0; k < 16; ++k) matrix.push_back(world(k % 4, k / 4));  // column-major, as glTF
    SkeletonJson r = SkeletonJson::object();
    r["id"] = i;
    r["kind"] = "primitive";
    r["node"] = pr.node;
    r["mesh"] = p.meshes[pr.mesh].name;
    r["matrix"] = std::move(matrix);
    return r;
  }, out);
  out.write("\n]}");
}

}  // namespace

void writeSkeleton(const std::vector<plant::PlantModel>& plants, const std::filesystem::path& path) {
  for (size_t i = 0; i < plants.size(); ++i)
    plant::validate(plants[i], plants[i].name.empty() ? fmt::format("plant {}", i) : plants[i].name);
  checkOutputPath(path);

  SkeletonJson head = SkeletonJson::object();
  head["format"] = kSkeletonFormat;
  head["version"] = kSkeletonVersion;
  head["generator"] = "Tendril " TENDRIL_VERSION;
  head["units"] = {{"length", "m"}, {"age", "s"}};
  head["up"] = vec3(Vec3::UnitY());
  AtomicFileWriter out(path);
  out.write(openObject(head));
  out.write(",\"plants\":[\n");
  for (size_t i = 0; i < plants.size(); ++i) {
    if (i > 0) out.write(",\n");
    writePlant(plants[i], out);
  }
  out.write("\n]}\n");
  out.commit();
}

}  // namespace tendril::io
