#include "tendril/mesh/lod.h"

#include "tendril/core/error.h"
#include "tendril/core/parallel.h"
#include "tendril/mesh/branch_sweep.h"
#include "tendril/mesh/leaf_mesh.h"
#include "tendril/mesh/primitive_mesh.h"

#include <fmt/format.h>
#include <meshoptimizer.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <tuple>

namespace tendril::mesh {

using plant::PlantModel;

void validateLodSettings(const LodSettings& lods, const std::string& source) {
  if (lods.levels < 1 || lods.levels > kMaxLods)
    throw Error(source, "lods", fmt::format("must be an integer in [1, {}], got {}", kMaxLods, lods.levels));
  if (!(lods.ratio >= 0.01f && lods.ratio <= 1.0f))
    throw Error(source, "lod_ratio", fmt::format("must be a number in [0.01, 1], got {}", lods.ratio));
  if (lods.triangles.empty()) return;
  if (lods.triangles.size() != size_t(lods.levels - 1))
    throw Error(source, "lod_triangles",
                fmt::format("has {} budget(s) but lods is {}: give one per level below LOD0", lods.triangles.size(),
                            lods.levels));
  for (size_t i = 0; i < lods.triangles.size(); ++i) {
    if (lods.triangles[i] == 0)
      throw Error(source, fmt::format("lod_triangles/{}", i), "must be a positive number of triangles, got 0");
    if (i > 0 && lods.triangles[i] > lods.triangles[i - 1])
      throw Error(source, fmt::format("lod_triangles/{}", i),
                  fmt::format("must not exceed the budget before it ({}), got {}", lods.triangles[i - 1],
                              lods.triangles[i]));
  }
}

uint64_t lodBudget(const LodSettings& lods, size_t lod0Triangles, int level) {
  if (!lods.triangles.empty()) return lods.triangles.at(size_t(level - 1));
  return uint64_t(std::floor(double(lod0Triangles) * std::pow(double(lods.ratio), double(level))));
}

std::vector<float> lodScreenCoverage(const std::vector<size_t>& triangles) {
  const size_t n = triangles.size();
  std::vector<float> coverage(n, 0.0f);
  if (n == 0 || triangles[0] == 0) return coverage;
  for (size_t k = 0; k + 1 < n; ++k) coverage[k] = float(std::sqrt(double(triangles[k + 1]) / double(triangles[0])));
  coverage[n - 1] = n >= 2 ? std::min(0.01f, 0.5f * coverage[n - 2]) : 0.01f;
  return coverage;
}

namespace {

// Per node, its place in the branch chains (chain by chain, base to tip): an order that runs
// along the branches.
std::vector<uint32_t> chainRank(const PlantModel& plant) {
  const BranchChains chains = buildBranchChains(plant);
  std::vector<uint32_t> rank(plant.nodeCount(), 0);
  for (size_t i = 0; i < chains.nodes.size(); ++i) rank[size_t(chains.nodes[i])] = uint32_t(i);
  return rank;
}

uint32_t reverseBits(uint32_t v) {
  v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
  v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
  v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
  v = ((v >> 8) & 0x00ff00ffu) | ((v & 0x00ff00ffu) << 8);
  return (v >> 16) | (v << 16);
}

size_t leafTriangles(const PlantMesh& m) {
  size_t n = 0;
  for (const TriangleMesh& l : m.leaves) n += l.triangleCount();
  return n;
}

size_t primitiveTriangles(const PlantMesh& m) {
  size_t n = 0;
  for (const PrimitiveGroup& g : m.primitives) n += g.mesh.triangleCount();
  return n;
}

// At most `target` triangles: meshopt_simplify (edge collapses that keep the topology, attribute
// seams and borders, in order of least error, with no error limit), and where that stops short,
// meshopt_simplifySloppy (vertex clustering) from the original triangles.
// With `keepBorders`, open surfaces (a leaf's blade) first keep their outline
// (meshopt_SimplifyLockBorder), and lose it only if the target needs that.
void simplifyTo(TriangleMesh& mesh, size_t target, bool allowSloppy, LodLevel& level, bool keepBorders = false) {
  if (mesh.triangleCount() <= target) return;
  const float* positions = mesh.positions.data()->data();
  std::vector<uint32_t> out(mesh.indices.size());
  size_t n = 3 * target + 1;
  if (keepBorders)
    n = meshopt_simplify(out.data(), mesh.indices.data(), mesh.indices.size(), positions, mesh.vertexCount(),
                         sizeof(Vec3), 3 * target, 1.0f, meshopt_SimplifyLockBorder, nullptr);
  if (n > 3 * target)
    n = meshopt_simplify(out.data(), mesh.indices.data(), mesh.indices.size(), positions, mesh.vertexCount(),
                         sizeof(Vec3), 3 * target, 1.0f, 0, nullptr);
  level.simplified = true;
  if (n > 3 * target && allowSloppy) {
    level.sloppy = true;
    auto sloppy = [&](size_t ask, std::vector<uint32_t>& into) {
      return meshopt_simplifySloppy(into.data(), mesh.indices.data(), mesh.indices.size(), positions,
                                    mesh.vertexCount(), sizeof(Vec3), 3 * ask, 1.0f, nullptr);
    };
    n = sloppy(target, out);
    // Clustering on a grid comes in steps and may land far below the target: ask for more
    // while the answer stays within it.
    std::vector<uint32_t> more(mesh.indices.size());
    size_t ask = target;
    for (int tries = 0; tries < 6 && n < (3 * target) * 7 / 10; ++tries) {
      ask = ask + std::max<size_t>(1, ask / 2);
      if (3 * ask > mesh.indices.size()) break;
      const size_t m = sloppy(ask, more);
      if (m > 3 * target) break;
      if (m > n) {
        n = m;
        out.swap(more);
      }
    }
  }
  out.resize(n);
  mesh.indices.swap(out);
}

template <class F>
void forEachMesh(PlantMesh& m, F&& f) {
  f(m.bark);
  for (TriangleMesh& l : m.leaves) f(l);
  for (PrimitiveGroup& g : m.primitives) f(g.mesh);
}

// A level's primitive groups in the order of LOD0's (groups are made in order of first use,
// and a thinned plant may use fewer looks): each at the index of LOD0's group of the same
// colour and texture, empty where the level has none of it.
void alignPrimitiveGroups(std::vector<PrimitiveGroup>& groups, const std::vector<PrimitiveGroup>& lod0) {
  std::vector<PrimitiveGroup> aligned(lod0.size());
  for (size_t i = 0; i < lod0.size(); ++i) {
    aligned[i].name = lod0[i].name;
    aligned[i].color = lod0[i].color;
    aligned[i].texture = lod0[i].texture;
  }
  for (PrimitiveGroup& g : groups)
    for (size_t i = 0; i < lod0.size(); ++i)
      if (lod0[i].color == g.color && lod0[i].texture == g.texture) {
        aligned[i].mesh = std::move(g.mesh);
        break;
      }
  groups = std::move(aligned);
}


// A primitive's kind: its mesh's texture and size (the seeds of a seed head, whatever their
// colours). Kinds with fewer than kMinThinned instances are not thinned.
using PrimitiveKind = std::tuple<std::string, size_t, size_t>;
constexpr size_t kMinThinned = 16;

PrimitiveKind kindOf(const PlantModel& plant, const plant::Primitive& pr) {
  const plant::PrimitiveMesh* pm = pr.mesh < plant.meshes.size() ? &plant.meshes[pr.mesh] : nullptr;
  return {pm ? pm->texture : std::string(), pm ? pm->mesh.vertexCount() : 0, pm ? pm->mesh.indices.size() : 0};
}

// Per group of `groups` (LOD0's), whether every primitive of `plant` in it is of a kind too few
// to thin (and it has some).
std::vector<uint8_t> wholeGroups(const PlantModel& plant, const std::vector<PrimitiveGroup>& groups) {
  std::map<PrimitiveKind, size_t> instances;
  for (const plant::Primitive& pr : plant.primitives) ++instances[kindOf(plant, pr)];
  std::map<std::tuple<float, float, float, std::string>, size_t> groupOf;
  for (size_t g = groups.size(); g-- > 0;)
    groupOf[{groups[g].color.x(), groups[g].color.y(), groups[g].color.z(), groups[g].texture}] = g;
  std::vector<uint8_t> some(groups.size(), 0), thinnable(groups.size(), 0);
  for (const plant::Primitive& pr : plant.primitives) {
    if (pr.mesh >= plant.meshes.size()) continue;
    const plant::PrimitiveMesh& pm = plant.meshes[pr.mesh];
    const auto it = groupOf.find({pm.color.x(), pm.color.y(), pm.color.z(), pm.texture});
    if (it == groupOf.end()) continue;
    some[it->second] = 1;
    if (instances[kindOf(plant, pr)] >= kMinThinned) thinnable[it->second] = 1;
  }
  std::vector<uint8_t> whole(groups.size(), 0);
  for (size_t g = 0; g < groups.size(); ++g) whole[g] = some[g] && !thinnable[g];
  return whole;
}
}  // namespace

PlantModel pruneTwigs(const PlantModel& plant, float minLength, std::vector<uint32_t>* keptNodes) {
  const size_t n = plant.nodeCount();
  // Stem length of each node's whole subtree (children come after their parents).
  std::vector<double> subtree(plant.length.begin(), plant.length.end());
  for (size_t i = n; i-- > 0;)
    if (plant.parent[i] >= 0) subtree[size_t(plant.parent[i])] += subtree[i];
  std::vector<uint8_t> chainStart(n, 0);
  const BranchChains chains = buildBranchChains(plant);
  for (size_t c = 0; c < chains.size(); ++c)
    if (!chains.chain(c).empty()) chainStart[size_t(chains.chain(c)[0])] = 1;

  PlantModel out;
  out.name = plant.name;
  out.species = plant.species;
  out.bark = plant.bark;
  out.leafShapes = plant.leafShapes;
  out.meshes = plant.meshes;
  out.reserve(n, plant.leafCount());
  std::vector<int32_t> newIndex(n, -1);
  std::vector<uint32_t> host(n, 0);  // the kept node standing in for each node (itself if kept)
  if (keptNodes) keptNodes->clear();
  for (size_t i = 0; i < n; ++i) {
    const int32_t p = plant.parent[i];
    const bool pruned = p >= 0 && (newIndex[size_t(p)] < 0 || (chainStart[i] && subtree[i] < double(minLength)));
    if (pruned) {
      host[i] = host[size_t(p)];
      continue;
    }
    host[i] = uint32_t(i);
    newIndex[i] = out.addNode({plant.position[i], plant.orientation[i], plant.length[i], plant.radius[i],
                               p >= 0 ? newIndex[size_t(p)] : -1, plant.age[i], plant.order[i], plant.flags[i]});
    if (keptNodes) keptNodes->push_back(uint32_t(i));
  }

  const bool motion = plant.leafMotion.size() == plant.leafCount();
  for (size_t l = 0; l < plant.leafCount(); ++l) {
    const size_t node = size_t(plant.leafNode[l]);
    const size_t h = host[node];
    PlantModel::LeafDef d{newIndex[h],           plant.leafOffset[l],    plant.leafRotation[l], plant.leafSize[l],
                          plant.leafThickness[l], plant.leafPetiole[l], plant.leafShape[l]};
    if (h != node) {  // re-hung on its host, where it was
      const Quat hostFromWorld = plant.orientation[h].conjugate();
      d.offset = hostFromWorld * (plant.position[node] + plant.orientation[node] * plant.leafOffset[l] - plant.position[h]);
      d.rotation = (hostFromWorld * plant.orientation[node] * plant.leafRotation[l]).normalized();
    }
    const int32_t added = out.addLeaf(d);
    if (motion) out.leafMotion[size_t(added)] = plant.leafMotion[l];
  }

  out.primitives = plant.primitives;
  for (plant::Primitive& pr : out.primitives) {
    if (pr.node < 0) continue;
    const size_t node = size_t(pr.node);
    const size_t h = host[node];
    if (h != node)
      pr.nodeFromPrimitive = worldFromNode(plant, int32_t(h)).inverse() * worldFromNode(plant, pr.node) * pr.nodeFromPrimitive;
    pr.node = newIndex[h];
  }
  return out;
}

float thinLeaves(PlantModel& plant, size_t keep) {
  const size_t count = plant.leafCount();
  if (keep >= count) return 1.0f;
  const std::vector<uint32_t> rank = chainRank(plant);
  const size_t shapes = leafShapeCount(plant);
  // Each shape's leaves along the branches.
  std::vector<std::vector<uint32_t>> byShape(shapes);
  for (size_t l = 0; l < count; ++l) byShape[plant.leafShape[l]].push_back(uint32_t(l));
  std::vector<uint8_t> kept(count, 0);
  std::vector<float> scaleOf(shapes, 1.0f);
  for (size_t s = 0; s < shapes; ++s) {
    std::vector<uint32_t>& leaves = byShape[s];
    if (leaves.empty()) continue;
    std::stable_sort(leaves.begin(), leaves.end(), [&](uint32_t a, uint32_t b) {
      return rank[size_t(plant.leafNode[a])] < rank[size_t(plant.leafNode[b])];
    });
    const size_t m = std::clamp<size_t>(
        size_t(std::llround(double(keep) * double(leaves.size()) / double(count))), 1, leaves.size());
    // The m leaves whose places along the branches come first in bit-reversed order (a van der
    // Corput sequence): spread evenly over the run, and nested as m shrinks.
    std::vector<uint32_t> order(leaves.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [](uint32_t a, uint32_t b) { return reverseBits(a) < reverseBits(b); });
    double all = 0.0, chosen = 0.0;
    for (uint32_t l : leaves) all += double(plant.leafSize[l]) * double(plant.leafSize[l]);
    for (size_t k = 0; k < m; ++k) {
      const uint32_t l = leaves[order[k]];
      kept[l] = 1;
      chosen += double(plant.leafSize[l]) * double(plant.leafSize[l]);
    }
    scaleOf[s] = chosen > 0.0 ? float(std::sqrt(all / chosen)) : 1.0f;
  }
  std::vector<uint32_t> keptList;
  double scaleSum = 0.0;
  for (size_t l = 0; l < count; ++l) {
    if (!kept[l]) continue;
    keptList.push_back(uint32_t(l));
    const float scale = scaleOf[plant.leafShape[l]];
    scaleSum += scale;
    // Larger about the blade's centre: the petiole, then the attachment, moves back by half the growth.
    const float size = plant.leafSize[l], grown = size * scale;
    const float back = 0.5f * (grown - size);
    const float fromPetiole = std::min(plant.leafPetiole[l], back);
    plant.leafPetiole[l] -= fromPetiole;
    plant.leafOffset[l] -= (back - fromPetiole) * (plant.leafRotation[l] * Vec3::UnitY());
    plant.leafSize[l] = grown;
  }
  plant.keepLeaves(keptList);
  return keptList.empty() ? 1.0f : float(scaleSum / double(keptList.size()));
}

float thinPrimitives(PlantModel& plant, size_t keep) {
  const size_t count = plant.primitives.size();
  if (keep >= count) return 1.0f;
  const std::vector<uint32_t> rank = chainRank(plant);
  auto rankOf = [&](uint32_t i) {
    const int32_t node = plant.primitives[i].node;
    return node < 0 ? 0u : rank[size_t(node)];
  };
  // Instances of one kind (texture and mesh size: the seeds of a seed head, whatever their
  // colours) along the branches. Kinds with few instances (a head, a few large leaves) stay whole.
  std::map<PrimitiveKind, std::vector<uint32_t>> byKind;
  std::vector<double> meshArea(plant.meshes.size(), 0.0);
  for (size_t m = 0; m < plant.meshes.size(); ++m) {
    const TriangleMesh& t = plant.meshes[m].mesh;
    for (size_t k = 0; k + 2 < t.indices.size(); k += 3)
      meshArea[m] += 0.5 * double((t.positions[t.indices[k + 1]] - t.positions[t.indices[k]])
                                      .cross(t.positions[t.indices[k + 2]] - t.positions[t.indices[k]])
                                      .norm());
  }
  for (size_t i = 0; i < count; ++i) byKind[kindOf(plant, plant.primitives[i])].push_back(uint32_t(i));
  std::vector<uint8_t> kept(count, 0);
  std::vector<float> scaleOf(count, 1.0f);
  // An instance's surface: its mesh's, grown as its transform's determinant to the power 2/3.
  auto area = [&](uint32_t i) {
    const plant::Primitive& pr = plant.primitives[i];
    return (pr.mesh < meshArea.size() ? meshArea[pr.mesh] : 0.0) *
           std::pow(std::abs(double(pr.nodeFromPrimitive.topLeftCorner<3, 3>().determinant())), 2.0 / 3.0);
  };
  for (auto& [kind, instances] : byKind) {
    std::stable_sort(instances.begin(), instances.end(), [&](uint32_t a, uint32_t b) { return rankOf(a) < rankOf(b); });
    const size_t m = instances.size() < kMinThinned ? instances.size()
                                                    : std::clamp<size_t>(size_t(std::llround(double(keep) *
                                                                                              double(instances.size()) /
                                                                                              double(count))),
                                                                         1, instances.size());
    std::vector<uint32_t> order(instances.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [](uint32_t a, uint32_t b) { return reverseBits(a) < reverseBits(b); });
    double all = 0.0, chosen = 0.0;
    for (uint32_t i : instances) all += area(i);
    for (size_t k = 0; k < m; ++k) {
      kept[instances[order[k]]] = 1;
      chosen += area(instances[order[k]]);
    }
    const float scale = chosen > 0.0 ? float(std::sqrt(all / chosen)) : 1.0f;
    for (uint32_t i : instances) scaleOf[i] = scale;
  }
  std::vector<plant::Primitive> out;
  double scaleSum = 0.0;
  for (size_t i = 0; i < count; ++i) {
    if (!kept[i]) continue;
    plant::Primitive pr = plant.primitives[i];
    // Larger about the centre of its mesh's bounds.
    const float scale = scaleOf[i];
    scaleSum += scale;
    const Vec3 c = pr.mesh < plant.meshes.size() ? plant.meshes[pr.mesh].mesh.bounds().center() : Vec3::Zero();
    Mat4 about = Mat4::Identity();
    about.topLeftCorner<3, 3>() *= scale;
    about.topRightCorner<3, 1>() = c - scale * c;
    pr.nodeFromPrimitive = pr.nodeFromPrimitive * about;
    out.push_back(pr);
  }
  plant.primitives = std::move(out);
  return plant.primitives.empty() ? 1.0f : float(scaleSum / double(plant.primitives.size()));
}

namespace {

// Meshes are ordered in runs of about this many triangles that share no vertices (a branch
// chain's tube, a run of leaf quads), independently and in parallel; the runs depend only on
// the mesh, never on the thread count.
constexpr size_t kOrderRunTriangles = size_t(1) << 16;

// One run: triangles [begin, end) using only vertices [vertexBegin, vertexEnd).
struct OrderRun {
  size_t begin = 0, end = 0;
  uint32_t vertexBegin = 0, vertexEnd = 0;
};

// Cuts the triangles, in their order, into runs of at least kOrderRunTriangles (the last one
// aside) at places where every vertex used before is below every vertex used after. A mesh
// that has no such place is one run.
std::vector<OrderRun> orderRuns(const TriangleMesh& mesh) {
  const size_t triangles = mesh.indices.size() / 3;
  const uint32_t vertices = uint32_t(mesh.vertexCount());
  if (triangles < 2 * kOrderRunTriangles) return {{0, triangles, 0, vertices}};
  const uint32_t* idx = mesh.indices.data();
  // The smallest vertex used by triangle t and every one after it.
  std::vector<uint32_t> suffixMin(triangles + 1);
  suffixMin[triangles] = vertices;
  for (size_t t = triangles; t-- > 0;)
    suffixMin[t] = std::min({suffixMin[t + 1], idx[3 * t], idx[3 * t + 1], idx[3 * t + 2]});
  std::vector<OrderRun> runs;
  size_t start = 0;
  uint32_t vertexStart = 0, usedEnd = 0;  // one past the largest vertex used so far
  for (size_t t = 0; t < triangles; ++t) {
    if (t - start >= kOrderRunTriangles && triangles - t >= kOrderRunTriangles / 2 && usedEnd <= suffixMin[t]) {
      runs.push_back({start, t, vertexStart, suffixMin[t]});
      start = t;
      vertexStart = suffixMin[t];
    }
    usedEnd = std::max({usedEnd, idx[3 * t] + 1, idx[3 * t + 1] + 1, idx[3 * t + 2] + 1});
  }
  runs.push_back({start, triangles, vertexStart, vertices});
  return runs;
}

template <class T>
void remapArrayParallel(std::vector<T>& v, const std::vector<uint32_t>& remap, size_t unique) {
  if (v.empty()) return;
  std::vector<T> out(unique);
  parallelForRange(0, remap.size(), [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i)
      if (remap[i] != ~0u) out[remap[i]] = v[i];
  }, size_t(1) << 15);
  v.swap(out);
}

}  // namespace

void optimizeMeshOrder(TriangleMesh& mesh) {
  const size_t vertices = mesh.vertexCount();
  if (vertices == 0) return;
  const std::vector<OrderRun> runs = orderRuns(mesh);
  // Each run on its own: its triangles for the vertex cache, then its vertices in the order the
  // triangles use them, numbered after the runs before it.
  std::vector<uint32_t> cached(mesh.indices.size());
  std::vector<uint32_t> remap(vertices, ~0u);
  std::vector<size_t> unique(runs.size() + 1, 0);
  parallelFor(0, runs.size(), [&](size_t r) {
    const OrderRun& run = runs[r];
    const size_t first = 3 * run.begin, count = 3 * (run.end - run.begin);
    const size_t runVertices = run.vertexEnd - run.vertexBegin;
    if (count == 0) return;
    std::vector<uint32_t> local(mesh.indices.begin() + ptrdiff_t(first), mesh.indices.begin() + ptrdiff_t(first + count));
    if (run.vertexBegin > 0)
      for (uint32_t& i : local) i -= run.vertexBegin;
    meshopt_optimizeVertexCache(cached.data() + first, local.data(), count, runVertices);
    unique[r + 1] = meshopt_optimizeVertexFetchRemap(remap.data() + run.vertexBegin, cached.data() + first, count,
                                                     runVertices);
  }, 1);
  for (size_t r = 0; r < runs.size(); ++r) unique[r + 1] += unique[r];
  parallelFor(0, runs.size(), [&](size_t r) {
    const OrderRun& run = runs[r];
    const uint32_t offset = uint32_t(unique[r]);
    for (uint32_t v = run.vertexBegin; v < run.vertexEnd; ++v)
      if (remap[v] != ~0u) remap[v] += offset;
    for (size_t i = 3 * run.begin; i < 3 * run.end; ++i) mesh.indices[i] = remap[run.vertexBegin + cached[i]];
  }, 1);
  const size_t total = unique[runs.size()];
  tbb::parallel_invoke([&] { remapArrayParallel(mesh.positions, remap, total); },
                       [&] { remapArrayParallel(mesh.normals, remap, total); },
                       [&] { remapArrayParallel(mesh.uvs, remap, total); },
                       [&] { remapArrayParallel(mesh.nodeIds, remap, total); });
}

void optimizeMeshOrder(PlantMesh& mesh) {
  std::vector<TriangleMesh*> parts;
  forEachMesh(mesh, [&](TriangleMesh& m) { parts.push_back(&m); });
  parallelFor(0, parts.size(), [&](size_t i) { optimizeMeshOrder(*parts[i]); }, 1);
}

namespace {

// What one level is made with, from its budget and the level above's plan alone (a pure
// function of them, so levels can be made in parallel on planned budgets and checked after).
struct LevelPlan {
  uint64_t budget = 0;
  bool copy = false;       // budget >= LOD0's triangles: LOD0 as it is
  MeshOptions tess;
  float twig = 0.0f;
  size_t keep = 0;         // leaves
  double f = 1.0;          // budget / LOD0's triangles
  bool operator==(const LevelPlan& o) const {
    return budget == o.budget && copy == o.copy && tess.radialSegments == o.tess.radialSegments &&
           tess.subdivisions == o.tess.subdivisions && tess.leafSubdivisions == o.tess.leafSubdivisions &&
           tess.caps == o.tess.caps && twig == o.twig && keep == o.keep && f == o.f;
  }
};

// What buildLods needs of the plant and LOD0.
struct ChainBasis {
  size_t n0 = 0, prim0 = 0, bark0 = 0, leaves = 0, shapesInUse = 0;
  double size = 0.0;  // the plant's bounding box diagonal
};

LevelPlan planLevel(const ChainBasis& b, const MeshOptions& options, uint64_t budget, const MeshOptions& tessAbove,
                    float twigAbove) {
  LevelPlan plan;
  plan.budget = budget;
  plan.tess = tessAbove;
  plan.twig = twigAbove;
  if (budget >= b.n0) {  // nothing to take away
    plan.copy = true;
    return plan;
  }
  const double f = double(budget) / double(b.n0);
  plan.f = f;
  const double halvings = std::log2(1.0 / std::max(f, 1e-9));
  // Leaves fall more gently than the budget (√f of them, each larger), within what is left
  // after the primitives' share and half the bark's; one quad each. (Pruning re-hangs
  // leaves, so their number does not depend on it.)
  const double leafRoom = std::max(0.0, double(budget) - f * double(b.prim0) - 0.5 * f * double(b.bark0));
  size_t keep = size_t(std::min(double(b.leaves) * std::sqrt(f), 0.5 * leafRoom));
  plan.keep = std::min(b.leaves, std::max(keep, b.shapesInUse));
  // Tessellation for the bark's share of what is left: radial segments and subdivisions
  // each by its square root, never finer than the level above.
  const double barkRoom = std::max(0.0, double(budget) - double(2 * plan.keep) - f * double(b.prim0));
  const double g = b.bark0 > 0 ? std::min(1.0, barkRoom / double(b.bark0)) : 1.0;
  plan.tess.radialSegments =
      std::clamp(int(std::lround(options.radialSegments * std::sqrt(g))), 3, tessAbove.radialSegments);
  plan.tess.subdivisions = std::clamp(int(std::lround(options.subdivisions * std::sqrt(g))), 1, tessAbove.subdivisions);
  plan.tess.leafSubdivisions = 1;
  // Twigs: side branches with less stem than 0.5 % of the plant's size per halving of the
  // triangles go (too small to see where this level is drawn), never fewer than the level
  // above pruned. Pruning harder to meet the budget took whole branches' worth of shape
  // away; the simplifier below does that job better.
  plan.twig = std::max(twigAbove, float(0.005 * b.size * halvings));
  return plan;
}

// Makes (and orders) one level by its plan.
void makeLevel(const PlantModel& plant, const MeshOptions& options, const PlantMesh& lod0, const ChainBasis& b,
               const LevelPlan& plan, LodLevel& level) {
  PlantMesh reuse = std::move(level.mesh);
  level = LodLevel();
  level.mesh = std::move(reuse);
  level.budget = plan.budget;
  if (plan.copy) {
    level.mesh = lod0;
    level.options = options;
    level.leaves = plant.leafCount();
    level.primitives = plant.primitives.size();
  } else {
    const double f = plan.f;
    const MeshOptions& tess = plan.tess;
    level.options = tess;
    std::vector<uint32_t> keptNodes;
    PlantModel reduced = pruneTwigs(plant, plan.twig, &keptNodes);
    // A coarser ring is a polygon inscribed in the branch's circle and narrower than LOD0's
    // (a triangle's mean width is 0.83 of the circle's, an octagon's 0.97): the radii grow so
    // that the mean width (the perimeter over π) is LOD0's, and thin stems keep their outline.
    if (tess.radialSegments != options.radialSegments) {
      auto perimeter = [](int n) { return double(n) * std::sin(3.14159265358979323846 / double(n)); };
      const float widen = float(perimeter(options.radialSegments) / perimeter(tess.radialSegments));
      for (float& r : reduced.radius) r *= widen;
    }
    level.twigLength = plan.twig;
    level.prunedNodes = plant.nodeCount() - reduced.nodeCount();
    level.leafScale = thinLeaves(reduced, plan.keep);
    level.leaves = reduced.leafCount();
    // Primitives (a graph plant's leaves, seeds, petals) thin as leaves do, √f of them.
    const PlantModel unthinned = reduced;
    const size_t primitiveCount = reduced.primitives.size();
    size_t primitiveKeep = std::max<size_t>(1, size_t(double(primitiveCount) * std::sqrt(f)));
    level.primitiveScale = thinPrimitives(reduced, primitiveKeep);
    level.primitives = reduced.primitives.size();
    buildPlantMesh(reduced, tess, level.mesh);
    // Vertex node ids name the plant's own nodes, not the pruned copy's.
    auto ownNodeIds = [&](TriangleMesh& m) {
      for (uint32_t& id : m.nodeIds) id = keptNodes[id];
    };
    forEachMesh(level.mesh, ownNodeIds);
    alignPrimitiveGroups(level.mesh.primitives, lod0.primitives);
    const size_t bark0 = b.bark0;
    // Groups of LOD0 whose primitives are all of kinds too few to thin (a head, a few large
    // leaves) stay whole while the budget allows: each is a large part of the outline, and
    // simplifying a curved, folded blade pulls its outline in even where its border is locked.
    // The others (seeds, petals) take the rest of the primitives' share, and are thinned
    // further where the simplifier stops short (small closed shapes), up to three times.
    const std::vector<uint8_t> whole = wholeGroups(unthinned, lod0.primitives);
    size_t wholeTriangles = 0, otherTriangles0 = 0;
    for (size_t g2 = 0; g2 < lod0.primitives.size(); ++g2) {
      if (whole[g2]) wholeTriangles += level.mesh.primitives[g2].mesh.triangleCount();
      else otherTriangles0 += lod0.primitives[g2].mesh.triangleCount();
    }
    // What the whole groups take beyond their share comes out of the others' and the bark's,
    // in proportion to what they had at LOD0.
    const double rest = double(level.budget) - double(leafTriangles(level.mesh)) - double(wholeTriangles);
    const double otherShare =
        otherTriangles0 > 0 ? std::max(0.0, rest) * double(otherTriangles0) / double(otherTriangles0 + bark0) : 0.0;
    const double otherF = otherTriangles0 > 0 ? otherShare / double(otherTriangles0) : 0.0;
    for (int round = 0;; ++round) {
      for (size_t g2 = 0; g2 < level.mesh.primitives.size() && g2 < lod0.primitives.size(); ++g2)
        if (!whole[g2])
          simplifyTo(level.mesh.primitives[g2].mesh,
                     size_t(std::floor(otherF * double(lod0.primitives[g2].mesh.triangleCount()))), false, level,
                     true);
      const size_t now = primitiveTriangles(level.mesh);
      if (double(now) <= double(wholeTriangles) + otherShare || round == 3 || primitiveKeep <= 1) break;
      // Never fewer than the budget's fraction of them (the kept ones of a kind at most about
      // 1/√f times as large), so that the enlarged ones stay within the plant's bounds.
      const size_t fewest = std::max<size_t>(1, size_t(std::ceil(f * double(primitiveCount))));
      if (primitiveKeep <= fewest) break;
      primitiveKeep = std::max<size_t>(
          fewest, size_t(double(primitiveKeep) * otherShare / std::max(1.0, double(now) - double(wholeTriangles))));
      reduced.primitives = unthinned.primitives;
      const float scale = thinPrimitives(reduced, primitiveKeep);
      if (reduced.primitives.size() == level.primitives) break;  // only kinds too few to thin are left
      level.primitiveScale = scale;
      level.primitives = reduced.primitives.size();
      level.mesh.primitives = buildPrimitiveMeshes(reduced);
      for (PrimitiveGroup& g2 : level.mesh.primitives) ownNodeIds(g2.mesh);
      alignPrimitiveGroups(level.mesh.primitives, lod0.primitives);
    }
    // The bark keeps at least half its share of the budget, so that it never vanishes for
    // primitives that cannot be simplified further without clustering.
    const size_t used = leafTriangles(level.mesh) + primitiveTriangles(level.mesh);
    const size_t barkFloor = size_t(0.5 * f * double(bark0));
    simplifyTo(level.mesh.bark, std::max(level.budget > used ? size_t(level.budget - used) : 0, barkFloor), true,
               level);
    // Still over: the groups that may be simplified (the whole ones only if that is not enough)
    // share what is left.
    for (int pass = 0; pass < 2 && level.mesh.triangleCount() > level.budget; ++pass) {
      size_t other = leafTriangles(level.mesh) + level.mesh.bark.triangleCount(), prims = 0;
      for (size_t g2 = 0; g2 < level.mesh.primitives.size(); ++g2)
        (pass == 0 && whole[g2] ? other : prims) += level.mesh.primitives[g2].mesh.triangleCount();
      const size_t room = level.budget > other ? size_t(level.budget - other) : 0;
      for (size_t g2 = 0; g2 < level.mesh.primitives.size(); ++g2) {
        TriangleMesh& group = level.mesh.primitives[g2].mesh;
        if (prims > 0 && !(pass == 0 && whole[g2]))
          simplifyTo(group, size_t(double(room) * double(group.triangleCount()) / double(prims)), true, level);
      }
    }
  }
  optimizeMeshOrder(level.mesh);
  level.triangles = level.mesh.triangleCount();
}

}  // namespace

void buildLods(const PlantModel& plant, const MeshOptions& options, const PlantMesh& lod0, const LodSettings& lods,
               std::vector<LodLevel>& out) {
  const size_t levels = size_t(std::max(lods.levels, 1)) - 1;
  out.resize(levels);
  ChainBasis b;
  b.n0 = lod0.triangleCount();
  b.prim0 = primitiveTriangles(lod0);
  b.bark0 = lod0.bark.triangleCount();
  b.leaves = plant.leafCount();
  const Bounds3 bounds = plant::computeStats(plant).bounds;
  b.size = bounds.empty() ? 0.0 : double(bounds.size().norm());
  {
    std::vector<uint8_t> used(leafShapeCount(plant), 0);
    for (uint16_t s : plant.leafShape) used[s] = 1;
    for (uint8_t u : used) b.shapesInUse += u;
  }
  // Each level's budget is at most what the level above has. Planned on the assumption that
  // every level meets its budget, the levels are made in parallel; then, in order, a level
  // whose plan that assumption changed (the level above stayed over its budget) is made again
  // with its real plan. The result is the same as making them one after another.
  std::vector<LevelPlan> plans(levels);
  {
    uint64_t previous = b.n0;
    MeshOptions tess = options;
    float twig = 0.0f;
    for (size_t k = 1; k <= levels; ++k) {
      plans[k - 1] = planLevel(b, options, std::min<uint64_t>(lodBudget(lods, b.n0, int(k)), previous), tess, twig);
      previous = plans[k - 1].budget;
      tess = plans[k - 1].tess;
      twig = plans[k - 1].twig;
    }
  }
  parallelFor(0, levels, [&](size_t k) { makeLevel(plant, options, lod0, b, plans[k], out[k]); }, 1);
  uint64_t previous = b.n0;
  MeshOptions tess = options;
  float twig = 0.0f;
  for (size_t k = 1; k <= levels; ++k) {
    const LevelPlan plan =
        planLevel(b, options, std::min<uint64_t>(lodBudget(lods, b.n0, int(k)), previous), tess, twig);
    if (!(plan == plans[k - 1])) makeLevel(plant, options, lod0, b, plan, out[k - 1]);
    previous = out[k - 1].triangles;
    tess = plan.tess;
    twig = plan.twig;
  }
}

}  // namespace tendril::mesh
