// Checks shared by tests of climbing plants (climb model now, L-system ivy later): every
// assertion here is something a user would see in the exported plant.
#pragma once

#include "tendril/env/environment.h"
#include "tendril/plant/plant_model.h"

#include <filesystem>
#include <string>

namespace tendril::test {

struct ClimbReport {
  size_t segments = 0;
  size_t crossings = 0;             // segments that pass through an obstacle surface
  size_t insideSegments = 0;        // segment ends inside a closed obstacle
  size_t climbingSegments = 0;      // segments at or after the first climbing segment of their path
  size_t nearSurface = 0;           // ... of which have their midpoint within the adhesion distance
  size_t leaves = 0;
  size_t leafCornersBehind = 0;     // corners inside an obstacle, on a blade outline through a surface, or unreachable
  size_t leavesFacingSurface = 0;   // clinging blades whose upper side faces their support
  double nearFraction() const { return climbingSegments ? double(nearSurface) / climbingSegments : 0.0; }
};

// Corners of a leaf blade, world space (same construction as mesh/leaf quads).
void leafCorners(const plant::PlantModel& p, size_t leaf, Vec3 out[4]);

ClimbReport checkClimbingPlant(const plant::PlantModel& p, const env::Environment& env, float adhesionDistance);

// A torus (genus one, concave around its hole) lying in the XZ plane about the origin, written
// as an OBJ file: a support shape read from a file.
void writeTorusObj(const std::filesystem::path& path, float major, float minor, int nu, int nv);

}  // namespace tendril::test
