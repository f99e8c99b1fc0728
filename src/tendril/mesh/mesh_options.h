// How finely plant geometry is tessellated. Shared by the bark sweep, the leaf quads and the
// exporters; checked where it enters (validateMeshOptions) so bad values get a clear answer.
#pragma once

#include <string>

namespace tendril::mesh {

struct MeshOptions {
  int radialSegments = 8;    // vertices around a branch ring (3..256)
  int subdivisions = 3;      // spline samples per skeleton segment; 1 = polyline (1..64)
  bool caps = true;          // close every branch chain at its base and tip
  int leafSubdivisions = 1;  // quads along a leaf blade, bent by the leaf's motion (1..64)
};

inline MeshOptions defaultMeshOptions() { return {}; }

// Throws Error(source, "<field>", what was expected) for an out-of-range field.
void validateMeshOptions(const MeshOptions& options, const std::string& source);

}  // namespace tendril::mesh
