// A uniform hash grid of points (segment ends of every climbing plant in the scene), used to
// stop growth where the plant is already dense — the role voxel occupancy plays in Greene 1989
// and Beneš & Millán 2002, here as a sparse grid so scene size does not matter.
#pragma once

#include "tendril/core/math.h"

#include <cstdint>
#include <unordered_map>
#include <vector>

namespace tendril::climb {

class OccupancyGrid {
 public:
  // Queries are fastest for radii up to cell / 2: a sphere then touches at most 8 cells.
  explicit OccupancyGrid(float cell = 0.12f) : cell_(cell > 0.0f ? cell : 0.12f) {}
  // Changes the cell size (re-bins the stored points).
  void setCell(float cell);
  void insert(const Vec3& p);
  // Number of stored points within `radius` of p, counting no further than `limit`.
  int countWithin(const Vec3& p, float radius, int limit) const;
  size_t size() const { return count_; }
  float cell() const { return cell_; }

 private:
  static uint64_t key(int x, int y, int z);
  float cell_;
  size_t count_ = 0;
  std::unordered_map<uint64_t, std::vector<Vec3>> cells_;
};

}  // namespace tendril::climb
