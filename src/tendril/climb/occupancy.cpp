#include "tendril/climb/occupancy.h"

#include <algorithm>
#include <cmath>

namespace tendril::climb {

uint64_t OccupancyGrid::key(int x, int y, int z) {
  auto u = [](int v) { return static_cast<uint64_t>(static_cast<uint32_t>(v + (1 << 20))) & 0x1fffff; };
  return u(x) | (u(y) << 21) | (u(z) << 42);
}

void OccupancyGrid::insert(const Vec3& p) {
  cells_[key(int(std::floor(p.x() / cell_)), int(std::floor(p.y() / cell_)), int(std::floor(p.z() / cell_)))]
      .push_back(p);
  ++count_;
}

void OccupancyGrid::setCell(float cell) {
  if (!(cell > 0.0f) || cell == cell_) return;
  std::vector<Vec3> all;
  all.reserve(count_);
  for (const auto& [key, points] : cells_) all.insert(all.end(), points.begin(), points.end());
  // Re-insert in a canonical order so the result never depends on hash iteration order.
  std::sort(all.begin(), all.end(), [](const Vec3& a, const Vec3& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  cells_.clear();
  count_ = 0;
  cell_ = cell;
  for (const Vec3& p : all) insert(p);
}

int OccupancyGrid::countWithin(const Vec3& p, float radius, int limit) const {
  if (cells_.empty()) return 0;
  const float r2 = radius * radius;
  // Only the cells the query sphere overlaps: at most 2 per axis when radius <= cell / 2.
  const Vec3 lo = (p.array() - radius) / cell_, hi = (p.array() + radius) / cell_;
  int n = 0;
  for (int z = int(std::floor(lo.z())); z <= int(std::floor(hi.z())); ++z)
    for (int y = int(std::floor(lo.y())); y <= int(std::floor(hi.y())); ++y)
      for (int x = int(std::floor(lo.x())); x <= int(std::floor(hi.x())); ++x) {
        auto it = cells_.find(key(x, y, z));
        if (it == cells_.end()) continue;
        for (const Vec3& q : it->second)
          if ((q - p).squaredNorm() <= r2 && ++n >= limit) return n;
      }
  return n;
}

}  // namespace tendril::climb
