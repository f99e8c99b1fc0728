// Levels of detail (mesh/lod.h): what a LOD chain adds to writing a .glb, for the chestnut
// component graph (12k segments, 47k leaves, 816k triangles) and a synthetic 100k-segment ivy.
// BM_GlbWithLods/<plant>/<levels>: plant 0 the chestnut, 1 the ivy; 1 level = no chain.
#include "support/synthetic_plants.h"
#include "tendril/core/json_reader.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/render/impostor_baker.h"
#include "tendril/mesh/lod.h"
#include "tendril/scene/scene.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <filesystem>
#include <memory>

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

struct EngineExportScene;
const EngineExportScene& chestnut100k();
const plant::PlantModel& plantOf(int64_t which);

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
  const plant::PlantModel& p = plantOf(state.range(0));
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
BENCHMARK(BM_BuildLods)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_OptimizeMeshOrder(benchmark::State& state) {
  const plant::PlantModel& p = plantOf(state.range(0));
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
BENCHMARK(BM_OptimizeMeshOrder)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();


// Issue 26's done-when export: bench/scenes/chestnut-100k.json (the example chestnut with a
// denser crown: 107,800 leaflets, 22,730 segments, 1.58 M triangles at LOD0), written as an
// engine would take it, with the scene's output settings (4 levels, lod_ratio 0.5, leaf atlas):
// meshing, the LOD chain, the leaf atlas, vertex cache and fetch ordering and the .glb written
// to a file, all timed. The graph's expansion into the plant (once, before) is reported as the
// counter "expand s". BM_ChestnutEngineExportWithImpostor (below) adds the impostor.
struct EngineExportScene {
  io::ExportScene scene;
  io::ExportOptions options;
  double expandSeconds = 0.0;
};

const EngineExportScene& chestnut100k() {
  static const EngineExportScene s = [] {
    EngineExportScene e;
    const auto start = std::chrono::steady_clock::now();
    const std::unique_ptr<session::Session> session =
        session::Session::open(std::filesystem::path(__FILE__).parent_path() / "scenes" / "chestnut-100k.json");
    e.expandSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    e.scene = session::exportScene(*session, "chestnut-100k.json");
    e.options = session::exportOptions(session->scene().output);
    return e;
  }();
  return s;
}

void BM_ChestnutEngineExport(benchmark::State& state) {
  const EngineExportScene& e = chestnut100k();
  const std::filesystem::path out = std::filesystem::temp_directory_path() / "tendril_engine_export_bench.glb";
  for (auto _ : state) io::writeGlb(e.scene, out, e.options);
  state.counters["MB"] = double(std::filesystem::file_size(out)) / 1e6;
  state.counters["leaves"] = double(e.scene.plants[0].leafCount());
  state.counters["expand s"] = e.expandSeconds;
  std::filesystem::remove(out);
}
// BM_BuildLods and BM_OptimizeMeshOrder: plant 0 the chestnut, 1 the ivy, 2 the 100k chestnut.
const plant::PlantModel& plantOf(int64_t which) {
  return which == 0 ? chestnut() : which == 1 ? ivy100k() : chestnut100k().scene.plants.at(0);
}

BENCHMARK(BM_ChestnutEngineExport)->Unit(benchmark::kMillisecond)->UseRealTime();

// The impostor (io/impostor.h, issue 26 part 3), default settings (8 slabs per axis, 256
// texels): BM_ChestnutImpostor/<plant> bakes the slab billboard cloud from LOD0 (the renderer's
// baker: one orthographic llvmpipe pass per slab), packs its atlas pair and encodes the two
// PNGs — io::addImpostors alone, the model built untimed; plant 0 the example chestnut, 2 the
// 100k-leaf chestnut. BM_ChestnutEngineExportWithImpostor: BM_ChestnutEngineExport's whole
// export (4 levels, leaf atlas) plus the impostor as LOD4, written to a .glb.
void BM_ChestnutImpostor(benchmark::State& state) {
  render::installRendererImpostorBaker();
  io::ExportScene scene;
  scene.plants.push_back(plantOf(state.range(0)));
  io::ExportOptions options;
  size_t quads = 0;
  for (auto _ : state) {
    state.PauseTiming();
    io::ExportModel model = io::buildExportModel(scene, options);
    options.impostor.enabled = true;
    state.ResumeTiming();
    io::addImpostors(scene, options, model);
    state.PauseTiming();
    options.impostor.enabled = false;
    quads = model.impostors.at(0).quads.size();
    state.counters["atlas px"] = double(model.impostors[0].color.width) * double(model.impostors[0].color.height);
    state.ResumeTiming();
  }
  state.counters["quads"] = double(quads);
}
BENCHMARK(BM_ChestnutImpostor)->Arg(0)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ChestnutEngineExportWithImpostor(benchmark::State& state) {
  render::installRendererImpostorBaker();
  const EngineExportScene& e = chestnut100k();
  io::ExportOptions options = e.options;
  options.impostor.enabled = true;
  const std::filesystem::path out = std::filesystem::temp_directory_path() / "tendril_engine_export_impostor_bench.glb";
  for (auto _ : state) io::writeGlb(e.scene, out, options);
  state.counters["MB"] = double(std::filesystem::file_size(out)) / 1e6;
  std::filesystem::remove(out);
}
BENCHMARK(BM_ChestnutEngineExportWithImpostor)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
