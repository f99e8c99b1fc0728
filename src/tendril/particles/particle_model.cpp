#include "tendril/particles/particle_model.h"

#include "tendril/core/error.h"
#include "tendril/scene/species_presets.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace tendril::particles {

namespace {

void readSpeciesDocument(const scene::SpeciesDocument& d, ParticleSpecies& s) {
  JsonObject o(d.json, d.source);
  readParticleSpecies(o, s, d.dir.string());  // its "model" was checked by the loader
  o.finish();
}

std::shared_ptr<const scene::ModelParams> readParticlePlant(JsonObject& o, const std::filesystem::path& baseDir) {
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
  readSpeciesDocument(scene::loadSpeciesDocument("particles", ref, baseDir, source, pointer), s);
  return s;
}

ParticlePlantSystem::ParticlePlantSystem(const models::SystemContext& context) {
  WorldSettings s;
  s.seed = context.sceneSeed;
  world_.setSettings(s);
}

void ParticlePlantSystem::addPlant(const scene::PlantSpec& spec, const env::Environment& env) {
  const auto* params = spec.paramsAs<ParticleParams>();
  world_.addPlant(spec.name, params ? params->species : ParticleSpecies(), spec.position, spec.direction, spec.seed,
                  env);
}

void ParticlePlantSystem::step(const env::Environment& env) { world_.step(env); }

void ParticlePlantSystem::setParams(size_t plant, const scene::PlantSpec& spec) {
  const auto* params = spec.paramsAs<ParticleParams>();
  if (!params) throw Error("", "/species", "expected particle species settings");
  world_.setSpecies(uint32_t(plant), params->species);
}

void ParticlePlantSystem::cut(size_t plant, uint32_t node) {
  const std::vector<uint32_t> particles = world_.snapshotParticles(uint32_t(plant));
  if (node >= particles.size())
    throw Error("", "", fmt::format("plant {} has no node {} (it has {})", plant, node, particles.size()));
  world_.cut(particles[node]);
}

models::ModelType particleModelType() {
  return {"particles",
          "oriented-particle plants after seed 000 (growth, shape-matching dynamics, anchors, collisions, breaking)",
          readParticlePlant,
          [](const models::SystemContext& c) { return std::make_unique<ParticlePlantSystem>(c); }};
}

}  // namespace tendril::particles
