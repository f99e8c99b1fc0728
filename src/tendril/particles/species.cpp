#include "tendril/particles/species.h"

#include "tendril/particles/species_schema.h"

#include "tendril/core/json_reader.h"
#include "tendril/plant/species_materials.h"

#include <nlohmann/json.hpp>


namespace tendril::particles {


const schema::Schema<ParticleSpecies>& particleSpeciesSchema() {
  using S = ParticleSpecies;
  static const S d;  // the defaults are the struct's
  static const schema::Schema<S> schema{
      "particle species",
      {
          // Shape (§4.2, §4.3).
          schema::number<S>("particle_length", &S::particleLength, d.particleLength, 1e-3, 10.0, "m", "particle length",
                            "full-grown length `2a` of a branch particle")
              .slider(0.005, 0.5),
          schema::number<S>("radius", &S::radius, d.radius, 1e-4, 1.0, "m", "radius", "radius of a plant's first particle"),
          schema::number<S>("min_radius", &S::minRadius, d.minRadius, 1e-5, 1.0, "m", "min radius", "no radius is smaller"),
          schema::number<S>("thickness_falloff", &S::thicknessFalloff, d.thicknessFalloff, 0.05, 1.0, "",
                            "thickness falloff", "`f`: a lateral starts at `t_c = t_p·f`"),
          schema::number<S>("apex_taper", &S::apexTaper, d.apexTaper, 0.5, 1.0, "", "apex taper",
                            "each successor along a branch is this much thinner"),
          schema::number<S>("density", &S::density, d.density, 1.0, 20000.0, "kg/m³", "density",
                            "mass `m = 4/3 π a b² ρ` (eq. 2)"),
          // Growth (§4.2).
          schema::number<S>("growth_rate", &S::growthRate, d.growthRate, 0.0, 100.0, "m/s", "growth rate",
                            "apex elongation in full light (per second of growth time)")
              .slider(0.0, 0.1),
          schema::number<S>("min_growth_light", &S::minGrowthLight, d.minGrowthLight, 0.0, 1.0, "", "min growth light",
                            "share of the rate kept in full shade"),
          schema::number<S>("growth_speed", &S::growthSpeed, d.growthSpeed, 0.0, 1e6, "", "growth speed",
                            "growth time per simulated second")
              .slider(0.0, 100.0),
          schema::integer<S>("lateral_buds", &S::maxLateralBuds, d.maxLateralBuds, 0, 64, "B lateral buds", "`B`")
              .slider(0, 8),
          schema::number<S>("branch_probability", &S::branchProbability, d.branchProbability, 0.0, 1.0, "",
                            "BP branch probability", "`BP`"),
          schema::number<S>("branch_variance", &S::branchVariance, d.branchVariance, 0.0, 1.0, "", "V branch variance",
                            "`V`"),
          schema::number<S>("phototropism", &S::phototropism, d.phototropism, 0.0, 100.0, "rad/s", "Ph phototropism",
                            "`Ph` = η (eq. 7)")
              .slider(0.0, 2.0),
          schema::number<S>("surface_adaption", &S::surfaceAdaption, d.surfaceAdaption, 0.0, 1.0, "", "surface adaption",
                            "τ (eq. 6)"),
          schema::number<S>("random_walk", &S::randomWalk, d.randomWalk, 0.0, 100.0, "rad/s", "random walk",
                            "random turning of the apex")
              .slider(0.0, 1.0),
          schema::number<S>("attraction", &S::attraction, d.attraction, 0.0, 100.0, "rad/s", "attraction",
                            "turn rate toward painted attractors")
              .slider(0.0, 5.0),
          schema::number<S>("adhesion_distance", &S::adhesionDistance, d.adhesionDistance, 0.0, 10.0, "m",
                            "adhesion distance", "how far an apex looks for a support"),
          schema::integer<S>("max_particles", &S::maxParticles, d.maxParticles, 1, 10000000, "max particles",
                             "per plant; growth stops with a warning"),
          schema::number<S>("secondary_growth", &S::secondaryGrowth, d.secondaryGrowth, 0.0, 100.0, "1/s",
                            "secondary growth", "rate toward the pipe-model radius"),
          schema::integer<S>("crowding", &S::crowding, d.crowding, 0, 100000, "crowding",
                             "an apex stops where more than this many stems of other branches lie within a particle "
                             "length (0: never)"),
          schema::number<S>("spreading", &S::spreading, d.spreading, 0.0, 100.0, "rad/s", "spreading",
                            "turn rate away from nearby stems of other branches")
              .slider(0.0, 5.0),
          // Material (§4.3).
          schema::number<S>("stiffness", &S::stiffness, d.stiffness, 0.0, 1.0, "", "stiffness", "`s` at full age"),
          schema::number<S>("stiffness_start", &S::stiffnessStart, d.stiffnessStart, 0.0, 1.0, "", "stiffness start",
                            "`s` at birth"),
          schema::number<S>("stiffness_time", &S::stiffnessTime, d.stiffnessTime, 1e-3, 1e9, "s", "stiffness time",
                            "`t_m`: time to full stiffness"),
          schema::number<S>("break_threshold", &S::breakThreshold, d.breakThreshold, 0.0, 1.0, "", "break threshold",
                            "`t_s` (0 never breaks)"),
          schema::number<S>("max_strain", &S::maxStrain, d.maxStrain, 1e-3, 100.0, "", "max strain",
                            "strain at which a connection with `t_s → 0+` would break")
              .slider(0.01, 2.0),
          schema::number<S>("damping", &S::damping, d.damping, 0.0, 1.0, "", "damping", "velocity damping per step"),
          // Anchors (eq. 5).
          schema::number<S>("anchor_strength", &S::anchorStrength, d.anchorStrength, 0.0, 0.99, "", "anchor strength",
                            "φ of a full-grown particle (eq. 5)"),
          schema::number<S>("anchor_distance", &S::anchorDistance, d.anchorDistance, 0.0, 10.0, "m", "anchor distance",
                            "a growing particle this close to a surface (beyond its radius) anchors"),
          schema::number<S>("anchor_release", &S::anchorRelease, d.anchorRelease, 1e-4, 10.0, "m", "anchor release",
                            "anchors let go past this distance"),
          // Collisions (§5.2).
          schema::number<S>("friction", &S::friction, d.friction, 0.0, 1.0, "", "friction",
                            "share of tangential velocity removed on contact"),
          schema::number<S>("elasticity", &S::elasticity, d.elasticity, 0.0, 1.0, "", "elasticity",
                            "share of normal velocity reflected on contact"),
      }};
  return schema;
}

void readParticleSpecies(JsonObject& o, ParticleSpecies& s, const std::string& baseDir) {
  s.name = o.string("name", s.name);
  s.description = o.string("description", s.description);
  o.markRead("model");

  schema::readOver(o, particleSpeciesSchema(), s);

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
