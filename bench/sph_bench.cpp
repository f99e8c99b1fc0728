// One frame of SPH air (seed 000 §5.3) coupled with particle plants: about 20k air particles
// blowing through about 10k grown branch particles, with the per-phase breakdown, for each
// solver (pbf:0 weakly compressible, pbf:1 position-based). The plants'
// own step is timed apart (it is not part of the air's cost). Results and the command:
// bench/README.md.
#include "tendril/core/timer.h"
#include "tendril/env/environment.h"
#include "tendril/env/primitives.h"
#include "tendril/particles/particle_model.h"
#include "tendril/wind/sph.h"

#include "process_cpu.h"

#include <benchmark/benchmark.h>

// Under `valgrind --tool=callgrind --instr-atstart=no --collect-atstart=no`, only the timed
// frames' SphAir::step are counted (the setup runs uninstrumented); no-ops otherwise.
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_TOGGLE_COLLECT
#endif

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <vector>

namespace tendril {
namespace {

struct Scene {
  std::unique_ptr<env::Environment> env;
  std::unique_ptr<particles::ParticleWorld> world;
  std::unique_ptr<wind::SphAir> air;
  size_t branchParticles = 0;
  uint32_t plantSteps = 0;
  size_t airFilled = 0;  // particles the tunnel was filled with
  int attempts = 0;
  double setupSeconds = 0;
};

// Free-standing bushes on the ground — 16 in a 4 × 4 grid, branching freely (no crowding
// stop, no surface adaption) and growing fast, so that the plants reach `plantTarget` grown
// branch particles in about a hundred cheap steps — in an open wind tunnel around them holding
// `airTarget` particles moving at 2 m/s along +x, fed by a disc emitter covering its inlet face.
Scene& scene(size_t airTarget, size_t plantTarget, wind::SphSolver solver) {
  static Scene scenes[2];
  Scene& s = scenes[solver == wind::SphSolver::PositionBased];
  if (s.air) return s;
  Timer t;
  s.env = std::make_unique<env::Environment>();
  env::ObstacleDef ground;
  ground.name = "ground";
  ground.kind = env::ObstacleKind::Plane;
  ground.mesh = env::makePlane(Vec2(12, 12), 0.2f);
  s.env->addObstacle(ground);
  env::Light sun;
  sun.direction = Vec3(0.2f, -1, -0.3f).normalized();
  s.env->addLight(sun);
  s.env->commit();

  particles::ParticleSpecies species = particles::loadSpecies("ivy-particles", "");
  const int plants = 16;
  // Growth stops at maxParticles with the apices still growing (they do not couple): about 14%
  // over the target leaves `plantTarget` grown ones.
  species.maxParticles = int(plantTarget * 116 / 100 / plants) + 1;
  species.leafStep = 0;  // every particle a branch particle: all of them couple with the air
  species.growthSpeed = 200.0f;
  species.branchProbability = 0.3f;
  species.surfaceAdaption = 0.0f;  // bushes, not ground cover
  species.crowding = 0;
  particles::WorldSettings ws;
  ws.plantCollisions = false;  // the air's benchmark: the plants' own contacts are not its business
  s.world = std::make_unique<particles::ParticleWorld>(ws);
  for (int k = 0; k < plants; ++k)
    s.world->addPlant("bush" + std::to_string(k), species,
                      Vec3(0.35f * float(k % 4) - 0.525f, 0.01f, 0.35f * float(k / 4) - 0.525f), Vec3(0, 1, 0),
                      uint64_t(k + 1), *s.env);
  auto grown = [&] {
    size_t n = 0;
    for (uint32_t i = 0; i < s.world->capacity(); ++i)
      if (s.world->active(i) && (s.world->flags(i) & particles::kGrown) && !(s.world->flags(i) & particles::kLeaf)) ++n;
    return n;
  };
  const size_t cap = size_t(plants) * size_t(species.maxParticles);
  for (int step = 0; step < 2000 && grown() < plantTarget && s.world->particleCount() < cap; ++step)
    s.world->step(*s.env);
  for (int step = 0; step < 20; ++step) s.world->step(*s.env);
  s.plantSteps = s.world->stepCount();

  // The tunnel: the bushes' bounds plus a margin, the spacing chosen so that the settled flow
  // holds `airTarget` particles.
  Bounds3 b;
  for (uint32_t i = 0; i < s.world->capacity(); ++i)
    if (s.world->active(i)) {
      b.extend(s.world->position(i));
      if ((s.world->flags(i) & particles::kGrown) && !(s.world->flags(i) & particles::kLeaf)) ++s.branchParticles;
    }
  wind::SphSettings settings;
  settings.solver = solver;
  settings.domainMin = Vec3(b.min.x() - 0.4f, -0.1f, b.min.z() - 0.2f);
  settings.domainMax = Vec3(b.max.x() + 0.3f, b.max.y() + 0.2f, b.max.z() + 0.2f);
  const Vec3 size = settings.domainMax - settings.domainMin;
  // The air's volume above the ground for `fill` particles at the rest spacing.
  const float volume = size.x() * settings.domainMax.y() * size.z();
  // The open tunnel loses air through its sides and top until the inlet's supply balances the
  // loss, after about one flow-through (1.2 s): about half the fill leaves, and the count keeps
  // drifting down by a few percent. Fill for that, let it settle for 1.5 s, and if it holds less
  // than 5% or more than 20% over the target, again (twice at most) with the spacing scaled by
  // the share that stayed (the position-based solver's incompressible air keeps more).
  float fill = float(airTarget) / 0.5f;
  for (int attempt = 0; attempt < 3; ++attempt) {
    settings.spacing = std::cbrt(volume / fill);
    s.air = std::make_unique<wind::SphAir>(settings);
    s.airFilled = s.air->fillBox(settings.domainMin, settings.domainMax, *s.env, Vec3(2, 0, 0));
    s.attempts = attempt + 1;
    // The inlet disc covers the whole inlet face (sites outside the domain or in the ground are
    // skipped), so the tunnel does not drain through its corners.
    wind::SphEmitter inlet;
    inlet.position = Vec3(settings.domainMin.x() + 0.5f * settings.spacing, 0.5f * settings.domainMax.y(),
                          0.5f * (settings.domainMin.z() + settings.domainMax.z()));
    inlet.direction = Vec3(1, 0, 0);
    inlet.speed = 2.0f;
    inlet.radius = 0.5f * std::hypot(settings.domainMax.y(), size.z()) + settings.spacing;
    s.air->addEmitter(inlet);
    // Let the flow settle in (and the plants feel it) before timing.
    particles::ParticleWorld plantsCopy = *s.world;
    for (int step = 0; step < 60; ++step) {
      s.air->step(*s.env, &plantsCopy);
      plantsCopy.step(*s.env);
    }
    if (attempt == 2 || (s.air->count() >= airTarget * 105 / 100 && s.air->count() <= airTarget * 120 / 100)) {
      *s.world = std::move(plantsCopy);
      break;
    }
    fill *= 1.1f * float(airTarget) / float(s.air->count());
  }
  s.setupSeconds = t.seconds();
  return s;
}

using bench::processCpuSeconds;

// Timed frames: 40, or TENDRIL_SPH_BENCH_FRAMES (a few, for callgrind).
int frames() {
  const char* e = std::getenv("TENDRIL_SPH_BENCH_FRAMES");
  return e ? std::max(1, std::atoi(e)) : 40;
}

void BM_SphStep(benchmark::State& state) {
  const auto solver = state.range(2) ? wind::SphSolver::PositionBased : wind::SphSolver::WeaklyCompressible;
  Scene& s = scene(size_t(state.range(0)), size_t(state.range(1)), solver);
  std::vector<double> total, neighbours, density, forces, coupling, plantFrame, obstacles, plantStep, cpu;
  int substeps = 0;
  double substepSum = 0;
  double particleSubsteps = 0, airPairs = 0, plantPairs = 0;
  size_t minAir = s.air->count(), minCoupled = s.air->coupledPlantParticles();
  CALLGRIND_START_INSTRUMENTATION;
  for (auto _ : state) {
    const double cpu0 = processCpuSeconds();
    CALLGRIND_TOGGLE_COLLECT;
    s.air->step(*s.env, s.world.get());
    CALLGRIND_TOGGLE_COLLECT;
    cpu.push_back(processCpuSeconds() - cpu0);
    minAir = std::min(minAir, s.air->count());
    minCoupled = std::min(minCoupled, s.air->coupledPlantParticles());
    const wind::SphTimings& t = s.air->timings();
    state.SetIterationTime(t.total);
    total.push_back(t.total);
    neighbours.push_back(t.neighbours);
    density.push_back(t.density);
    forces.push_back(t.forces);
    coupling.push_back(t.coupling);
    plantFrame.push_back(t.plantFrame);
    obstacles.push_back(t.obstacles);
    substeps = std::max(substeps, t.substeps);
    substepSum += t.substeps;
    particleSubsteps += double(t.particles), airPairs += double(t.airPairs), plantPairs += double(t.plantPairs);
    Timer plant;
    s.world->step(*s.env);
    plantStep.push_back(plant.seconds());
  }
  auto medianMs = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2] * 1e3;
  };
  // How compressed the air is after the last frame: its densest particle and the share of
  // particles more than 3% over the rest density.
  {
    const float rho0 = s.air->settings().restDensity;
    float densest = 0.0f;
    size_t over = 0;
    for (float rho : s.air->densities()) densest = std::max(densest, rho / rho0), over += rho > 1.03f * rho0;
    state.counters["rho_max"] = double(densest);
    state.counters["over3_pct"] = 100.0 * double(over) / double(std::max<size_t>(s.air->count(), 1));
  }
  state.counters["air"] = double(s.air->count());
  state.counters["air_min"] = double(minAir);
  state.counters["coupled"] = double(s.air->coupledPlantParticles());
  state.counters["coupled_min"] = double(minCoupled);
  state.counters["cpu_ms"] = medianMs(cpu);  // both threads
  state.counters["plant_steps"] = s.plantSteps;
  state.counters["air_filled"] = double(s.airFilled);
  state.counters["fills"] = s.attempts;
  state.counters["plant_particles"] = double(s.world->particleCount());
  state.counters["spacing_mm"] = 1e3 * s.air->settings().spacing;
  state.counters["substeps"] = substeps;  // the most in a frame
  state.counters["substeps_mean"] = substepSum / double(std::max<size_t>(total.size(), 1));
  // Mean air neighbours and plant particles met per air particle and substep.
  state.counters["air_pairs"] = airPairs / std::max(particleSubsteps, 1.0);
  state.counters["plant_pairs"] = plantPairs / std::max(particleSubsteps, 1.0);
  state.counters["median_ms"] = medianMs(total);
  state.counters["neighbours_ms"] = medianMs(neighbours);
  state.counters["density_ms"] = medianMs(density);
  state.counters["forces_ms"] = medianMs(forces);
  state.counters["coupling_ms"] = medianMs(coupling);
  state.counters["plant_frame_ms"] = medianMs(plantFrame);  // coupling's once-per-frame part
  state.counters["obstacles_ms"] = medianMs(obstacles);
  state.counters["plant_step_ms"] = medianMs(plantStep);
  state.counters["setup_s"] = s.setupSeconds;
}
BENCHMARK(BM_SphStep)
    ->Args({20000, 10000, 0})
    ->Args({20000, 10000, 1})
    ->ArgNames({"air", "plants", "pbf"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(frames());

}  // namespace
}  // namespace tendril
