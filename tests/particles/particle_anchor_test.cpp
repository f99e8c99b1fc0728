// Anchors that grow with their particle and breaking on the strain the paper defines (seed 000
// eq. 5 and §4.3): an undisturbed climber keeps every particle at any threshold, and a dragged
// one breaks exactly where its strain passes the species' breaking strain.
#include "support/test_paths.h"
#include "tendril/core/json_reader.h"
#include "tendril/particles/particle_model.h"
#include "tendril/particles/world.h"
#include "tendril/scene/scene.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>

namespace tendril::particles {
namespace {

std::unique_ptr<env::Environment> makeEnv(const std::string& environmentJson) {
  std::string text = R"({"tendril": 1, "environment": )" + environmentJson + R"(, "plants": []})";
  scene::Scene s = scene::parseScene(parseJson(text, "test scene"), "test scene", test::sourceDir());
  auto env = std::make_unique<env::Environment>();
  scene::populateEnvironment(s, *env);
  env->commit();
  return env;
}

// A wall 3 m wide and 2.5 m high, its face at z = 0.1, on the ground; light from the front.
constexpr const char* kGroundAndWall =
    R"({"obstacles": [{"name": "ground", "type": "plane", "size": [10, 10]},
                      {"name": "wall", "type": "wall", "size": [3, 2.5, 0.2]}],
        "lights": [{"type": "directional", "direction": [0, -0.6, -1]}]})";

// The strain of the connection between i and p as breaking measures it (§4.3): how far the
// two centres are pulled apart beyond the connection's length as grown (the two half lengths,
// end to end; a root, a ball, reaches its radius where that is more), relative to that length.
float strainBetween(const ParticleWorld& w, uint32_t i, uint32_t p) {
  const float reach = (w.flags(p) & kRoot) ? std::max(w.halfLength(p), w.radius(p)) : w.halfLength(p);
  const float length = w.halfLength(i) + reach;
  if (!(length > 0.0f)) return 0.0f;
  return std::max(0.0f, (w.position(i) - w.position(p)).norm() - length) / length;
}

struct Losses {
  size_t detached = 0;       // particles of broken-off pieces
  size_t unlinked = 0;       // connections that broke (non-roots without a parent)
};

Losses losses(const ParticleWorld& w) {
  Losses l;
  for (uint32_t i = 0; i < w.capacity(); ++i) {
    if (!w.active(i)) continue;
    if (w.flags(i) & kDetached) ++l.detached;
    if (!(w.flags(i) & kRoot) && w.parent(i) == kNone) ++l.unlinked;
  }
  return l;
}

// The largest strain of any connection breaking would judge (not growing apices).
float largestJudgedStrain(const ParticleWorld& w) {
  float most = 0.0f;
  for (uint32_t i = 0; i < w.capacity(); ++i)
    if (w.active(i) && w.parent(i) != kNone && !(w.flags(i) & kApex)) most = std::max(most, w.strain(i));
  return most;
}

ParticleSpecies wallIvy(float breakThreshold, int maxParticles) {
  ParticleSpecies s = loadSpecies("ivy-particles", test::sourceDir());
  s.breakThreshold = breakThreshold;
  s.maxParticles = maxParticles;
  return s;
}

// The shipped ivy on a wall with break_threshold 0.3 (a breaking strain of 0.35): over 60 s of
// simulated time nothing breaks and nothing detaches. With the anchor fixed where a growing tip
// first touched the wall (a tenth of its length), eq. 5 pulled every grown particle back by up
// to half its length, and the plants broke off at their base within a second.
TEST(ParticleAnchors, AnUndisturbedIvyOnAWallLosesNothingOver60Seconds) {
  auto env = makeEnv(kGroundAndWall);
  ParticleWorld w;
  // Capped at 2,500 particles, which it reaches after about 15 s, still on the wall (grown on
  // without a cap: AnUncappedIvyOnATallWallKeepsItsFootPast30Seconds below).
  const ParticleSpecies s = wallIvy(0.3f, 2500);
  const uint32_t plant = w.addPlant("ivy", s, Vec3(0, 0.03f, 0.11f), Vec3(0, 1, 0), 1, *env);
  const int steps = int(std::lround(60.0f / w.settings().dt));
  float most = 0.0f;
  int firstLoss = -1;
  size_t countAt15 = 0;
  for (int k = 0; k < steps; ++k) {
    w.step(*env);
    most = std::max(most, largestJudgedStrain(w));
    const Losses l = losses(w);
    if (firstLoss < 0 && (l.detached > 0 || l.unlinked > 0)) firstLoss = k;
    if (k + 1 == steps / 4) countAt15 = w.particleCount(plant);
  }
  EXPECT_NEAR(w.time(), 60.0f, 0.01f);
  const Losses l = losses(w);
  EXPECT_EQ(l.detached, 0u) << "first loss at step " << firstLoss;
  EXPECT_EQ(l.unlinked, 0u);
  // It grew to its cap, all of it on the wall.
  EXPECT_GT(w.particleCount(plant), 2400u);
  // An undisturbed plant carries about no strain: far below the breaking strain of any
  // threshold up to 0.3 (so 0.1, with a breaking strain of 0.45, loses nothing either).
  EXPECT_LT(most, 0.1f) << "largest strain over the minute";
  // Still climbing: most stems on the wall are anchored to it.
  size_t onWall = 0, anchored = 0;
  for (uint32_t i = 0; i < w.capacity(); ++i) {
    if (!w.active(i) || (w.flags(i) & kLeaf)) continue;
    const Vec3 x = w.position(i);
    if (x.y() < 0.1f || std::abs(x.z() - 0.1f) > 0.05f) continue;
    ++onWall;
    if (w.flags(i) & kAnchored) ++anchored;
  }
  EXPECT_GE(double(anchored) / double(std::max<size_t>(onWall, 1)), 0.6) << anchored << " of " << onWall;
  std::printf("[ measured ] 60 s at break_threshold 0.3: %zu particles (%zu at 15 s), largest strain %.4f "
              "(breaking strain %.3f), %zu of %zu stems on the wall anchored\n",
              w.particleCount(plant), countAt15, double(most), double(breakingStrain(s)), anchored, onWall);
}

// The grown ivy dragged away from the wall by a stem particle: connections break, and exactly
// those whose strain (as §4.3 defines it, against the rest length as grown) passed the
// species' breaking strain in the step they broke; none other.
TEST(ParticleAnchors, ADraggedIvyBreaksExactlyWhereItsStrainPassesTheThreshold) {
  auto env = makeEnv(kGroundAndWall);
  ParticleWorld w;
  const ParticleSpecies s = wallIvy(0.3f, 1500);
  const uint32_t plant = w.addPlant("ivy", s, Vec3(0, 0.03f, 0.11f), Vec3(0, 1, 0), 1, *env);
  for (int k = 0; k < 600; ++k) w.step(*env);
  ASSERT_EQ(losses(w).detached, 0u) << "undisturbed, nothing breaks";
  const size_t before = w.particleCount(plant);
  // The anchored, grown stem particle nearest 40 cm up the wall.
  uint32_t held = kNone;
  for (uint32_t i = 0; i < w.capacity(); ++i) {
    if (!w.active(i) || (w.flags(i) & (kLeaf | kApex)) || !(w.flags(i) & kAnchored)) continue;
    if (held == kNone || std::abs(w.position(i).y() - 0.4f) < std::abs(w.position(held).y() - 0.4f)) held = i;
  }
  ASSERT_NE(held, kNone);
  const Vec3 start = w.position(held);
  const float breaking = breakingStrain(s);
  size_t broke = 0, judged = 0;
  float largestKept = 0.0f, smallestBroken = 1e9f;
  std::vector<uint32_t> parentBefore(w.capacity());
  std::vector<uint32_t> flagsBefore(w.capacity());
  for (int k = 0; k < 80; ++k) {
    // Away from the wall, 60 cm over a second, then held there.
    w.setDrag(held, start + Vec3(0, 0, 0.6f * std::min(1.0f, float(k) / 40.0f)), 0.5f);
    parentBefore.assign(w.capacity(), kNone);
    flagsBefore.assign(w.capacity(), 0);
    for (uint32_t i = 0; i < w.capacity(); ++i)
      if (w.active(i)) parentBefore[i] = w.parent(i), flagsBefore[i] = w.flags(i);
    w.step(*env);
    // Breaking is the step's last change to positions: the strains it judged are those now.
    for (uint32_t i = 0; i < parentBefore.size(); ++i) {
      const uint32_t p = parentBefore[i];
      if (p == kNone || !w.active(i)) continue;
      const bool broken = w.parent(i) == kNone;
      // Breaking judges every connection but a growing apex's. An apex that grew up in this
      // step and lies in a piece that broke off lost its apex flag with the piece: unknown.
      if (!broken && (w.flags(i) & kApex)) continue;
      if (!broken && (flagsBefore[i] & kApex) && (w.flags(i) & kDetached)) continue;
      ++judged;
      const float strain = strainBetween(w, i, p);
      EXPECT_EQ(broken, strain > breaking) << "step " << k << ", particle " << i << ": strain " << strain
                                           << " against the breaking strain " << breaking;
      if (broken) {
        ++broke;
        smallestBroken = std::min(smallestBroken, strain);
      } else {
        largestKept = std::max(largestKept, strain);
      }
    }
  }
  w.clearDrag();
  EXPECT_GT(broke, 0u) << "dragged 60 cm off the wall, the plant breaks";
  // Away from the drag the plant stays on the wall: most of it is neither broken off nor freed.
  size_t detached = 0;
  for (uint32_t i = 0; i < w.capacity(); ++i)
    if (w.active(i) && w.plantOf(i) == plant && (w.flags(i) & kDetached)) ++detached;
  EXPECT_LT(detached, before / 2) << "of " << before;
  std::printf("[ measured ] drag 60 cm off the wall: %zu of %zu connection-steps judged broke (smallest strain "
              "%.3f), the largest kept strain %.3f, breaking strain %.3f; %zu of %zu particles detached\n",
              broke, judged, double(smallestBroken), double(largestKept), double(breaking), detached, before);
}

// Grown without a cap on a wall 14 m high, past the 30 s at which the first break used to come:
// the root, held where it was seeded, thickens with its first particle to 3.5 cm, and collisions
// hold that particle a radius off the ground and the wall, away from the root. Measured against
// the root's half length as seeded (6 mm), the foot connection was pulled 35 % beyond its length,
// broke at 31 s, and the whole plant — 14,000 particles — fell off the wall (a broken-off piece
// lets go of its anchors) and shattered (kinetic energy 180 J). The foot connection now reaches
// the root's surface: a + max(a_root, b_root).
TEST(ParticleAnchors, AnUncappedIvyOnATallWallKeepsItsFootPast30Seconds) {
  auto env = makeEnv(R"({"obstacles": [{"name": "ground", "type": "plane", "size": [40, 40]},
                                       {"name": "wall", "type": "wall", "size": [20, 14, 0.2]}],
                         "lights": [{"type": "directional", "direction": [0, -0.6, -1]}]})");
  ParticleWorld w;
  const ParticleSpecies s = wallIvy(0.3f, 25000);  // the shipped cap: not reached in this run
  const uint32_t plant = w.addPlant("ivy", s, Vec3(0, 0.03f, 0.11f), Vec3(0, 1, 0), 1, *env);
  uint32_t foot = kNone;  // the plant's first particle
  for (uint32_t i = 0; i < w.capacity(); ++i)
    if (w.active(i) && !(w.flags(i) & kRoot) && w.plantOf(i) == plant && w.parent(i) != kNone &&
        (w.flags(w.parent(i)) & kRoot))
      foot = i;
  ASSERT_NE(foot, kNone);
  const uint32_t root = w.parent(foot);
  float most = 0.0f, footMost = 0.0f;
  size_t mostDetached = 0;  // particles of broken-off pieces at any step (they vanish after resting)
  int firstLoss = -1;
  for (int k = 0; k < 1300; ++k) {  // 32.5 s
    w.step(*env);
    most = std::max(most, largestJudgedStrain(w));
    if (w.parent(foot) == root) footMost = std::max(footMost, w.strain(foot));
    const Losses l = losses(w);
    mostDetached = std::max(mostDetached, l.detached);
    if (firstLoss < 0 && (l.detached > 0 || l.unlinked > 0)) firstLoss = k;
  }
  EXPECT_EQ(w.parent(foot), root) << "the foot connection broke";
  EXPECT_GT(w.particleCount(plant), 12000u) << "grown past the size at which it used to break";
  // A few single particles may break off (measured: 3, at 21 s, when the plant passes 10,000
  // particles and its leaf particles become attached leaves), never a large piece.
  EXPECT_LT(mostDetached, 30u) << "first loss at step " << firstLoss;
  EXPECT_LT(footMost, 0.05f) << "the foot's thickening does not strain the foot connection";
  std::printf("[ measured ] 32.5 s uncapped on a 14 m wall at break_threshold 0.3: %zu particles, root radius %.4f m, "
              "largest strain %.4f, at the foot %.4f (breaking strain %.3f); at most %zu particles broken off at "
              "once (first at step %d)\n",
              w.particleCount(plant), double(w.radius(root)), double(most), double(footMost),
              double(breakingStrain(s)), mostDetached, firstLoss);
}

}  // namespace
}  // namespace tendril::particles
