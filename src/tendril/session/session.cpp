#include "tendril/session/session.h"

#include "tendril/core/error.h"
#include "tendril/particles/particle_model.h"

#include <fmt/format.h>

namespace tendril::session {

Session::Session(scene::Scene scene) : scene_(std::move(scene)), env_(std::make_unique<env::Environment>()) {
  scene::populateEnvironment(scene_, *env_);
  const models::SystemContext context{scene_.seed, scene_.stepTime};
  for (const scene::PlantSpec& p : scene_.plants) {
    size_t s = 0;
    while (s < systemModels_.size() && systemModels_[s] != p.model) ++s;
    if (s == systems_.size()) {
      const models::ModelType* type = models::findModelType(p.model);
      if (!type) throw Error(scene_.source, p.pointer + "/model", fmt::format("unknown model \"{}\"", p.model));
      systems_.push_back(type->createSystem(context));
      systemModels_.push_back(p.model);
    }
    try {
      systems_[s]->addPlant(p, *env_);
    } catch (const Error& e) {
      throw Error(scene_.source, e.location().empty() ? p.pointer + "/position" : p.pointer + e.location(),
                  e.message());
    }
    plants_.push_back({s, systems_[s]->plantCount() - 1});
  }
  // Simulated air (seed 000 §5.3): the scene's emitters feed it, the wind field samples it.
  if (scene_.wind.mode == env::WindMode::Sph) {
    wind::SphSettings settings = scene_.sph;
    for (const auto& s : systems_)
      if (auto* p = dynamic_cast<const particles::ParticlePlantSystem*>(s.get())) settings.dt = p->world().settings().dt;
    air_ = std::make_unique<wind::SphAir>(settings);
    for (const env::WindEmitter& e : scene_.wind.emitters) {
      wind::SphEmitter se;
      se.position = e.position;
      se.direction = e.direction;
      se.speed = e.speed;
      se.rate = e.rate;
      se.radius = e.radius;
      air_->addEmitter(se);
    }
    if (scene_.sphFill) air_->fillBox(settings.domainMin, settings.domainMax, *env_, scene_.wind.velocity);
    env_->setAirFlow(air_.get());
  }
}

Session::~Session() = default;

void Session::step() {
  if (air_) {
    // The air and the particle plants act on each other (two-way coupling), then the plants step.
    particles::ParticleWorld* world = nullptr;
    for (auto& s : systems_)
      if (auto* p = dynamic_cast<particles::ParticlePlantSystem*>(s.get())) world = &p->world();
    air_->step(*env_, world);
  }
  for (auto& s : systems_) s->step(*env_);
  ++steps_;
}

void Session::run(uint32_t steps, const std::function<void(uint32_t)>& onStep) {
  for (uint32_t i = 0; i < steps && !finished(); ++i) {
    step();
    if (onStep) onStep(i + 1);
  }
}

bool Session::finished() const {
  for (const auto& s : systems_)
    if (!s->finished()) return false;
  return true;
}

std::vector<plant::PlantModel> Session::plants() const {
  std::vector<plant::PlantModel> out;
  out.reserve(plants_.size());
  for (const PlantRef& r : plants_) out.push_back(systems_[r.system]->snapshot(r.index));
  return out;
}

std::vector<wind::GrowthFlowSpecies> Session::growthFlow() const {
  std::vector<wind::GrowthFlowSpecies> out;
  out.reserve(plants_.size());
  for (const PlantRef& r : plants_) out.push_back(systems_[r.system]->growthFlow(r.index));
  return out;
}

size_t Session::segmentCount() const {
  size_t n = 0;
  for (const auto& s : systems_) n += s->segmentCount();
  return n;
}

}  // namespace tendril::session
