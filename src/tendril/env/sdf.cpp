#include "tendril/env/sdf.h"

#include "tendril/core/parallel.h"

#include <algorithm>
#include <cmath>

namespace tendril::env {

SdfGrid::SdfGrid(const Bounds3& bounds, float cell, const std::function<float(const Vec3&)>& distance)
    : origin_(bounds.min), cell_(cell), invCell_(1.0f / cell) {
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
  max_ = origin_ + cell_ * (dims_ - Eigen::Vector3i::Ones()).cast<float>();
}

Bounds3 SdfGrid::bounds() const {
  Bounds3 b;
  b.extend(origin_);
  b.extend(max_);
  return b;
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
