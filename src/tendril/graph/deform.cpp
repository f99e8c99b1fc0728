#include "tendril/graph/deform.h"

#include "tendril/core/random.h"
#include "tendril/graph/param.h"

#include <algorithm>
#include <cmath>

namespace tendril::graph {

namespace {

constexpr uint64_t kPurposeFfd = purposeId("graph.ffd");

// Bernstein polynomials of degree d (<= 4) at u.
void bernstein(int d, float u, float* b) {
  static const float kBinomial[5][5] = {{1, 0, 0, 0, 0}, {1, 1, 0, 0, 0}, {1, 2, 1, 0, 0}, {1, 3, 3, 1, 0}, {1, 4, 6, 4, 1}};
  float v = 1.0f - u;
  for (int i = 0; i <= d; ++i) b[i] = kBinomial[d][i] * std::pow(u, float(i)) * std::pow(v, float(d - i));
}

}  // namespace

Vec3 hyperpatchOffset(const Deformer& d, const Vec3& p) {
  float u = std::clamp((p.x() + 0.5f * d.size.x()) / d.size.x(), 0.0f, 1.0f);
  float v = std::clamp(p.y() / d.size.y(), 0.0f, 1.0f);
  float w = std::clamp((p.z() + 0.5f * d.size.z()) / d.size.z(), 0.0f, 1.0f);
  float bu[5], bv[5], bw[5];
  bernstein(d.degree, u, bu);
  bernstein(d.degree, v, bv);
  bernstein(d.degree, w, bw);
  int m = d.degree + 1;
  Vec3 offset = Vec3::Zero();
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        const Vec3& o = d.offsets[size_t(i + m * (j + m * k))];
        if (o.x() != 0.0f || o.y() != 0.0f || o.z() != 0.0f) offset += (bu[i] * bv[j] * bw[k]) * o;
      }
  return offset;
}

Vec3 deformPoint(const ITree& tree, int32_t index, const Vec3& world) {
  const Deformer& d = tree.deformers[size_t(index)];
  // Local coordinates without the instance's scale: functions see metres of the FFD's frame.
  Vec3 local = d.frame.rotation.conjugate() * (world - d.frame.position);
  Vec3 moved;
  const Component& c = tree.graph->components[size_t(d.component)];
  if (c.type == ComponentType::Hyperpatch) {
    moved = local + hyperpatchOffset(d, local);
  } else {
    const FfdParams& f = c.as<FfdParams>();
    EvalVars v = d.vars;
    v.x = local.x();
    v.y = local.y();
    v.z = local.z();
    // Random functions give one value per FFD instance (the same for every point), so the
    // deformation stays continuous.
    RandomKey key{tree.seed, uint64_t(d.component + 1), tree.instances[size_t(d.instance)].key, 0, kPurposeFfd};
    const ParamEvaluator& e = *tree.evaluator;
    moved = Vec3(f.hasX ? float(e.eval(f.x, v, v.t, key)) : local.x(), f.hasY ? float(e.eval(f.y, v, v.t, key)) : local.y(),
                 f.hasZ ? float(e.eval(f.z, v, v.t, key)) : local.z());
  }
  return d.frame.position + d.frame.rotation * moved;
}

std::vector<int32_t> chainDeformers(const ITree& tree, int32_t chain) {
  std::vector<int32_t> out;
  for (int32_t c = chain; c >= 0; c = tree.chains[size_t(c)].next) {
    int32_t d = tree.chains[size_t(c)].deformer;
    if (!tree.deformers[size_t(d)].identity) out.push_back(d);
  }
  return out;
}

}  // namespace tendril::graph
