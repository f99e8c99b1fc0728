// Engine wind data (issue 26 part 4, docs/engine-wind.md): what the .glb writer puts in a plant
// vertex's extra attributes, per skeleton node (a vertex finds its node by _NODE_ID). Made by
// wind::engineWindNodes from the plant's Growth-Flow sway; io only writes it.
#pragma once

#include "tendril/core/math.h"

#include <vector>

namespace tendril::io {

struct WindVertexNode {
  Vec3 pivot = Vec3::Zero();  // _WIND_PIVOT: the point the vertex bends about (m)
  Vec3 lever = Vec3::Zero();  // _WIND_AXIS: the branch direction, its length the compliance (rad per (m/s)²)
  float level = 0.0f;         // COLOR_0.r: branch order / the plant's highest order, in [0, 1]
  float phase = 0.0f;         // COLOR_0.g: the branch's phase, in [0, 1)
  float period = 0.0f;        // COLOR_0.b: (natural period − 0.4 s) / 5.6 s, in [0, 1]
};

// One table per plant (by node index); an empty table writes no wind attributes.
using WindTables = std::vector<std::vector<WindVertexNode>>;

}  // namespace tendril::io
