#include "tendril/graph/graph_model.h"

#include "tendril/core/error.h"
#include "tendril/env/seed_check.h"
#include "tendril/graph/build_plant.h"
#include "tendril/plant/plant_archive.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace tendril::graph {

namespace {

class GraphPlantSystem final : public models::PlantSystem {
 public:
  void addPlant(const models::PlantSpec& spec, const env::Environment& env) override {
    const auto* params = spec.paramsAs<GraphPlantParams>();
    if (!params || !params->model) throw Error("", "/graph", "a graph plant needs a \"graph\" file");
    env::checkSeedPosition(env, spec.position, spec.direction);
    plant::PlantModel model = *params->model;
    model.name = spec.name;
    plants_.push_back(std::move(model));
  }
  // A new graph (the studio's p-graph editor): the plant is generated again at once.
  void regrow(size_t plant, const models::PlantSpec& spec, const env::Environment&) override {
    const auto* params = spec.paramsAs<GraphPlantParams>();
    if (!params || !params->model) throw Error("", "/graph", "a graph plant needs a \"graph\" file");
    plant::PlantModel model = *params->model;
    model.name = spec.name;
    plants_.at(plant) = std::move(model);
  }
  void step(const env::Environment&) override {}
  bool finished() const override { return true; }
  size_t plantCount() const override { return plants_.size(); }
  plant::PlantModel snapshot(size_t plant) const override { return plants_[plant]; }
  size_t segmentCount() const override {
    size_t n = 0;
    for (const plant::PlantModel& p : plants_) n += p.nodeCount();
    return n;
  }
  // Graph plants are generated whole and never change: their PlantModels are the state.
  void saveState(ArchiveWriter& out) const override {
    out.u64(plants_.size());
    for (const plant::PlantModel& p : plants_) plant::savePlantModel(out, p);
  }
  void loadState(ArchiveReader& in) override {
    const size_t at = in.position();
    if (in.u64() != plants_.size()) in.fail(at, "the saved graph plants differ from the session's");
    for (plant::PlantModel& p : plants_) plant::loadPlantModel(in, p);
  }

 private:
  std::vector<plant::PlantModel> plants_;
};

// The graph's plant as it stands in a scene.
void generateAt(GraphPlantParams& params, uint64_t seed, const Vec3& position, const Vec3& direction) {
  ExpandOptions options;
  options.seed = seed;
  options.placement.position = position;
  options.placement.rotation = rotationBetween(Vec3::UnitY(), direction);
  const ITree tree = expand(params.graph, options);
  params.instances = tree.instances.size();
  params.model = std::make_shared<const plant::PlantModel>(buildPlant(tree));
}

std::shared_ptr<const models::ModelParams> readGraphPlant(JsonObject& o, const std::filesystem::path& baseDir) {
  auto params = std::make_shared<GraphPlantParams>();
  // "graph_document": the graph itself (an edited graph, e.g. from the studio); "graph" then
  // only names it and places its relative files.
  const Json* document = o.find("graph_document");
  if (document) {
    if (!document->is_object())
      throw o.error("graph_document", "expected a graph object (docs/graph-format.md), got " + describeJson(*document));
  }
  if (!o.has("graph") && !document)
    throw o.error("graph", "is required for a graph plant: the graph file (JSON)");
  std::filesystem::path path = o.string("graph", "");
  if (!path.empty() && path.is_relative()) path = baseDir / path;
  path = path.lexically_normal();
  if (!document && !std::filesystem::exists(path))
    throw o.error("graph", fmt::format("graph file {} does not exist", path.string()));

  std::vector<Override> overrides;
  if (auto ov = o.optionalObject("overrides")) {
    for (auto it = ov->json().begin(); it != ov->json().end(); ++it) {
      ov->markRead(it.key());
      overrides.push_back({it.key(), it.value(), {o.source(), ov->pointerTo(it.key())}});
    }
    ov->finish();
  }
  if (document) {
    const std::string name = path.empty() ? o.source() + " " + o.pointerTo("graph_document") : path.string() + " (edited)";
    params->graph = parseGraph(*document, name, path.empty() ? baseDir : path.parent_path(), overrides);
  } else {
    params->graph = loadGraph(path, overrides);
  }

  // The placement and seed are the scene's shared plant keys (already checked by the scene
  // reader); they are needed here because the plant is generated now.
  const uint64_t seed = o.has("seed") ? o.seed("seed", 0) : params->graph->seed;
  const Vec3 position = o.vec3("position", Vec3::Zero());
  generateAt(*params, seed, position, o.direction("direction", Vec3::UnitY()));
  return params;
}

}  // namespace

models::PlantSpec graphPlant(models::PlantSpec plant, std::shared_ptr<const Graph> graph) {
  auto params = std::make_shared<GraphPlantParams>();
  params->graph = std::move(graph);
  generateAt(*params, plant.seed, plant.position, plant.direction);
  plant.model = "graph";
  plant.params = std::move(params);
  return plant;
}

models::ModelType graphModelType() {
  return {"graph", "component graph after seed 004 (Xfrog: p-graph expanded to an i-tree, then geometry)",
          readGraphPlant, [](const models::SystemContext&) { return std::make_unique<GraphPlantSystem>(); }, "graph"};
}

}  // namespace tendril::graph
