// Growth-Flow motion (seed 001): one frame of branch sway and leaf motion for a free-standing
// plant of 100k segments and 100k leaves, in a constant and in a gusty wind; and growth and
// motion together, as the studio runs them: 20 particle plants growing through 25k particles
// while they sway in a gusty wind.
#include "tendril/core/timer.h"
#include "tendril/env/wind_field.h"
#include "tendril/session/plant_sway.h"
#include "tendril/session/session.h"
#include "tendril/wind/motion.h"

#include "support/particle_session.h"
#include "support/synthetic_plants.h"

#include "process_cpu.h"

#include <benchmark/benchmark.h>

// Under `valgrind --tool=callgrind --instr-atstart=no --collect-atstart=no`, BM_GrowAndSway
// counts its timed frames only (the scene's first 0.8 s of growth runs uninstrumented); no-ops
// otherwise.
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_TOGGLE_COLLECT
#endif

#include <algorithm>
#include <filesystem>

namespace tendril {
namespace {

plant::PlantModel windPlant(size_t segments, size_t leaves) {
  plant::PlantModel p = meshtest::syntheticIvy(segments, 11);
  for (uint32_t& f : p.flags) f &= ~uint32_t(plant::kNodeClimbing | plant::kNodeAnchored);  // nothing held: all sway
  // A second blade on leaf nodes until there are `leaves` leaves.
  for (size_t j = 0; p.leafCount() < leaves; ++j) {
    plant::PlantModel::LeafDef l;
    l.node = p.leafNode[j];
    l.offset = p.leafOffset[j];
    l.rotation = axisAngle(Vec3::UnitY(), kPi) * p.leafRotation[j];
    l.size = p.leafSize[j];
    l.petiole = p.leafPetiole[j];
    l.shape = p.leafShape[j];
    p.addLeaf(l);
  }
  return p;
}

void BM_WindMotion(benchmark::State& state) {
  const size_t segments = size_t(state.range(0)), leaves = size_t(state.range(1));
  const bool gusty = state.range(2) != 0;
  plant::PlantModel rest = windPlant(segments, leaves);
  env::WindSettings s;
  s.mode = gusty ? env::WindMode::Gusty : env::WindMode::Constant;
  s.velocity = Vec3(9, 0, 3);
  env::WindField wind(s);
  wind::WindMotion motion(rest, plant::GrowthFlowSpecies{});
  plant::PlantModel posed;
  float t = 0.0f;
  for (auto _ : state) {
    motion.step(t, 0.04f, wind, posed);
    t += 0.04f;
    benchmark::DoNotOptimize(posed.position.data());
  }
  state.counters["segments"] = double(rest.nodeCount());
  state.counters["leaves"] = double(rest.leafCount());
}
BENCHMARK(BM_WindMotion)
    ->ArgNames({"segments", "leaves", "gusty"})
    ->Args({10000, 10000, 0})
    ->Args({100000, 100000, 0})
    ->Args({100000, 100000, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// One frame of growing and moving at once, what the studio does every frame apart from meshing
// and drawing: a simulation step through the Session (the plants grow; particle dynamics,
// collisions), the plants' snapshots (Session::plants(), stems kept off their supports) and
// their Growth-Flow motion (session::PlantSway: eq. 1 integrated over the frame for every
// plant that changed carrying on from where it was, leaves moving). The scene is
// bench/scenes/grow-sway-25k.json, 20 particle ivies grown to `particles` before the timed frames,
// still growing while they are timed. The counters are medians; `grown` says how many particles
// the timed frames added.
void BM_GrowAndSway(benchmark::State& state) {
  const size_t target = size_t(state.range(0));
  Timer setup;
  std::unique_ptr<session::Session> s =
      session::Session::open(std::filesystem::path(__FILE__).parent_path() / "scenes" / "grow-sway-25k.json");
  const particles::ParticleWorld* world = test::particleWorld(*s);
  session::PlantSway sway;
  const float dt = 1.0f / 60.0f;
  float t = 0.0f;
  for (int step = 0; step < 3000 && world->particleCount() < target; ++step) s->step();
  // A few frames of motion first, so that every plant has a WindMotion, as in a running studio.
  for (int f = 0; f < 3; ++f, t += dt) {
    s->step();
    std::vector<plant::PlantModel> plants = s->plants();
    sway.pose(*s, plants, t, dt);
  }
  const double setupSeconds = setup.seconds();
  const size_t before = world->particleCount();
  std::vector<double> total, stepMs, snapshotMs, swayMs, growthMs, dynamicsMs, collisionsMs, cpuMs;
  size_t segments = 0;
  CALLGRIND_START_INSTRUMENTATION;
  for (auto _ : state) {
    CALLGRIND_TOGGLE_COLLECT;
    const double cpu0 = bench::processCpuSeconds();
    Timer timer;
    s->step();
    const double step = timer.seconds();
    const particles::StepTimings& parts = world->timings();
    growthMs.push_back(parts.growth), dynamicsMs.push_back(parts.dynamics), collisionsMs.push_back(parts.collisions);
    std::vector<plant::PlantModel> plants = s->plants();
    const double snapshot = timer.seconds() - step;
    sway.pose(*s, plants, t, dt);
    t += dt;
    const double seconds = timer.seconds();
    cpuMs.push_back(bench::processCpuSeconds() - cpu0);
    CALLGRIND_TOGGLE_COLLECT;
    benchmark::DoNotOptimize(plants.data());
    state.SetIterationTime(seconds);
    total.push_back(seconds);
    stepMs.push_back(step);
    snapshotMs.push_back(snapshot);
    swayMs.push_back(seconds - step - snapshot);
    segments = 0;
    for (const plant::PlantModel& p : plants) segments += p.nodeCount();
  }
  auto medianMs = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2] * 1e3;
  };
  state.counters["particles"] = double(world->particleCount());
  state.counters["grown"] = double(world->particleCount() - before);
  state.counters["segments"] = double(segments);
  state.counters["median_ms"] = medianMs(total);
  state.counters["step_ms"] = medianMs(stepMs);
  state.counters["snapshot_ms"] = medianMs(snapshotMs);
  state.counters["sway_ms"] = medianMs(swayMs);
  state.counters["cpu_ms"] = medianMs(cpuMs);  // every thread's CPU time per frame
  // The step's parts (ParticleWorld::timings): growth, dynamics (prediction, anchors, shape
  // matching), collisions (obstacles, plants).
  state.counters["growth_ms"] = medianMs(growthMs);
  state.counters["dynamics_ms"] = medianMs(dynamicsMs);
  state.counters["collisions_ms"] = medianMs(collisionsMs);
  state.counters["setup_s"] = setupSeconds;
}
BENCHMARK(BM_GrowAndSway)
    ->Arg(23000)
    ->ArgName("particles")
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(30);

}  // namespace
}  // namespace tendril
