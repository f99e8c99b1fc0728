#include "tendril/particles/particle_model.h"

#include "tendril/core/embedded.h"
#include "tendril/core/error.h"

#include <fmt/format.h>
#include <algorithm>
#include <nlohmann/json.hpp>

namespace tendril::particles {

namespace {

void readSpeciesDocument(const Json& json, const std::string& source, const std::filesystem::path& dir,
                         ParticleSpecies& s) {
  JsonObject o(json, source);
  std::string model = o.string("model", "");
  if (model != "particles")
    throw o.error("model", fmt::format("this species is for the \"{}\" model, not \"particles\"", model));
  readParticleSpecies(o, s, dir.string());
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
  bool isPath = ref.find('/') != std::string::npos || (ref.size() > 5 && ref.compare(ref.size() - 5, 5, ".json") == 0);
  ParticleSpecies s;
  if (!isPath) {
    const EmbeddedFile* f = findEmbeddedFile("species/" + ref + ".json");
    if (!f) {
      std::string names;
      for (const EmbeddedFile& e : embeddedFiles()) {
        if (e.path.rfind("species/", 0) != 0) continue;
        if (e.contents.find("\"model\": \"particles\"") == std::string_view::npos) continue;
        names += (names.empty() ? "" : ", ") + std::string(e.path.substr(8, e.path.size() - 13));
      }
      throw Error(source, pointer,
                  fmt::format("unknown particle species \"{}\" (built-in: {}; or give a path to a .json file)", ref,
                              names));
    }
    std::string name = "<built-in>/" + std::string(f->path);
    try {
      readSpeciesDocument(parseJson(f->contents, name), name, "", s);
    } catch (const Error& e) {
      throw Error(source, pointer, e.what());
    }
    return s;
  }
  std::filesystem::path p = std::filesystem::path(ref).is_absolute() ? std::filesystem::path(ref) : baseDir / ref;
  if (!std::filesystem::exists(p)) throw Error(source, pointer, fmt::format("species file {} does not exist", p.string()));
  readSpeciesDocument(readJsonFile(p), p.string(), p.parent_path(), s);
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

void ParticlePlantSystem::cut(size_t plant, uint32_t node) {
  const std::vector<uint32_t> particles = world_.snapshotParticles(uint32_t(plant));
  if (node >= particles.size())
    throw Error("", "", fmt::format("plant {} has no node {} (it has {})", plant, node, particles.size()));
  world_.cut(particles[node]);
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
    if (i == kNone || (world_.flags(i) & (kApex | kLeaf))) continue;
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
  auto add = [&](const char* group, const char* label, const char* key, double value, double lo, double hi,
                 int decimals = 3, bool integer = false) {
    out.push_back(Setting{key, label, group, integer, value, lo, hi, decimals});
  };
  const char* table2 = "Table 2 of seed 000";
  add(table2, "B lateral buds", "lateral_buds", s.maxLateralBuds, 0, 8, 0, true);
  add(table2, "BP branch probability", "branch_probability", s.branchProbability, 0, 1);
  add(table2, "V branch variance", "branch_variance", s.branchVariance, 0, 1);
  add(table2, "Ph phototropism", "phototropism", s.phototropism, 0, 2);
  add("growth", "growth rate (m/s)", "growth_rate", s.growthRate, 0, 0.1, 4);
  add("growth", "growth speed", "growth_speed", s.growthSpeed, 0, 100, 1);
  add("growth", "particle length (m)", "particle_length", s.particleLength, 0.005, 0.5);
  add("growth", "surface adaption", "surface_adaption", s.surfaceAdaption, 0, 1);
  add("growth", "random walk", "random_walk", s.randomWalk, 0, 1);
  add("growth", "attraction", "attraction", s.attraction, 0, 5);
  add("growth", "spreading", "spreading", s.spreading, 0, 5);
  add("mechanics", "stiffness", "stiffness", s.stiffness, 0, 1);
  add("mechanics", "break threshold", "break_threshold", s.breakThreshold, 0, 1);
  add("mechanics", "max strain", "max_strain", s.maxStrain, 0.01, 2);
  add("mechanics", "anchor strength", "anchor_strength", s.anchorStrength, 0, 0.99);
  add("mechanics", "damping", "damping", s.damping, 0, 1);
  return out;
}

models::ModelType particleModelType() {
  return {"particles",
          "oriented-particle plants after seed 000 (growth, shape-matching dynamics, anchors, collisions, breaking)",
          readParticlePlant,
          [](const models::SystemContext& c) { return std::make_unique<ParticlePlantSystem>(c); }};
}

}  // namespace tendril::particles
