#include "tendril/particles/species.h"

#include "tendril/core/json_reader.h"
#include "tendril/plant/species_materials.h"

#include <nlohmann/json.hpp>


namespace tendril::particles {


void readParticleSpecies(JsonObject& o, ParticleSpecies& s, const std::string& baseDir) {
  s.name = o.string("name", s.name);
  s.description = o.string("description", s.description);
  o.markRead("model");

  s.particleLength = o.numberf("particle_length", s.particleLength, 1e-3, 10.0);
  s.radius = o.numberf("radius", s.radius, 1e-4, 1.0);
  s.minRadius = o.numberf("min_radius", s.minRadius, 1e-5, 1.0);
  s.thicknessFalloff = o.numberf("thickness_falloff", s.thicknessFalloff, 0.05, 1.0);
  s.apexTaper = o.numberf("apex_taper", s.apexTaper, 0.5, 1.0);
  s.density = o.numberf("density", s.density, 1.0, 20000.0);

  s.growthRate = o.numberf("growth_rate", s.growthRate, 0.0, 100.0);
  s.minGrowthLight = o.numberf("min_growth_light", s.minGrowthLight, 0.0, 1.0);
  s.growthSpeed = o.numberf("growth_speed", s.growthSpeed, 0.0, 1e6);
  s.maxLateralBuds = int(o.integer("lateral_buds", s.maxLateralBuds, 0, 64));
  s.branchProbability = o.numberf("branch_probability", s.branchProbability, 0.0, 1.0);
  s.branchVariance = o.numberf("branch_variance", s.branchVariance, 0.0, 1.0);
  s.phototropism = o.numberf("phototropism", s.phototropism, 0.0, 100.0);
  s.surfaceAdaption = o.numberf("surface_adaption", s.surfaceAdaption, 0.0, 1.0);
  s.randomWalk = o.numberf("random_walk", s.randomWalk, 0.0, 100.0);
  s.attraction = o.numberf("attraction", s.attraction, 0.0, 100.0);
  s.adhesionDistance = o.numberf("adhesion_distance", s.adhesionDistance, 0.0, 10.0);
  s.maxParticles = int(o.integer("max_particles", s.maxParticles, 1, 10000000));
  s.secondaryGrowth = o.numberf("secondary_growth", s.secondaryGrowth, 0.0, 100.0);
  s.crowding = int(o.integer("crowding", s.crowding, 0, 100000));
  s.spreading = o.numberf("spreading", s.spreading, 0.0, 100.0);

  s.stiffness = o.numberf("stiffness", s.stiffness, 0.0, 1.0);
  s.stiffnessStart = o.numberf("stiffness_start", s.stiffnessStart, 0.0, 1.0);
  s.stiffnessTime = o.numberf("stiffness_time", s.stiffnessTime, 1e-3, 1e9);
  s.breakThreshold = o.numberf("break_threshold", s.breakThreshold, 0.0, 1.0);
  s.maxStrain = o.numberf("max_strain", s.maxStrain, 1e-3, 100.0);
  s.damping = o.numberf("damping", s.damping, 0.0, 1.0);

  s.anchorStrength = o.numberf("anchor_strength", s.anchorStrength, 0.0, 0.99);
  s.anchorDistance = o.numberf("anchor_distance", s.anchorDistance, 0.0, 10.0);
  s.anchorRelease = o.numberf("anchor_release", s.anchorRelease, 1e-4, 10.0);

  s.friction = o.numberf("friction", s.friction, 0.0, 1.0);
  s.elasticity = o.numberf("elasticity", s.elasticity, 0.0, 1.0);

  if (auto l = o.optionalObject("leaf")) {
    plant::readLeafShapes(*l, s.leafShapes, baseDir);
    s.phyllotaxisAngle = l->angle("phyllotaxis_angle", degrees(s.phyllotaxisAngle), 0.0, 360.0);
    s.leafStep = int(l->integer("step", s.leafStep, 0, 1000));
    s.leafSize = l->numberf("size", s.leafSize, 0.0, 5.0);
    s.leafJitter = l->angle("jitter", degrees(s.leafJitter), 0.0, 90.0);
    s.leafPetiole = l->numberf("petiole", s.leafPetiole, 0.0, 1.0);
    s.leafThickness = l->numberf("thickness", s.leafThickness, 0.0, 0.1);
    s.leafLightTurn = l->numberf("light_turn", s.leafLightTurn, 0.0, 1.0);
    s.leafParticleLimit = int(l->integer("particle_limit", s.leafParticleLimit, 0, 100000000));
    l->finish();
  }
  if (auto b = o.optionalObject("bark")) plant::readBark(*b, s.bark, baseDir);
  if (auto g = o.optionalObject("growth_flow")) plant::readGrowthFlow(*g, s.growthFlow);
}

}  // namespace tendril::particles
