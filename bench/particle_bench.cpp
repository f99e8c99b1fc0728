// One simulation step of the oriented-particle plants (seed 000): growth + dynamics +
// collisions + integration, no rendering, for 1k to 200k particles in grown plants, and for
// 25k and 100k in plants still growing, with the per-phase breakdown of the paper's Table 1. Results and the command: bench/README.md.
#include "tendril/core/timer.h"
#include "tendril/env/environment.h"
#include "tendril/env/primitives.h"
#include "tendril/particles/particle_model.h"

#include <benchmark/benchmark.h>

// Under `valgrind --tool=callgrind --instr-atstart=no --collect-atstart=no`, only the timed
// steps are counted (the setup runs uninstrumented); no-ops otherwise.
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_TOGGLE_COLLECT
#endif

#include <algorithm>
#include <map>
#include <tuple>
#include <memory>
#include <vector>

namespace tendril {
namespace {

// Plants `plants` ivies 1.5 m apart along the foot of a 3 m high wall (as long as the row) and
// grows them until the world holds `particles` particles (each plant is capped at its share)
// or growth has stopped (crowded apices stop, so a few plants may end short of their share).
struct Grown {
  std::unique_ptr<env::Environment> env;
  std::unique_ptr<particles::ParticleWorld> world;
  double growSeconds = 0;
};

// `growing`: stop at 80 % of the particles instead, without settling, so that the plants are
// still growing fast when the steps are timed (BM_ParticleGrowStep).
Grown& grown(size_t target, int plants, bool growing = false) {
  static std::map<std::tuple<size_t, int, bool>, Grown> cache;
  Grown& g = cache[{target, plants, growing}];
  if (g.world) return g;
  Timer t;
  const float width = 1.5f * float(plants) + 1.0f;
  g.env = std::make_unique<env::Environment>();
  env::ObstacleDef ground;
  ground.name = "ground";
  ground.mesh = env::makePlane(Vec2(width + 4, 6), 0.2f);
  g.env->addObstacle(ground);
  env::ObstacleDef wall;
  wall.name = "wall";
  wall.mesh = env::makeBox(Vec3(width, 3.0f, 0.2f));
  wall.worldFromLocal.translation = Vec3(0, 1.5f, 0);
  g.env->addObstacle(wall);
  env::Light sun;
  sun.direction = Vec3(0, -0.6f, -1).normalized();
  g.env->addLight(sun);
  g.env->commit();

  particles::ParticleSpecies s = particles::loadSpecies("ivy-particles", "");
  s.maxParticles = int(target / size_t(plants)) + 4;
  s.growthSpeed = 60.0f;  // reach the size sooner; the step's work depends on the count only
  g.world = std::make_unique<particles::ParticleWorld>();
  for (int k = 0; k < plants; ++k)
    g.world->addPlant("ivy" + std::to_string(k), s, Vec3(1.5f * (k - 0.5f * (plants - 1)), 0.03f, 0.11f),
                      Vec3(0, 1, 0), uint64_t(k + 1), *g.env);
  size_t last = 0;
  const size_t stop = growing ? target * 80 / 100 : target * 97 / 100;
  for (int step = 0, still = 0; step < 6000 && g.world->particleCount() < stop && still < 100; ++step) {
    g.world->step(*g.env);
    still = g.world->particleCount() == last ? still + 1 : 0;
    last = g.world->particleCount();
  }
  // Let the last particles finish growing and the plants settle.
  if (!growing)
    for (int step = 0; step < 100; ++step) g.world->step(*g.env);
  g.growSeconds = t.seconds();
  return g;
}

// Times single steps of g's world and reports the medians per phase; `growing`: also what
// grew in the timed steps and growth's share of a step.
void timeSteps(benchmark::State& state, Grown& g, bool growing) {
  particles::ParticleWorld& w = *g.world;
  const size_t before = w.particleCount();
  std::vector<double> total, growth, dynamics, collisions, integrate, share;
  CALLGRIND_START_INSTRUMENTATION;
  for (auto _ : state) {
    Timer t;
    CALLGRIND_TOGGLE_COLLECT;
    w.step(*g.env);
    CALLGRIND_TOGGLE_COLLECT;
    const double seconds = t.seconds();
    state.SetIterationTime(seconds);
    total.push_back(seconds);
    growth.push_back(w.timings().growth);
    dynamics.push_back(w.timings().dynamics);
    collisions.push_back(w.timings().collisions);
    integrate.push_back(w.timings().breaking);
    share.push_back(w.timings().growth / seconds);
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  auto medianMs = [&](const std::vector<double>& v) { return median(v) * 1e3; };
  state.counters["particles"] = double(w.particleCount());
  state.counters["median_ms"] = medianMs(total);
  state.counters["growth_ms"] = medianMs(growth);
  state.counters["dynamics_ms"] = medianMs(dynamics);
  state.counters["collisions_ms"] = medianMs(collisions);
  state.counters["integrate_ms"] = medianMs(integrate);
  state.counters["setup_s"] = g.growSeconds;
  if (growing) {
    state.counters["grown"] = double(w.particleCount() - before);
    state.counters["growth_share"] = median(share) * 100.0;  // %
  }
}

void BM_ParticleStep(benchmark::State& state) {
  timeSteps(state, grown(size_t(state.range(0)), int(state.range(1))), false);
}
BENCHMARK(BM_ParticleStep)
    ->Args({1000, 1})
    ->Args({5000, 4})
    ->Args({25000, 20})
    ->Args({50000, 40})
    ->Args({100000, 80})
    ->Args({200000, 160})
    ->ArgNames({"particles", "plants"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(50);

// Seed 000's Table 1 times steps of plants that are growing: here the plants are grown to 80 %
// of N (untimed), and the 50 timed steps go on growing them (`grown`: particles added in the
// timed steps; `growth_share`: growth's part of the step, in %).
void BM_ParticleGrowStep(benchmark::State& state) {
  timeSteps(state, grown(size_t(state.range(0)), int(state.range(1)), true), true);
}
BENCHMARK(BM_ParticleGrowStep)
    ->Args({25000, 20})
    ->Args({100000, 80})
    ->ArgNames({"particles", "plants"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(50);

}  // namespace
}  // namespace tendril
