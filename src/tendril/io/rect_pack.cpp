#include "tendril/io/rect_pack.h"

#include <stb/stb_rect_pack.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace tendril::io {

PackedRects packRects(const std::vector<std::array<int, 2>>& sizes, PackGoal goal, int divisions, int align) {
  auto roundUp = [align](int v) { return (v + align - 1) / align * align; };
  const size_t n = sizes.size();
  int sumW = 0, sumH = 0, maxW = 0;
  uint64_t area = 0;
  for (const auto& [w, h] : sizes) {
    sumW += w;
    sumH += h;
    maxW = std::max(maxW, w);
    area += uint64_t(w) * uint64_t(h);
  }
  PackedRects out;
  if (n == 0) return out;
  const int start = std::max(maxW, roundUp(int(std::ceil(std::sqrt(double(area))))));
  const int end = std::max(start, sumW);
  const int step = std::max(4, roundUp((end - start) / divisions));
  std::vector<stbrp_rect> best, cells(n);
  int bestW = 0, bestH = 0;
  std::vector<stbrp_node> nodes;
  for (int W = start; W <= end; W += step) {
    for (size_t i = 0; i < n; ++i) {
      cells[i] = {};
      cells[i].id = int(i);
      cells[i].w = sizes[i][0];
      cells[i].h = sizes[i][1];
    }
    nodes.resize(size_t(W));
    stbrp_context context;
    stbrp_init_target(&context, W, sumH, nodes.data(), W);
    if (!stbrp_pack_rects(&context, cells.data(), int(n))) continue;  // cannot happen: sumH always fits
    int H = 0;
    for (const stbrp_rect& c : cells) H = std::max(H, int(c.y + c.h));
    const uint64_t cost = uint64_t(W) * uint64_t(H), bestCost = uint64_t(bestW) * uint64_t(bestH);
    const int side = std::max(W, H), bestSide = std::max(bestW, bestH);
    const bool better = goal == PackGoal::SmallestArea ? (cost < bestCost || (cost == bestCost && side < bestSide))
                                                       : (side < bestSide || (side == bestSide && cost < bestCost));
    if (best.empty() || better) {
      best = cells;
      bestW = W;
      bestH = H;
    }
  }
  out.width = bestW;
  out.height = bestH;
  out.corners.resize(n);
  for (const stbrp_rect& c : best) out.corners[size_t(c.id)] = {int(c.x), int(c.y)};
  return out;
}

}  // namespace tendril::io
