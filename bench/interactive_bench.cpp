// The studio's interactive frame without the GL draw: one simulation step of a particle scene,
// the plant snapshots the viewport draws and the renderer's per-frame instance arrays
// (render/plant_instances.h), for about 5k and 25k particles. The scenes are
// bench/scenes/interactive-*.json (fast-growing ivies, so the setup takes a few hundred
// steps). Results and commands: bench/README.md.
#include "tendril/core/parallel.h"
#include "tendril/core/timer.h"
#include "tendril/mesh/leaf_mesh.h"
#include "tendril/models/stand_off.h"
#include "support/particle_session.h"
#include "tendril/particles/world.h"
#include "tendril/render/plant_instances.h"
#include "tendril/session/session.h"

#include "process_cpu.h"

#include <benchmark/benchmark.h>

// Under `valgrind --tool=callgrind --instr-atstart=no --collect-atstart=no`, only the timed
// frames are counted (the setup runs uninstrumented); no-ops otherwise.
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_TOGGLE_COLLECT
#endif

#include <time.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <vector>

namespace tendril {
namespace {

using bench::processCpuSeconds;

struct Grown {
  std::unique_ptr<session::Session> session;
  double growSeconds = 0;
};

// Opens the scene and steps it until the particle world holds 97 % of `target` particles or
// has stopped growing for 50 steps.
Grown& grown(size_t target) {
  static std::map<size_t, Grown> cache;
  Grown& g = cache[target];
  if (g.session) return g;
  Timer t;
  const char* file = target <= 5000 ? "interactive-5k.json" : "interactive-25k.json";
  g.session = session::Session::open(std::filesystem::path(__FILE__).parent_path() / "scenes" / file);
  const particles::ParticleWorld* world = test::particleWorld(*g.session);
  size_t last = 0;
  for (int step = 0, still = 0; step < 3000 && world->particleCount() < target * 97 / 100 && still < 50; ++step) {
    g.session->step();
    still = world->particleCount() == last ? still + 1 : 0;
    last = world->particleCount();
  }
  g.growSeconds = t.seconds();
  return g;
}

void BM_InteractiveFrame(benchmark::State& state) {
  Grown& g = grown(size_t(state.range(0)));
  session::Session& s = *g.session;
  std::vector<render::BranchInstance> branches;
  std::vector<render::LeafInstance> leaves;
  std::vector<render::PlantView> views;
  std::vector<render::PlantMaterial> materials;
  std::vector<double> total, stepMs, snapshotMs, instanceMs, cpu;
  size_t nodes = 0, leafCount = 0;
  CALLGRIND_START_INSTRUMENTATION;
  for (auto _ : state) {
    const double cpu0 = processCpuSeconds();
    Timer t;
    CALLGRIND_TOGGLE_COLLECT;
    s.step();
    const double step = t.seconds();
    std::vector<plant::PlantModel> plants = s.plants();
    const double snapshot = t.seconds() - step;
    // As the renderer does it: materials resolved first, then every plant's instances at once.
    views.assign(plants.size(), render::PlantView{});
    materials.resize(plants.size());
    for (size_t i = 0; i < plants.size(); ++i) {
      views[i].model = &plants[i];
      size_t shapes = mesh::leafShapeCount(plants[i]);
      materials[i].shapeLayer.assign(shapes, 0.0f);
      materials[i].shapeAspect.assign(shapes, 1.0f);
      materials[i].shapeTint.assign(shapes, Vec3::Ones());
    }
    render::buildPlantInstances(views, materials, branches, leaves);
    CALLGRIND_TOGGLE_COLLECT;
    const double seconds = t.seconds();
    cpu.push_back(processCpuSeconds() - cpu0);
    state.SetIterationTime(seconds);
    total.push_back(seconds);
    stepMs.push_back(step);
    snapshotMs.push_back(snapshot);
    instanceMs.push_back(seconds - step - snapshot);
    nodes = branches.size();
    leafCount = leaves.size();
  }
  auto medianMs = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2] * 1e3;
  };
  state.counters["particles"] = double(test::particleWorld(s)->particleCount());
  state.counters["segments"] = double(nodes);
  state.counters["leaves"] = double(leafCount);
  state.counters["median_ms"] = medianMs(total);
  state.counters["step_ms"] = medianMs(stepMs);
  state.counters["snapshot_ms"] = medianMs(snapshotMs);
  state.counters["instances_ms"] = medianMs(instanceMs);
  state.counters["cpu_ms"] = medianMs(cpu);
  state.counters["setup_s"] = g.growSeconds;
}
BENCHMARK(BM_InteractiveFrame)
    ->Arg(5000)
    ->Arg(25000)
    ->ArgName("particles")
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(30);

// The part of the snapshots that keeps every stem's bark off its support
// (models/stand_off.h), on the plants as the models hand them out, plants in parallel as
// Session::plants() does it.
void BM_KeepStemsOutside(benchmark::State& state) {
  Grown& g = grown(size_t(state.range(0)));
  session::Session& s = *g.session;
  std::vector<plant::PlantModel> raw;
  for (models::PlantSystem* system : s.systems())
    for (plant::PlantModel& p : system->snapshots()) raw.push_back(std::move(p));
  size_t moved = 0, nodes = 0;
  for (const plant::PlantModel& p : raw) nodes += p.nodeCount();
  for (auto _ : state) {
    state.PauseTiming();
    std::vector<plant::PlantModel> plants = raw;
    state.ResumeTiming();
    std::vector<size_t> count(plants.size());
    parallelFor(size_t(0), plants.size(), [&](size_t i) { count[i] = models::keepStemsOutside(plants[i], s.environment()); }, 1);
    moved = 0;
    for (size_t c : count) moved += c;
    benchmark::DoNotOptimize(plants.data());
  }
  state.counters["segments"] = double(nodes);
  state.counters["moved"] = double(moved);  // points moved plus leaves laid, shrunk or dropped
}
BENCHMARK(BM_KeepStemsOutside)->Arg(5000)->Arg(25000)->ArgName("particles")->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(20);

}  // namespace
}  // namespace tendril
