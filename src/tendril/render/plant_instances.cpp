#include "tendril/render/plant_instances.h"

#include "tendril/core/parallel.h"
#include "tendril/mesh/primitive_mesh.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace tendril::render {
namespace {

using plant::PlantModel;

GpuVec4 gpu(const Vec3& v, float w) { return {v.x(), v.y(), v.z(), w}; }
Vec3 xyz(const GpuVec4& v) { return Vec3(v.x, v.y, v.z); }

// `v` made perpendicular to unit `axis` and unit length; any perpendicular if v is (nearly)
// parallel to it.
Vec3 perpendicularPart(const Vec3& v, const Vec3& axis) {
  Vec3 p = v - v.dot(axis) * axis;
  return p.squaredNorm() > 1e-10f ? Vec3(p.normalized()) : anyPerpendicular(axis);
}

// Unit normal of the ring plane between two consecutive unit directions: their bisector (a
// mitre joint). Folding back on itself (a + b ≈ 0) falls back to the first direction.
Vec3 bisector(const Vec3& a, const Vec3& b) {
  Vec3 s = a + b;
  return s.squaredNorm() > 1e-8f ? Vec3(s.normalized()) : a;
}

// The node's continuing child: its first child that is not flagged as the start of a lateral
// branch and starts where the node ends. -1 when the chain ends here.
std::vector<int32_t> continuingChildren(const PlantModel& m) {
  std::vector<int32_t> cont(m.nodeCount(), -1);
  for (size_t i = 0; i < m.nodeCount(); ++i) {
    int32_t p = m.parent[i];
    if (p < 0 || cont[p] >= 0 || (m.flags[i] & plant::kNodeBranchStart)) continue;
    float tolerance = std::max(0.5f * m.radius[p], 1e-3f * m.length[p]) + 1e-6f;
    if ((m.position[i] - m.tip(p)).squaredNorm() <= tolerance * tolerance) cont[p] = int32_t(i);
  }
  return cont;
}

}  // namespace

Vec3 stressColor(float stress) {
  float s = std::clamp(stress, 0.0f, 1.0f);
  const Vec3 low(0.05f, 0.18f, 0.85f), high(0.85f, 0.06f, 0.04f);
  return (1.0f - s) * low + s * high;
}

namespace {

// Writes view.model's nodeCount() branch instances to out[0, nodeCount()).
void writeBranchInstances(const PlantView& view, float barkLayer, const Vec3& barkMean, BranchInstance* out) {
  assert(view.model);
  const PlantModel& m = *view.model;
  assert(view.stress.empty() || view.stress.size() == m.nodeCount());
  std::vector<int32_t> cont = continuingChildren(m);
  for (size_t i = 0; i < m.nodeCount(); ++i) {
    BranchInstance& b = out[i];
    const Vec3 dir = m.direction(i);
    const int32_t p = m.parent[i];
    const bool joined = p >= 0 && cont[p] == int32_t(i);
    uint32_t caps = 0;
    Vec3 startAxis, startRef;
    float v0 = 0.0f;
    if (joined) {
      // The parent's end ring, exactly.
      const BranchInstance& pb = out[size_t(p)];
      b.start = pb.end;
      startAxis = xyz(pb.endAxis);
      startRef = xyz(pb.endRef);
      v0 = pb.startRef.w;
    } else {
      caps |= kCapStart;
      b.start = gpu(m.position[i], m.radius[i]);
      startAxis = dir;
      startRef = perpendicularPart(m.orientation[i] * Vec3::UnitX(), dir);
    }
    const int32_t c = cont[i];
    Vec3 endAxis;
    if (c >= 0) {
      endAxis = bisector(dir, m.direction(size_t(c)));
      b.end = gpu(m.position[c], m.radius[c]);
    } else {
      caps |= kCapEnd;
      endAxis = dir;
      b.end = gpu(m.tip(i), m.radius[i]);
    }
    // Parallel transport of the reference from the start ring to the end ring.
    Vec3 endRef = perpendicularPart(rotationBetween(startAxis, endAxis) * startRef, endAxis);
    float meanRadius = std::max(0.5f * (b.start.w + b.end.w), 1e-5f);
    float v1 = v0 + m.length[i] / (kTwoPi * meanRadius);
    b.startAxis = gpu(startAxis, v0);
    b.startRef = gpu(startRef, v1);
    b.endAxis = gpu(endAxis, float(caps));
    b.endRef = gpu(endRef, barkLayer);
    Vec3 color = view.stress.empty() ? m.bark.color : stressColor(view.stress[i]);
    b.color = gpu(color.cwiseQuotient(barkMean), view.selected.contains(i) ? 1.0f : 0.0f);
  }
}

// Writes view.model's leafCount() leaf instances to out[0, leafCount()).
void writeLeafInstances(const PlantView& view, std::span<const float> shapeLayer, std::span<const float> shapeAspect,
                        std::span<const Vec3> shapeTint, LeafInstance* out) {
  assert(view.model);
  const PlantModel& m = *view.model;
  for (size_t i = 0; i < m.leafCount(); ++i) {
    const uint16_t shape = m.leafShape[i];
    assert(shape < shapeLayer.size() && shape < shapeAspect.size() && shape < shapeTint.size());
    Mat3 axes = m.leafWorldRotation(i).toRotationMatrix();
    float size = m.leafSize[i];
    LeafInstance& l = out[i];
    l.base = gpu(m.leafWorldPosition(i) + m.leafPetiole[i] * axes.col(1), m.leafMotion[i].x());
    l.halfWidth = gpu((0.5f * size * shapeAspect[shape]) * axes.col(0), shapeLayer[shape]);
    l.along = gpu(size * axes.col(1), view.selected.contains(size_t(m.leafNode[i])) ? 1.0f : 0.0f);
    l.tint = gpu(shapeTint[shape], 0.0f);
  }
}

}  // namespace

void appendBranchInstances(const PlantView& view, float barkLayer, const Vec3& barkMean,
                           std::vector<BranchInstance>& out) {
  assert(view.model);
  const size_t base = out.size();
  out.resize(base + view.model->nodeCount());
  writeBranchInstances(view, barkLayer, barkMean, out.data() + base);
}

void appendLeafInstances(const PlantView& view, std::span<const float> shapeLayer, std::span<const float> shapeAspect,
                         std::span<const Vec3> shapeTint, std::vector<LeafInstance>& out) {
  assert(view.model);
  const size_t base = out.size();
  out.resize(base + view.model->leafCount());
  writeLeafInstances(view, shapeLayer, shapeAspect, shapeTint, out.data() + base);
}

void buildPlantInstances(std::span<const PlantView> views, std::span<const PlantMaterial> materials,
                         std::vector<BranchInstance>& branches, std::vector<LeafInstance>& leaves) {
  assert(materials.size() == views.size());
  // Each plant's slices start where the plants before it end, so the order is the sequential one.
  std::vector<size_t> branchStart(views.size() + 1, 0), leafStart(views.size() + 1, 0);
  for (size_t i = 0; i < views.size(); ++i) {
    const plant::PlantModel* m = views[i].model;
    branchStart[i + 1] = branchStart[i] + (m ? m->nodeCount() : 0);
    leafStart[i + 1] = leafStart[i] + (m ? m->leafCount() : 0);
  }
  branches.resize(branchStart.back());
  leaves.resize(leafStart.back());
  parallelFor(
      0, views.size(),
      [&](size_t i) {
        if (!views[i].model) return;
        const PlantMaterial& mat = materials[i];
        writeBranchInstances(views[i], mat.barkLayer, mat.barkMean, branches.data() + branchStart[i]);
        writeLeafInstances(views[i], mat.shapeLayer, mat.shapeAspect, mat.shapeTint, leaves.data() + leafStart[i]);
      },
      1);
}

void appendPrimitiveInstances(const PlantView& view, std::vector<std::vector<PrimitiveInstance>>& perMesh) {
  assert(view.model);
  const PlantModel& m = *view.model;
  perMesh.resize(std::max(perMesh.size(), m.meshes.size()));
  for (const plant::Primitive& p : m.primitives) {
    assert(p.mesh < m.meshes.size());
    Mat4 world = mesh::worldFromNode(m, p.node) * p.nodeFromPrimitive;
    PrimitiveInstance inst;
    for (int c = 0; c < 4; ++c) inst.worldFromPrimitive[c] = {world(0, c), world(1, c), world(2, c), world(3, c)};
    bool selected = p.node >= 0 && view.selected.contains(size_t(p.node));
    inst.color = gpu(m.meshes[p.mesh].color, selected ? 1.0f : 0.0f);
    perMesh[p.mesh].push_back(inst);
  }
}

}  // namespace tendril::render
