// Stems that stay outside their support as they thicken. A growth model places a stem's
// centreline off the surfaces it climbs at the radius the stem has when it is born; stems then
// thicken (the pipe model, secondary growth, Growth-Flow's eq. 7), and a thick stem pressed
// against a wall grows away from it. keepStemsOutside moves each node's points out of the
// nearest surface until the ring of bark around it clears it, for every model's plants alike.
#pragma once

#include "tendril/env/environment.h"
#include "tendril/plant/plant_model.h"

namespace tendril::models {

// Moves the start of every node (and the tip of every node that ends a chain) along the normal
// of the nearest obstacle surface until the bark ring there — radius r, perpendicular to the
// segment — keeps `margin` (plus 1 % of r) off it. A ring lying in the surface (a trunk
// standing on the ground) needs no clearance. Lengths and orientations follow the moved
// points; leaves keep their world rotation and move with their node's start. Then every leaf
// blade that passes through a surface, or whose moved node leaves its upper side facing a
// surface within the blade's reach, is laid parallel to the surface nearest its attachment
// (upper side away from it), shrunk to 0.7 or 0.45 of its size if that is not enough, or
// dropped. Returns the number of points moved plus the number of leaves changed or dropped.
// How far a bark ring of this radius keeps its centre off a surface it lies along: the radius,
// 1 % of it and `margin`. keepStemsOutside moves points nearer than this; a model that keeps
// its stems there itself (particle plants collide at it) leaves the pass nothing to do.
inline float barkClearance(float radius, float margin = 1e-4f) { return 1.01f * radius + margin; }

// The bark between a node's points is cleared at the rings a mesh of `subdivisions` spline
// samples per segment sweeps there (mesh::MeshOptions, the scene's output settings).
size_t keepStemsOutside(plant::PlantModel& plant, const env::Environment& env, int subdivisions = 3,
                        float margin = 1e-4f);

}  // namespace tendril::models
