#include "tendril/scene/model_types.h"
#include "tendril/session/session.h"

#include "tendril/core/archive.h"
#include "tendril/core/error.h"
#include "tendril/core/hash.h"
#include "tendril/core/log.h"
#include "tendril/core/parallel.h"
#include "tendril/core/parallel_largest_first.h"
#include "tendril/env/mesh_import.h"
#include "tendril/models/stand_off.h"
#include "tendril/scene/settings_schema.h"

#include <fmt/format.h>

#include <utility>

namespace tendril::session {

namespace {

constexpr uint32_t kStateTag = 0x54535331;  // "1SST"
// Version 2 added obstacle scales and imported obstacles; version 1 states are still read.
constexpr uint32_t kStateVersion = 2;

void saveWind(ArchiveWriter& out, const env::WindSettings& w) {
  out.value(w.mode);
  out.value(w.velocity);
  out.f32(w.gustStrength), out.f32(w.gustPeriod), out.f32(w.gustScale), out.f32(w.gustTurn);
  out.u64(w.seed);
  out.vector(w.emitters);
}

env::WindSettings loadWind(ArchiveReader& in) {
  env::WindSettings w;
  const size_t at = in.position();
  in.value(w.mode);
  if (uint32_t(w.mode) > uint32_t(env::WindMode::Sph)) in.fail(at, "unknown wind mode");
  in.value(w.velocity);
  w.gustStrength = in.f32(), w.gustPeriod = in.f32(), w.gustScale = in.f32(), w.gustTurn = in.f32();
  w.seed = in.u64();
  in.vector(w.emitters);
  // The limits the scene and edit readers apply (scene/settings_schema.h).
  if (auto bad = scene::checkWind(w)) in.fail(at, "the saved wind is out of range: " + *bad);
  return w;
}

wind::SphEmitter sphEmitter(const env::WindEmitter& e) {
  wind::SphEmitter se;
  se.position = e.position;
  se.direction = e.direction;
  se.speed = e.speed;
  se.rate = e.rate;
  se.radius = e.radius;
  return se;
}

// The scene key of an SphSettings member named in an Error (camelCase → snake_case; the
// domain's checks concern its extent).
std::string sphSettingKey(const std::string& member) {
  if (member == "domain") return "domain_max";
  std::string key;
  for (char c : member) {
    if (c >= 'A' && c <= 'Z') key += '_', key += char(c - 'A' + 'a');
    else key += c;
  }
  return key;
}

}  // namespace

Session::Session(scene::Scene scene) : Session(std::move(scene), Json(), {}) {}

Session::Session(scene::Scene scene, Json sceneDocument, std::filesystem::path baseDir)
    : scene_(std::move(scene)),
      sceneDocument_(std::move(sceneDocument)),
      baseDir_(std::move(baseDir)),
      env_(std::make_unique<env::Environment>()) {
  if (baseDir_.empty() && !scene_.path.empty()) baseDir_ = scene_.path.parent_path();
  scene::populateEnvironment(scene_, *env_);
  obstacleScales_.assign(scene_.obstacles.size(), Vec3::Ones());
  const Json* plants = sceneDocument_.is_object() && sceneDocument_.contains("plants") ? &sceneDocument_["plants"]
                                                                                        : nullptr;
  for (size_t i = 0; i < scene_.plants.size(); ++i) {
    const models::PlantSpec& p = scene_.plants[i];
    size_t s = systemFor(p.model);
    if (s == systems_.size()) throw Error(scene_.source, p.pointer + "/model", fmt::format("unknown model \"{}\"", p.model));
    try {
      systems_[s]->addPlant(p, *env_);
    } catch (const Error& e) {
      throw Error(scene_.source, e.location().empty() ? p.pointer + "/position" : p.pointer + e.location(),
                  e.message());
    }
    plants_.push_back({s, systems_[s]->plantCount() - 1});
    Json description = plants && plants->is_array() && i < plants->size() ? (*plants)[i] : Json();
    std::string text = description.is_null() ? std::string() : description.dump();
    specs_.push_back({p, std::move(description), std::move(text)});
  }
  // Simulated air (seed 000 §5.3): the scene's emitters feed it, the wind field samples it.
  if (scene_.wind.mode == env::WindMode::Sph) {
    wind::SphSettings settings = scene_.sph;
    for (const auto& s : systems_)
      if (const models::AirCoupling* a = std::as_const(*s).airCoupling()) settings.dt = a->airTimeStep();
    // What the air refuses is named in the scene: its settings' keys under /environment/wind/sph,
    // an emitter's under /environment/wind/emitters/i.
    const std::string wind = "/environment/wind";
    try {
      air_ = std::make_unique<wind::SphAir>(settings);
    } catch (const Error& e) {
      throw Error(scene_.source, wind + "/sph/" + sphSettingKey(e.location()), e.message());
    }
    for (size_t i = 0; i < scene_.wind.emitters.size(); ++i) {
      try {
        air_->addEmitter(sphEmitter(scene_.wind.emitters[i]));
      } catch (const Error& e) {
        throw Error(scene_.source, fmt::format("{}/emitters/{}/{}", wind, i, e.location()), e.message());
      }
    }
    if (scene_.sphFill) {
      try {
        air_->fillBox(settings.domainMin, settings.domainMax, *env_, scene_.wind.velocity);
      } catch (const Error& e) {
        throw Error(scene_.source, wind + "/sph/fill", e.message());
      }
    }
    env_->setAirFlow(air_.get());
  }
  // The support plants' stems from the start: a click on a trunk finds it before any step.
  refreshSupports();
}

std::unique_ptr<Session> Session::open(const std::filesystem::path& scenePath) {
  if (!std::filesystem::exists(scenePath)) throw Error(scenePath.string(), "", "scene file does not exist");
  Json json = readJsonFile(scenePath);
  scene::Scene scene = scene::parseScene(json, scenePath.string(), scenePath.parent_path());
  scene.path = scenePath;
  return std::make_unique<Session>(std::move(scene), std::move(json), scenePath.parent_path());
}

Session::~Session() = default;

size_t Session::systemFor(const std::string& model) {
  for (size_t s = 0; s < systemModels_.size(); ++s)
    if (systemModels_[s] == model) return s;
  const models::ModelType* type = scene::findModelType(model);
  if (!type) return systems_.size();
  systems_.push_back(type->createSystem(models::SystemContext{scene_.seed, scene_.stepTime}));
  systemModels_.push_back(model);
  return systems_.size() - 1;
}

void Session::step() {
  updateSupports(true);
  if (air_) {
    // The air and the plants that take the air's push act on each other (two-way coupling),
    // then the plants step.
    std::vector<models::AirCoupling*> coupled;
    for (auto& s : systems_)
      if (models::AirCoupling* a = s->airCoupling()) coupled.push_back(a);
    // The air meets obstacles, not the plants' stems (particle plants push it themselves).
    viewingAs(env::Environment::kNoStems, [&] { air_->step(*env_, std::span<models::AirCoupling* const>(coupled)); });
    airSeconds_ += air_->timings().total;
    ++airSteps_;
  }
  for (size_t s = 0; s < systems_.size(); ++s) viewingAs(s, [&] { systems_[s]->step(*env_); });
  ++steps_;
}

void Session::run(uint32_t steps, const std::function<void(uint32_t)>& onStep) {
  for (uint32_t i = 0; i < steps && !finished(); ++i) {
    step();
    if (onStep) onStep(i + 1);
  }
  reportGrowth();
}

std::vector<Session::GrowthReport> Session::diagnoseGrowth() const {
  std::vector<GrowthReport> out;
  for (size_t i = 0; i < plants_.size(); ++i)
    if (auto p = viewingAs(plants_[i].system, [&] {
          return models::diagnoseGrowth(*systems_[plants_[i].system], plants_[i].index, specs_[i].spec, *env_);
        }))
      out.push_back({i, std::move(*p)});
  return out;
}

std::vector<Session::GrowthReport> Session::reportGrowth() {
  std::vector<GrowthReport> found = diagnoseGrowth();
  for (const GrowthReport& r : found)
    // A model warns itself when a plant reaches a cap (max_segments, max_particles).
    if (r.problem.cause != models::GrowthCause::Cap && reportedGrowth_.insert({r.plant, r.problem.cause}).second)
      log::warn("{}", r.problem.message);
  return found;
}

bool Session::finished() const {
  for (const auto& s : systems_)
    if (!s->finished()) return false;
  return true;
}

std::vector<plant::PlantModel> Session::plants() const {
  // Each system snapshots all its plants at once (particle plants share one buffer).
  std::vector<std::vector<plant::PlantModel>> bySystem(systems_.size());
  for (size_t s = 0; s < systems_.size(); ++s) bySystem[s] = systems_[s]->snapshots();
  std::vector<plant::PlantModel> out;
  out.reserve(plants_.size());
  for (const PlantRef& r : plants_) out.push_back(std::move(bySystem[r.system].at(r.index)));
  // Every model's stems, thickened since they were placed, clear of their supports.
  // Their bark is cleared at the rings the scene's meshes sweep.
  const int subdivisions = scene_.output.subdivisions;
  // Plants of very unequal size: the largest first (each also shares out its own work).
  // Each system's plants clear the stems of other systems' support plants too.
  for (size_t s = 0; s < systems_.size(); ++s) {
    std::vector<size_t> mine;
    for (size_t i = 0; i < out.size(); ++i)
      if (plants_[i].system == s) mine.push_back(i);
    std::vector<size_t> size(mine.size());
    for (size_t k = 0; k < mine.size(); ++k) size[k] = out[mine[k]].nodeCount() + out[mine[k]].leafCount();
    viewingAs(s, [&] {
      parallelForLargestFirst(size, [&](size_t k) { models::keepStemsOutside(out[mine[k]], *env_, subdivisions); });
    });
  }
  return out;
}

std::vector<plant::GrowthFlowSpecies> Session::growthFlow() const {
  std::vector<plant::GrowthFlowSpecies> out;
  out.reserve(plants_.size());
  for (const PlantRef& r : plants_) out.push_back(systems_[r.system]->growthFlow(r.index));
  return out;
}

size_t Session::segmentCount() const {
  size_t n = 0;
  for (const auto& s : systems_) n += s->segmentCount();
  return n;
}

std::vector<models::PlantSystem*> Session::systems() {
  supportsStale_ = true;
  std::vector<models::PlantSystem*> out;
  for (const auto& s : systems_) out.push_back(s.get());
  return out;
}

size_t Session::airBodyCount() const {
  size_t n = 0;
  for (const auto& s : systems_)
    if (const models::AirCoupling* a = std::as_const(*s).airCoupling()) n += a->airBodies().ids.size();
  return n;
}

uint32_t Session::addPlant(models::PlantSpec spec, Json description) {
  for (const SpecEntry& e : specs_)
    if (&e - specs_.data() < std::ptrdiff_t(plants_.size()) && e.spec.name == spec.name)
      throw Error("", "/name", fmt::format("plant name \"{}\" is used twice", spec.name));
  const size_t systemsBefore = systems_.size();
  const size_t s = systemFor(spec.model);
  if (s == systems_.size()) throw Error("", "/model", fmt::format("unknown model \"{}\"", spec.model));
  supportsStale_ = true;
  try {
    viewingAs(s, [&] { systems_[s]->addPlant(spec, *env_); });
  } catch (const Error&) {
    if (systems_.size() > systemsBefore) {  // a system made for this plant alone goes again
      systems_.pop_back();
      systemModels_.pop_back();
    }
    throw;
  }
  plants_.push_back({s, systems_[s]->plantCount() - 1});
  // Specs beyond the current plants belong to undone edits: a new plant replaces them.
  specs_.resize(plants_.size() - 1);
  std::string text = description.is_null() ? std::string() : description.dump();
  specs_.push_back({std::move(spec), std::move(description), std::move(text)});
  return uint32_t(plants_.size() - 1);
}

uint32_t Session::addPlant(const Json& plant, const std::string& source) {
  models::PlantSpec spec = scene::parsePlant(plant, source, "", baseDir_, plants_.size());
  try {
    return addPlant(std::move(spec), plant);
  } catch (const Error& e) {
    // As for scene plants: the model's errors are placed in the plant object.
    throw Error(source, e.location().empty() ? "/position" : e.location(), e.message());
  }
}

void Session::setPlantDescription(size_t plant, const Json& description, const std::string& source) {
  if (plant >= plants_.size()) throw Error(source, "", fmt::format("there is no plant {}", plant));
  models::PlantSpec spec = scene::parsePlant(description, source, "", baseDir_, plant);
  SpecEntry& entry = specs_[plant];
  if (spec.model != entry.spec.model)
    throw Error(source, "/model", fmt::format("plant {} is of model \"{}\", not \"{}\"", plant, entry.spec.model, spec.model));
  try {
    viewingAs(plants_.at(plant).system, [&] { system(plant).regrow(indexInSystem(plant), spec, *env_); });
  } catch (const Error& e) {
    if (!e.source().empty()) throw;
    throw Error(source, e.location(), e.message());
  }
  entry.spec = std::move(spec);
  entry.description = description;
  entry.text = description.dump();
}

void Session::environmentChanged() { env_->commit(); }

// --- obstacles at run time ---

namespace {

bool validScale(const Vec3& s) {
  return isFinite(s) && (s.array() >= 1e-4f).all() && (s.array() <= 1e4f).all();
}

}  // namespace

std::shared_ptr<const TriangleMesh> Session::importedMesh(const std::string& path) {
  std::filesystem::path p = path;
  if (p.is_relative()) p = baseDir_ / p;
  const std::string key = p.lexically_normal().string();
  auto it = meshCache_.find(key);
  if (it != meshCache_.end()) return it->second;
  auto mesh = std::make_shared<const TriangleMesh>(env::loadMeshFile(key));
  meshCache_.emplace(key, mesh);
  return mesh;
}

env::ObstacleDef Session::obstacleDef(size_t index) const {
  env::ObstacleDef d;
  if (index < scene_.obstacles.size()) {
    d = scene_.obstacles[index];
  } else {
    const ImportedObstacle& o = imported_.at(index - scene_.obstacles.size());
    d.name = o.name;
    d.kind = env::ObstacleKind::Mesh;
    d.source = o.path;
    d.mesh = *o.mesh;
    d.color = o.color;
  }
  const Vec3& scale = obstacleScales_.at(index);
  if (scale != Vec3::Ones())
    for (Vec3& v : d.mesh.positions) v = v.cwiseProduct(scale);
  return d;
}

void Session::rebuildEnvironment(const std::vector<RigidTransform>& transforms) {
  auto env = std::make_unique<env::Environment>();
  for (size_t i = 0; i < obstacleScales_.size(); ++i) {
    env::ObstacleDef d = obstacleDef(i);
    if (i < transforms.size()) d.worldFromLocal = transforms[i];
    env->addObstacle(std::move(d));
  }
  env->setLights(env_->lights());
  env->setStrokes(env_->strokes());
  env->setWind(env_->windField().settings());
  if (air_) env->setAirFlow(air_.get());
  env->commit();
  env_ = std::move(env);
  // The new environment has no stems yet.
  systemHasSupports_.clear();
  supportsStale_ = true;
  ++obstacleRevision_;
}

uint32_t Session::importObstacle(const std::string& path, std::string name, const RigidTransform& worldFromLocal,
                                 const Vec3& scale, const Vec3& color) {
  if (path.empty()) throw Error("", "/path", "is empty: give a mesh file (.obj, .ply, .stl, .gltf, .glb...)");
  if (!validScale(scale))
    throw Error("", "/scale",
                fmt::format("must be in [1e-4, 1e4] on every axis, got [{}, {}, {}]", scale.x(), scale.y(), scale.z()));
  if (!isFinite(worldFromLocal.translation) || !isFinite(Vec3(worldFromLocal.rotation.vec())) ||
      !std::isfinite(worldFromLocal.rotation.w()))
    throw Error("", "/position", "the obstacle's transform is not finite");
  ImportedObstacle o;
  o.path = path;
  o.name = name.empty() ? std::filesystem::path(path).stem().string() : std::move(name);
  o.color = color;
  o.mesh = importedMesh(path);  // throws Error(file, ...) naming the file
  imported_.push_back(o);
  obstacleScales_.push_back(scale);
  env::ObstacleDef d = obstacleDef(obstacleScales_.size() - 1);
  d.worldFromLocal = worldFromLocal;
  env_->addObstacle(std::move(d));
  env_->commit();
  ++obstacleRevision_;
  return uint32_t(env_->obstacleCount() - 1);
}

const std::string& Session::obstaclePath(uint32_t obstacle) const {
  static const std::string kNone;
  if (obstacle >= obstacleScales_.size()) throw Error("", "", fmt::format("there is no obstacle {}", obstacle));
  return obstacle < scene_.obstacles.size() ? kNone : imported_[obstacle - scene_.obstacles.size()].path;
}

void Session::setObstacleScale(uint32_t obstacle, const Vec3& scale) {
  if (obstacle >= obstacleScales_.size())
    throw Error("", "/obstacle",
                fmt::format("there is no obstacle {} (the scene has {})", obstacle, obstacleScales_.size()));
  if (!validScale(scale))
    throw Error("", "/scale",
                fmt::format("must be in [1e-4, 1e4] on every axis, got [{}, {}, {}]", scale.x(), scale.y(), scale.z()));
  if (obstacleScales_[obstacle] == scale) return;
  std::vector<RigidTransform> transforms(env_->obstacleCount());
  for (uint32_t o = 0; o < transforms.size(); ++o) transforms[o] = env_->obstacle(o).worldFromLocal;
  obstacleScales_[obstacle] = scale;
  rebuildEnvironment(transforms);
}

std::vector<uint8_t> Session::saveState() const {
  ArchiveWriter out;
  out.tag(kStateTag);
  out.u32(kStateVersion);
  out.u32(steps_);
  out.u64(plants_.size());
  for (size_t i = 0; i < plants_.size(); ++i) {
    out.string(specs_[i].spec.model);
    out.string(specs_[i].text);
  }
  // The environment's editable state; obstacle meshes come from the scene and from the
  // imported files (read again on load).
  out.u64(env_->obstacleCount());
  for (uint32_t o = 0; o < env_->obstacleCount(); ++o) {
    out.value(env_->obstacle(o).worldFromLocal);
    out.value(obstacleScales_[o]);
  }
  out.u64(imported_.size());
  for (const ImportedObstacle& o : imported_) {
    out.string(o.path);
    out.string(o.name);
    out.value(o.color);
  }
  out.vector(env_->lights());
  out.u64(env_->strokes().size());
  for (const env::Stroke& s : env_->strokes()) {
    out.boolean(s.attract);
    out.f32(s.radius);
    out.f32(s.strength);
    out.vector(s.points);
  }
  saveWind(out, env_->windField().settings());
  out.u64(systems_.size());
  for (size_t s = 0; s < systems_.size(); ++s) {
    out.string(systemModels_[s]);
    systems_[s]->saveState(out);
  }
  out.boolean(air_ != nullptr);
  if (air_) air_->saveState(out);
  return out.take();
}

// Everything a saved state holds, read and checked before the session changes.
struct Session::Loaded {
  uint32_t steps = 0;
  std::vector<SpecEntry> specs;
  std::vector<RigidTransform> transforms;
  std::vector<Vec3> scales;
  std::vector<ImportedObstacle> imported;
  std::vector<env::Light> lights;
  std::vector<env::Stroke> strokes;
  env::WindSettings wind;
  std::vector<std::unique_ptr<models::PlantSystem>> systems;
  std::vector<std::string> systemModels;
  std::vector<PlantRef> plants;
  std::unique_ptr<wind::SphAir> air;
};

void Session::loadState(std::span<const uint8_t> bytes, const std::string& source) {
  ArchiveReader in(bytes, source);
  in.tag(kStateTag, "a session state");
  const size_t versionAt = in.position();
  const uint32_t version = in.u32();
  if (version != kStateVersion && version != 1)
    in.fail(versionAt, fmt::format("session state version {} is not supported (this build reads {})", version,
                                   kStateVersion));
  Loaded loaded;
  loaded.steps = in.u32();

  readSavedPlants(in, source, loaded);
  readSavedEnvironment(in, version, loaded);
  restoreSystems(in, loaded);
  if (!in.atEnd()) in.fail("unexpected data after the session state");
  // The imported meshes (from this session's cache, or read again from their files).
  for (ImportedObstacle& o : loaded.imported) {
    try {
      o.mesh = importedMesh(o.path);
    } catch (const Error& e) {
      throw Error(source, "", fmt::format("imported obstacle \"{}\": {}", o.name, e.what()));
    }
  }
  // Everything read: now the session changes.
  applyLoaded(std::move(loaded));
  refreshSupports();
}


void Session::readSavedPlants(ArchiveReader& in, const std::string& source, Loaded& loaded) const {
  // The plants: the ones this session knows by the same description are reused; others are
  // read again from their scene-file objects.
  const uint64_t plantCount = in.count(16, "plants");
  std::vector<SpecEntry>& specs = loaded.specs;
  for (uint64_t i = 0; i < plantCount; ++i) {
    const size_t at = in.position();
    std::string model = in.string();
    std::string text = in.string();
    if (i < specs_.size() && specs_[i].spec.model == model && specs_[i].text == text) {
      specs.push_back(specs_[i]);
      continue;
    }
    if (text.empty()) in.fail(at, fmt::format("plant {} was added from code and cannot be restored here", i));
    Json description;
    try {
      description = parseJson(text, source);
    } catch (const Error& e) {
      in.fail(at, fmt::format("plant {}: {}", i, e.message()));
    }
    models::PlantSpec spec = scene::parsePlant(description, source, fmt::format("/plants/{}", i), baseDir_, i);
    if (spec.model != model) in.fail(at, fmt::format("plant {} is of model \"{}\", not \"{}\"", i, spec.model, model));
    specs.push_back({std::move(spec), std::move(description), std::move(text)});
  }
}

void Session::readSavedEnvironment(ArchiveReader& in, uint32_t version, Loaded& loaded) const {
  const size_t obstaclesAt = in.position();
  const uint64_t obstacles = in.count(sizeof(RigidTransform), "obstacles");
  if (obstacles < scene_.obstacles.size())
    in.fail(obstaclesAt, fmt::format("the saved environment has {} obstacles, the scene {}", obstacles,
                                     scene_.obstacles.size()));
  std::vector<RigidTransform>& transforms = loaded.transforms;
  std::vector<Vec3>& scales = loaded.scales;
  transforms.resize(obstacles);
  scales.assign(obstacles, Vec3::Ones());
  for (size_t o = 0; o < obstacles; ++o) {
    in.value(transforms[o]);
    if (version >= 2) {
      const size_t at = in.position();
      in.value(scales[o]);
      if (!validScale(scales[o])) in.fail(at, fmt::format("obstacle {} has a bad scale", o));
    }
  }
  std::vector<ImportedObstacle>& imported = loaded.imported;
  if (version >= 2) {
    const size_t importedAt = in.position();
    imported.resize(size_t(in.count(24, "imported obstacles")));
    if (scene_.obstacles.size() + imported.size() != obstacles)
      in.fail(importedAt, fmt::format("the saved environment has {} obstacles: {} from the scene and {} imported",
                                      obstacles, scene_.obstacles.size(), imported.size()));
    for (ImportedObstacle& o : imported) {
      o.path = in.string();
      o.name = in.string();
      in.value(o.color);
    }
  } else if (obstacles != scene_.obstacles.size()) {
    in.fail(obstaclesAt, fmt::format("the saved environment has {} obstacles, the scene {}", obstacles,
                                     scene_.obstacles.size()));
  }
  std::vector<env::Light>& lights = loaded.lights;
  std::vector<env::Stroke>& strokes = loaded.strokes;
  lights = in.vector<env::Light>();
  strokes.resize(size_t(in.count(17, "strokes")));
  for (env::Stroke& s : strokes) {
    s.attract = in.boolean();
    s.radius = in.f32();
    s.strength = in.f32();
    in.vector(s.points);
  }
  loaded.wind = loadWind(in);
  // What the scene format would refuse is refused here too: an obstacle moved past the world's
  // extent, a light or stroke out of range (the readers' own limits, scene/settings_schema.h).
  // Edits only make such values from checked input.
  {
    auto near = [](const Vec3& p) { return isFinite(p) && p.cwiseAbs().maxCoeff() <= JsonObject::kWorldExtent; };
    auto unit = [](const Quat& q) { return std::isfinite(q.squaredNorm()) && std::abs(q.squaredNorm() - 1.0f) < 1e-2f; };
    for (size_t o = 0; o < obstacles; ++o)
      if (!near(transforms[o].translation) || !unit(transforms[o].rotation))
        in.fail(obstaclesAt, fmt::format("obstacle {} of the saved environment has a bad position or rotation", o));
    for (size_t i = 0; i < lights.size(); ++i)
      if (auto bad = scene::checkLight(lights[i]))
        in.fail(fmt::format("a light of the saved environment is out of range: /lights/{}{}", i, *bad));
    for (size_t i = 0; i < strokes.size(); ++i)
      if (auto bad = scene::checkStroke(strokes[i]))
        in.fail(fmt::format("a painted stroke of the saved environment is out of range: /strokes/{}{}", i, *bad));
  }
}

void Session::restoreSystems(ArchiveReader& in, Loaded& loaded) const {
  // Systems made afresh for the saved plants (seeded in an empty world: their seeds are not
  // checked against obstacles that may have moved since), then given their saved state.
  env::Environment empty;
  empty.commit();
  std::vector<std::unique_ptr<models::PlantSystem>>& systems = loaded.systems;
  std::vector<std::string>& systemModels = loaded.systemModels;
  std::vector<PlantRef>& plants = loaded.plants;
  for (const SpecEntry& e : loaded.specs) {
    size_t s = 0;
    while (s < systemModels.size() && systemModels[s] != e.spec.model) ++s;
    if (s == systems.size()) {
      const models::ModelType* type = scene::findModelType(e.spec.model);
      if (!type) in.fail(fmt::format("unknown model \"{}\"", e.spec.model));
      systems.push_back(type->createSystem(models::SystemContext{scene_.seed, scene_.stepTime}));
      systemModels.push_back(e.spec.model);
    }
    try {
      systems[s]->addPlant(e.spec, empty);
    } catch (const Error& err) {
      in.fail(fmt::format("plant \"{}\": {}", e.spec.name, err.message()));
    }
    plants.push_back({s, systems[s]->plantCount() - 1});
  }
  const size_t systemsAt = in.position();
  if (in.u64() != systems.size()) in.fail(systemsAt, "the saved plant systems differ from the saved plants");
  for (size_t s = 0; s < systems.size(); ++s) {
    const size_t at = in.position();
    if (in.string() != systemModels[s]) in.fail(at, "the saved plant systems differ from the saved plants");
    systems[s]->loadState(in);
  }
  const size_t airAt = in.position();
  const bool hasAir = in.boolean();
  if (hasAir != (air_ != nullptr))
    in.fail(airAt, hasAir ? "the saved state has simulated air, this scene has none"
                          : "the saved state has no simulated air, this scene has");
  if (hasAir) {
    loaded.air = std::make_unique<wind::SphAir>(air_->settings());
    loaded.air->loadState(in);
  }
}

// The environment is rebuilt when its obstacle meshes differ (an import or a rescale undone);
// obstacles imported since are appended.
void Session::applyLoaded(Loaded&& loaded) {
  std::vector<ImportedObstacle>& imported = loaded.imported;
  std::vector<Vec3>& scales = loaded.scales;
  const std::vector<RigidTransform>& transforms = loaded.transforms;
  if (loaded.air) {
    air_ = std::move(loaded.air);
    env_->setAirFlow(air_.get());
  }
  const bool samePrefix = imported.size() >= imported_.size() &&
                          std::equal(imported_.begin(), imported_.end(), imported.begin()) &&
                          std::equal(obstacleScales_.begin(), obstacleScales_.end(), scales.begin());
  if (!samePrefix) {
    imported_ = std::move(imported);
    obstacleScales_ = std::move(scales);
    rebuildEnvironment(transforms);
  } else if (imported.size() > imported_.size()) {
    for (size_t i = imported_.size(); i < imported.size(); ++i) {
      imported_.push_back(imported[i]);
      obstacleScales_.push_back(scales[scene_.obstacles.size() + i]);
      env::ObstacleDef d = obstacleDef(obstacleScales_.size() - 1);
      d.worldFromLocal = transforms[obstacleScales_.size() - 1];
      env_->addObstacle(std::move(d));
    }
    ++obstacleRevision_;
  }
  for (uint32_t o = 0; o < transforms.size(); ++o) env_->setObstacleTransform(o, transforms[o]);
  env_->setLights(std::move(loaded.lights));
  env_->setStrokes(std::move(loaded.strokes));
  env_->setWind(std::move(loaded.wind));
  env_->commit();
  systems_ = std::move(loaded.systems);
  systemModels_ = std::move(loaded.systemModels);
  supportsStale_ = true;
  plants_ = std::move(loaded.plants);
  // Specs beyond the restored plants are kept (a redo may bring their plants back).
  for (size_t i = 0; i < loaded.specs.size(); ++i) {
    if (i < specs_.size())
      specs_[i] = std::move(loaded.specs[i]);
    else
      specs_.push_back(std::move(loaded.specs[i]));
  }
  steps_ = loaded.steps;
}

void Session::setEmitters(std::vector<env::WindEmitter> emitters) {
  env::WindSettings w = env_->windField().settings();
  if (air_) {
    // Checked first, so that a bad emitter leaves the air as it was.
    for (const env::WindEmitter& e : emitters) air_->checkEmitter(sphEmitter(e));
    air_->clearEmitters();
    for (const env::WindEmitter& e : emitters) air_->addEmitter(sphEmitter(e));
  }
  w.emitters = std::move(emitters);
  env_->setWind(std::move(w));
}

uint64_t Session::stateHash() const {
  Hasher h;
  h.add(steps_);
  h.add(uint64_t(plants_.size()));
  for (const plant::PlantModel& p : plants()) h.add(plant::contentHash(p));
  for (size_t i = 0; i < plants_.size(); ++i) h.add(std::string_view(specs_[i].text));
  h.add(uint64_t(env_->obstacleCount()));
  for (uint32_t o = 0; o < env_->obstacleCount(); ++o) {
    const RigidTransform& t = env_->obstacle(o).worldFromLocal;
    h.add(t.rotation.coeffs().data(), 4 * sizeof(float));
    h.add(t.translation);
    h.add(obstacleScales_[o]);
  }
  for (const ImportedObstacle& o : imported_) {
    h.add(std::string_view(o.path)), h.add(std::string_view(o.name)), h.add(o.color);
  }
  for (const env::Light& l : env_->lights()) {
    h.add(uint32_t(l.type)), h.add(l.direction), h.add(l.position), h.add(l.intensity), h.add(l.angularRadius);
    h.add(l.samples);
  }
  for (const env::Stroke& s : env_->strokes()) {
    h.add(uint8_t(s.attract)), h.add(s.radius), h.add(s.strength), h.add(s.points);
  }
  const env::WindSettings& w = env_->windField().settings();
  h.add(uint32_t(w.mode)), h.add(w.velocity), h.add(w.gustStrength), h.add(w.gustPeriod), h.add(w.gustScale);
  h.add(w.gustTurn), h.add(w.seed);
  for (const env::WindEmitter& e : w.emitters) {
    h.add(e.position), h.add(e.direction), h.add(e.speed), h.add(e.radius), h.add(e.reach), h.add(e.spread);
    h.add(e.rate);
  }
  if (air_) {
    h.add(air_->positions());
    h.add(air_->velocities());
  }
  return h.digest();
}

}  // namespace tendril::session
