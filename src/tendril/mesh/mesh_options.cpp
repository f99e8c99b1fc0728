#include "tendril/mesh/mesh_options.h"

#include "tendril/core/error.h"

#include <fmt/format.h>

namespace tendril::mesh {

void validateMeshOptions(const MeshOptions& o, const std::string& source) {
  auto check = [&](const char* field, int value, int lo, int hi) {
    if (value < lo || value > hi)
      throw Error(source, field, fmt::format("must be an integer in [{}, {}], got {}", lo, hi, value));
  };
  check("radialSegments", o.radialSegments, 3, 256);
  check("subdivisions", o.subdivisions, 1, 64);
  check("leafSubdivisions", o.leafSubdivisions, 1, 64);
}

}  // namespace tendril::mesh
