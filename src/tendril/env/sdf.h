// A signed distance field sampled on a regular grid in an obstacle's local frame, read back
// with trilinear interpolation (seed 000 §5.2 gives every obstacle one; its future-work note in
// seed 003 suggests the same for climbing queries).
#pragma once

#include "tendril/core/math.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

namespace tendril::env {

class SdfGrid {
 public:
  SdfGrid() = default;
  // Samples `distance` at every grid point of a grid covering `bounds` with cubic cells of
  // edge `cell` (in parallel; each value depends only on its point).
  SdfGrid(const Bounds3& bounds, float cell, const std::function<float(const Vec3&)>& distance);

  bool empty() const { return values_.empty(); }
  float cell() const { return cell_; }
  const Eigen::Vector3i& dims() const { return dims_; }
  Bounds3 bounds() const;

  // Trilinear distance. Outside the grid: the value at the nearest grid point plus the
  // distance to the grid (an upper bound that grows correctly away from the obstacle).
  float sample(const Vec3& p) const;
  // Unit gradient of the trilinear field by central differences (points away from the
  // surface outside a closed obstacle). Zero where the field is flat.
  Vec3 gradient(const Vec3& p) const;
  // Distance and the (unnormalised) analytic gradient of the trilinear interpolant, from one
  // cell's eight samples: the cheap query for collision handling.
  float sampleWithGradient(const Vec3& p, Vec3* gradient) const;

 private:
  float at(int x, int y, int z) const { return values_[(static_cast<size_t>(z) * dims_.y() + y) * dims_.x() + x]; }
  // The grid cell holding p (clamped to the grid): the index of its lowest corner and p's
  // fractional position in it.
  size_t locate(const Vec3& clamped, Vec3* fraction) const;
  float trilinear(const Vec3& p) const;

  Vec3 origin_ = Vec3::Zero();
  Vec3 max_ = Vec3::Zero();  // the last grid point (bounds().max), kept for the per-query clamp
  float cell_ = 1.0f;
  float invCell_ = 1.0f;
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  std::vector<float> values_;
};

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

inline float SdfGrid::trilinear(const Vec3& p) const {
  Vec3 f;
  const float* c = values_.data() + locate(p, &f);
  const size_t dy = static_cast<size_t>(dims_.x()), dz = dy * static_cast<size_t>(dims_.y());
  auto lerp = [](float a, float b, float t) { return a + (b - a) * t; };
  const float c00 = lerp(c[0], c[1], f.x()), c10 = lerp(c[dy], c[dy + 1], f.x());
  const float c01 = lerp(c[dz], c[dz + 1], f.x()), c11 = lerp(c[dz + dy], c[dz + dy + 1], f.x());
  return lerp(lerp(c00, c10, f.y()), lerp(c01, c11, f.y()), f.z());
}

inline float SdfGrid::sample(const Vec3& p) const {
  if (values_.empty() || !isFinite(p)) return std::numeric_limits<float>::infinity();
  const Vec3 clamped = p.cwiseMax(origin_).cwiseMin(max_);
  const Vec3 outside = p - clamped;
  const float extra2 = outside.squaredNorm();
  return trilinear(clamped) + (extra2 > 0.0f ? std::sqrt(extra2) : 0.0f);
}

inline float SdfGrid::sampleWithGradient(const Vec3& p, Vec3* gradient) const {
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

}  // namespace tendril::env
