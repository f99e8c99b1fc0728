// Species of the oriented-particle model (seed 000): shared, immutable settings; the particles
// themselves live in the ParticleWorld. Table 2's parameters are B (maxLateralBuds),
// BP (branchProbability), V (branchVariance) and Ph (phototropism); §4.3 adds material
// properties. docs/species.md documents every key.
#pragma once

#include "tendril/core/math.h"
#include "tendril/plant/plant_model.h"
#include "tendril/plant/growth_flow.h"

#include <string>
#include <vector>

namespace tendril {
class JsonObject;
}

namespace tendril::particles {

struct ParticleSpecies {
  std::string name = "ivy-particles";
  std::string description;

  // --- Shape (§4.2, §4.3) ---
  float particleLength = 0.05f;  // full-grown length of a branch particle (m): its long axis 2a
  float radius = 0.006f;         // radius (b = c) of a plant's first particle (m)
  float minRadius = 0.0008f;     // radii never drop below (m)
  float thicknessFalloff = 0.8f; // f: a lateral branch starts at t_c = t_p·f
  float apexTaper = 0.97f;       // each successor on a branch is this much thinner
  float density = 700.0f;        // kg/m³ (wood 300–1000, eq. 2)

  // --- Growth (§4.2) ---
  float growthRate = 0.01f;      // apex elongation at full light (m of length per second of growth time)
  float minGrowthLight = 0.15f;  // fraction of the growth rate kept in full shade
  float growthSpeed = 20.0f;     // growth time per second of simulated time (a user multiple of dt)
  int maxLateralBuds = 2;        // B: lateral buds a full-grown particle may sprout
  float branchProbability = 0.4f;  // BP: probability for each lateral bud
  float branchVariance = 0.2f;   // V in [0, 1]: lateral directions deviate up to V·90°
  float phototropism = 0.5f;     // Ph = η (eq. 7)
  float surfaceAdaption = 0.8f;  // τ (eq. 6)
  float randomWalk = 0.15f;      // directed random walk of the apex (rad per second of growth)
  float attraction = 1.0f;       // turn rate toward painted attractors (rad per second of growth)
  float adhesionDistance = 0.1f; // an apex looks this far for a support surface (m)
  int maxParticles = 25000;      // per plant; growth stops with a warning when reached
  float secondaryGrowth = 0.05f; // rate at which radii approach the pipe-model radius (1/s of growth)
  int crowding = 4;              // an apex stops growing where more stem particles than this (of other
                                 // branches, any plant) lie within a particle length; 0 = never
  float spreading = 2.0f;        // turn rate away from nearby stems (rad per second of growth)

  // --- Material (§4.3) ---
  float stiffness = 1.0f;        // s at full age (most of the paper's results use 1)
  float stiffnessStart = 1.0f;   // s at birth: s = clamp(start + (1 − start)·age / stiffnessTime) · stiffness.
                                 // The paper starts at 0.2; young particles that soft can be flung
                                 // while a plant grows fast in open air, so the default is 1.
  float stiffnessTime = 10.0f;   // t_m: seconds (simulated) until full stiffness
  float breakThreshold = 0.0f;   // t_s in [0, 1]: 0 never breaks; connections break above a
                                 // strain of (1 − t_s)·maxStrain
  float maxStrain = 0.5f;        // strain (ParticleWorld::strain) at which t_s → 0+ would break
  float damping = 0.02f;         // velocity damping per step (energy bound)

  // --- Anchors (eq. 5) ---
  float anchorStrength = 0.6f;   // φ of a full-grown particle (0 < φ < 1); young ones scale by size
  float anchorDistance = 0.015f; // a particle this close to a surface (beyond its radius) anchors (m)
  float anchorRelease = 0.05f;   // anchors let go when their particle is farther than this (m)

  // --- Collisions (§5.2) ---
  float friction = 0.6f;         // in [0, 1]: share of tangential velocity removed on contact
  float elasticity = 0.1f;       // in [0, 1]: share of normal velocity reflected on contact

  // --- Leaves (§4.3) ---
  std::vector<plant::LeafShape> leafShapes = {{"builtin:ivy-0", 1.0f, Vec3::Ones()},
                                              {"builtin:ivy-1", 1.0f, Vec3::Ones()},
                                              {"builtin:ivy-2", 1.0f, Vec3::Ones()}};
  float phyllotaxisAngle = radians(137.5f);  // angle around the stem between successive leaves
  int leafStep = 1;                          // a leaf every this many particles along a branch
  float leafSize = 0.07f;                    // full-grown blade length (m)
  float leafJitter = radians(10.0f);         // random extra rotation
  float leafPetiole = 0.02f;                 // m
  float leafThickness = 0.0004f;             // m
  float leafLightTurn = 0.5f;                // how far blades turn toward the light (0–1)
  int leafParticleLimit = 10000;             // below this many particles, leaves are particles

  plant::BarkMaterial bark;

  // How growth answers the wind (seed 001, Growth-Flow). See docs/wind.md.
  plant::GrowthFlowSpecies growthFlow;
};

// The strain (ParticleWorld::strain) above which a connection of the species breaks (§4.3): (1 − t_s)·
// maxStrain. Connections of a species with t_s = 0 never break; maxStrain is then their scale.
inline float breakingStrain(const ParticleSpecies& s) { return (1.0f - s.breakThreshold) * s.maxStrain; }

// Reads the fields present in `o` over `s` (absent fields keep their value). Strict: unknown
// keys, wrong types and out-of-range values throw Error naming file and JSON pointer.
void readParticleSpecies(JsonObject& o, ParticleSpecies& s, const std::string& baseDir);

}  // namespace tendril::particles
