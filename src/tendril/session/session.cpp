#include "tendril/session/session.h"

#include "tendril/core/error.h"

namespace tendril::session {

Session::Session(scene::Scene scene)
    : scene_(std::move(scene)), env_(std::make_unique<env::Environment>()), climb_(scene_.seed, scene_.stepTime) {
  scene::populateEnvironment(scene_, *env_);
  const std::string& source = scene_.source;
  for (const scene::PlantSpec& p : scene_.plants) {
    climb::ClimbPlantDef def;
    def.name = p.name;
    def.species = p.climbSpecies;
    def.position = p.position;
    def.direction = p.direction;
    def.seed = p.seed;
    try {
      climbIds_.push_back(climb_.addPlant(def, *env_));
    } catch (const Error& e) {
      throw Error(source, p.pointer + "/position", e.message());
    }
  }
}

Session::~Session() = default;

void Session::step() {
  climb_.step(*env_);
  ++steps_;
}

void Session::run(uint32_t steps, const std::function<void(uint32_t)>& onStep) {
  for (uint32_t i = 0; i < steps && !finished(); ++i) {
    step();
    if (onStep) onStep(i + 1);
  }
}

bool Session::finished() const { return climb_.finished(); }

std::vector<plant::PlantModel> Session::plants() const {
  std::vector<plant::PlantModel> out;
  for (uint32_t id : climbIds_) out.push_back(climb_.snapshot(id));
  return out;
}

size_t Session::segmentCount() const { return climb_.stats().segments; }

}  // namespace tendril::session
