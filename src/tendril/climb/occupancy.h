// A uniform hash grid of points (segment ends of every climbing plant in the scene), used to
// stop growth where the plant is already dense — the role voxel occupancy plays in Greene 1989
// and Beneš & Millán 2002, here as a sparse grid so scene size does not matter.
//
// Every growing tip asks it once per step, so lookups are cheap: an open-addressing table of
// occupied cells (linear probing, at most half full) in front of each cell's points, stored in
// blocks of eight per axis.
#pragma once

#include "tendril/core/math.h"

#include <cstdint>
#include <vector>

namespace tendril::climb {

class OccupancyGrid {
 public:
  // Queries are fastest for radii up to cell / 2: a sphere then touches at most 8 cells.
  explicit OccupancyGrid(float cell = 0.12f) : cell_(cell > 0.0f ? cell : 0.12f) {}
  // Changes the cell size (re-bins the stored points).
  void setCell(float cell);
  void insert(const Vec3& p);
  // Number of stored points within `radius` of p, counting no further than `limit`. The
  // answer, min(points within radius, limit), does not depend on the order of insertion.
  int countWithin(const Vec3& p, float radius, int limit) const;
  size_t size() const { return count_; }
  float cell() const { return cell_; }

 private:
  static constexpr uint32_t kEmpty = ~uint32_t(0);
  static uint64_t key(int x, int y, int z);
  static size_t home(uint64_t key);
  // Index of the cell holding `key` in cells_, or kEmpty.
  uint32_t find(uint64_t key) const;
  void grow();

  // Eight points, one array per axis; unused entries are far away (they never count).
  struct Block {
    float x[8], y[8], z[8];
  };
  // A cell's first eight points live in the cell itself, so that a lookup usually touches
  // one table slot and one cell.
  struct Cell {
    uint64_t key = 0;
    uint32_t count = 0;
    Block first;
    std::vector<Block> more;
  };
  struct Slot {
    uint64_t key = 0;
    uint32_t cell = kEmpty;  // kEmpty = free slot
  };

  float cell_;
  size_t count_ = 0;
  std::vector<Slot> slots_;  // open addressing, power-of-two capacity, at most half full
  std::vector<Cell> cells_;
};

}  // namespace tendril::climb
