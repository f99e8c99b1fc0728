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

inline size_t SdfGrid::locate(const Vec3& clamped, Vec3* fraction) const {
  // Collision handling samples every particle up to three times per step: the cell and its
  // fractions come from one multiply per axis (no division, no bounds() rebuild per query).
  const Vec3 g = (clamped - origin_) * invCell_;
  int i[3];
  for (int k = 0; k < 3; ++k) {
    const float c = std::clamp(g[k], 0.0f, float(dims_[k] - 1));
    i[k] = std::min(static_cast<int>(c), dims_[k] - 2);
    (*fraction)[k] = c - float(i[k]);
  }
  return (static_cast<size_t>(i[2]) * dims_.y() + i[1]) * dims_.x() + i[0];
}

float SdfGrid::trilinear(const Vec3& p) const {
  Vec3 f;
  const float* c = values_.data() + locate(p, &f);
  const size_t dy = static_cast<size_t>(dims_.x()), dz = dy * static_cast<size_t>(dims_.y());
  auto lerp = [](float a, float b, float t) { return a + (b - a) * t; };
  const float c00 = lerp(c[0], c[1], f.x()), c10 = lerp(c[dy], c[dy + 1], f.x());
  const float c01 = lerp(c[dz], c[dz + 1], f.x()), c11 = lerp(c[dz + dy], c[dz + dy + 1], f.x());
  return lerp(lerp(c00, c10, f.y()), lerp(c01, c11, f.y()), f.z());
}

float SdfGrid::sample(const Vec3& p) const {
  if (values_.empty() || !isFinite(p)) return std::numeric_limits<float>::infinity();
  const Vec3 clamped = p.cwiseMax(origin_).cwiseMin(max_);
  const Vec3 outside = p - clamped;
  const float extra2 = outside.squaredNorm();
  return trilinear(clamped) + (extra2 > 0.0f ? std::sqrt(extra2) : 0.0f);
}

float SdfGrid::sampleWithGradient(const Vec3& p, Vec3* gradient) const {
  if (values_.empty() || !isFinite(p)) {
    *gradient = Vec3::Zero();
    return std::numeric_limits<float>::infinity();
  }
  const Vec3 clamped = p.cwiseMax(origin_).cwiseMin(max_);
  const Vec3 outside = p - clamped;
  const float extra2 = outside.squaredNorm();
  Vec3 f;
  const float* c = values_.data() + locate(clamped, &f);
  const size_t dy = static_cast<size_t>(dims_.x()), dz = dy * static_cast<size_t>(dims_.y());
  const float c000 = c[0], c100 = c[1], c010 = c[dy], c110 = c[dy + 1];
  const float c001 = c[dz], c101 = c[dz + 1], c011 = c[dz + dy], c111 = c[dz + dy + 1];
  const float fx = f.x(), fy = f.y(), fz = f.z(), gy = 1 - fy, gz = 1 - fz;
  // The trilinear interpolant and its analytic gradient, sharing the edge differences.
  const float x00 = c100 - c000, x10 = c110 - c010, x01 = c101 - c001, x11 = c111 - c011;
  const float e00 = c000 + fx * x00, e10 = c010 + fx * x10, e01 = c001 + fx * x01, e11 = c011 + fx * x11;
  const float y0 = e10 - e00, y1 = e11 - e01;
  const float f0 = e00 + fy * y0, f1 = e01 + fy * y1;
  const float d = f0 + fz * (f1 - f0);
  Vec3 grad(gz * (gy * x00 + fy * x10) + fz * (gy * x01 + fy * x11), gz * y0 + fz * y1, f1 - f0);
  grad *= invCell_;
  if (extra2 > 0.0f) {
    // Beyond the grid the distance grows along the way out.
    const float extra = std::sqrt(extra2);
    grad += outside / extra * std::max(1.0f, grad.norm());
    *gradient = grad;
    return d + extra;
  }
  *gradient = grad;
  return d;
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
