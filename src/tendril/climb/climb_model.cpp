#include "tendril/climb/climb_model.h"

#include "tendril/climb/climb_system.h"
#include "tendril/core/error.h"
#include "tendril/models/species_presets.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace tendril::climb {

namespace {

// Reads a species document (a preset or a user file) into `s`.
void readSpeciesDocument(const models::SpeciesDocument& d, ClimbSpecies& s) {
  JsonObject o(d.json, d.source);
  readClimbSpecies(o, s, d.dir.string());  // its "model" was checked by the loader
  o.finish();
}

class ClimbPlantSystem final : public models::PlantSystem, public models::GrowthGauge, public models::ObstacleHold {
 public:
  explicit ClimbPlantSystem(const models::SystemContext& c) : system_(c.sceneSeed, c.stepTime) {}

  void addPlant(const models::PlantSpec& spec, const env::Environment& env) override {
    const auto* params = spec.paramsAs<ClimbParams>();
    ClimbPlantDef def;
    def.name = spec.name;
    def.species = params ? params->species : ClimbSpecies();
    def.position = spec.position;
    def.direction = spec.direction;
    def.seed = spec.seed;
    system_.addPlant(def, env);
    growthFlow_.push_back(def.species.growthFlow);
  }
  void step(const env::Environment& env) override { system_.step(env); }
  bool finished() const override { return system_.finished(); }
  size_t plantCount() const override { return system_.plantCount(); }
  plant::PlantModel snapshot(size_t plant) const override { return system_.snapshot(uint32_t(plant)); }
  size_t segmentCount() const override { return system_.stats().segments; }
  plant::GrowthFlowSpecies growthFlow(size_t plant) const override { return growthFlow_[plant]; }
  void saveState(ArchiveWriter& out) const override { system_.saveState(out); }
  void loadState(ArchiveReader& in) override { system_.loadState(in); }
  void cut(size_t plant, uint32_t node, bool /*remove: always*/) override { system_.cut(uint32_t(plant), node); }
  const models::GrowthGauge* growthGauge() const override { return this; }
  const models::ObstacleHold* obstacleHold() const override { return this; }
  using models::PlantSystem::obstacleHold;
  // ObstacleHold: a plant seeded on the obstacle moves with it whole.
  size_t obstacleMoving(const env::Environment& env, uint32_t obstacle, const RigidTransform& motion) override {
    return system_.carryWithObstacle(env, obstacle, motion);
  }
  Reading growthReading(size_t plant) const override { return system_.growthReading(uint32_t(plant)); }
  double unhinderedGrowth(size_t plant, uint32_t steps) const override {
    return system_.unhinderedGrowth(uint32_t(plant), steps);
  }

 private:
  ClimbSystem system_;
  std::vector<plant::GrowthFlowSpecies> growthFlow_;
};

std::shared_ptr<const models::ModelParams> readClimbPlant(JsonObject& o, const std::filesystem::path& baseDir) {
  auto params = std::make_shared<ClimbParams>();
  const Json* sp = o.find("species");
  if (!sp) {
    params->species = loadSpecies("japanese-ivy", baseDir, o.source(), o.pointerTo("species"));
  } else if (sp->is_string()) {
    params->species = loadSpecies(sp->get<std::string>(), baseDir, o.source(), o.pointerTo("species"));
  } else if (sp->is_object()) {
    // Inline species: {"base": "<preset or file>", ...fields overriding it}.
    JsonObject so(*sp, o.source(), o.pointerTo("species"));
    std::string base = so.string("base", "japanese-ivy");
    params->species = loadSpecies(base, baseDir, o.source(), so.pointerTo("base"));
    readClimbSpecies(so, params->species, baseDir.string());
    so.finish();
  } else {
    throw o.error("species", "expected a species name, a .json path or an object, got " + describeJson(*sp));
  }
  return params;
}

}  // namespace

std::vector<std::string> builtinSpeciesNames() { return models::builtinSpeciesNames("climb"); }

ClimbSpecies loadSpecies(const std::string& ref, const std::filesystem::path& baseDir, const std::string& source,
                         const std::string& pointer) {
  ClimbSpecies s;
  readSpeciesDocument(models::loadSpeciesDocument("climb", ref, baseDir, source, pointer), s);
  return s;
}

models::ModelType climbModelType() {
  return {"climb", "climbing growth after seed 003 (tips, rules, tropisms, collision avoidance)", readClimbPlant,
          [](const models::SystemContext& c) { return std::make_unique<ClimbPlantSystem>(c); }};
}

}  // namespace tendril::climb
