// The component-graph model (seed 004) at scale: the chestnut example (a cascade of four Tree
// components with palmate leaves, Fig. 6) with its branch counts raised to more than 100k
// leaves and 1M triangles, timed per phase: expansion (p-graph → i-tree, stems and placements),
// geometry (i-tree → PlantModel) and export (meshing + .glb). Budget: 1.5 s in total on the
// 2-core CI machine. Results and the command that produced them: bench/README.md.
#include "tendril/core/timer.h"
#include "tendril/graph/build_plant.h"
#include "tendril/graph/expand.h"
#include "tendril/graph/graph.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>

#include <filesystem>

namespace tendril {
namespace {

std::shared_ptr<const graph::Graph> scaledChestnut() {
  auto set = [](const char* key, int value) {
    return graph::Override{key, Json(value), {"bench", std::string("--set ") + key}};
  };
  // 16 boughs × 12 branches × 10 twigs × 8 leaves × 7 leaflets = 107,520 leaves.
  return graph::loadGraph(std::filesystem::path(TENDRIL_EXAMPLES_DIR) / "graphs/chestnut.json",
                          {set("trunk/branches", 16), set("bough/branches", 12), set("branch/branches", 10),
                           set("twig/branches", 8)});
}

void BM_GraphChestnut(benchmark::State& state) {
  auto graph = scaledChestnut();
  std::filesystem::path out = std::filesystem::temp_directory_path() / "tendril_graph_bench.glb";
  double expandS = 0, geometryS = 0, exportS = 0;
  size_t leaves = 0, triangles = 0, instances = 0, nodes = 0;
  for (auto _ : state) {
    Timer t;
    graph::ITree tree = graph::expand(graph, {graph->seed, {}});
    double e = t.seconds();
    t.reset();
    io::ExportScene scene;
    scene.plants.push_back(graph::buildPlant(tree));
    double g = t.seconds();
    t.reset();
    io::ExportModel model = io::buildExportModel(scene, io::ExportOptions{});
    io::writeGlb(model, out);
    double x = t.seconds();
    state.SetIterationTime(e + g + x);
    expandS += e;
    geometryS += g;
    exportS += x;
    instances = tree.instances.size();
    nodes = scene.plants[0].nodeCount();
    leaves = scene.plants[0].leafCount();
    triangles = 0;
    for (const mesh::PlantMesh& m : model.plantMeshes) triangles += m.triangleCount();
  }
  double n = double(state.iterations());
  state.counters["expand_s"] = expandS / n;
  state.counters["geometry_s"] = geometryS / n;
  state.counters["export_s"] = exportS / n;
  state.counters["instances"] = double(instances);
  state.counters["nodes"] = double(nodes);
  state.counters["leaves"] = double(leaves);
  state.counters["triangles"] = double(triangles);
  state.counters["glb_MB"] = double(std::filesystem::file_size(out)) / 1e6;
  std::filesystem::remove(out);
}
BENCHMARK(BM_GraphChestnut)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
}  // namespace tendril
