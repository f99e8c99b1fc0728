// Levels of detail (mesh/lod.h): what a LOD chain adds to writing a .glb, for the chestnut
// component graph (12k segments, 47k leaves, 816k triangles) and a synthetic 100k-segment ivy.
// BM_GlbWithLods/<plant>/<levels>: plant 0 the chestnut, 1 the ivy; 1 level = no chain.
#include "support/synthetic_plants.h"
#include "tendril/core/json_reader.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/mesh/lod.h"
#include "tendril/scene/scene.h"
#include "tendril/session/session.h"

#include <benchmark/benchmark.h>

#include <filesystem>

namespace {

using namespace tendril;

const plant::PlantModel& chestnut() {
  static const plant::PlantModel plant = [] {
    const std::filesystem::path dir = std::filesystem::path(TENDRIL_EXAMPLES_DIR) / "scenes";
    const Json doc = parseJson(R"({"tendril": 1, "steps": 0, "plants": [
        {"name": "chestnut", "model": "graph", "graph": "../graphs/chestnut.json", "position": [0, 0, 0]}]})",
                               "bench");
    session::Session s(scene::parseScene(doc, "bench", dir));
    return s.plants().at(0);
  }();
  return plant;
}

const plant::PlantModel& ivy100k() {
  static const plant::PlantModel plant = meshtest::syntheticIvy(100000);
  return plant;
}

void BM_GlbWithLods(benchmark::State& state) {
  io::ExportScene scene;
  scene.plants.push_back(state.range(0) == 0 ? chestnut() : ivy100k());
  io::ExportOptions o;
  o.lods.levels = int(state.range(1));
  const std::filesystem::path out = std::filesystem::temp_directory_path() / "tendril_lod_bench.glb";
  for (auto _ : state) io::writeGlb(scene, out, o);
  state.counters["MB"] = double(std::filesystem::file_size(out)) / 1e6;
  state.counters["LOD0 triangles"] = double(mesh::buildPlantMesh(scene.plants[0], o.mesh).triangleCount());
  std::filesystem::remove(out);
}
BENCHMARK(BM_GlbWithLods)->Args({0, 1})->Args({0, 4})->Args({1, 1})->Args({1, 4})->Unit(benchmark::kMillisecond)->UseRealTime();

// The LOD chain alone (LOD1..LOD3 of an already meshed LOD0), and the vertex cache and fetch
// ordering of LOD0.
void BM_BuildLods(benchmark::State& state) {
  const plant::PlantModel& p = state.range(0) == 0 ? chestnut() : ivy100k();
  const mesh::PlantMesh lod0 = mesh::buildPlantMesh(p, {});
  mesh::LodSettings lods;
  lods.levels = 4;
  std::vector<mesh::LodLevel> levels;
  for (auto _ : state) {
    mesh::buildLods(p, {}, lod0, lods, levels);
    benchmark::DoNotOptimize(levels.data());
  }
  state.counters["LOD3 triangles"] = double(levels.back().triangles);
}
BENCHMARK(BM_BuildLods)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_OptimizeMeshOrder(benchmark::State& state) {
  const plant::PlantModel& p = state.range(0) == 0 ? chestnut() : ivy100k();
  const mesh::PlantMesh lod0 = mesh::buildPlantMesh(p, {});
  for (auto _ : state) {
    state.PauseTiming();
    mesh::PlantMesh m = lod0;
    state.ResumeTiming();
    mesh::optimizeMeshOrder(m);
    benchmark::DoNotOptimize(m.bark.indices.data());
  }
  state.counters["triangles"] = double(lod0.triangleCount());
}
BENCHMARK(BM_OptimizeMeshOrder)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
