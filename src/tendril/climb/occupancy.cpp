#include "tendril/climb/occupancy.h"

#include "tendril/core/random.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace tendril::climb {

namespace {
// Coordinate of unused block entries: its squared distance to any query overflows to +inf.
constexpr float kFar = 1e30f;
}  // namespace

uint64_t OccupancyGrid::key(int x, int y, int z) {
  auto u = [](int v) { return static_cast<uint64_t>(static_cast<uint32_t>(v + (1 << 20))) & 0x1fffff; };
  return u(x) | (u(y) << 21) | (u(z) << 42);
}

// A cell's home slot: its key hashed on its own. (Homes that kept 4 x 4 x 4 bricks of cells
// together in runs of 64 slots shared cache lines, but the cells of a plant on a wall fill
// only a layer or two of each brick, and two or more bricks shared each run: a lookup probed
// 11 slots on average, 90 per crowding query, most of the query's cost.)
size_t OccupancyGrid::home(uint64_t k) { return size_t(mix64(k)); }

uint32_t OccupancyGrid::find(uint64_t k) const {
  if (slots_.empty()) return kEmpty;
  const size_t mask = slots_.size() - 1;
  for (size_t i = home(k) & mask;; i = (i + 1) & mask) {
    const Slot& s = slots_[i];
    if (s.cell == kEmpty || s.key == k) return s.cell;
  }
}

void OccupancyGrid::grow() {
  slots_.assign(std::max<size_t>(1024, 2 * slots_.size()), Slot());
  const size_t mask = slots_.size() - 1;
  for (uint32_t c = 0; c < cells_.size(); ++c) {
    size_t i = home(cells_[c].key) & mask;
    while (slots_[i].cell != kEmpty) i = (i + 1) & mask;
    slots_[i] = {cells_[c].key, c};
  }
}

void OccupancyGrid::insert(const Vec3& p) {
  const uint64_t k = key(int(std::floor(p.x() / cell_)), int(std::floor(p.y() / cell_)), int(std::floor(p.z() / cell_)));
  ++count_;
  if (2 * (cells_.size() + 1) > slots_.size()) grow();
  const size_t mask = slots_.size() - 1;
  size_t i = home(k) & mask;
  while (slots_[i].cell != kEmpty && slots_[i].key != k) i = (i + 1) & mask;
  auto clear = [](Block& b) {
    std::fill(std::begin(b.x), std::end(b.x), kFar);
    std::fill(std::begin(b.y), std::end(b.y), kFar);
    std::fill(std::begin(b.z), std::end(b.z), kFar);
  };
  if (slots_[i].cell == kEmpty) {
    slots_[i] = {k, static_cast<uint32_t>(cells_.size())};
    Cell& c = cells_.emplace_back();
    c.key = k;
    clear(c.first);
  }
  Cell& c = cells_[slots_[i].cell];
  const uint32_t lane = c.count % 8;
  if (c.count >= 8 && lane == 0) clear(c.more.emplace_back());
  Block& b = c.count < 8 ? c.first : c.more.back();
  b.x[lane] = p.x();
  b.y[lane] = p.y();
  b.z[lane] = p.z();
  ++c.count;
}

void OccupancyGrid::setCell(float cell) {
  if (!(cell > 0.0f) || cell == cell_) return;
  std::vector<Vec3> all;
  all.reserve(count_);
  for (const Cell& c : cells_)
    for (uint32_t i = 0; i < c.count; ++i) {
      const Block& b = i < 8 ? c.first : c.more[i / 8 - 1];
      all.emplace_back(b.x[i % 8], b.y[i % 8], b.z[i % 8]);
    }
  // Re-insert in a canonical order so that the layout never depends on the insertion order.
  std::sort(all.begin(), all.end(), [](const Vec3& a, const Vec3& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  cells_.clear();
  slots_.clear();
  count_ = 0;
  cell_ = cell;
  for (const Vec3& p : all) insert(p);
}

namespace {
// Points of one block within the radius, four lanes at a time (GCC/Clang vector extensions,
// plain scalar code where the target has no SIMD). The same sum as (q − p).squaredNorm()
// (Eigen adds dx² + (dy² + dz²)), so that a point on the sphere counts exactly as it always did.
typedef float Float4 __attribute__((vector_size(16)));
typedef int32_t Int4 __attribute__((vector_size(16)));

inline Float4 load4(const float* f) {
  Float4 v;
  std::memcpy(&v, f, sizeof v);
  return v;
}

template <class Block>
int countInBlock(const Block& b, Float4 px, Float4 py, Float4 pz, Float4 r2) {
  Int4 inside = {0, 0, 0, 0};
  for (int h = 0; h < 8; h += 4) {
    Float4 dx = load4(b.x + h) - px, dy = load4(b.y + h) - py, dz = load4(b.z + h) - pz;
    inside -= (dx * dx + (dy * dy + dz * dz)) <= r2;  // true is -1 in every lane
  }
  return inside[0] + inside[1] + inside[2] + inside[3];
}
}  // namespace

int OccupancyGrid::countWithin(const Vec3& p, float radius, int limit) const {
  if (cells_.empty()) return 0;
  const float r2 = radius * radius;
  const Float4 px = {p.x(), p.x(), p.x(), p.x()}, py = {p.y(), p.y(), p.y(), p.y()},
               pz = {p.z(), p.z(), p.z(), p.z()}, r2v = {r2, r2, r2, r2};
  // Only the cells the query sphere overlaps: at most 2 per axis when radius <= cell / 2.
  const Vec3 lo = (p.array() - radius) / cell_, hi = (p.array() + radius) / cell_;
  const int x0 = int(std::floor(lo.x())), x1 = int(std::floor(hi.x()));
  const int y0 = int(std::floor(lo.y())), y1 = int(std::floor(hi.y()));
  const int z0 = int(std::floor(lo.z())), z1 = int(std::floor(hi.z()));
  int n = 0;
  for (int z = z0; z <= z1; ++z)
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        uint32_t ci = find(key(x, y, z));
        if (ci == kEmpty) continue;
        const Cell& c = cells_[ci];
        n += countInBlock(c.first, px, py, pz, r2v);
        if (n >= limit) return limit;
        for (const Block& b : c.more) {
          n += countInBlock(b, px, py, pz, r2v);
          if (n >= limit) return limit;
        }
      }
  return n;
}

}  // namespace tendril::climb
