// Plants as supports at scale: climbing ivy growing on a 100k-segment chestnut (a graph plant
// marked "support"), through the Session as `tendril grow` runs it, and the cost of giving the
// environment a host's stems again (what a growing or swaying host pays every step).
// Results and the command that produced them: bench/README.md, "Plants as supports".
#include "tendril/core/json_reader.h"
#include "tendril/core/timer.h"
#include "tendril/env/environment.h"
#include "tendril/env/seed_check.h"
#include "tendril/models/plant_support.h"
#include "tendril/session/session.h"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

namespace tendril {
namespace {

std::unique_ptr<session::Session> openHostScene() {
  return session::Session::open(std::filesystem::path(__FILE__).parent_path() / "scenes" /
                                "ivy-on-chestnut-100k.json");
}

// Ivy seeded along the host's stems: on the upper side of every `every`-th node of radius
// `minRadius` or more, 3 cm off the bark, growing along the stem (at most `count` plants). A
// point that lies inside another stem of the host (where boughs cross) is passed over: the
// session has the host's stems from its opening and refuses such a seed.
void seedAlongStems(session::Session& s, float minRadius, size_t every, size_t count) {
  const plant::PlantModel host = std::as_const(s).system(0).snapshot(0);
  size_t seen = 0, added = 0;
  for (size_t i = 0; i < host.nodeCount() && added < count; ++i) {
    if (host.radius[i] < minRadius || seen++ % every != 0) continue;
    const Vec3 dir = host.direction(i);
    Vec3 up = Vec3::UnitY() - Vec3::UnitY().dot(dir) * dir;
    if (up.norm() < 0.3f) up = Vec3::UnitX() - Vec3::UnitX().dot(dir) * dir;
    const Vec3 at = host.position[i] + 0.5f * host.length[i] * dir + (host.radius[i] + 0.03f) * up.normalized();
    if (env::seedInsideObstacle(s.environment(), at, dir)) continue;
    Json plant = {{"name", "ivy-on-" + std::to_string(i)},
                  {"position", {at.x(), at.y(), at.z()}},
                  {"direction", {dir.x(), dir.y(), dir.z()}},
                  {"seed", i + 1}};
    s.addPlant(plant, "bench");
    ++added;
  }
}

// The scene's 200 steps, with the four ivies at the trunk's foot and 40 more seeded along the
// host's boughs. The first step is reported as support_s (with the ivies added along the
// boughs it gives the environment the host's stems again; the scene alone has them from its
// opening); the growth time and rate are those of the climbers' steps after it.
void BM_ClimbOnHost(benchmark::State& state) {
  size_t climbers = 0, hostSegments = 0, plants = 0;
  for (auto _ : state) {
    state.PauseTiming();
    auto s = openHostScene();
    if (state.range(0)) seedAlongStems(*s, 0.06f, 7, 40);
    plants = s->plantCount() - 1;
    hostSegments = std::as_const(*s).system(0).segmentCount();
    const uint32_t steps = s->scene().steps;
    state.ResumeTiming();
    Timer first;
    s->step();
    state.counters["support_s"] = first.seconds();
    Timer grow;
    for (uint32_t i = 1; i < steps && !s->finished(); ++i) s->step();
    state.counters["grow_s"] = grow.seconds();
    climbers = s->segmentCount() - hostSegments;
    state.counters["climber_segments/s"] = double(climbers) / grow.seconds();
  }
  state.counters["host_segments"] = double(hostSegments);
  state.counters["climbers"] = double(plants);
  state.counters["climber_segments"] = double(climbers);
}
BENCHMARK(BM_ClimbOnHost)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// The queries a climber asks, one kind at a time, at 20,000 points 1-3 cm off the host's bark
// (every 5th node, on the side a climber would be): what each costs among 100k tubes and
// 490k shade triangles. Arg: 0 light (one shadow ray through stems and leaves), 1 closest
// stem point with the node's own stem as hint, 2 the same without a hint, 3 a 4 cm ray along
// the stem, 4 a leaf outline (5 segments of a 6 cm blade lying on the bark).
void BM_HostQueries(benchmark::State& state) {
  auto s = openHostScene();
  s->step();  // the host's stems and shade into the environment
  const env::Environment& env = s->environment();
  const plant::PlantModel host = std::as_const(*s).system(0).snapshot(0);
  struct Probe {
    Vec3 p, along, away;
    env::SurfacePoint hint;
  };
  std::vector<Probe> probes;
  for (size_t i = 0; i < host.nodeCount() && probes.size() < 20000; i += 5) {
    const Vec3 dir = host.direction(i);
    Vec3 side = Vec3::UnitY() - Vec3::UnitY().dot(dir) * dir;
    if (side.norm() < 0.3f) side = Vec3::UnitX() - Vec3::UnitX().dot(dir) * dir;
    side.normalize();
    const float off = 0.01f + 0.02f * float(i % 7) / 6.0f;
    const Vec3 p = host.position[i] + 0.5f * host.length[i] * dir + (host.radius[i] + off) * side;
    const auto hint = env.closestPoint(p, 0.1f);
    if (!hint) continue;
    probes.push_back({p, dir, side, *hint});
  }
  const int kind = int(state.range(0));
  size_t hits = 0;
  for (auto _ : state) {
    for (const Probe& q : probes) {
      switch (kind) {
        case 0: hits += env.light(q.p).exposure > 0.5f; break;
        case 1: hits += env.closestPoint(q.p, 0.1f, &q.hint).has_value(); break;
        case 2: hits += env.closestPoint(q.p, 0.1f).has_value(); break;
        case 3: hits += env.rayCast(q.p, q.along, 0.04f).has_value(); break;
        default: {
          const Vec3 w = 0.015f * q.along.cross(q.away);
          const Vec3 c[4] = {q.p - w + 0.01f * q.along, q.p + w + 0.01f * q.along, q.p + w + 0.07f * q.along,
                             q.p - w + 0.07f * q.along};
          const Vec3 from[5] = {q.p, c[0], c[1], c[2], c[3]}, to[5] = {c[0], c[1], c[2], c[3], c[0]};
          hits += env.anySegmentBlocked(from, to, 5);
        }
      }
    }
  }
  state.SetItemsProcessed(int64_t(state.iterations() * probes.size()));
  state.counters["probes"] = double(probes.size());
  state.counters["yes_share"] = double(hits) / double(state.iterations() * probes.size());
}
BENCHMARK(BM_HostQueries)->DenseRange(0, 4)->Unit(benchmark::kMillisecond);

// Giving the environment the host's stems and leaves again: its snapshot, the tubes and shade
// triangles, and the three Embree scenes (rays, closest points, shade) built afresh.
void BM_HostStemUpdate(benchmark::State& state) {
  auto s = openHostScene();
  env::Environment& env = s->environment();
  const models::PlantSystem& host = std::as_const(*s).system(0);
  double snapshot = 0, tubes = 0, build = 0;
  size_t count = 0, shadeCount = 0;
  for (auto _ : state) {
    Timer t;
    plant::PlantModel m = host.snapshot(0);
    snapshot += t.seconds();
    Timer u;
    std::vector<env::StemTube> stems;
    std::vector<env::ShadeTriangle> shade;
    models::appendSupport(m, 0, stems, shade);
    count = stems.size();
    shadeCount = shade.size();
    tubes += u.seconds();
    Timer b;
    env.setStems(0, std::move(stems), std::move(shade));
    env.commit();
    build += b.seconds();
  }
  const double n = double(state.iterations());
  state.counters["snapshot_ms"] = 1e3 * snapshot / n;
  state.counters["tubes_ms"] = 1e3 * tubes / n;
  state.counters["bvh_ms"] = 1e3 * build / n;
  state.counters["stems"] = double(count);
  state.counters["shade_triangles"] = double(shadeCount);
}
BENCHMARK(BM_HostStemUpdate)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace tendril
