// One frame of SPH air (seed 000 §5.3) coupled with particle plants: about 20k air particles
// blowing through about 10k grown branch particles, with the per-phase breakdown. The plants'
// own step is timed apart (it is not part of the air's cost). Results and the command:
// bench/README.md.
#include "tendril/core/timer.h"
#include "tendril/env/environment.h"
#include "tendril/env/primitives.h"
#include "tendril/particles/particle_model.h"
#include "tendril/wind/sph.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace tendril {
namespace {

struct Scene {
  std::unique_ptr<env::Environment> env;
  std::unique_ptr<particles::ParticleWorld> world;
  std::unique_ptr<wind::SphAir> air;
  size_t branchParticles = 0;
  double setupSeconds = 0;
};

// Free-standing bushes on the ground, grown (untimed) to about `plantTarget` branch particles,
// in a wind tunnel around them filled with about `airTarget` particles moving at 2 m/s along +x
// and fed by a disc emitter at its inlet.
Scene& scene(size_t airTarget, size_t plantTarget) {
  static Scene s;
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
  const int plants = 8;
  species.maxParticles = int(plantTarget / plants) + 4;
  species.leafStep = 0;  // every particle a branch particle: all of them couple with the air
  species.growthSpeed = 60.0f;
  s.world = std::make_unique<particles::ParticleWorld>();
  for (int k = 0; k < plants; ++k)
    s.world->addPlant("bush" + std::to_string(k), species, Vec3(0.6f * float(k % 4) - 0.9f, 0.01f, 0.6f * float(k / 4) - 0.3f),
                      Vec3(0, 1, 0), uint64_t(k + 1), *s.env);
  for (int step = 0; step < 8000 && s.world->particleCount() < plantTarget; ++step) s.world->step(*s.env);
  for (int step = 0; step < 100; ++step) s.world->step(*s.env);

  // The tunnel: the bushes' bounds plus a margin, the spacing chosen for `airTarget`.
  Bounds3 b;
  for (uint32_t i = 0; i < s.world->capacity(); ++i)
    if (s.world->active(i)) {
      b.extend(s.world->position(i));
      if (s.world->flags(i) & particles::kGrown) ++s.branchParticles;
    }
  wind::SphSettings settings;
  settings.domainMin = Vec3(b.min.x() - 0.4f, -0.1f, b.min.z() - 0.2f);
  settings.domainMax = Vec3(b.max.x() + 0.3f, b.max.y() + 0.2f, b.max.z() + 0.2f);
  const Vec3 size = settings.domainMax - settings.domainMin;
  settings.spacing = std::cbrt(size.x() * (size.y() - 0.1f) * size.z() / float(airTarget));
  s.air = std::make_unique<wind::SphAir>(settings);
  s.air->fillBox(settings.domainMin, settings.domainMax, *s.env, Vec3(2, 0, 0));
  wind::SphEmitter inlet;
  inlet.position = Vec3(settings.domainMin.x() + 0.5f * settings.spacing, 0.5f * settings.domainMax.y(),
                        0.5f * (settings.domainMin.z() + settings.domainMax.z()));
  inlet.direction = Vec3(1, 0, 0);
  inlet.speed = 2.0f;
  inlet.radius = 0.5f * std::max(size.y(), size.z());
  s.air->addEmitter(inlet);
  // Let the flow settle in (and the plants feel it) before timing.
  for (int step = 0; step < 20; ++step) {
    s.air->step(*s.env, s.world.get());
    s.world->step(*s.env);
  }
  s.setupSeconds = t.seconds();
  return s;
}

void BM_SphStep(benchmark::State& state) {
  Scene& s = scene(size_t(state.range(0)), size_t(state.range(1)));
  std::vector<double> total, neighbours, density, forces, coupling, obstacles, plantStep;
  int substeps = 0;
  for (auto _ : state) {
    s.air->step(*s.env, s.world.get());
    const wind::SphTimings& t = s.air->timings();
    state.SetIterationTime(t.total);
    total.push_back(t.total);
    neighbours.push_back(t.neighbours);
    density.push_back(t.density);
    forces.push_back(t.forces);
    coupling.push_back(t.coupling);
    obstacles.push_back(t.obstacles);
    substeps = std::max(substeps, t.substeps);
    Timer plant;
    s.world->step(*s.env);
    plantStep.push_back(plant.seconds());
  }
  auto medianMs = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2] * 1e3;
  };
  state.counters["air"] = double(s.air->count());
  state.counters["coupled"] = double(s.air->coupledPlantParticles());
  state.counters["plant_particles"] = double(s.world->particleCount());
  state.counters["spacing_mm"] = 1e3 * s.air->settings().spacing;
  state.counters["substeps"] = substeps;
  state.counters["median_ms"] = medianMs(total);
  state.counters["neighbours_ms"] = medianMs(neighbours);
  state.counters["density_ms"] = medianMs(density);
  state.counters["forces_ms"] = medianMs(forces);
  state.counters["coupling_ms"] = medianMs(coupling);
  state.counters["obstacles_ms"] = medianMs(obstacles);
  state.counters["plant_step_ms"] = medianMs(plantStep);
  state.counters["setup_s"] = s.setupSeconds;
}
BENCHMARK(BM_SphStep)
    ->Args({20000, 10000})
    ->ArgNames({"air", "plants"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(40);

}  // namespace
}  // namespace tendril
