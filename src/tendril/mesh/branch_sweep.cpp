#include "tendril/mesh/branch_sweep.h"

#include "tendril/core/error.h"
#include "tendril/core/parallel.h"
#include "tendril/core/curve.h"

#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace tendril::mesh {
namespace {

using plant::PlantModel;

struct ChainPoint {
  Vec3 p;
  float radius;
  int32_t node;  // the node whose segment starts here (the last tip: the chain's last node)
};

// The chain's distinct spline points: every segment start and the last tip, each with the
// radius the surface has there. A point within kMergeDistance of the previous one is merged
// into it and passes on its radius and node (it starts the segment that follows).
void chainPoints(const PlantModel& plant, std::span<const int32_t> nodes, std::vector<ChainPoint>& out) {
  out.clear();
  auto push = [&](const Vec3& p, float r, int32_t node) {
    if (!out.empty() && (p - out.back().p).squaredNorm() <= kMergeDistance * kMergeDistance) {
      out.back().radius = r;
      out.back().node = node;
      return;
    }
    out.push_back({p, r, node});
  };
  for (int32_t n : nodes) push(plant.position[n], plant.radius[n], n);
  int32_t last = nodes.back();
  push(plant.tip(last), plant.radius[last], last);
}

// One ring of the sweep, before tessellation.
struct RingSample {
  Vec3 centre;
  Vec3 tangent;  // unit, along the chain
  Vec3 normal;   // unit, rotation-minimising, ⟂ tangent
  float radius;
  float slope;  // d radius / d arc length: tilts the surface normals of a tapering branch
  float v;      // texture coordinate along the chain
  int32_t node;  // the node whose segment the ring lies on
};

struct RingTable {
  std::vector<float> cosine, sine;
  explicit RingTable(int radial) : cosine(radial), sine(radial) {
    for (int j = 0; j < radial; ++j) {
      double a = 2.0 * 3.14159265358979323846 * j / radial;
      cosine[j] = static_cast<float>(std::cos(a));
      sine[j] = static_cast<float>(std::sin(a));
    }
  }
};

// Direction from the centre to ring vertex j (unit up to rounding).
inline Vec3 ringDirection(const RingSample& s, const Vec3& binormal, const RingTable& table, int j) {
  return table.cosine[j] * s.normal + table.sine[j] * binormal;
}

size_t samplesFor(size_t points, int subdivisions) {
  return points < 2 ? 0 : (points - 1) * static_cast<size_t>(subdivisions) + 1;
}

// Spline samples of one chain with their rotation-minimising frames (sequential along the
// chain, as the frames are propagated from ring to ring).
void sampleChain(const PlantModel& plant, std::span<const int32_t> nodes, const std::vector<ChainPoint>& pts,
                 int subdivisions, std::span<RingSample> out) {
  size_t count = pts.size();
  assert(out.size() == samplesFor(count, subdivisions));
  float invSub = 1.0f / static_cast<float>(subdivisions);
  size_t i = 0;
  for (size_t k = 0; k + 1 < count; ++k) {
    const ChainPoint& a = pts[k];
    const ChainPoint& b = pts[k + 1];
    // Reflected neighbours at the chain's ends keep the end tangents along the end chords.
    Vec3 p0 = k > 0 ? pts[k - 1].p : Vec3(2.0f * a.p - b.p);
    Vec3 p3 = k + 2 < count ? pts[k + 2].p : Vec3(2.0f * b.p - a.p);
    CurveSegment seg = centripetalCatmullRom(p0, a.p, b.p, p3);
    Vec3 chord = b.p - a.p;
    float chordLength = chord.norm();
    Vec3 chordDir = chord / chordLength;
    float slope = (b.radius - a.radius) / chordLength;
    int last = (k + 2 == count) ? subdivisions : subdivisions - 1;
    for (int j = 0; j <= last; ++j, ++i) {
      float s = static_cast<float>(j) * invSub;
      RingSample& r = out[i];
      // Knots are hit exactly so that rings sit on the skeleton's points.
      r.centre = j == 0 ? a.p : j == subdivisions ? b.p : seg.point(s);
      Vec3 d = seg.derivative(s);
      float dn = d.norm();
      r.tangent = dn > 1e-6f * chordLength ? Vec3(d / dn) : chordDir;
      r.radius = j == subdivisions ? b.radius : a.radius + (b.radius - a.radius) * s;
      r.slope = slope;
      r.node = a.node;
    }
  }
  // Rotation-minimising frames (Wang et al. 2008), starting from the first node's +Z, which
  // faces away from the support: the texture seam then lies on the side facing the viewer
  // consistently rather than wandering around the stem.
  Vec3 hint = plant.orientation[nodes.front()] * Vec3::UnitZ();
  out[0].normal = perpendicularTo(out[0].tangent, hint);
  double arc = 0.0;
  double invCircumference = 1.0 / (2.0 * 3.14159265358979323846 * std::max(pts[0].radius, 1e-6f));
  out[0].v = 0.0f;
  for (size_t n = 1; n < out.size(); ++n) {
    const RingSample& prev = out[n - 1];
    RingSample& cur = out[n];
    cur.normal = doubleReflection(prev.centre, prev.tangent, prev.normal, cur.centre, cur.tangent);
    arc += static_cast<double>((cur.centre - prev.centre).norm());
    cur.v = static_cast<float>(arc * invCircumference);
  }
}

void emitRing(const RingSample& s, const RingTable& table, int radial, size_t vertex, const MeshSpans& out) {
  Vec3 binormal = s.tangent.cross(s.normal);
  float invRadial = 1.0f / static_cast<float>(radial);
  // dir ⟂ tangent and |dir| = 1, so |dir − slope·tangent| = sqrt(1 + slope²) for the whole ring.
  float invLength = 1.0f / std::sqrt(1.0f + s.slope * s.slope);
  Vec3 tilt = (s.slope * invLength) * s.tangent;
  for (int j = 0; j < radial; ++j) {
    Vec3 dir = ringDirection(s, binormal, table, j);
    out.positions[vertex + j] = s.centre + s.radius * dir;
    out.normals[vertex + j] = invLength * dir - tilt;
    out.uvs[vertex + j] = Vec2(static_cast<float>(j) * invRadial, s.v);
  }
  // The seam vertex repeats the first one with u = 1 so u interpolates continuously.
  out.positions[vertex + radial] = out.positions[vertex];
  out.normals[vertex + radial] = out.normals[vertex];
  out.uvs[vertex + radial] = Vec2(1.0f, s.v);
  if (!out.nodeIds.empty()) std::fill_n(out.nodeIds.begin() + vertex, radial + 1, uint32_t(s.node));
}

// A fan closing the chain at ring `s`, facing `facing` (±tangent).
void emitCap(const RingSample& s, const RingTable& table, int radial, bool tip, size_t vertex, size_t index,
             const MeshSpans& out) {
  Vec3 binormal = s.tangent.cross(s.normal);
  Vec3 facing = tip ? s.tangent : Vec3(-s.tangent);
  out.positions[vertex] = s.centre;
  out.normals[vertex] = facing;
  out.uvs[vertex] = Vec2(0.5f, s.v);
  for (int j = 0; j < radial; ++j) {
    Vec3 dir = ringDirection(s, binormal, table, j);
    out.positions[vertex + 1 + j] = s.centre + s.radius * dir;
    out.normals[vertex + 1 + j] = facing;
    out.uvs[vertex + 1 + j] = Vec2(0.5f + 0.5f * table.cosine[j], s.v + 0.5f * table.sine[j]);
  }
  if (!out.nodeIds.empty()) std::fill_n(out.nodeIds.begin() + vertex, radial + 1, uint32_t(s.node));
  // Ring order is counter-clockwise about the tangent: seen from the tip it is
  // counter-clockwise, seen from the base clockwise, hence the swapped winding there.
  uint32_t centre = out.baseVertex + static_cast<uint32_t>(vertex);
  for (int j = 0; j < radial; ++j) {
    uint32_t a = centre + 1 + j;
    uint32_t b = centre + 1 + (j + 1) % radial;
    uint32_t* tri = &out.indices[index + 3 * j];
    tri[0] = centre;
    tri[1] = tip ? a : b;
    tri[2] = tip ? b : a;
  }
}

}  // namespace

BranchChains buildBranchChains(const PlantModel& plant) {
  size_t n = plant.nodeCount();
  std::vector<int32_t> childStart, childIndex;
  plant.children(childStart, childIndex);
  // The child that continues each node's chain: its first child that is not a branch start.
  std::vector<int32_t> next(n, -1);
  std::vector<uint8_t> continues(n, 0);
  for (size_t i = 0; i < n; ++i) {
    for (int32_t k = childStart[i]; k < childStart[i + 1]; ++k) {
      int32_t c = childIndex[k];
      if (!(plant.flags[c] & plant::kNodeBranchStart)) {
        next[i] = c;
        continues[c] = 1;
        break;
      }
    }
  }
  BranchChains chains;
  chains.nodes.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (continues[i]) continue;  // reached from the chain it belongs to
    for (int32_t c = static_cast<int32_t>(i); c >= 0; c = next[c]) chains.nodes.push_back(c);
    chains.start.push_back(static_cast<uint32_t>(chains.nodes.size()));
  }
  return chains;
}

SweepLayout planSweep(const PlantModel& plant, const BranchChains& chains, const MeshOptions& options) {
  size_t count = chains.size();
  std::vector<uint32_t> samples(count, 0);
  parallelForRange(0, count, [&](size_t begin, size_t end) {
    std::vector<ChainPoint> pts;
    for (size_t c = begin; c < end; ++c) {
      chainPoints(plant, chains.chain(c), pts);
      samples[c] = static_cast<uint32_t>(samplesFor(pts.size(), options.subdivisions));
    }
  }, 256);
  uint64_t ring = static_cast<uint64_t>(options.radialSegments) + 1;
  uint64_t capVertices = options.caps ? 2 * ring : 0;
  uint64_t capIndices = options.caps ? 6 * static_cast<uint64_t>(options.radialSegments) : 0;
  SweepLayout layout;
  layout.sampleStart.resize(count + 1);
  layout.vertexStart.resize(count + 1);
  layout.indexStart.resize(count + 1);
  uint64_t s = 0, v = 0, x = 0;
  for (size_t c = 0; c < count; ++c) {
    layout.sampleStart[c] = static_cast<uint32_t>(s);
    layout.vertexStart[c] = static_cast<uint32_t>(v);
    layout.indexStart[c] = static_cast<uint32_t>(x);
    uint64_t k = samples[c];
    if (k > 0) {
      s += k;
      v += k * ring + capVertices;
      x += (k - 1) * 6 * static_cast<uint64_t>(options.radialSegments) + capIndices;
    }
    if (x > std::numeric_limits<uint32_t>::max())
      throw Error(plant.name, "", fmt::format("bark mesh needs more than 2^32 indices; lower radialSegments ({}) or "
                                              "subdivisions ({})",
                                              options.radialSegments, options.subdivisions));
  }
  layout.sampleStart[count] = static_cast<uint32_t>(s);
  layout.vertexStart[count] = static_cast<uint32_t>(v);
  layout.indexStart[count] = static_cast<uint32_t>(x);
  return layout;
}

void sweepBranches(const PlantModel& plant, const BranchChains& chains, const MeshOptions& options,
                   const SweepLayout& layout, const MeshSpans& out) {
  assert(out.positions.size() >= layout.vertexCount() && out.normals.size() >= layout.vertexCount() &&
         out.uvs.size() >= layout.vertexCount() && out.indices.size() >= layout.indexCount() &&
         (out.nodeIds.empty() || out.nodeIds.size() >= layout.vertexCount()));
  const int radial = options.radialSegments;
  const size_t ring = static_cast<size_t>(radial) + 1;
  const RingTable table(radial);
  std::vector<RingSample> samples(layout.sampleCount());

  // 1. Spline samples and frames, one chain per task.
  parallelForRange(0, chains.size(), [&](size_t begin, size_t end) {
    std::vector<ChainPoint> pts;
    for (size_t c = begin; c < end; ++c) {
      size_t first = layout.sampleStart[c], last = layout.sampleStart[c + 1];
      if (first == last) continue;
      chainPoints(plant, chains.chain(c), pts);
      sampleChain(plant, chains.chain(c), pts, options.subdivisions,
                  std::span<RingSample>(samples.data() + first, last - first));
    }
  }, 64);

  // 2. Rings and the quads joining them, over all samples at once so that a single long stem
  // is split across threads too.
  const auto& sampleStart = layout.sampleStart;
  parallelForRange(0, layout.sampleCount(), [&](size_t begin, size_t end) {
    // The chain holding `begin`: the last chain whose first sample is <= begin (chains without
    // samples have equal starts and are skipped by upper_bound).
    size_t c = std::upper_bound(sampleStart.begin(), sampleStart.end(), static_cast<uint32_t>(begin)) -
               sampleStart.begin() - 1;
    for (size_t g = begin; g < end; ++g) {
      while (g >= sampleStart[c + 1]) ++c;
      size_t local = g - sampleStart[c];
      size_t vertex = layout.vertexStart[c] + local * ring;
      emitRing(samples[g], table, radial, vertex, out);
      if (g + 1 < sampleStart[c + 1]) {
        uint32_t* q = &out.indices[layout.indexStart[c] + local * 6 * radial];
        uint32_t v0 = out.baseVertex + static_cast<uint32_t>(vertex);
        for (int j = 0; j < radial; ++j) {
          uint32_t a = v0 + j, b = a + 1, d = a + static_cast<uint32_t>(ring), e = d + 1;
          // Counter-clockwise seen from outside: around the ring is tangent × normal.
          q[6 * j + 0] = a;
          q[6 * j + 1] = b;
          q[6 * j + 2] = d;
          q[6 * j + 3] = b;
          q[6 * j + 4] = e;
          q[6 * j + 5] = d;
        }
      }
    }
  }, 512);

  // 3. Caps after the rings of each chain.
  if (options.caps) {
    parallelForRange(0, chains.size(), [&](size_t begin, size_t end) {
      for (size_t c = begin; c < end; ++c) {
        size_t first = sampleStart[c], count = sampleStart[c + 1] - first;
        if (count == 0) continue;
        size_t vertex = layout.vertexStart[c] + count * ring;
        size_t index = layout.indexStart[c] + (count - 1) * 6 * radial;
        emitCap(samples[first], table, radial, false, vertex, index, out);
        emitCap(samples[first + count - 1], table, radial, true, vertex + ring, index + 3 * radial, out);
      }
    }, 256);
  }
}

void sweepBranches(const PlantModel& plant, const MeshOptions& options, TriangleMesh& mesh) {
  BranchChains chains = buildBranchChains(plant);
  SweepLayout layout = planSweep(plant, chains, options);
  // resize() keeps the capacity a reused mesh already has: no new memory for a smaller plant.
  mesh.positions.resize(layout.vertexCount());
  mesh.normals.resize(layout.vertexCount());
  mesh.uvs.resize(layout.vertexCount());
  mesh.indices.resize(layout.indexCount());
  mesh.nodeIds.resize(layout.vertexCount());
  sweepBranches(plant, chains, options, layout,
                {mesh.positions, mesh.normals, mesh.uvs, mesh.indices, 0, mesh.nodeIds});
}

TriangleMesh sweepBranches(const PlantModel& plant, const MeshOptions& options) {
  TriangleMesh mesh;
  sweepBranches(plant, options, mesh);
  return mesh;
}

}  // namespace tendril::mesh
