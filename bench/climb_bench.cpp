// Growth throughput of the climbing model (seed 003) over support meshes of 10k, 100k and 1M
// triangles, and the whole job (grow + mesh + .glb) for a plant of more than 300k segments.
// Results and the command that produced them: bench/README.md.
#include "tendril/climb/climb_model.h"
#include "tendril/climb/climb_system.h"
#include "tendril/core/timer.h"
#include "tendril/env/environment.h"
#include "tendril/env/primitives.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/plant/plant_model.h"
#include "tendril/scene/scene.h"

#include <benchmark/benchmark.h>

// Under `valgrind --tool=callgrind --instr-atstart=no --collect-atstart=no`, only the growth
// steps and the export are counted (wall and BVH construction run uninstrumented); no-ops
// otherwise.
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_TOGGLE_COLLECT
#endif

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>

namespace tendril {
namespace {

// A closed slab whose front face is a bumpy height field of about `triangles` triangles:
// width × height metres, bumps of 3 cm every ~40 cm.
TriangleMesh makeBumpyWall(float width, float height, float thickness, size_t triangles) {
  size_t nx = std::max<size_t>(2, size_t(std::sqrt(double(triangles) / 2.0 * width / height)));
  size_t ny = std::max<size_t>(2, triangles / 2 / nx);
  TriangleMesh m;
  auto bump = [](float x, float y) { return 0.03f * std::sin(x * 15.7f) * std::sin(y * 15.7f); };
  for (size_t j = 0; j <= ny; ++j)
    for (size_t i = 0; i <= nx; ++i) {
      float x = width * (float(i) / nx - 0.5f), y = height * float(j) / ny;
      m.positions.push_back(Vec3(x, y, 0.5f * thickness + bump(x, y)));
    }
  auto id = [&](size_t i, size_t j) { return uint32_t(j * (nx + 1) + i); };
  for (size_t j = 0; j < ny; ++j)
    for (size_t i = 0; i < nx; ++i)
      m.indices.insert(m.indices.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1),
                                         id(i, j + 1)});
  // Back: one quad per border segment to close the solid (a fan from the border ring would
  // do, but quads keep triangles well shaped): border of the front grid to a flat back face.
  uint32_t base = uint32_t(m.positions.size());
  std::vector<uint32_t> ring;  // front border, counter-clockwise seen from the front
  for (size_t i = 0; i < nx; ++i) ring.push_back(id(i, 0));
  for (size_t j = 0; j < ny; ++j) ring.push_back(id(nx, j));
  for (size_t i = nx; i > 0; --i) ring.push_back(id(i, ny));
  for (size_t j = ny; j > 0; --j) ring.push_back(id(0, j));
  for (uint32_t v : ring) {
    Vec3 p = m.positions[v];
    m.positions.push_back(Vec3(p.x(), p.y(), -0.5f * thickness));
  }
  uint32_t n = uint32_t(ring.size());
  for (uint32_t k = 0; k < n; ++k) {
    uint32_t a = ring[k], b = ring[(k + 1) % n], c = base + (k + 1) % n, d = base + k;
    m.indices.insert(m.indices.end(), {a, d, c, a, c, b});
  }
  uint32_t center = uint32_t(m.positions.size());
  m.positions.push_back(Vec3(0, 0.5f * height, -0.5f * thickness));
  for (uint32_t k = 0; k < n; ++k) m.indices.insert(m.indices.end(), {center, base + (k + 1) % n, base + k});
  return m;
}

struct Support {
  std::unique_ptr<env::Environment> env;
  double buildSeconds = 0;
};

Support& support(size_t triangles, float width, float height) {
  static std::map<std::tuple<size_t, float, float>, Support> cache;
  Support& s = cache[{triangles, width, height}];
  if (!s.env) {
    Timer t;
    s.env = std::make_unique<env::Environment>();
    env::ObstacleDef ground;
    ground.name = "ground";
    ground.mesh = env::makePlane(Vec2(width + 4, 6), 0.2f);
    s.env->addObstacle(ground);
    env::ObstacleDef wall;
    wall.name = "wall";
    wall.mesh = makeBumpyWall(width, height, 0.3f, triangles);
    s.env->addObstacle(wall);
    env::Light sun;
    sun.direction = Vec3(-0.1f, -1, -0.5f).normalized();
    s.env->addLight(sun);
    s.env->commit();
    s.buildSeconds = t.seconds();
  }
  return s;
}

// Ivy planted every 0.5 m along the foot of a 4 m high wall.
constexpr float kWallHeight = 4.0f;
constexpr float kPlantSpacing = 0.5f;
constexpr int kSteps = 260;
// Growth: 120 plants on a 60 m wall (about 134k segments).
constexpr float kWallWidth = 60.0f;
// Whole job: 300 plants on a 150 m wall (about 330k segments), with the triangle density of
// the growth benchmark's 100k-triangle wall.
constexpr float kLongWallWidth = 150.0f;
constexpr size_t kLongWallTriangles = 250000;

// TENDRIL_CLIMB_BENCH_ITERATIONS overrides the iteration counts (1 keeps callgrind runs short).
int iterations(int fallback) {
  const char* v = std::getenv("TENDRIL_CLIMB_BENCH_ITERATIONS");
  int n = v ? std::atoi(v) : 0;
  return n > 0 ? n : fallback;
}

// Grows Japanese ivy plants every kPlantSpacing along the foot of a wall `width` wide; returns
// the system and the segment count, and adds the growth time (steps only) to *seconds.
std::unique_ptr<climb::ClimbSystem> growWall(const env::Environment& env, float width, double* seconds,
                                             size_t* segments) {
  static const climb::ClimbSpecies ivy = climb::loadSpecies("japanese-ivy", "");
  auto system = std::make_unique<climb::ClimbSystem>(7, 1.0f);
  const int plants = int(std::lround(width / kPlantSpacing));
  for (int i = 0; i < plants; ++i) {
    climb::ClimbPlantDef def;
    def.name = "ivy" + std::to_string(i);
    def.species = ivy;
    def.position = Vec3(width * ((i + 0.5f) / plants - 0.5f), 0.0f, 0.21f);
    def.seed = uint64_t(i + 1);
    system->addPlant(def, env);
  }
  CALLGRIND_START_INSTRUMENTATION;
  Timer t;
  CALLGRIND_TOGGLE_COLLECT;
  for (int step = 0; step < kSteps && !system->finished(); ++step) system->step(env);
  CALLGRIND_TOGGLE_COLLECT;
  *seconds += t.seconds();
  *segments = system->stats().segments;
  return system;
}

// The grown plants' content hash as the benchmark's label: a change in the grown result
// shows in the benchmark output.
std::string contentHashLabel(const climb::ClimbSystem& system) {
  std::vector<plant::PlantModel> plants;
  for (uint32_t p = 0; p < system.plantCount(); ++p) plants.push_back(system.snapshot(p));
  char text[32];
  std::snprintf(text, sizeof text, "hash=%016llx", static_cast<unsigned long long>(plant::contentHash(plants)));
  return text;
}

void BM_ClimbGrowth(benchmark::State& state) {
  Support& s = support(size_t(state.range(0)), kWallWidth, kWallHeight);
  double seconds = 0;
  size_t segments = 0, total = 0;
  std::string hash;
  for (auto _ : state) {
    auto system = growWall(*s.env, kWallWidth, &seconds, &segments);
    total += segments;
    hash = contentHashLabel(*system);
    state.SetIterationTime(seconds);
    seconds = 0;
    benchmark::DoNotOptimize(system.get());
  }
  state.counters["segments"] = double(segments);
  state.counters["segments/s"] = benchmark::Counter(double(total), benchmark::Counter::kIsRate);
  state.counters["bvh_build_s"] = s.buildSeconds;
  state.SetLabel(hash);
}
BENCHMARK(BM_ClimbGrowth)->Arg(10000)->Arg(100000)->Arg(1000000)->UseManualTime()->Unit(benchmark::kMillisecond)
    ->Iterations(iterations(3));

// grow + mesh + .glb, the whole `tendril grow` job without scene parsing, for a long wall.
void BM_ClimbWholeJob(benchmark::State& state) {
  Support& s = support(kLongWallTriangles, kLongWallWidth, kWallHeight);
  // TENDRIL_CLIMB_BENCH_GLB names a file to keep the .glb in (to compare exports byte for byte).
  const char* keep = std::getenv("TENDRIL_CLIMB_BENCH_GLB");
  std::filesystem::path out = keep ? std::filesystem::path(keep)
                                   : std::filesystem::temp_directory_path() / "tendril_bench_whole_job.glb";
  size_t total = 0, segments = 0;
  std::string hash;
  for (auto _ : state) {
    double grow = 0;
    auto system = growWall(*s.env, kLongWallWidth, &grow, &segments);
    Timer t;
    CALLGRIND_TOGGLE_COLLECT;
    io::ExportScene scene;
    for (uint32_t p = 0; p < system->plantCount(); ++p) scene.plants.push_back(system->snapshot(p));
    io::writeGlb(scene, out, io::ExportOptions{});
    CALLGRIND_TOGGLE_COLLECT;
    state.SetIterationTime(grow + t.seconds());
    state.counters["grow_s"] = grow;
    state.counters["mesh_export_s"] = t.seconds();
    total += segments;
    hash = contentHashLabel(*system);
  }
  state.SetLabel(hash);
  state.counters["segments"] = double(segments);
  state.counters["segments/s"] = benchmark::Counter(double(total), benchmark::Counter::kIsRate);
  state.counters["glb_MB"] = double(std::filesystem::file_size(out)) / 1e6;
  state.counters["bvh_build_s"] = s.buildSeconds;
  if (!keep) std::filesystem::remove(out);
}
BENCHMARK(BM_ClimbWholeJob)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(iterations(2));

}  // namespace
}  // namespace tendril
