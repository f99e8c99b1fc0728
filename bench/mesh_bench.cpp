// Meshing and .glb export of a synthetic 300k-segment ivy with leaves (the CLI's budget is
// >= 200k skeleton segments/s for grow + mesh + .glb on 2 cores).
#include "support/synthetic_plants.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/mesh/plant_mesh.h"

#include <benchmark/benchmark.h>

#include <filesystem>

namespace {

using namespace tendril;

const plant::PlantModel& ivy300k() {
  static const plant::PlantModel plant = meshtest::syntheticIvy(300000);
  return plant;
}

void setCounters(benchmark::State& state, size_t segments) {
  state.counters["segments/s"] =
      benchmark::Counter(static_cast<double>(segments), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_MeshPlant(benchmark::State& state) {
  const plant::PlantModel& p = ivy300k();
  mesh::MeshOptions o;
  o.subdivisions = static_cast<int>(state.range(0));
  size_t triangles = 0;
  for (auto _ : state) {
    mesh::PlantMesh m = mesh::buildPlantMesh(p, o);
    triangles = m.triangleCount();
    benchmark::DoNotOptimize(m.bark.positions.data());
  }
  state.counters["triangles"] = static_cast<double>(triangles);
  setCounters(state, p.nodeCount());
}
BENCHMARK(BM_MeshPlant)->Arg(1)->Arg(3)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_MeshAndWriteGlb(benchmark::State& state) {
  io::ExportScene scene;
  scene.plants.push_back(ivy300k());
  io::ExportOptions o;
  o.mesh.subdivisions = static_cast<int>(state.range(0));
  std::filesystem::path out = std::filesystem::temp_directory_path() / "tendril_mesh_bench.glb";
  for (auto _ : state) io::writeGlb(scene, out, o);
  state.counters["MB"] = static_cast<double>(std::filesystem::file_size(out)) / 1e6;
  std::filesystem::remove(out);
  setCounters(state, scene.plants[0].nodeCount());
}
BENCHMARK(BM_MeshAndWriteGlb)->Arg(1)->Arg(3)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
