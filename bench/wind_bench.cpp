// Growth-Flow motion (seed 001): one frame of branch sway and leaf motion for a free-standing
// plant of 100k segments and 100k leaves, in a constant and in a gusty wind.
#include "tendril/env/wind_field.h"
#include "tendril/wind/motion.h"

#include "support/synthetic_plants.h"

#include <benchmark/benchmark.h>

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

}  // namespace
}  // namespace tendril
