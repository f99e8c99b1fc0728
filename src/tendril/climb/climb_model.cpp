#include "tendril/climb/climb_model.h"

#include "tendril/climb/climb_system.h"
#include "tendril/core/embedded.h"
#include "tendril/core/error.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace tendril::climb {

namespace {

constexpr std::string_view kSpeciesDir = "species/";

std::string joinNames(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

// Reads a species document (a preset or a user file) into `s`.
void readSpeciesDocument(const Json& json, const std::string& source, const std::filesystem::path& dir,
                         ClimbSpecies& s) {
  JsonObject o(json, source);
  o.choice("model", "climb", {"climb"});
  readClimbSpecies(o, s, dir.string());
  o.finish();
}

class ClimbPlantSystem final : public models::PlantSystem {
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
  void cut(size_t plant, uint32_t node) override { system_.cut(uint32_t(plant), node); }

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

std::vector<std::string> builtinSpeciesNames() {
  std::vector<std::string> names;
  for (const EmbeddedFile& f : embeddedFiles()) {
    std::string_view path = f.path;
    // Species files of other models (e.g. "model": "particles") are not climbing species.
    if (f.contents.find("\"model\": \"climb\"") == std::string_view::npos) continue;
    if (path.rfind(kSpeciesDir, 0) == 0 && path.size() > 5 && path.substr(path.size() - 5) == ".json")
      names.emplace_back(path.substr(kSpeciesDir.size(), path.size() - kSpeciesDir.size() - 5));
  }
  return names;
}

ClimbSpecies loadSpecies(const std::string& ref, const std::filesystem::path& baseDir, const std::string& source,
                         const std::string& pointer) {
  bool isPath = ref.find('/') != std::string::npos || (ref.size() > 5 && ref.compare(ref.size() - 5, 5, ".json") == 0);
  ClimbSpecies s;
  if (!isPath) {
    const EmbeddedFile* f = findEmbeddedFile(std::string(kSpeciesDir) + ref + ".json");
    if (!f)
      throw Error(source, pointer,
                  fmt::format("unknown species \"{}\" (built-in: {}; or give a path to a .json file)", ref,
                              joinNames(builtinSpeciesNames())));
    std::string name = "<built-in>/" + std::string(f->path);
    readSpeciesDocument(parseJson(f->contents, name), name, "", s);
    return s;
  }
  std::filesystem::path p = std::filesystem::path(ref).is_absolute() ? std::filesystem::path(ref) : baseDir / ref;
  if (!std::filesystem::exists(p)) throw Error(source, pointer, fmt::format("species file {} does not exist", p.string()));
  readSpeciesDocument(readJsonFile(p), p.string(), p.parent_path(), s);
  return s;
}

models::ModelType climbModelType() {
  return {"climb", "climbing growth after seed 003 (tips, rules, tropisms, collision avoidance)", readClimbPlant,
          [](const models::SystemContext& c) { return std::make_unique<ClimbPlantSystem>(c); }};
}

}  // namespace tendril::climb
