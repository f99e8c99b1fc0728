#include "tendril/particles/particle_model.h"

#include "tendril/core/error.h"
#include "tendril/models/species_presets.h"
#include "tendril/particles/species_schema.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>

namespace tendril::particles {

namespace {

void readSpeciesDocument(const models::SpeciesDocument& d, ParticleSpecies& s) {
  JsonObject o(d.json, d.source);
  readParticleSpecies(o, s, d.dir.string());  // its "model" was checked by the loader
  o.finish();
}

std::shared_ptr<const models::ModelParams> readParticlePlant(JsonObject& o, const std::filesystem::path& baseDir) {
  auto params = std::make_shared<ParticleParams>();
  const Json* sp = o.find("species");
  if (!sp) {
    params->species = loadSpecies("ivy-particles", baseDir, o.source(), o.pointerTo("species"));
  } else if (sp->is_string()) {
    params->species = loadSpecies(sp->get<std::string>(), baseDir, o.source(), o.pointerTo("species"));
  } else if (sp->is_object()) {
    JsonObject so(*sp, o.source(), o.pointerTo("species"));
    std::string base = so.string("base", "ivy-particles");
    params->species = loadSpecies(base, baseDir, o.source(), so.pointerTo("base"));
    readParticleSpecies(so, params->species, baseDir.string());
    so.finish();
  } else {
    throw o.error("species", "expected a species name, a .json path or an object, got " + describeJson(*sp));
  }
  return params;
}

}  // namespace

ParticleSpecies loadSpecies(const std::string& ref, const std::filesystem::path& baseDir, const std::string& source,
                            const std::string& pointer) {
  ParticleSpecies s;
  readSpeciesDocument(models::loadSpeciesDocument("particles", ref, baseDir, source, pointer), s);
  return s;
}

ParticlePlantSystem::ParticlePlantSystem(const models::SystemContext& context) {
  WorldSettings s;
  s.seed = context.sceneSeed;
  world_.setSettings(s);
}

void ParticlePlantSystem::addPlant(const models::PlantSpec& spec, const env::Environment& env) {
  const auto* params = spec.paramsAs<ParticleParams>();
  world_.addPlant(spec.name, params ? params->species : ParticleSpecies(), spec.position, spec.direction, spec.seed,
                  env);
}

void ParticlePlantSystem::step(const env::Environment& env) { world_.step(env); }

void ParticlePlantSystem::setParams(size_t plant, const models::PlantSpec& spec) {
  const auto* params = spec.paramsAs<ParticleParams>();
  if (!params) throw Error("", "/species", "expected particle species settings");
  world_.setSpecies(uint32_t(plant), params->species);
}

void ParticlePlantSystem::cut(size_t plant, uint32_t node, bool remove) {
  const std::vector<uint32_t> particles = world_.snapshotParticles(uint32_t(plant));
  if (node >= particles.size())
    throw Error("", "", fmt::format("plant {} has no node {} (it has {})", plant, node, particles.size()));
  world_.cut(particles[node], remove);
}

void ParticlePlantSystem::requireHandle(size_t plant, uint32_t handle, const std::string& what) const {
  const ParticleWorld& w = world_;
  if (handle >= w.capacity() || !w.active(handle) || w.plantOf(handle) != plant || (w.flags(handle) & kDetached))
    throw Error(what, "/particle", fmt::format("particle {} is not part of the plant", handle));
}

void ParticlePlantSystem::seedBranch(size_t plant, uint32_t handle, const Vec3& direction, const std::string& what) {
  requireHandle(plant, handle, what);
  if (world_.flags(handle) & kLeaf) throw Error(what, "/particle", fmt::format("particle {} is a leaf", handle));
  if (world_.seedBranch(handle, direction) == kNone)
    throw Error(what, "/particle", fmt::format("particle {} cannot carry a branch", handle));
}

void ParticlePlantSystem::seedBranchNear(const env::Stroke& stroke) {
  if (!stroke.attract) return;
  const ParticleWorld& w = world_;
  uint32_t best = kNone;
  float bestDistance = stroke.radius;
  Vec3 toward = Vec3::Zero();
  for (uint32_t i = 0; i < w.capacity(); ++i) {
    const uint32_t f = w.flags(i);
    if (!(f & kActive) || !(f & kGrown) || (f & (kLeaf | kDetached | kRoot))) continue;
    for (const Vec3& p : stroke.points) {
      const float d = (p - w.head(i)).norm();
      if (d < bestDistance) {
        bestDistance = d;
        best = i;
        toward = p - w.head(i);
      }
    }
  }
  if (best != kNone) world_.seedBranch(best, toward);
}

std::vector<models::StrainGauge::NodeStrain> ParticlePlantSystem::nodeStrain(size_t plant) const {
  const std::vector<uint32_t> ids = world_.snapshotParticles(uint32_t(plant));
  const float full = std::max(1e-4f, breakingStrain(world_.species(uint32_t(plant))));
  std::vector<NodeStrain> out(ids.size());
  for (size_t n = 0; n < ids.size(); ++n) {
    const uint32_t i = ids[n];
    if (i == kNone || !world_.judgedForBreaking(i)) continue;  // what breaking judges, nothing else
    out[n] = NodeStrain{i, world_.strain(i) / full};
  }
  return out;
}

std::string ParticlePlantSystem::settingsTitle(size_t plant) const {
  return "Species " + world_.species(uint32_t(plant)).name;
}

std::vector<models::LiveSettings::Setting> ParticlePlantSystem::liveSettings(size_t plant) const {
  const ParticleSpecies& s = world_.species(uint32_t(plant));
  std::vector<Setting> out;
  // Labels, units and slider ranges from the species' description (species_schema.h).
  auto add = [&](const char* group, std::string_view key, int decimals = 3) {
    const schema::Field<ParticleSpecies>& f = particleSpeciesSchema().at(key);
    out.push_back(Setting{std::string(key), f.labelWithUnit(), group, f.kind == schema::Kind::Integer,
                          schema::fileValue(f, s), f.sliderLow(), f.sliderHigh(), decimals});
  };
  for (std::string_view key : {"lateral_buds", "branch_probability", "branch_variance", "phototropism"})
    add("Table 2 of seed 000", key);
  add("growth", "growth_rate", 4);
  add("growth", "growth_speed", 1);
  for (std::string_view key : {"particle_length", "surface_adaption", "random_walk", "attraction", "spreading"})
    add("growth", key);
  for (std::string_view key : {"stiffness", "break_threshold", "max_strain", "anchor_strength", "damping"})
    add("mechanics", key);
  return out;
}

models::ModelType particleModelType() {
  return {"particles",
          "oriented-particle plants after seed 000 (growth, shape-matching dynamics, anchors, collisions, breaking)",
          readParticlePlant,
          [](const models::SystemContext& c) { return std::make_unique<ParticlePlantSystem>(c); }};
}

}  // namespace tendril::particles
