#include "tendril/climb/occupancy.h"

#include "tendril/core/random.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace tendril::climb {
namespace {

int bruteCount(const std::vector<Vec3>& points, const Vec3& p, float radius, int limit) {
  int n = 0;
  for (const Vec3& q : points) n += (q - p).squaredNorm() <= radius * radius;
  return std::min(n, limit);
}

// The crowding grid answers min(points within the radius, limit) exactly, wherever the points
// crowd (cells with many blocks of eight, a thin layer like ivy on a wall, negative
// coordinates) and after its cells are resized.
TEST(OccupancyGrid, CountsMatchBruteForce) {
  Rng rng(RandomKey{41});
  std::vector<Vec3> points;
  OccupancyGrid grid(0.12f);
  for (int i = 0; i < 6000; ++i) {
    Vec3 p;
    if (i % 3 == 0) p = Vec3(rng.uniform(-0.2f, 0.2f), rng.uniform(-0.2f, 0.2f), rng.uniform(-0.2f, 0.2f));
    else p = Vec3(rng.uniform(-30.0f, 30.0f), rng.uniform(0.0f, 4.0f), 0.17f + rng.uniform(-0.02f, 0.02f));
    points.push_back(p);
    grid.insert(p);
  }
  auto check = [&] {
    for (int i = 0; i < 2000; ++i) {
      const Vec3 p = i % 2 ? points[rng.below(uint32_t(points.size()))] + 0.05f * rng.unitVector()
                           : Vec3(rng.uniform(-31.0f, 31.0f), rng.uniform(-1.0f, 5.0f), rng.uniform(-0.5f, 0.5f));
      const float radius = rng.uniform(0.01f, 0.06f);
      for (int limit : {1, 8, 1000})
        ASSERT_EQ(grid.countWithin(p, radius, limit), bruteCount(points, p, radius, limit)) << "at " << p.transpose();
    }
  };
  check();
  grid.setCell(0.2f);
  EXPECT_EQ(grid.size(), points.size());
  check();
}

}  // namespace
}  // namespace tendril::climb
