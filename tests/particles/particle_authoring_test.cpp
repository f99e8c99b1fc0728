// Seed 000's authoring tools and contact response shown to act on particle plants: painted
// attractors draw growth toward a stroke and repulsors push it away (§5.1), a repelling
// stroke stops the shoots of every model that climbs (climbing, L-system and particle ivy) where
// they enter the region it keeps clear (Fig. 1's pruned windows), friction slows a
// piece sliding down a slope and elasticity makes a dropped piece bounce (§5.2), and Fig. 5's
// four branching settings give the branch counts and angles its caption describes (§4.2).
#include "support/determinism.h"
#include "support/particle_session.h"
#include "support/test_paths.h"
#include "tendril/core/json_reader.h"
#include "tendril/env/primitives.h"
#include "tendril/particles/particle_model.h"
#include "tendril/scene/scene.h"
#include "tendril/session/session.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace tendril::particles {
namespace {

std::unique_ptr<env::Environment> makeEnv(const std::string& environmentJson) {
  const std::string text = R"({"tendril": 1, "environment": )" + environmentJson + R"(, "plants": []})";
  scene::Scene s = scene::parseScene(parseJson(text, "test scene"), "test scene", test::sourceDir());
  auto env = std::make_unique<env::Environment>();
  scene::populateEnvironment(s, *env);
  env->commit();
  return env;
}

bool isStem(const ParticleWorld& w, uint32_t i, uint32_t plant) {
  return w.active(i) && w.plantOf(i) == plant && !(w.flags(i) & (kLeaf | kDetached | kRoot));
}

// --- attractors and repulsors (§5.1, Fig. 8) ---

// The shipped ivy climbing a 3 m wide wall (its face at z = 0.1) from x = 0, with light from
// the front. A stroke painted up the wall at x = 0.3 (a vertical line of points on its face
// from y = 0.1 to 1.9 m, radius 0.6 m, strength 1) attracts or repels it; the result is the
// stems' mean horizontal distance to the stroke and the share of them within 15 cm of it.
constexpr float kStrokeX = 0.3f;

struct NearStroke {
  double distance = 0, within = 0;
};

NearStroke nearStroke(int stroke /* 0 none, +1 attract, −1 repel */) {
  auto env = makeEnv(R"({"obstacles": [{"name": "ground", "type": "plane", "size": [10, 10]},
                                       {"name": "wall", "type": "wall", "size": [3, 2.5, 0.2]}],
                         "lights": [{"type": "directional", "direction": [0, -0.6, -1]}]})");
  if (stroke != 0) {
    env::Stroke st;
    st.attract = stroke > 0;
    st.radius = 0.6f;
    for (float y = 0.1f; y <= 1.9f; y += 0.05f) st.points.push_back(Vec3(kStrokeX, y, 0.1f));
    env->addStroke(st);
    env->commit();
  }
  ParticleWorld w;
  ParticleSpecies s = loadSpecies("ivy-particles", test::sourceDir());
  s.maxParticles = 1200;
  const uint32_t p = w.addPlant("ivy", s, Vec3(0, 0.03f, 0.11f), Vec3(0, 1, 0), 1, *env);
  for (int k = 0; k < 600; ++k) w.step(*env);
  NearStroke r;
  size_t n = 0;
  for (uint32_t i = 0; i < w.capacity(); ++i)
    if (isStem(w, i, p)) {
      const double d = std::abs(w.position(i).x() - kStrokeX);
      r.distance += d;
      r.within += d < 0.15;
      ++n;
    }
  EXPECT_GT(n, 500u) << "the plant should have grown";
  r.distance /= double(n);
  r.within /= double(n);
  return r;
}

TEST(ParticleAuthoring, AnAttractorStrokeDrawsGrowthTowardItAndARepulsorPushesItAway) {
  const NearStroke none = nearStroke(0), attracted = nearStroke(+1), repelled = nearStroke(-1);
  std::printf("stems' mean distance to the stroke (share within 15 cm): %.3f m (%.0f%%) without it, %.3f m (%.0f%%) "
              "attracted, %.3f m (%.0f%%) repelled\n",
              none.distance, 100 * none.within, attracted.distance, 100 * attracted.within, repelled.distance,
              100 * repelled.within);
  EXPECT_LT(attracted.distance, 0.75 * none.distance) << "an attractor stroke draws the stems toward it";
  EXPECT_GT(attracted.within, 1.5 * none.within);
  EXPECT_GT(repelled.distance, 1.25 * none.distance) << "a repulsor stroke pushes them away";
  EXPECT_LT(repelled.within, 0.5 * none.within);
}

// A band of repelling points painted across a 3 m wall at 1 m (every 10 cm, radius 0.4 m: it
// keeps growth out where strength · (1 − d/r)² ≥ ½, within 0.117 m of a point) and a plant of
// `model` at the wall's foot, grown with and without the band: its stem nodes in the region the
// band keeps clear, and the highest of them.
constexpr float kBandRadius = 0.4f;

bool inBandRegion(const Vec3& p) {
  for (int k = 0; k <= 30; ++k)
    if ((p - Vec3(-1.5f + 0.1f * float(k), 1.0f, 0.1f)).norm() < kBandRadius * (1.0f - std::sqrt(0.5f))) return true;
  return false;
}

struct Band {
  float top = 0.0f;
  size_t inside = 0, stems = 0;
};

Band growUnderBand(const std::string& model, bool band) {
  std::string stroke;
  if (band) {
    stroke = R"(, "strokes": [{"kind": "repel", "radius": 0.4, "strength": 1, "points": [)";
    for (int k = 0; k <= 30; ++k) stroke += (k ? ", [" : "[") + std::to_string(-1.5 + 0.1 * k) + ", 1.0, 0.1]";
    stroke += "]}]";
  }
  const std::string plant =
      model == "climb"     ? R"({"name": "ivy", "position": [0, 0, 0.15], "seed": 2, "species": {"base": "japanese-ivy"}})"
      : model == "lsystem" ? R"({"name": "ivy", "model": "lsystem", "grammar": "japanese-ivy", "position": [0, 0, 0.15], "seed": 2})"
                           : R"({"name": "ivy", "model": "particles", "position": [0, 0.05, 0.13], "seed": 2,
                                "species": {"base": "ivy-particles", "max_particles": 2500}})";
  const std::string json = R"({"tendril": 1, "seed": 4, "environment": {"obstacles": [
        {"name": "ground", "type": "plane", "size": [10, 10]},
        {"name": "wall", "type": "wall", "size": [3, 2.5, 0.2]}],
      "lights": [{"type": "directional", "direction": [0, -1, -0.4]}])" + stroke + R"(},
    "plants": [)" + plant + "]}";
  session::Session s(scene::parseScene(parseJson(json, "test scene"), "test scene", test::sourceDir()));
  s.run(model == "climb" ? 260 : model == "lsystem" ? 220 : 900);
  const plant::PlantModel p = s.plants().at(0);
  Band b;
  b.stems = p.nodeCount();
  for (size_t i = 0; i < p.nodeCount(); ++i) {
    if (p.flags[i] & plant::kNodeBroken) continue;
    b.top = std::max(b.top, p.position[i].y());
    b.inside += inBandRegion(p.position[i]);
  }
  return b;
}

TEST(PaintedStrokes, ARepellingStrokeStopsTheShootsOfEveryModelThatReachIt) {
  for (const std::string model : {"climb", "lsystem", "particles"}) {
    SCOPED_TRACE(model);
    const Band free = growUnderBand(model, false), held = growUnderBand(model, true);
    std::printf("%s: without the band %zu stems up to %.2f m, %zu in its region; with it %zu stems up to %.2f m, %zu "
                "in its region\n",
                model.c_str(), free.stems, free.top, free.inside, held.stems, held.top, held.inside);
    EXPECT_GT(free.inside, 10u) << "without the band the plant climbs through its region";
    EXPECT_EQ(held.inside, 0u) << "no shoot grows into the region the band keeps clear";
    EXPECT_GT(held.stems, 100u);
  }
}

// --- friction and elasticity (§5.2) ---

// A chain of six particles (30 cm) grown straight along +x from `root` in weightless air, then
// cut off its root: the piece falls under gravity onto `env`'s obstacles. Returns the piece's
// centre of mass after each of the `steps` steps after the cut.
std::vector<Vec3> fallingPiece(const env::Environment& env, float friction, float elasticity, const Vec3& root,
                               int steps) {
  WorldSettings ws;
  ws.plantCollisions = false;
  ws.removeRestingAfter = 0.0f;  // keep the piece where it came to rest
  WorldSettings weightless = ws;
  weightless.gravity = Vec3::Zero();
  ParticleWorld w(weightless);
  ParticleSpecies s = loadSpecies("ivy-particles", test::sourceDir());
  s.maxParticles = 7;
  s.maxLateralBuds = 0;
  s.leafStep = 0;
  s.phototropism = 0.0f;
  s.randomWalk = 0.0f;
  s.surfaceAdaption = 0.0f;
  s.crowding = 0;
  s.growthRate = 0.2f;
  s.minGrowthLight = 1.0f;
  s.friction = friction;
  s.elasticity = elasticity;
  const uint32_t p = w.addPlant("piece", s, root, Vec3(1, 0, 0), 1, env);
  for (int k = 0; k < 400; ++k) w.step(env);
  uint32_t first = kNone;
  size_t stems = 0;
  for (uint32_t i = 0; i < w.capacity(); ++i)
    if (isStem(w, i, p)) {
      ++stems;
      if (w.flags(w.parent(i)) & kRoot) first = i;
    }
  EXPECT_EQ(stems, 6u);
  EXPECT_NE(first, kNone);
  w.cut(first);
  w.setSettings(ws);
  std::vector<Vec3> centroids;
  for (int k = 0; k < steps; ++k) {
    w.step(env);
    Vec3 c = Vec3::Zero();
    float mass = 0.0f;
    for (uint32_t i = 0; i < w.capacity(); ++i)
      if (w.active(i) && (w.flags(i) & kDetached)) c += w.mass(i) * w.position(i), mass += w.mass(i);
    EXPECT_GT(mass, 0.0f);
    centroids.push_back(c / mass);
  }
  return centroids;
}

// A slab tilted 20° about z, its top descending toward +x: how far (m) a piece dropped onto it
// slides downhill between 0.75 s and 3 s after the cut (it lands after about 0.2 s).
float slide(float friction) {
  const float tilt = radians(-20.0f);
  auto env = std::make_unique<env::Environment>();
  env::ObstacleDef slab;
  slab.name = "slope";
  slab.kind = env::ObstacleKind::Box;
  slab.mesh = env::makeBox(Vec3(6.0f, 0.2f, 1.0f));
  slab.worldFromLocal.rotation = Quat(Eigen::AngleAxisf(tilt, Vec3::UnitZ()));
  env->addObstacle(std::move(slab));
  env->commit();
  const Vec3 downhill = Quat(Eigen::AngleAxisf(tilt, Vec3::UnitZ())) * Vec3::UnitX();
  const std::vector<Vec3> c = fallingPiece(*env, friction, 0.1f, Vec3(-0.15f, 0.35f, 0.0f), 120);
  for (const Vec3& x : c) EXPECT_TRUE(isFinite(x));
  return (c[119] - c[29]).dot(downhill);
}

TEST(ParticleContact, FrictionSlowsAPieceSlidingDownASlope) {
  const float slippery = slide(0.05f), shipped = slide(0.6f), rough = slide(0.95f);
  std::printf("slid downhill in 2.25 s: %.3f m at friction 0.05, %.3f m at 0.6, %.3f m at 0.95\n", slippery, shipped,
              rough);
  EXPECT_GT(slippery, 0.3f) << "with little friction the piece slides away";
  EXPECT_GT(slippery, 3.0f * shipped) << "more friction, less sliding";
  EXPECT_GT(shipped, rough) << "more friction, less sliding";
  EXPECT_GE(rough, 0.0f) << "nothing slides uphill";
}

// How high (m) a piece dropped flat from 30 cm onto the ground rises after its first bounce.
float bounce(float elasticity) {
  auto env = makeEnv(R"({"obstacles": [{"name": "ground", "type": "plane", "size": [10, 10]}]})");
  const std::vector<Vec3> c = fallingPiece(*env, 0.6f, elasticity, Vec3(-0.15f, 0.3f, 0.0f), 80);
  size_t lowest = 0;  // the first contact: where the centroid stops falling
  while (lowest + 1 < c.size() && c[lowest + 1].y() < c[lowest].y()) ++lowest;
  float top = c[lowest].y();
  for (size_t k = lowest; k < c.size(); ++k) top = std::max(top, c[k].y());
  EXPECT_LT(c[lowest].y(), 0.05f) << "the piece reaches the ground";
  return top - c[lowest].y();
}

TEST(ParticleContact, ElasticityMakesADroppedPieceBounce) {
  const float dull = bounce(0.0f), shipped = bounce(0.1f), springy = bounce(0.9f);
  std::printf("rebound after a 30 cm drop: %.4f m at elasticity 0, %.4f m at 0.1, %.4f m at 0.9\n", dull, shipped,
              springy);
  EXPECT_GT(springy, 0.05f) << "an elastic piece bounces back up";
  EXPECT_GT(springy, 4.0f * shipped) << "more elasticity, a larger bounce";
  EXPECT_GE(shipped, dull);
}

// --- Fig. 5: branching settings (§4.2) ---

struct Branching {
  size_t stems = 0, laterals = 0;
  double meanAngle = 0;  // degrees between a lateral's first particle and its parent
};

Branching branching(const ParticleWorld& w, uint32_t plant) {
  Branching b;
  const plant::PlantModel m = w.snapshot(plant);
  const std::vector<uint32_t> particle = w.snapshotParticles(plant);
  for (size_t n = 0; n < m.nodeCount(); ++n) {
    if (m.flags[n] & plant::kNodeBroken) continue;
    ++b.stems;
    const int32_t parent = m.parent[n];
    if (parent < 0 || m.order[n] <= m.order[size_t(parent)]) continue;
    ++b.laterals;
    const Vec3 own = w.orientation(particle[n]) * Vec3::UnitY();
    const Vec3 theirs = w.orientation(particle[size_t(parent)]) * Vec3::UnitY();
    b.meanAngle += std::acos(std::clamp(own.dot(theirs), -1.0f, 1.0f)) * 180.0 / kPi;
  }
  if (b.laterals > 0) b.meanAngle /= double(b.laterals);
  return b;
}

// The scene's four plants, one seed with (a)–(d)'s settings: (b) and (c)'s high branching
// probability gives several times the laterals of (a) and (d)'s low one, and the laterals part
// from their parents at angles ordered as the direction variance: (b) high, (d) medium, (c) and
// (a) low.
TEST(ParticleFigures, Fig5sBranchingSettingsGiveTheCountsAndAnglesItsCaptionDescribes) {
  session::Session session(scene::loadScene(test::sourceDir() / "examples/scenes/particles-fig05-branching.json"));
  session.run(uint32_t(session.scene().steps));
  const ParticleWorld& w = *test::particleWorld(session);
  ASSERT_EQ(w.plantCount(), 4u);
  Branching f[4];
  for (uint32_t p = 0; p < 4; ++p) {
    f[p] = branching(w, p);
    std::printf("Fig. 5 (%c): %zu stem particles, %zu laterals, mean branching angle %.1f°\n", char('a' + p),
                f[p].stems, f[p].laterals, f[p].meanAngle);
  }
  enum { a, b, c, d };
  for (int high : {b, c})
    for (int low : {a, d})
      EXPECT_GT(f[high].laterals, 2.5 * double(f[low].laterals)) << char('a' + high) << " against " << char('a' + low);
  EXPECT_GT(f[b].meanAngle, 1.5 * f[d].meanAngle);
  EXPECT_GT(f[d].meanAngle, 1.5 * f[c].meanAngle);
  EXPECT_GT(f[d].meanAngle, 1.5 * f[a].meanAngle);
  for (int k : {a, b, c, d}) EXPECT_GE(f[k].laterals, 20u) << "(" << char('a' + k) << ") branches";
}

}  // namespace
}  // namespace tendril::particles
