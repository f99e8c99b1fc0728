// A signed distance field sampled on a regular grid in an obstacle's local frame, read back
// with trilinear interpolation (seed 000 §5.2 gives every obstacle one; its future-work note in
// seed 003 suggests the same for climbing queries).
#pragma once

#include "tendril/core/math.h"

#include <Eigen/Core>
#include <functional>
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

}  // namespace tendril::env
