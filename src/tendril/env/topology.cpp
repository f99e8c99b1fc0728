#include "tendril/env/topology.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

namespace tendril::env {
namespace {

struct PositionHash {
  size_t operator()(const Vec3& p) const {
    uint32_t b[3];
    std::memcpy(b, p.data(), sizeof(b));
    uint64_t h = b[0] * 0x9e3779b97f4a7c15ull;
    h ^= (b[1] + 0x632be59bd9b4e019ull) * 0xc2b2ae3d27d4eb4full;
    h ^= (b[2] + 0x165667b19e3779f9ull) * 0x85ebca77c2b2ae63ull;
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

uint64_t edgeKey(uint32_t a, uint32_t b) {
  return (static_cast<uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
}

}  // namespace

WeldedMesh weld(const TriangleMesh& mesh) {
  WeldedMesh w;
  w.remap.resize(mesh.positions.size());
  std::unordered_map<Vec3, uint32_t, PositionHash> index;
  index.reserve(mesh.positions.size());
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    Vec3 p = mesh.positions[i];
    for (int k = 0; k < 3; ++k)
      if (p[k] == 0.0f) p[k] = 0.0f;  // -0 and +0 are the same point
    auto [it, inserted] = index.emplace(p, static_cast<uint32_t>(w.positions.size()));
    if (inserted) w.positions.push_back(p);
    w.remap[i] = it->second;
  }
  w.indices.resize(mesh.indices.size());
  for (size_t i = 0; i < mesh.indices.size(); ++i) w.indices[i] = w.remap[mesh.indices[i]];
  return w;
}

TopologyReport analyzeTopology(const WeldedMesh& m) {
  TopologyReport r;
  r.triangles = m.indices.size() / 3;
  // For every undirected edge: how many triangles use it, and the net direction count
  // (+1 for a->b with a<b, -1 for the reverse). A consistently wound closed manifold has
  // count 2 and net 0 on every edge.
  struct EdgeUse {
    int count = 0;
    int net = 0;
  };
  std::unordered_map<uint64_t, EdgeUse> edges;
  edges.reserve(m.indices.size());
  double volume = 0.0;
  for (size_t t = 0; t < r.triangles; ++t) {
    const uint32_t* tri = &m.indices[3 * t];
    const Vec3d a = m.positions[tri[0]].cast<double>();
    const Vec3d b = m.positions[tri[1]].cast<double>();
    const Vec3d c = m.positions[tri[2]].cast<double>();
    if ((b - a).cross(c - a).squaredNorm() == 0.0) ++r.degenerateTriangles;
    volume += a.dot(b.cross(c)) / 6.0;
    for (int k = 0; k < 3; ++k) {
      uint32_t u = tri[k], v = tri[(k + 1) % 3];
      if (u == v) continue;
      EdgeUse& e = edges[edgeKey(u, v)];
      e.count++;
      e.net += (u < v) ? 1 : -1;
    }
  }
  for (const auto& [key, e] : edges) {
    if (e.count == 1) ++r.boundaryEdges;
    else if (e.count > 2) ++r.nonManifoldEdges;
    else if (e.net != 0) ++r.inconsistentEdges;
  }
  r.signedVolume = volume;
  return r;
}

std::vector<uint32_t> triangleNeighbors(const WeldedMesh& m) {
  const size_t nt = m.indices.size() / 3;
  std::vector<uint32_t> out(3 * nt, kNoNeighbor);
  // Every edge's triangle-edge slots; only edges with exactly two get linked.
  struct Use {
    uint32_t slots[2] = {kNoNeighbor, kNoNeighbor};
    int count = 0;
  };
  std::unordered_map<uint64_t, Use> edges;
  edges.reserve(3 * nt);
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      Use& e = edges[edgeKey(m.indices[3 * t + k], m.indices[3 * t + (k + 1) % 3])];
      if (e.count < 2) e.slots[e.count] = uint32_t(3 * t + k);
      ++e.count;
    }
  for (const auto& [key, e] : edges) {
    if (e.count != 2) continue;
    out[e.slots[0]] = e.slots[1] / 3;
    out[e.slots[1]] = e.slots[0] / 3;
  }
  return out;
}

ClosestOnTriangle closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return {a, TriangleFeature::VertexA};
  const Vec3 bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0f && d4 <= d3) return {b, TriangleFeature::VertexB};
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
    const float v = d1 / (d1 - d3);
    return {a + v * ab, TriangleFeature::EdgeAB};
  }
  const Vec3 cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0f && d5 <= d6) return {c, TriangleFeature::VertexC};
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
    const float w = d2 / (d2 - d6);
    return {a + w * ac, TriangleFeature::EdgeCA};
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
    const float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {b + w * (c - b), TriangleFeature::EdgeBC};
  }
  const float denom = 1.0f / (va + vb + vc);
  const float v = vb * denom, w = vc * denom;
  return {a + ab * v + ac * w, TriangleFeature::Face};
}

Vec3 Pseudonormals::at(uint32_t t, TriangleFeature f, const uint32_t* tri) const {
  switch (f) {
    case TriangleFeature::Face: return face[t];
    case TriangleFeature::EdgeAB: return edge[3 * t + 0];
    case TriangleFeature::EdgeBC: return edge[3 * t + 1];
    case TriangleFeature::EdgeCA: return edge[3 * t + 2];
    case TriangleFeature::VertexA: return vertex[tri[0]];
    case TriangleFeature::VertexB: return vertex[tri[1]];
    case TriangleFeature::VertexC: return vertex[tri[2]];
  }
  return face[t];
}

Pseudonormals computePseudonormals(const WeldedMesh& m) {
  const size_t nt = m.indices.size() / 3;
  Pseudonormals pn;
  pn.face.resize(nt);
  pn.edge.assign(3 * nt, Vec3::Zero());
  std::vector<Vec3d> vertex(m.positions.size(), Vec3d::Zero());
  std::unordered_map<uint64_t, Vec3d> edgeSum;
  edgeSum.reserve(3 * nt);
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* tri = &m.indices[3 * t];
    Vec3d p[3] = {m.positions[tri[0]].cast<double>(), m.positions[tri[1]].cast<double>(),
                  m.positions[tri[2]].cast<double>()};
    Vec3d n = (p[1] - p[0]).cross(p[2] - p[0]);
    double len = n.norm();
    n = len > 0.0 ? Vec3d(n / len) : Vec3d::Zero();
    pn.face[t] = n.cast<float>();
    for (int k = 0; k < 3; ++k) {
      // Angle-weighted vertex normal: weight = interior angle at the vertex.
      Vec3d e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
      double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      vertex[tri[k]] += angle * n;
      // try_emplace: a default-constructed Eigen vector would be uninitialised.
      edgeSum.try_emplace(edgeKey(tri[k], tri[(k + 1) % 3]), Vec3d::Zero()).first->second += n;
    }
  }
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* tri = &m.indices[3 * t];
    for (int k = 0; k < 3; ++k) {
      Vec3d e = edgeSum.at(edgeKey(tri[k], tri[(k + 1) % 3]));
      double len = e.norm();
      pn.edge[3 * t + k] = (len > 0.0 ? Vec3d(e / len) : Vec3d::Zero()).cast<float>();
    }
  }
  pn.vertex.resize(vertex.size());
  for (size_t i = 0; i < vertex.size(); ++i) {
    double len = vertex[i].norm();
    pn.vertex[i] = (len > 0.0 ? Vec3d(vertex[i] / len) : Vec3d::Zero()).cast<float>();
  }
  return pn;
}

}  // namespace tendril::env
