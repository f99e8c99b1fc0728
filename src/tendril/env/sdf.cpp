#include "tendril/env/sdf.h"

#include "tendril/core/parallel.h"

#include <algorithm>
#include <cmath>

namespace tendril::env {

SdfGrid::SdfGrid(const Bounds3& bounds, float cell, const std::function<float(const Vec3&)>& distance)
    : origin_(bounds.min), cell_(cell) {
  Vec3 extent = bounds.size();
  for (int k = 0; k < 3; ++k) dims_[k] = std::max(2, static_cast<int>(std::ceil(extent[k] / cell)) + 1);
  values_.resize(static_cast<size_t>(dims_.x()) * dims_.y() * dims_.z());
  const size_t slab = static_cast<size_t>(dims_.x()) * dims_.y();
  parallelFor(0, values_.size(), [&](size_t i) {
    int z = static_cast<int>(i / slab);
    int y = static_cast<int>((i % slab) / dims_.x());
    int x = static_cast<int>(i % dims_.x());
    values_[i] = distance(origin_ + cell_ * Vec3(float(x), float(y), float(z)));
  }, 256);
}

Bounds3 SdfGrid::bounds() const {
  Bounds3 b;
  b.extend(origin_);
  b.extend(origin_ + cell_ * (dims_ - Eigen::Vector3i::Ones()).cast<float>());
  return b;
}

float SdfGrid::trilinear(const Vec3& p) const {
  Vec3 g = (p - origin_) / cell_;
  int i[3];
  float f[3];
  for (int k = 0; k < 3; ++k) {
    float c = std::clamp(g[k], 0.0f, float(dims_[k] - 1));
    i[k] = std::min(static_cast<int>(c), dims_[k] - 2);
    f[k] = c - float(i[k]);
  }
  auto lerp = [](float a, float b, float t) { return a + (b - a) * t; };
  float c00 = lerp(at(i[0], i[1], i[2]), at(i[0] + 1, i[1], i[2]), f[0]);
  float c10 = lerp(at(i[0], i[1] + 1, i[2]), at(i[0] + 1, i[1] + 1, i[2]), f[0]);
  float c01 = lerp(at(i[0], i[1], i[2] + 1), at(i[0] + 1, i[1], i[2] + 1), f[0]);
  float c11 = lerp(at(i[0], i[1] + 1, i[2] + 1), at(i[0] + 1, i[1] + 1, i[2] + 1), f[0]);
  return lerp(lerp(c00, c10, f[1]), lerp(c01, c11, f[1]), f[2]);
}

float SdfGrid::sample(const Vec3& p) const {
  if (values_.empty() || !isFinite(p)) return std::numeric_limits<float>::infinity();
  Bounds3 b = bounds();
  Vec3 clamped = p.cwiseMax(b.min).cwiseMin(b.max);
  return trilinear(clamped) + (p - clamped).norm();
}

float SdfGrid::sampleWithGradient(const Vec3& p, Vec3* gradient) const {
  if (values_.empty() || !isFinite(p)) {
    *gradient = Vec3::Zero();
    return std::numeric_limits<float>::infinity();
  }
  Bounds3 b = bounds();
  Vec3 clamped = p.cwiseMax(b.min).cwiseMin(b.max);
  Vec3 outside = p - clamped;
  float extra = outside.norm();
  Vec3 g = (clamped - origin_) / cell_;
  int i[3];
  float f[3];
  for (int k = 0; k < 3; ++k) {
    float c = std::clamp(g[k], 0.0f, float(dims_[k] - 1));
    i[k] = std::min(static_cast<int>(c), dims_[k] - 2);
    f[k] = c - float(i[k]);
  }
  const float c000 = at(i[0], i[1], i[2]), c100 = at(i[0] + 1, i[1], i[2]);
  const float c010 = at(i[0], i[1] + 1, i[2]), c110 = at(i[0] + 1, i[1] + 1, i[2]);
  const float c001 = at(i[0], i[1], i[2] + 1), c101 = at(i[0] + 1, i[1], i[2] + 1);
  const float c011 = at(i[0], i[1] + 1, i[2] + 1), c111 = at(i[0] + 1, i[1] + 1, i[2] + 1);
  const float fx = f[0], fy = f[1], fz = f[2], gx = 1 - fx, gy = 1 - fy, gz = 1 - fz;
  float d = gz * (gy * (gx * c000 + fx * c100) + fy * (gx * c010 + fx * c110)) +
            fz * (gy * (gx * c001 + fx * c101) + fy * (gx * c011 + fx * c111));
  Vec3 grad((gz * (gy * (c100 - c000) + fy * (c110 - c010)) + fz * (gy * (c101 - c001) + fy * (c111 - c011))),
            (gz * (gx * (c010 - c000) + fx * (c110 - c100)) + fz * (gx * (c011 - c001) + fx * (c111 - c101))),
            (gy * (gx * (c001 - c000) + fx * (c101 - c100)) + fy * (gx * (c011 - c010) + fx * (c111 - c110))));
  grad /= cell_;
  // Beyond the grid the distance grows along the way out.
  if (extra > 0.0f) grad += outside / extra * std::max(1.0f, grad.norm());
  *gradient = grad;
  return d + extra;
}

Vec3 SdfGrid::gradient(const Vec3& p) const {
  if (values_.empty()) return Vec3::Zero();
  const float h = 0.5f * cell_;
  Vec3 g(sample(p + Vec3(h, 0, 0)) - sample(p - Vec3(h, 0, 0)),
         sample(p + Vec3(0, h, 0)) - sample(p - Vec3(0, h, 0)),
         sample(p + Vec3(0, 0, h)) - sample(p - Vec3(0, 0, h)));
  float n = g.norm();
  return n > 1e-12f ? Vec3(g / n) : Vec3::Zero();
}

}  // namespace tendril::env
