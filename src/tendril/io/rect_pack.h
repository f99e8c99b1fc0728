// Packing rectangles into one atlas with stb_rect_pack (the leaf atlas, io/leaf_atlas.h, and the
// impostor's, io/impostor.h): every atlas width from the widest cell (or the square root of the
// cells' total area) up to all cells in a row is tried, in about `divisions` steps, with an
// unbounded height, and the best packing by `goal` kept. Deterministic.
#pragma once

#include <array>
#include <vector>

namespace tendril::io {

enum class PackGoal {
  SmallestArea,  // the least atlas area, then the squarer
  Squarest,      // the smallest longer side (what texture size limits care about), then the least area
};

struct PackedRects {
  int width = 0, height = 0;                 // 0 × 0 when there is nothing to pack
  std::vector<std::array<int, 2>> corners;   // each cell's top-left corner, in the order given
};

// `sizes` are the cells' (width, height) in pixels. Widths tried start at the square root of the
// area rounded up to a multiple of `align` and go up in steps of at least 4 (multiples of
// `align`).
PackedRects packRects(const std::vector<std::array<int, 2>>& sizes, PackGoal goal, int divisions, int align);

}  // namespace tendril::io
