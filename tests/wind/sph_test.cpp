// SPH air coupled both ways with particle plants (seed 000 §5.3): still air keeps its rest
// density and stays out of obstacles, a stream never passes through a wall, a plant in a stream
// bends downwind and slows the air behind it, results do not depend on the thread count, the
// neighbour search finds what a brute-force search finds, and bad settings are refused.
#include "support/determinism.h"
#include "support/sph_stream.h"
#include "support/test_paths.h"
#include "tendril/core/error.h"
#include "tendril/core/hash.h"
#include "tendril/env/environment.h"
#include "tendril/env/primitives.h"
#include "tendril/particles/particle_model.h"
#include "tendril/wind/sph.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>

namespace tendril::wind {
namespace {

std::unique_ptr<env::Environment> emptyEnv() {
  auto env = std::make_unique<env::Environment>();
  env->commit();
  return env;
}

void addBox(env::Environment& env, const std::string& name, const Vec3& size, const Vec3& centre) {
  env::ObstacleDef def;
  def.name = name;
  def.kind = env::ObstacleKind::Box;
  def.mesh = env::makeBox(size);
  def.worldFromLocal.translation = centre;
  env.addObstacle(std::move(def));
}

void addGround(env::Environment& env, const Vec2& size) {
  env::ObstacleDef def;
  def.name = "ground";
  def.kind = env::ObstacleKind::Plane;
  def.mesh = env::makePlane(size, 0.2f);
  env.addObstacle(std::move(def));
}

float maxDensityError(const SphAir& air) {
  float worst = 0.0f;
  for (float rho : air.densities()) worst = std::max(worst, std::abs(rho / air.settings().restDensity - 1.0f));
  return worst;
}

float maxSpeed(const SphAir& air) {
  float v = 0.0f;
  for (const Vec3& u : air.velocities()) v = std::max(v, u.norm());
  return v;
}

// The behaviour below holds for both solvers (weakly compressible and position-based).
class SphSolvers : public ::testing::TestWithParam<SphSolver> {
 protected:
  SphSettings settings() const {
    SphSettings s;
    s.solver = GetParam();
    return s;
  }
  bool positionBased() const { return GetParam() == SphSolver::PositionBased; }
};

INSTANTIATE_TEST_SUITE_P(Sph, SphSolvers,
                         ::testing::Values(SphSolver::WeaklyCompressible, SphSolver::PositionBased),
                         [](const ::testing::TestParamInfo<SphSolver>& info) {
                           return info.param == SphSolver::PositionBased ? "PositionBased" : "WeaklyCompressible";
                         });

TEST_P(SphSolvers, StillAirInAClosedBoxKeepsItsRestDensityAndNeverEntersAnObstacle) {
  // A closed 1 × 0.8 × 0.8 m box of still air (5k particles) around a 30 cm cube standing on
  // its floor, for 2.25 s.
  auto env = std::make_unique<env::Environment>();
  addBox(*env, "cube", Vec3(0.3f, 0.3f, 0.3f), Vec3(0.5f, 0.15f, 0.4f));
  env->commit();
  SphSettings s = settings();
  s.setBoundary(SphBoundary::Closed);
  s.domainMin = Vec3(0, 0, 0);
  s.domainMax = Vec3(1.0f, 0.8f, 0.8f);
  SphAir air(s);
  const size_t n = air.fillBox(s.domainMin, s.domainMax, *env);
  EXPECT_GT(n, 4500u);
  // The lattice the box is filled with is the model's equilibrium next to flat walls, not next
  // to the cube's convex edges (walls act as mirrored lattices across the nearest surface):
  // the particles there settle within the first 0.1 s.
  const int frames = 90, settling = 4;
  float firstFrames = 0.0f, afterwards = 0.0f, worstSdf = 1.0f;
  size_t crossings = 0;
  std::vector<Vec3> before = air.positions();
  for (int frame = 0; frame < frames; ++frame) {
    air.step(*env, nullptr);
    ASSERT_EQ(air.count(), n);  // closed: nothing leaves, nothing is added
    float& worst = frame < settling ? firstFrames : afterwards;
    worst = std::max(worst, maxDensityError(air));
    for (size_t i = 0; i < n; ++i) {
      worstSdf = std::min(worstSdf, env->signedDistance(air.positions()[i]));
      crossings += env->countSegmentHits(before[i], air.positions()[i]);
    }
    before = air.positions();
  }
  std::printf("still air: max |rho/rho0 - 1| %.4f in the first %d frames, %.4f afterwards; min sdf %.4f m; "
              "max speed %.4f m/s\n",
              firstFrames, settling, afterwards, worstSdf, maxSpeed(air));
  EXPECT_LT(afterwards, 0.03f) << "every particle, every frame after the first 0.1 s, within 3% of rest density";
  EXPECT_LT(firstFrames, 0.06f);
  EXPECT_GE(worstSdf, 0.0f) << "no particle inside the cube";
  EXPECT_EQ(crossings, 0u) << "no particle path through the cube's surface";
  EXPECT_LT(maxSpeed(air), 0.1f) << "still air stays still (a stream here is 3–5 m/s)";
}

TEST_P(SphSolvers, AStreamAgainstAWallNeverPassesThroughIt) {
  // A 3 m/s stream from a disc hits a 4 cm thick wall that closes the domain's cross-section:
  // the air piles up and leaves sideways, never through or into the wall.
  auto env = std::make_unique<env::Environment>();
  addBox(*env, "wall", Vec3(0.04f, 2.0f, 2.0f), Vec3(0.5f, 0.4f, 0.0f));
  env->commit();
  SphSettings s = settings();
  s.spacing = 0.04f;
  s.domainMin = Vec3(-0.4f, 0.0f, -0.4f);
  s.domainMax = Vec3(0.9f, 0.8f, 0.4f);
  SphAir air(s);
  SphEmitter e;
  e.position = Vec3(-0.35f, 0.4f, 0.0f);
  e.direction = Vec3(1, 0, 0);
  e.speed = 3.0f;
  e.radius = 0.2f;
  air.addEmitter(e);
  size_t behind = 0, inside = 0, maxCount = 0;
  float fastest = 0.0f;
  for (int frame = 0; frame < 40; ++frame) {
    air.step(*env, nullptr);
    maxCount = std::max(maxCount, air.count());
    for (const Vec3& p : air.positions()) {
      if (p.x() > 0.48f) ++behind;
      if (env->signedDistance(p) < 0.0f) ++inside;
    }
    fastest = std::max(fastest, maxSpeed(air));
  }
  std::printf("stream: up to %zu particles, fastest %.2f m/s\n", maxCount, fastest);
  EXPECT_GT(maxCount, 1500u) << "the stream reached the wall";
  EXPECT_EQ(behind, 0u);
  EXPECT_EQ(inside, 0u);
}

// The share of the rest density's particle count found in the box lo–hi.
double fillShare(const SphAir& air, const Vec3& lo, const Vec3& hi) {
  size_t n = 0;
  for (const Vec3& p : air.positions()) n += (p.array() >= lo.array()).all() && (p.array() < hi.array()).all();
  const float s = air.settings().spacing;
  return double(n) / double((hi - lo).prod() / (s * s * s));
}

TEST_P(SphSolvers, AWindTunnelKeepsItsAirInAndLetsItOutAtTheOutlet) {
  // A 2 m/s stream over a 30 cm block standing across the floor of a duct closed but for its
  // outlet (+x), against the same duct with every face open. The walls hold the air in (no
  // particle ever lies beyond a closed face), the air leaves at the outlet as fast as the inlet
  // brings it (the count levels off); the open duct loses most of its air through its top and
  // sides. (The tunnel is not full either: without tension, the block's lee stays thin.)
  auto env = std::make_unique<env::Environment>();
  addBox(*env, "block", Vec3(0.2f, 0.3f, 1.0f), Vec3(0.0f, 0.15f, 0.0f));
  env->commit();
  auto run = [&](bool tunnel, double* full, size_t* beyond, size_t* counts) {
    SphSettings s = settings();
    s.domainMin = Vec3(-0.5f, 0.0f, -0.25f);
    s.domainMax = Vec3(1.2f, 0.6f, 0.25f);
    if (tunnel) s.setBoundary(SphBoundary::Closed), s.faces[1] = SphBoundary::Outflow;
    SphAir air(s);
    air.fillBox(s.domainMin, s.domainMax, *env, Vec3(2, 0, 0));
    SphEmitter e;
    e.position = Vec3(-0.47f, 0.3f, 0.0f);
    e.direction = Vec3(1, 0, 0);
    e.speed = 2.0f;
    e.radius = 0.45f;  // the whole inlet face (sites outside the domain are skipped)
    air.addEmitter(e);
    *beyond = 0;
    const int frames = 60;
    for (int frame = 0; frame < frames; ++frame) {
      air.step(*env, nullptr);
      for (const Vec3& p : air.positions())
        *beyond += p.x() < s.domainMin.x() || p.y() < s.domainMin.y() || p.y() > s.domainMax.y() ||
                   p.z() < s.domainMin.z() || p.z() > s.domainMax.z();
      if (frame == frames - 21) counts[0] = air.count();
    }
    counts[1] = air.count();
    *full = fillShare(air, s.domainMin, s.domainMax) / (1.0 - 0.2 * 0.3 * 0.5 / (s.domainMax - s.domainMin).prod());
  };
  double fullTunnel = 0.0, fullOpen = 0.0;
  size_t beyondTunnel = 0, beyondOpen = 0, countsTunnel[2] = {}, countsOpen[2] = {};
  run(true, &fullTunnel, &beyondTunnel, countsTunnel);
  run(false, &fullOpen, &beyondOpen, countsOpen);
  std::printf("after 1.5 s the tunnel holds %.0f%% of the rest density's particles, the open duct %.0f%%; "
              "tunnel %zu -> %zu particles over the last 0.5 s\n",
              100.0 * fullTunnel, 100.0 * fullOpen, countsTunnel[0], countsTunnel[1]);
  EXPECT_EQ(beyondTunnel, 0u);
  // The weakly compressible air piles up ahead of the block (150–190% of the rest density's
  // particles in the first 40 cm); the position-based air stays near ρ0 there (its emitter
  // leaves out sites the air ahead still holds), so the same flow holds fewer particles
  // (57% against 78%), and its open duct keeps more (35% against 20%: no particle is thrown
  // out faster than the stream).
  EXPECT_GT(fullTunnel, positionBased() ? 0.5 : 0.7);
  EXPECT_GT(fullTunnel, fullOpen + (positionBased() ? 0.15 : 0.3));
  EXPECT_LT(std::fabs(double(countsTunnel[1]) / double(countsTunnel[0]) - 1.0), 0.05) << "outflow balances the inlet";
}

TEST(SphAir, VelocityAtInterpolatesTheFlowAndIsZeroWhereThereIsNoAir) {
  auto env = emptyEnv();
  SphSettings s;
  s.domainMin = Vec3(0, 0, 0);
  s.domainMax = Vec3(1, 1, 1);
  SphAir air(s);
  air.fillBox(Vec3(0, 0, 0), Vec3(0.5f, 1, 1), Vec3(1.5f, -0.5f, 0.25f));
  const Vec3 inside = air.velocityAt(Vec3(0.25f, 0.5f, 0.5f));
  EXPECT_LT((inside - Vec3(1.5f, -0.5f, 0.25f)).norm(), 0.015f) << inside.transpose();
  bool covered = true;
  EXPECT_EQ(air.velocityAt(Vec3(0.9f, 0.5f, 0.5f), &covered), Vec3::Zero()) << "farther than h from any particle";
  EXPECT_FALSE(covered);
  air.velocityAt(Vec3(0.25f, 0.5f, 0.5f), &covered);
  EXPECT_TRUE(covered);
  EXPECT_EQ(air.velocityAt(Vec3(2, 0.5f, 0.5f)), Vec3::Zero()) << "outside the domain";
  // At the edge of the air the velocity fades instead of jumping.
  const float edge = air.velocityAt(Vec3(0.5f + 0.5f * air.supportRadius(), 0.5f, 0.5f)).x();
  EXPECT_GT(edge, 0.0f);
  EXPECT_LT(edge, 1.5f);
}

// A 4 × 4 clump of upright stems 6 cm apart, 60 cm tall, grown without air, then stopped growing.
particles::ParticleWorld grownClump(const env::Environment& env) {
  particles::ParticleSpecies s = particles::loadSpecies("ivy-particles", test::sourceDir());
  s.maxParticles = 12;
  s.maxLateralBuds = 0;
  s.leafStep = 0;
  s.phototropism = 0.0f;
  s.randomWalk = 0.0f;
  s.surfaceAdaption = 0.0f;
  s.spreading = 0.0f;
  s.crowding = 0;
  s.growthRate = 0.2f;
  s.minGrowthLight = 1.0f;
  s.radius = 0.01f;
  s.apexTaper = 1.0f;
  s.secondaryGrowth = 0.0f;
  s.density = 300.0f;  // light wood (seed 000 uses 300–1000 kg/m³)
  s.stiffness = 0.25f;
  particles::WorldSettings ws;
  ws.plantCollisions = false;
  particles::ParticleWorld w(ws);
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 4; ++k)
      w.addPlant("stem", s, Vec3(0.06f * (float(i) - 1.5f), 0.0f, 0.06f * (float(k) - 1.5f)), Vec3(0, 1, 0),
                 uint64_t(4 * i + k + 1), env);
  for (int step = 0; step < 300; ++step) w.step(env);
  s.growthSpeed = 0.0f;
  for (uint32_t p = 0; p < w.plantCount(); ++p) w.setSpecies(p, s);
  for (int step = 0; step < 100; ++step) w.step(env);
  return w;
}

// Mean x of the stems' top particles.
float meanTopX(const particles::ParticleWorld& w) {
  std::vector<float> topY(w.plantCount(), -1.0f), topX(w.plantCount(), 0.0f);
  for (uint32_t i = 0; i < w.capacity(); ++i)
    if (w.active(i) && w.position(i).y() > topY[w.plantOf(i)]) {
      topY[w.plantOf(i)] = w.position(i).y();
      topX[w.plantOf(i)] = w.position(i).x();
    }
  float sum = 0.0f;
  for (float x : topX) sum += x;
  return sum / float(topX.size());
}

using test::meanSpeedX;

struct Tunnel {
  std::unique_ptr<env::Environment> env;
  SphSettings settings;
};

Tunnel windTunnel(SphSolver solver = SphSolver::WeaklyCompressible) {
  Tunnel t;
  t.settings.solver = solver;
  t.env = std::make_unique<env::Environment>();
  addGround(*t.env, Vec2(4, 4));
  t.env->commit();
  t.settings.spacing = 0.06f;
  t.settings.domainMin = Vec3(-0.7f, -0.1f, -0.5f);
  t.settings.domainMax = Vec3(1.0f, 0.9f, 0.5f);
  return t;
}

SphAir streamingAir(const Tunnel& t, float speed) { return test::streamingAir(t.settings, *t.env, speed, 0.75f); }

TEST_P(SphSolvers, APlantInAStreamBendsDownwindAndSlowsTheAirInItsLee) {
  const Tunnel tunnel = windTunnel(GetParam());
  const env::Environment& env = *tunnel.env;
  const particles::ParticleWorld grown = grownClump(env);
  ASSERT_EQ(grown.particleCount(), 16u * 12u);

  const float wind = 5.0f;
  particles::ParticleWorld windy = grown, calm = grown;
  SphAir coupled = streamingAir(tunnel, wind), alone = streamingAir(tunnel, wind);
  const Vec3 leeLo(0.15f, 0.1f, -0.1f), leeHi(0.45f, 0.5f, 0.1f);  // behind the clump
  double leeCoupled = 0.0, leeAlone = 0.0;
  size_t coupledParticles = 0;
  const int frames = 32, averaged = 12;
  for (int frame = 0; frame < frames; ++frame) {
    coupled.step(env, &windy);
    windy.step(env);
    alone.step(env, nullptr);
    calm.step(env);
    coupledParticles = std::max(coupledParticles, coupled.coupledPlantParticles());
    if (frame >= frames - averaged) {
      leeCoupled += meanSpeedX(coupled, leeLo, leeHi) / averaged;
      leeAlone += meanSpeedX(alone, leeLo, leeHi) / averaged;
    }
  }
  const float bend = meanTopX(windy) - meanTopX(calm);
  const double slowdown = 1.0 - leeCoupled / leeAlone;
  std::printf("coupled %zu plant particles; tops moved %.3f m downwind; lee speed %.3f vs %.3f m/s (%.1f%% slower)\n",
              coupledParticles, bend, leeCoupled, leeAlone, 100.0 * slowdown);
  EXPECT_GE(coupledParticles, 16u * 10u) << "grown stem particles take part, roots and apices need not";
  EXPECT_GT(bend, 0.02f) << "the stems' tops lean downwind by more than 2 cm";
  EXPECT_GT(slowdown, 0.10) << "the air behind the clump is at least 10% slower than without it";
  EXPECT_GT(leeAlone, 0.9 * wind) << "without plants the stream keeps its speed";
}

// The hash of the air and the plants (positions and the air's push on them) after 12 coupled
// frames of a stream at `speed` through the clump, at a coarse 7 cm spacing.
uint64_t coupledRunHash(float speed, SphSolver solver) {
  Tunnel tunnel = windTunnel(solver);
  tunnel.settings.spacing = 0.07f;
  particles::ParticleWorld w = grownClump(*tunnel.env);
  SphAir air = streamingAir(tunnel, speed);
  for (int frame = 0; frame < 12; ++frame) {
    air.step(*tunnel.env, &w);
    w.step(*tunnel.env);
  }
  Hasher h;
  h.add(air.positions());
  h.add(air.velocities());
  h.add(air.densities());
  for (uint32_t i = 0; i < w.capacity(); ++i)
    if (w.active(i)) h.add(w.position(i)), h.add(w.externalAcceleration()[i]);
  return h.digest();
}

TEST_P(SphSolvers, CoupledResultsAreTheSameForAnyThreadCount) {
  const uint64_t one = tendril::test::sameAtEveryThreadCount([&] { return coupledRunHash(3.0f, GetParam()); });
  EXPECT_NE(one, coupledRunHash(3.1f, GetParam()));
}

// The passes' AVX2 versions (eight lanes in one register) and baseline ones (two SSE registers)
// do the same operations in the same order, without fused multiply-adds: the same bits.
TEST_P(SphSolvers, CoupledAvx2AndBaselinePassesGiveTheSameResults) {
  if (!detail::avx2Kernels()) GTEST_SKIP() << "this CPU runs only the baseline passes";
  const uint64_t avx2 = coupledRunHash(3.0f, GetParam());
  detail::forceBaselineKernels(true);
  EXPECT_FALSE(detail::avx2Kernels());
  const uint64_t baseline = coupledRunHash(3.0f, GetParam());
  detail::forceBaselineKernels(false);
  EXPECT_EQ(avx2, baseline);
}

// Undo restores an earlier state into the same air; a session loads into a fresh one. Either
// way the wind the air gives (velocityAt) is the restored air's at once, not the air's before.
TEST_P(SphSolvers, RestoredAirGivesItsOwnVelocityAtOnce) {
  const Tunnel tunnel = windTunnel(GetParam());
  SphAir air = streamingAir(tunnel, 3.0f);
  for (int frame = 0; frame < 4; ++frame) air.step(*tunnel.env, nullptr);
  ArchiveWriter saved;
  air.saveState(saved);
  std::vector<Vec3> probes, before;
  for (int i = 0; i < 20; ++i) probes.push_back(Vec3(-0.5f + 0.07f * float(i), 0.3f + 0.01f * float(i), 0.05f));
  for (const Vec3& p : probes) before.push_back(air.velocityAt(p));
  for (int frame = 0; frame < 8; ++frame) air.step(*tunnel.env, nullptr);  // the air moves on

  ArchiveReader undo(saved.data(), "undo");
  air.loadState(undo);
  SphAir fresh(tunnel.settings);
  ArchiveReader load(saved.data(), "session");
  fresh.loadState(load);
  int moving = 0;
  for (size_t i = 0; i < probes.size(); ++i) {
    EXPECT_EQ(air.velocityAt(probes[i]), before[i]) << "probe " << i;
    EXPECT_EQ(fresh.velocityAt(probes[i]), before[i]) << "probe " << i;
    moving += before[i].x() > 1.0f;
  }
  EXPECT_GT(moving, 10) << "the probes lie in the stream";
}

TEST(SphNeighbourSearch, ARowsCellSpanHoldsEveryPointWithinItsHalfWidth) {
  // Against a brute-force reference: points across x ± w — its ends nudged one float inward,
  // points on and beside the cell boundaries in reach, random ones — binned as the grid bins
  // them, on rows far from the origin too (where round-off is largest).
  std::mt19937 rng(7);
  auto uniform = [&](float a, float b) { return std::uniform_real_distribution<float>(a, b)(rng); };
  const float inf = std::numeric_limits<float>::infinity();
  size_t checked = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const float origin = uniform(-200.0f, 200.0f), edge = std::exp(uniform(std::log(1e-3f), 0.0f));
    const int cells = 1 + int(rng() % 300);
    const float inv = 1.0f / edge;
    const float x = origin + uniform(-0.2f, 1.2f) * edge * float(cells), w = uniform(0.0f, 10.0f) * edge;
    const detail::CellSpan span = detail::rowCells(x, w, origin, edge, cells);
    auto cellOf = [&](float p) { return std::clamp(int(std::floor((p - origin) * inv)), 0, cells - 1); };
    auto check = [&](float p) {
      if (!(std::abs(p - x) < w)) return;
      ++checked;
      const int c = cellOf(p);
      ASSERT_TRUE(c >= int(span.first) && c <= int(span.last))
          << "point " << p << " in cell " << c << " outside " << span.first << ".." << span.last << " for x " << x
          << " ± " << w << ", origin " << origin << ", edge " << edge;
    };
    check(std::nextafter(x - w, x));
    check(std::nextafter(x + w, x));
    for (int c = cellOf(x - w); c <= cellOf(x + w) + 1; ++c) {
      const float boundary = origin + float(c) * edge;
      check(boundary);
      check(std::nextafter(boundary, -inf));
      check(std::nextafter(boundary, inf));
    }
    for (int k = 0; k < 4; ++k) check(x + uniform(-w, w));
    // No wider than the cells x ± w meets and one more at either end.
    EXPECT_LE(int(span.last) - int(span.first), int(std::ceil(2.0f * w * inv)) + 2);
    if (HasFatalFailure()) return;
  }
  // The hardest case: a point on (or a float beside) a cell boundary, the half-width a float
  // more than its distance from x.
  for (int trial = 0; trial < 200000; ++trial) {
    const float origin = uniform(-200.0f, 200.0f), edge = std::exp(uniform(std::log(1e-3f), 0.0f));
    const int cells = 2 + int(rng() % 300);
    const float inv = 1.0f / edge;
    const float boundary = origin + float(1 + int(rng() % uint32_t(cells - 1))) * edge;
    const float p = std::nextafter(boundary, float(int(rng() % 3) - 1) * inf);
    const float x = p + (rng() % 2 ? 1.0f : -1.0f) * uniform(0.0f, 10.0f) * edge;
    const float w = std::nextafter(std::abs(p - x), inf);
    const detail::CellSpan span = detail::rowCells(x, w, origin, edge, cells);
    const int c = std::clamp(int(std::floor((p - origin) * inv)), 0, cells - 1);
    ASSERT_TRUE(c >= int(span.first) && c <= int(span.last))
        << "point " << p << " in cell " << c << " outside " << span.first << ".." << span.last << " for x " << x
        << " ± " << w << ", origin " << origin << ", edge " << edge;
  }
  EXPECT_GT(checked, 100000u);
}

TEST(SphNeighbourSearch, AppendLanesWritesTheSetLanesInOrder) {
  for (const uint32_t base : {0u, 5u, 1u << 20, 0xfffffff0u})
    for (unsigned mask = 0; mask < 16; ++mask) {
      uint32_t out[4] = {7, 7, 7, 7};
      const uint32_t n = detail::appendLanes(mask, base, out);
      std::vector<uint32_t> expected;
      for (uint32_t l = 0; l < 4; ++l)
        if (mask & (1u << l)) expected.push_back(base + l);
      ASSERT_EQ(n, expected.size()) << "mask " << mask;
      EXPECT_EQ(std::vector<uint32_t>(out, out + n), expected) << "mask " << mask;
    }
}

TEST(SphNeighbourSearch, VelocityAtMatchesABruteForceSum) {
  // Air streamed past a block for a few frames (irregular positions, some outside the
  // domain's cells' middle), then velocityAt at random points against the sum over every
  // particle: a run that misses a cell of neighbours shows as a wrong velocity.
  auto env = std::make_unique<env::Environment>();
  addBox(*env, "block", Vec3(0.2f, 0.3f, 0.2f), Vec3(0.1f, 0.15f, 0.0f));
  env->commit();
  SphSettings s;
  s.spacing = 0.04f;
  s.domainMin = Vec3(-0.4f, 0.0f, -0.3f);
  s.domainMax = Vec3(0.5f, 0.5f, 0.3f);
  SphAir air(s);
  air.fillBox(s.domainMin, s.domainMax, *env, Vec3(1.5f, 0.2f, -0.3f));
  SphEmitter e;
  e.position = Vec3(-0.38f, 0.25f, 0.0f);
  e.speed = 1.5f;
  e.radius = 0.3f;
  air.addEmitter(e);
  for (int frame = 0; frame < 6; ++frame) air.step(*env, nullptr);
  const float h = air.supportRadius(), norm6 = 315.0f / (64.0f * kPi * h * h * h);
  std::mt19937 rng(11);
  auto uniform = [&](float a, float b) { return std::uniform_real_distribution<float>(a, b)(rng); };
  int covered = 0;
  for (int sample = 0; sample < 400; ++sample) {
    const Vec3 p(uniform(s.domainMin.x(), s.domainMax.x()), uniform(s.domainMin.y(), s.domainMax.y()),
                 uniform(s.domainMin.z(), s.domainMax.z()));
    double z = 0.0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (size_t j = 0; j < air.count(); ++j) {
      const float q = (air.positions()[j] - p).squaredNorm() / (h * h);
      if (!(q < 1.0f)) continue;
      const double w = air.particleMass() / air.densities()[j] * norm6 * std::pow(1.0 - q, 3.0);
      z += w;
      sum += w * air.velocities()[j].cast<double>();
    }
    const Eigen::Vector3d expected = sum / std::max(z, 0.5);
    const Vec3 found = air.velocityAt(p);
    covered += z > 0.0;
    EXPECT_LT((found.cast<double>() - expected).norm(), 1e-4 * (1.0 + expected.norm())) << "at " << p.transpose();
  }
  EXPECT_GT(covered, 300);
}

// Within a frame only particles that may have come within h of an obstacle ask for its
// distance; at a frame's start everyone asks only when an obstacle was added or moved (the
// others' distance bounds still hold). That gives the distances asking everyone gives: a run
// whose obstacle is "moved" to where it stands before every frame (everyone asks) is bit for bit
// the same. And an obstacle really moved into the air pushes it out at once.
TEST_P(SphSolvers, ObstacleDistancesAreAskedAgainWhenAnObstacleMoves) {
  auto stream = [](env::Environment& env) {
    // Clear of the ground: air caught between an obstacle and the ground has nowhere to go
    // (docs/sph.md, "Where two walls meet").
    addBox(env, "block", Vec3(0.3f, 0.3f, 0.3f), Vec3(0.2f, 0.35f, 0.0f));
    addGround(env, Vec2(4, 4));
    env.commit();
  };
  Tunnel a = windTunnel(GetParam()), b = windTunnel(GetParam());
  a.env = std::make_unique<env::Environment>(), b.env = std::make_unique<env::Environment>();
  stream(*a.env), stream(*b.env);
  SphAir kept = streamingAir(a, 3.0f), asked = streamingAir(b, 3.0f);
  const RigidTransform still = b.env->obstacle(0).worldFromLocal;
  auto hash = [](const SphAir& air) {
    Hasher h;
    h.add(air.positions()), h.add(air.velocities()), h.add(air.densities());
    return h.digest();
  };
  for (int frame = 0; frame < 10; ++frame) {
    const uint64_t revision = b.env->obstacleRevision();
    b.env->setObstacleTransform(0, still);  // not moved, but everyone asks again
    ASSERT_NE(b.env->obstacleRevision(), revision);
    kept.step(*a.env, nullptr);
    asked.step(*b.env, nullptr);
    ASSERT_EQ(hash(kept), hash(asked)) << "frame " << frame;
  }

  // Now move the block 20 cm upstream, into air that was clear of it: the particles it now
  // covers are pushed out by the next step.
  RigidTransform moved = still;
  moved.translation.x() -= 0.2f;
  a.env->setObstacleTransform(0, moved);
  a.env->commit();
  size_t covered = 0;
  for (const Vec3& p : kept.positions()) covered += a.env->signedDistance(p) < 0.0f;
  ASSERT_GT(covered, 20u) << "the block moved over air particles";
  kept.step(*a.env, nullptr);
  float deepest = 1.0f;
  for (const Vec3& p : kept.positions()) deepest = std::min(deepest, a.env->signedDistance(p));
  EXPECT_GE(deepest, 0.0f) << covered << " particles were covered; none is inside after a step";
}

// A damaged session must not hand the air values it cannot hold: each is an Error.
TEST(SphAir, DamagedSavedAirIsRefused) {
  const Tunnel tunnel = windTunnel();
  SphAir air = streamingAir(tunnel, 3.0f);
  air.step(*tunnel.env, nullptr);
  // The layout of SphAir::saveState, written by hand with one value changed: "2SPH" with the
  // pressures (the first one `pressure`), or the earlier "1SPH" without them.
  bool before = false;
  float pressure = 0.0f;
  auto write = [&](auto&& change) {
    std::vector<SphEmitter> emitters = air.emitters();
    std::vector<double> clocks(emitters.size(), 0.0);
    float mass = air.particleMass(), h = air.supportRadius(), time = air.time();
    std::vector<Vec3> x = air.positions(), v = air.velocities();
    std::vector<float> rho = air.densities();
    change(emitters, clocks, mass, h, time, x, v, rho);
    const size_t n = x.size();
    ArchiveWriter out;
    out.tag(before ? 0x48505331 : 0x48505332);
    out.vector(emitters), out.vector(clocks);
    out.f32(mass), out.f32(h), out.f32(time);
    out.u64(1);
    out.boolean(false), out.boolean(false);
    out.vector(x), out.vector(v), out.vector(rho);
    out.vector(std::vector<float>(n, 0.0f)), out.vector(std::vector<float>(n, std::numeric_limits<float>::infinity()));
    out.vector(std::vector<Vec3>(n, Vec3::Zero())), out.vector(std::vector<uint8_t>(n, 0));
    if (!before) {
      std::vector<float> p(n, 0.0f);
      p[0] = pressure;
      out.vector(p);
    }
    return out;
  };
  auto loads = [&](const ArchiveWriter& out) {
    SphAir fresh(tunnel.settings);
    ArchiveReader in(out.data(), "saved.tses");
    fresh.loadState(in);
    return fresh.count();
  };
  using E = std::vector<SphEmitter>;
  using D = std::vector<double>;
  using P = std::vector<Vec3>;
  using R = std::vector<float>;
  EXPECT_EQ(loads(write([](E&, D&, float&, float&, float&, P&, P&, R&) {})), air.count()) << "undamaged";
  before = true;
  EXPECT_EQ(loads(write([](E&, D&, float&, float&, float&, P&, P&, R&) {})), air.count()) << "the earlier layout";
  before = false;
  auto refused = [&](const char* what, auto&& change) {
    try {
      loads(write(change));
      ADD_FAILURE() << what << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("saved.tses"), std::string::npos) << e.what();
    }
  };
  refused("a NaN position", [](E&, D&, float&, float&, float&, P& x, P&, R&) { x[3].y() = std::nanf(""); });
  refused("a position far outside the domain", [](E&, D&, float&, float&, float&, P& x, P&, R&) { x[0].x() = 1e30f; });
  refused("an infinite velocity", [](E&, D&, float&, float&, float&, P&, P& v, R&) { v[5].z() = std::numeric_limits<float>::infinity(); });
  // Found by fuzzing: finite, but its square overflows the forces to NaN in the first step.
  refused("a velocity of 1e37 m/s", [](E&, D&, float&, float&, float&, P&, P& v, R&) { v[5].x() = -3.85e37f; });
  refused("a density of 1e29", [](E&, D&, float&, float&, float&, P&, P&, R& rho) { rho[2] = 1e29f; });
  refused("a zero density", [](E&, D&, float&, float&, float&, P&, P&, R& rho) { rho[7] = 0.0f; });
  refused("another particle mass", [](E&, D&, float& m, float&, float&, P&, P&, R&) { m *= 2.0f; });
  refused("another support radius", [](E&, D&, float&, float& h, float&, P&, P&, R&) { h = 0.0f; });
  refused("an emitter as wide as a city", [](E& e, D&, float&, float&, float&, P&, P&, R&) { e[0].radius = 1e6f; });
  refused("an emitter outside the domain", [](E& e, D&, float&, float&, float&, P&, P&, R&) { e[0].position.x() = 50; });
  refused("a negative emitter clock", [](E&, D& c, float&, float&, float&, P&, P&, R&) { c[0] = -1.0; });
  pressure = std::nanf("");
  refused("a NaN pressure", [](E&, D&, float&, float&, float&, P&, P&, R&) {});
  pressure = 1e30f;
  refused("a pressure of 1e30 Pa", [](E&, D&, float&, float&, float&, P&, P&, R&) {});
}

TEST(SphAir, BadSettingsAreRefused) {
  auto refuses = [](auto&& change) {
    SphSettings s;
    change(s);
    EXPECT_THROW(SphAir{s}, Error);
  };
  refuses([](SphSettings& s) { s.spacing = 0.0f; });
  refuses([](SphSettings& s) { s.restDensity = std::nanf(""); });
  refuses([](SphSettings& s) { s.soundSpeed = -1.0f; });
  refuses([](SphSettings& s) { s.viscosity = -0.1f; });
  refuses([](SphSettings& s) { s.supportFactor = 1.0f; });
  refuses([](SphSettings& s) { s.cfl = 0.0f; });
  refuses([](SphSettings& s) { s.maxSubsteps = 0; });
  refuses([](SphSettings& s) { s.iterations = 0; });
  refuses([](SphSettings& s) { s.iterations = 51; });
  refuses([](SphSettings& s) { s.domainMax = Vec3(-2, 1, 1); });
  refuses([](SphSettings& s) { s.domainMax = Vec3(1e4f, 1e4f, 1e4f); });  // too many grid cells
  try {
    SphSettings s;
    s.spacing = -0.05f;
    SphAir air(s);
    FAIL() << "a negative spacing was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.location(), "spacing");
    EXPECT_NE(e.message().find("-0.05"), std::string::npos) << e.what();
  }

  SphAir air;
  SphEmitter e;
  e.position = Vec3(5, 0, 0);  // outside the default domain
  EXPECT_THROW(air.addEmitter(e), Error);
  e.position = Vec3(0, 1, 0);
  e.speed = air.settings().soundSpeed;  // the model is weakly compressible: slower than sound
  EXPECT_THROW(air.addEmitter(e), Error);
  e.speed = 2.0f;
  e.direction = Vec3::Zero();
  EXPECT_THROW(air.addEmitter(e), Error);
  e.direction = Vec3(1, 0, 0);
  e.radius = 1e6f;  // its layers would span 10¹⁵ lattice sites
  try {
    air.addEmitter(e);
    ADD_FAILURE() << "a 1000 km emitter was accepted";
  } catch (const Error& error) {
    EXPECT_EQ(error.location(), "radius") << error.what();
  }
  EXPECT_TRUE(air.emitters().empty());
  EXPECT_THROW(air.fillBox(Vec3(3, 3, 3), Vec3(4, 4, 4)), Error) << "outside the domain";
  SphSettings small;
  small.maxParticles = 100;
  SphAir capped(small);
  EXPECT_THROW(capped.fillBox(small.domainMin, small.domainMax), Error) << "more than maxParticles";
  EXPECT_EQ(capped.count(), 0u);
}

}  // namespace
}  // namespace tendril::wind
