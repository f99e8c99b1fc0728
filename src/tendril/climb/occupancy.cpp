#include "tendril/climb/occupancy.h"

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

int OccupancyGrid::countWithin(const Vec3& p, float radius, int limit) const {
  if (cells_.empty()) return 0;
  const float r2 = radius * radius;
  const int reach = static_cast<int>(std::ceil(radius / cell_));
  const int cx = int(std::floor(p.x() / cell_)), cy = int(std::floor(p.y() / cell_)), cz = int(std::floor(p.z() / cell_));
  int n = 0;
  for (int z = cz - reach; z <= cz + reach; ++z)
    for (int y = cy - reach; y <= cy + reach; ++y)
      for (int x = cx - reach; x <= cx + reach; ++x) {
        auto it = cells_.find(key(x, y, z));
        if (it == cells_.end()) continue;
        for (const Vec3& q : it->second)
          if ((q - p).squaredNorm() <= r2 && ++n >= limit) return n;
      }
  return n;
}

}  // namespace tendril::climb
