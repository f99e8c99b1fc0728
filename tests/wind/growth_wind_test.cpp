// Growth-Flow growth in the growth models: a plant grown in a wind above w_max against the same
// seed in still air (seed 001 §3.1.2, §3.2.2), and a wind below w_min changing nothing.
#include "support/particle_session.h"
#include "support/test_paths.h"
#include "tendril/session/edit.h"
#include "tendril/scene/scene.h"
#include "tendril/session/session.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

namespace tendril {
namespace {

std::vector<plant::PlantModel> growClimb(const std::string& wind, int steps) {
  // A wide wall with the wind blowing along it (+X): shoots that turn downwind stay on it.
  std::string json = std::string(R"({"tendril": 1, "seed": 4, "steps": )") + std::to_string(steps) +
                     R"(, "environment": {"obstacles": [
        {"name": "ground", "type": "plane", "size": [20, 20]},
        {"name": "wall", "type": "wall", "size": [12, 6, 0.2]}],
      "lights": [{"type": "directional", "direction": [0, -1, -0.4]}],
      "wind": )" + wind + R"(},
    "plants": [{"name": "ivy", "position": [0, 0, 0.15],
                "species": {"base": "japanese-ivy", "pipe_model": false}}]})";
  scene::Scene s = scene::parseScene(parseJson(json, "test scene"), "test scene", test::sourceDir());
  session::Session session(std::move(s));
  session.run(uint32_t(steps));
  return session.plants();
}

// The main shoot: node 0 and its first children, up to the first branch start or tip.
std::vector<size_t> mainShoot(const plant::PlantModel& p) {
  std::vector<size_t> out;
  std::vector<int32_t> firstChild(p.nodeCount(), -1);
  for (size_t i = p.nodeCount(); i-- > 1;)
    if (p.parent[i] >= 0 && !(p.flags[i] & plant::kNodeBranchStart)) firstChild[size_t(p.parent[i])] = int32_t(i);
  for (int32_t i = 0; i >= 0; i = firstChild[size_t(i)]) out.push_back(size_t(i));
  return out;
}

// Per segment index along its shoot (0 at a root or branch start): mean segment length, mean
// size and thickness of the leaves on it, mean growth direction.
struct ByIndex {
  std::vector<double> length, leafSize, leafThickness;
  std::vector<Vec3d> direction;
  std::vector<int> nodes, leaves;
};

ByIndex byShootIndex(const plant::PlantModel& p, size_t maxIndex) {
  ByIndex b;
  b.length.assign(maxIndex, 0.0);
  b.leafSize.assign(maxIndex, 0.0);
  b.leafThickness.assign(maxIndex, 0.0);
  b.direction.assign(maxIndex, Vec3d::Zero());
  b.nodes.assign(maxIndex, 0);
  b.leaves.assign(maxIndex, 0);
  std::vector<size_t> index(p.nodeCount());
  for (size_t i = 0; i < p.nodeCount(); ++i) {
    bool start = p.parent[i] < 0 || (p.flags[i] & plant::kNodeBranchStart);
    index[i] = start ? 0 : index[size_t(p.parent[i])] + 1;
    if (index[i] >= maxIndex) continue;
    b.length[index[i]] += p.length[i];
    b.direction[index[i]] += p.direction(i).cast<double>();
    b.nodes[index[i]] += 1;
  }
  for (size_t j = 0; j < p.leafCount(); ++j) {
    size_t k = index[size_t(p.leafNode[j])];
    if (k >= maxIndex) continue;
    b.leafSize[k] += p.leafSize[j];
    b.leafThickness[k] += p.leafThickness[j];
    b.leaves[k] += 1;
  }
  for (size_t k = 0; k < maxIndex; ++k) {
    if (b.nodes[k]) b.length[k] /= b.nodes[k], b.direction[k] /= b.nodes[k];
    if (b.leaves[k]) b.leafSize[k] /= b.leaves[k], b.leafThickness[k] /= b.leaves[k];
  }
  return b;
}

TEST(GrowthFlowClimb, WindAboveMaxGivesShorterThickerSmallerLeavedPlantsTurnedDownwind) {
  const int steps = 1000;
  plant::PlantModel calm = growClimb(R"({"velocity": [0, 0, 0]})", steps)[0];
  plant::PlantModel windy = growClimb(R"({"velocity": [20, 0, 0]})", steps)[0];  // f(w) = 1
  ASSERT_GT(calm.nodeCount(), 300u);
  ASSERT_GT(windy.nodeCount(), 100u);
  ASSERT_GT(windy.leafCount(), 20u);
  const size_t kMax = 24;
  ByIndex c = byShootIndex(calm, kMax), w = byShootIndex(windy, kMax);

  // Along the main shoot the same random choices (keyed by tip and step) steer both plants, so
  // segment k is Δl^(k+1) = 0.97^(k+1) as long (eq. 8; a few segments that collision avoidance
  // shortened are skipped) and its leaves Δd^(k+1) = 0.98^(k+1) as long (eq. 17) and
  // ((1 + 0.01·1.5) / 1.01)^(k+1) as thick (eq. 16).
  std::vector<size_t> cs = mainShoot(calm), ws = mainShoot(windy);
  ASSERT_GE(std::min(cs.size(), ws.size()), 20u);
  size_t leafChecks = 0;
  std::vector<double> relative;  // (length ratio) / 0.97^(k+1)
  for (size_t k = 0; k < 20; ++k) {
    const double t = double(k + 1);
    relative.push_back(double(windy.length[ws[k]]) / double(calm.length[cs[k]]) / std::pow(0.97, t));
    for (size_t a = 0; a < calm.leafCount(); ++a) {
      if (size_t(calm.leafNode[a]) != cs[k]) continue;
      for (size_t b = 0; b < windy.leafCount(); ++b) {
        if (size_t(windy.leafNode[b]) != ws[k]) continue;
        EXPECT_NEAR(windy.leafThickness[b] / calm.leafThickness[a], std::pow(1.015 / 1.01, t), 1e-4) << k;
        // Blades squeezed by a surface shrink to 0.7 or 0.45 of their size, in either plant.
        double size = double(windy.leafSize[b]) / double(calm.leafSize[a]);
        bool fits = false;
        for (double squeeze : {1.0, 0.7, 0.45, 1 / 0.7, 1 / 0.45, 0.7 / 0.45, 0.45 / 0.7})
          fits |= std::fabs(size - squeeze * std::pow(0.98, t)) < 1e-3;
        EXPECT_TRUE(fits) << "leaf on segment " << k << ": size ratio " << size;
        ++leafChecks;
      }
    }
  }
  std::sort(relative.begin(), relative.end());
  EXPECT_NEAR(relative[relative.size() / 2], 1.0, 1e-3) << "median of (length ratio) / 0.97^(k+1)";
  EXPECT_GE(leafChecks, 4u);
  // Over the whole plant: shoots in the wind are shorter segment for segment from the 10th on.
  for (size_t k : {9u, 14u, 19u}) EXPECT_LT(w.length[k], 0.9 * c.length[k]) << "segment " << k;

  // Branches point closer to the wind (+X): past the 15th segment of their shoot, their mean
  // direction leans clearly downwind; in still air it does not.
  Vec3d cd = Vec3d::Zero(), wd = Vec3d::Zero();
  for (size_t k = 15; k < kMax; ++k) {
    cd += c.direction[k] * c.nodes[k];
    wd += w.direction[k] * w.nodes[k];
  }
  double calmAngle = std::acos(cd.normalized().x()), windAngle = std::acos(wd.normalized().x());
  EXPECT_LT(windAngle, calmAngle - 0.25) << "angle to the wind: " << windAngle << " rad in wind, " << calmAngle
                                          << " rad in still air";

  // Along the main shoot, segment k is exactly eq. 7's factor thicker: the same random choices
  // (keyed by tip and step) decrease both plants alike, so the ratio is (1.015/1.01)^(k+1).
  const double kr = (1.0 + 0.01 * 1.5) / 1.01;
  size_t compared = 0;
  for (size_t k = 0; k < std::min<size_t>({cs.size(), ws.size(), 25}); ++k) {
    double ratio = double(windy.radius[ws[k]]) / double(calm.radius[cs[k]]);
    if (calm.radius[cs[k]] <= 0.0008f + 1e-6f) break;  // the species' minimum radius clamps both
    EXPECT_NEAR(ratio, std::pow(kr, double(k + 1)), 1e-4 * std::pow(kr, double(k + 1))) << "segment " << k;
    ++compared;
  }
  EXPECT_GE(compared, 10u);
  EXPECT_GT(double(windy.radius[ws[9]]) / double(calm.radius[cs[9]]), 1.04);
}

TEST(GrowthFlowClimb, MatureSegmentsKeepTheirLengthAndRadiusWhileTheWindGoesOn) {
  // A climbing ivy (no pipe-model thickening) at 40 and at 120 steps in a storm along its
  // wall: every segment grown by step 40 has, 80 steps of wind later, the length and radius it
  // grew with, bit for bit, and its leaves their size (the models' own plants, before the
  // stems are kept off the wall).
  auto grow = [](int steps) {
    std::string json = std::string(R"({"tendril": 1, "seed": 4, "steps": )") + std::to_string(steps) +
                       R"(, "environment": {"obstacles": [
          {"name": "ground", "type": "plane", "size": [20, 20]},
          {"name": "wall", "type": "wall", "size": [12, 6, 0.2]}],
        "lights": [{"type": "directional", "direction": [0, -1, -0.4]}],
        "wind": {"mode": "gusty", "velocity": [18, 0, 0]}},
      "plants": [{"name": "ivy", "position": [0, 0, 0.15],
                  "species": {"base": "japanese-ivy", "pipe_model": false}}]})";
    session::Session session(scene::parseScene(parseJson(json, "test scene"), "test scene", test::sourceDir()));
    session.run(uint32_t(steps));
    return session.systems().at(0)->snapshots().at(0);
  };
  const plant::PlantModel before = grow(40), after = grow(120);
  ASSERT_GT(before.nodeCount(), 100u);
  ASSERT_GT(after.nodeCount(), before.nodeCount());
  for (size_t i = 0; i < before.nodeCount(); ++i) {
    ASSERT_EQ(after.length[i], before.length[i]) << "node " << i;
    ASSERT_EQ(after.radius[i], before.radius[i]) << "node " << i;
    ASSERT_EQ(after.position[i], before.position[i]) << "node " << i;
  }
  ASSERT_GE(after.leafCount(), before.leafCount());
  for (size_t j = 0; j < before.leafCount(); ++j) ASSERT_EQ(after.leafSize[j], before.leafSize[j]) << "leaf " << j;
}

TEST(GrowthFlowClimb, WindBelowMinChangesNothing) {
  const int steps = 300;
  uint64_t calm = plant::contentHash(growClimb(R"({"velocity": [0, 0, 0]})", steps));
  uint64_t light = plant::contentHash(growClimb(R"({"velocity": [3.5, 0, 1]})", steps));  // 3.6 m/s < w_min = 4
  uint64_t gusty = plant::contentHash(
      growClimb(R"({"mode": "gusty", "velocity": [2, 0, 0], "gust_strength": 0.5})", steps));  // ≤ 3 m/s
  EXPECT_EQ(light, calm);
  EXPECT_EQ(gusty, calm);
  uint64_t strong = plant::contentHash(growClimb(R"({"velocity": [8, 0, 0]})", steps));
  EXPECT_NE(strong, calm);
}


// Mean angle (rad) between successive segments along every shoot of the plant, past the 20th
// segment of the shoot (where eq. 9's angle has grown large enough to show).
double meanSuccessiveTurn(const plant::PlantModel& p) {
  std::vector<size_t> index(p.nodeCount(), 0);
  double sum = 0.0;
  size_t count = 0;
  for (size_t i = 0; i < p.nodeCount(); ++i) {
    const bool start = p.parent[i] < 0 || (p.flags[i] & plant::kNodeBranchStart);
    index[i] = start ? 0 : index[size_t(p.parent[i])] + 1;
    if (start || index[i] < 20) continue;
    const double c = double(p.direction(i).dot(p.direction(size_t(p.parent[i]))));
    sum += std::acos(std::clamp(c, -1.0, 1.0));
    ++count;
  }
  return count ? sum / double(count) : 0.0;
}

TEST(GrowthFlowClimb, GustsDroppingBelowWindMinDoNotMakeShootsZigZag) {
  // A gusty wind whose speed swings between 0 and 18 m/s, across the species' w_min (4 m/s):
  // eq. 9's angle grows only while f(w) > 0, but a shoot keeps the turn it has grown when a
  // gust drops below w_min; it does not snap back to its still-air direction and out again.
  const int steps = 700;
  plant::PlantModel gusty =
      growClimb(R"({"mode": "gusty", "velocity": [9, 0, 0], "gust_strength": 1.0, "gust_period": 1})", steps)[0];
  plant::PlantModel steady = growClimb(R"({"velocity": [9, 0, 0]})", steps)[0];
  plant::PlantModel calm = growClimb(R"({"velocity": [0, 0, 0]})", steps)[0];
  ASSERT_GT(gusty.nodeCount(), 200u);
  const double g = meanSuccessiveTurn(gusty), s = meanSuccessiveTurn(steady), c = meanSuccessiveTurn(calm);
  // Shoots in still air and in a steady wind bend alike (tropisms, climbing: 0.084 and 0.088
  // rad); gusts crossing w_min add no bending of their own (0.085 rad; 0.100 when the turn
  // snapped back below w_min).
  EXPECT_LT(g, 1.07 * std::max(s, c)) << "mean turn between successive segments: gusty " << g << " rad, steady " << s
                                      << " rad, still air " << c << " rad";
}

// An ivy of oriented particles on a wide wall in `wind` (a scene's "wind" object), the scene
// file as JSON.
Json particleIvySceneJson(const std::string& wind) {
  return parseJson(std::string(R"({"tendril": 1, "seed": 4, "environment": {"obstacles": [
        {"name": "ground", "type": "plane", "size": [20, 20]},
        {"name": "wall", "type": "wall", "size": [8, 4, 0.2]}],
      "lights": [{"type": "directional", "direction": [0, -1, -0.4]}],
      "wind": )") + wind + R"(},
    "plants": [{"name": "ivy", "model": "particles", "position": [0, 0.05, 0.13], "seed": 3,
                "species": {"base": "ivy-particles", "max_particles": 1500, "branch_probability": 0.3}}]})",
                   "test scene");
}

std::vector<plant::PlantModel> growParticles(const std::string& wind, int steps, const Json& species = Json::object()) {
  // The wind blowing along the wall (+X).
  Json doc = particleIvySceneJson(wind);
  doc["steps"] = steps;
  for (const auto& [key, value] : species.items()) doc["plants"][0]["species"][key] = value;
  scene::Scene s = scene::parseScene(doc, "test scene", test::sourceDir());
  session::Session session(std::move(s));
  session.run(uint32_t(steps));
  return session.plants();
}

// Internode generations from the plant's first apex (node 1 of a particle plant: its root is
// node 0) to each node.
std::vector<int> generations(const plant::PlantModel& p) {
  std::vector<int> g(p.nodeCount(), 0);
  for (size_t i = 1; i < p.nodeCount(); ++i) g[i] = p.parent[i] < 0 ? 0 : g[size_t(p.parent[i])] + (p.parent[i] > 0);
  return g;
}

TEST(GrowthFlowParticles, WindAboveMaxGivesShorterThickerSmallerLeavedPlantsTurnedDownwind) {
  const int steps = 1000;
  plant::PlantModel calm = growParticles(R"({"velocity": [0, 0, 0]})", steps)[0];
  plant::PlantModel windy = growParticles(R"({"velocity": [20, 0, 0]})", steps)[0];  // f(w) = 1
  ASSERT_GT(calm.nodeCount(), 100u);
  ASSERT_GT(windy.nodeCount(), 100u);
  const std::vector<int> gc = generations(calm), gw = generations(windy);
  std::vector<bool> hasChild(windy.nodeCount(), false), calmHasChild(calm.nodeCount(), false);
  for (size_t i = 1; i < windy.nodeCount(); ++i)
    if (windy.parent[i] >= 0) hasChild[size_t(windy.parent[i])] = true;
  for (size_t i = 1; i < calm.nodeCount(); ++i)
    if (calm.parent[i] >= 0) calmHasChild[size_t(calm.parent[i])] = true;

  // Eq. 8: a full-grown internode (one with a successor) of generation g is 0.97^g of the
  // species' particle length (0.05 m); in still air every one is 0.05 m. (An apex counts as
  // grown at 99.9 % of its length, and a stem lying on the wall is lifted off it by its radius,
  // models/stand_off.h, which changes its length by up to another 0.1 %.)
  size_t checked = 0;
  for (size_t i = 1; i < windy.nodeCount(); ++i) {
    if (!hasChild[i]) continue;
    EXPECT_NEAR(windy.length[i] / (0.05 * std::pow(0.97, gw[i])), 1.0, 2e-3) << "node " << i << ", generation " << gw[i];
    ++checked;
  }
  for (size_t i = 1; i < calm.nodeCount(); ++i) {
    if (calmHasChild[i]) {
      EXPECT_NEAR(calm.length[i] / 0.05, 1.0, 2e-3) << "node " << i;
    }
  }
  EXPECT_GT(checked, 50u);

  // Eq. 16–17: leaves on an internode of generation g are ((1 + 0.01·1.5) / 1.01)^g as thick
  // and at most 0.98^g as long as the species' (0.4 mm, 7 cm).
  ASSERT_GT(windy.leafCount(), 20u);
  ASSERT_GT(calm.leafCount(), 20u);
  double calmSize = 0, windySize = 0;
  int calmLeaves = 0, windyLeaves = 0;
  for (size_t j = 0; j < windy.leafCount(); ++j) {
    const int g = gw[size_t(windy.leafNode[j])];
    EXPECT_NEAR(windy.leafThickness[j], 0.0004 * std::pow(1.015 / 1.01, g), 1e-9) << "leaf " << j;
    EXPECT_LE(windy.leafSize[j], 0.07 * std::pow(0.98, g) * (1 + 1e-5)) << "leaf " << j;
    if (g >= 10) windySize += windy.leafSize[j], ++windyLeaves;
  }
  for (size_t j = 0; j < calm.leafCount(); ++j) {
    EXPECT_FLOAT_EQ(calm.leafThickness[j], 0.0004f);
    if (gc[size_t(calm.leafNode[j])] >= 10) calmSize += calm.leafSize[j], ++calmLeaves;
  }
  ASSERT_GT(windyLeaves, 10);
  ASSERT_GT(calmLeaves, 10);
  EXPECT_LT(windySize / windyLeaves, 0.85 * calmSize / calmLeaves) << "mean leaf size from generation 10 on";

  // Eq. 7 is how thick an internode is born: a successor is its predecessor's radius times the
  // species' apex taper (0.97) times eq. 7's factor for one unit, (1 + 0.01·1.5) / 1.01 at
  // f(w) = 1. Secondary growth (the pipe model) then thickens it by what it carries, so births
  // are read off plants grown without it, internode by internode (a mean radius per generation
  // compares two plants' shapes as much as their births: with secondary growth the windy plant's
  // generations 5–19 measured 0.80–1.60 times the calm one's, depending on how each branched).
  const plant::PlantModel calmBorn = growParticles(R"({"velocity": [0, 0, 0]})", steps, Json{{"secondary_growth", 0}})[0];
  const plant::PlantModel windyBorn = growParticles(R"({"velocity": [20, 0, 0]})", steps, Json{{"secondary_growth", 0}})[0];
  auto bornRatios = [](const plant::PlantModel& p) {
    std::vector<double> r;
    for (size_t i = 1; i < p.nodeCount(); ++i) {
      const int32_t q = p.parent[i];
      if (q <= 0 || (p.flags[i] & plant::kNodeBranchStart)) continue;  // successors of stems only
      if (p.radius[i] <= 0.0008f * 1.001f) continue;                    // not held at min_radius
      r.push_back(double(p.radius[i]) / double(p.radius[size_t(q)]));
    }
    return r;
  };
  const std::vector<double> calmRatios = bornRatios(calmBorn), windyRatios = bornRatios(windyBorn);
  ASSERT_GT(calmRatios.size(), 50u);
  ASSERT_GT(windyRatios.size(), 50u);
  for (double r : calmRatios) EXPECT_NEAR(r, 0.97, 1e-5) << "a successor's radius in still air";
  for (double r : windyRatios) EXPECT_NEAR(r, 0.97 * 1.015 / 1.01, 1e-5) << "a successor's radius in wind";

  // Eq. 9: from the 10th generation on, internodes point closer to the wind (+X).
  auto meanDirection = [](const plant::PlantModel& p, const std::vector<int>& g) {
    Vec3d d = Vec3d::Zero();
    for (size_t i = 1; i < p.nodeCount(); ++i)
      if (g[i] >= 10) d += p.direction(i).cast<double>();
    return d.normalized();
  };
  const double calmAngle = std::acos(meanDirection(calm, gc).x()), windAngle = std::acos(meanDirection(windy, gw).x());
  EXPECT_LT(windAngle, calmAngle - 0.2) << "angle to the wind: " << windAngle << " rad in wind, " << calmAngle
                                         << " rad in still air";
}

// Growth-Flow's unit of growth time is one internode, in the particle model one particle: the
// wind shortens what grows in a unit (eq. 8), not the unit. A particle shortened by the wind
// therefore takes as long to grow as a still-air one, and a plant in wind grows about as many
// particles in the same time, each shorter. (When short particles grew at the still-air speed,
// they came faster, each with its chance to branch: these four plants at 20 m/s reached the
// 50,000 particles below within the 400 steps, against 673-1,215 internodes in still air.)
TEST(GrowthFlowParticles, WindShortensTheParticlesNotTheTimeEachTakesToGrow) {
  const int steps = 400;
  auto grow = [&](const std::string& wind, int seed) {
    Json doc = particleIvySceneJson(wind);
    doc["steps"] = steps;
    doc["plants"][0]["seed"] = seed;
    doc["plants"][0]["species"]["max_particles"] = 50000;  // never reached: the time decides
    session::Session session(scene::parseScene(doc, "test scene", test::sourceDir()));
    session.run(uint32_t(steps));
    const plant::PlantModel p = session.plants().at(0);
    double length = 0;
    for (size_t i = 0; i < p.nodeCount(); ++i) length += p.length[i];
    return std::pair<size_t, double>{p.nodeCount(), length};
  };
  size_t calmNodes = 0, windyNodes = 0;
  double calmLength = 0, windyLength = 0;
  for (int seed = 1; seed <= 4; ++seed) {
    const auto [cn, cl] = grow(R"({"velocity": [0, 0, 0]})", seed);
    const auto [wn, wl] = grow(R"({"velocity": [20, 0, 0]})", seed);
    std::printf("seed %d, %d steps: still air %zu internodes, %.1f m of stem; 20 m/s %zu internodes, %.1f m\n", seed,
                steps, cn, cl, wn, wl);
    calmNodes += cn, windyNodes += wn, calmLength += cl, windyLength += wl;
  }
  ASSERT_GT(calmNodes, 400u);
  // Four seeds' plants branch differently (the growth is chaotic), so the sums are compared.
  EXPECT_GT(double(windyNodes), 0.7 * double(calmNodes)) << "not starved";
  EXPECT_LT(double(windyNodes), 1.4 * double(calmNodes)) << "not sped up";
  EXPECT_LT(windyLength, calmLength) << "shorter";
}

// A live species edit (the studio's sliders, `set_species`) that sets a key to the value it has
// changes nothing, in still air and in a wind that shortens the internodes and shrinks the leaves:
// growing particles keep the target lengths their growth gave them (a leaf particle its blade's),
// and only a changed particle_length or leaf size rescales them.
TEST(GrowthFlowParticles, ALiveSpeciesEditThatChangesNothingChangesNothing) {
  for (const char* wind : {R"({"velocity": [0, 0, 0]})", R"({"velocity": [20, 0, 0]})"}) {
    SCOPED_TRACE(wind);
    auto open = [&] {  // with the scene's JSON, which a species edit rewrites
      const Json doc = particleIvySceneJson(wind);
      return std::make_unique<session::Session>(scene::parseScene(doc, "test scene", test::sourceDir()), doc,
                                                test::sourceDir());
    };
    auto edited = open(), plain = open();
    session::Editor editor(*edited);
    editor.step(300);
    const float phototropism = test::particleWorld(*edited)->species(0).phototropism;
    editor.apply(session::SetSpecies{.plant = 0, .keys = Json{{"phototropism", phototropism}}});
    editor.step(300);
    plain->run(600);
    const std::vector<plant::PlantModel> a = edited->plants(), b = plain->plants();
    ASSERT_GT(b[0].nodeCount(), 300u);
    EXPECT_EQ(plant::contentHash(a), plant::contentHash(b))
        << a[0].nodeCount() << " nodes after the edit, " << b[0].nodeCount() << " without it";
  }
}

TEST(GrowthFlowParticles, WindBelowMinChangesNothing) {
  const int steps = 400;
  uint64_t calm = plant::contentHash(growParticles(R"({"velocity": [0, 0, 0]})", steps));
  uint64_t light = plant::contentHash(growParticles(R"({"velocity": [3.5, 0, 1]})", steps));  // 3.6 m/s < w_min = 4
  EXPECT_EQ(light, calm);
  uint64_t strong = plant::contentHash(growParticles(R"({"velocity": [8, 0, 0]})", steps));
  EXPECT_NE(strong, calm);
}


plant::PlantModel growLSystem(const std::string& wind, const std::string& growthFlow = "", int steps = 30) {
  // ABOP's Lychnis coronaria: internodes and leaves that, once made, stay in the string.
  std::string json = std::string(R"({"tendril": 1, "seed": 4, "steps": )") + std::to_string(steps) + R"(,
    "environment": {"obstacles": [{"name": "ground", "type": "plane", "size": [4, 4]}], "wind": )" + wind +
                     R"(},
    "plants": [{"name": "lychnis", "model": "lsystem", "grammar": "examples/grammars/abop-ch3-lychnis.ls",
                "position": [0, 0, 0])" + growthFlow + R"(}]})";
  scene::Scene s = scene::parseScene(parseJson(json, "test scene"), "test scene", test::sourceDir());
  session::Session session(std::move(s));
  session.run(uint32_t(steps));
  return session.plants()[0];
}

TEST(GrowthFlowLSystem, OrgansCarryTheFactorsOfTheWindTheyGrewIn) {
  const plant::PlantModel calm = growLSystem(R"({"velocity": [0, 0, 0]})");
  const plant::PlantModel windy = growLSystem(R"({"velocity": [20, 0, 0]})");  // f(w) = 1
  // The wind changes no production of this grammar: the same nodes and leaves, in order.
  ASSERT_EQ(windy.nodeCount(), calm.nodeCount());
  ASSERT_EQ(windy.leafCount(), calm.leafCount());
  ASSERT_GT(calm.nodeCount(), 100u);
  ASSERT_GT(calm.leafCount(), 10u);
  // An organ born at step b grew in the wind of the growth_units (10) steps before it: eq. 8,
  // 7, 17, 16 over u = min(b − 1, 10) units (the wind blows from the first step on). The
  // derivation stops at the grammar's length D; the oldest organs were born in its first step
  // (b = 1, age D − 1), so b − 1 = oldest age − age.
  const double oldest = *std::max_element(calm.age.begin(), calm.age.end());
  auto units = [oldest](double age) { return std::clamp(oldest - age, 0.0, 10.0); };
  size_t aged = 0;
  for (size_t i = 0; i < calm.nodeCount(); ++i) {
    const double u = units(calm.age[i]);
    ASSERT_EQ(windy.age[i], calm.age[i]);
    EXPECT_NEAR(windy.length[i] / calm.length[i], std::pow(0.97, u), 1e-5) << "node " << i << ", age " << calm.age[i];
    EXPECT_NEAR(windy.radius[i] / calm.radius[i], std::pow(1.015 / 1.01, u), 1e-5) << "node " << i;
    aged += u >= 10;
  }
  EXPECT_GT(aged, 20u);
  // A leaf's age is not its segment's (internodes elongate below it), so read its units u from
  // eq. 16 and check that it is a whole number of steps and that eq. 17 gives the same u.
  size_t agedLeaves = 0;
  for (size_t j = 0; j < calm.leafCount(); ++j) {
    const double thicker = double(windy.leafThickness[j]) / double(calm.leafThickness[j]);
    const double u = std::log(thicker) / std::log(1.015 / 1.01);
    EXPECT_NEAR(u, std::round(u), 1e-2) << "leaf " << j;
    EXPECT_LE(std::round(u), 10.0) << "leaf " << j;
    EXPECT_NEAR(windy.leafSize[j] / calm.leafSize[j], std::pow(0.98, std::round(u)), 1e-5) << "leaf " << j;
    agedLeaves += std::round(u) >= 5;
  }
  EXPECT_GT(agedLeaves, 5u);
  // Eq. 9 and Algorithm 1: a segment is drawn turned toward the wind (+X) by the angle its
  // growth reached, α = 2° · 1.1^u, from its still-air heading (which the turtle keeps).
  size_t turned = 0;
  for (size_t i = 0; i < calm.nodeCount(); ++i) {
    const double still = std::acos(std::clamp(double(calm.direction(i).x()), -1.0, 1.0));
    const double bent = std::acos(std::clamp(double(windy.direction(i).x()), -1.0, 1.0));
    const double u = units(calm.age[i]);
    const double alpha = u > 0.0 ? 2.0 * double(kPi) / 180.0 * std::pow(1.1, u) : 0.0;
    EXPECT_NEAR(bent, std::max(0.0, still - alpha), 2e-3) << "node " << i << ", age " << calm.age[i];
    turned += alpha > 5.0 * double(kPi) / 180.0 && still > alpha;
  }
  EXPECT_GT(turned, 10u);
}

TEST(GrowthFlowLSystem, MatureOrgansKeepWhatTheyGrewWhileTheWindGoesOn) {
  // Ten more steps in a storm: every segment and leaf of the plant at step 16 is still there
  // at the end of the derivation (step D, its oldest organs D − 1 steps old) with the length,
  // radius and leaf size it had (a model that applied the wind over an organ's whole life would
  // shrink them by another 0.97^(D − 16)).
  const char* storm = R"({"velocity": [20, 0, 0]})";
  const plant::PlantModel before = growLSystem(storm, "", 16), after = growLSystem(storm, "", 30);
  const float oldest = *std::max_element(after.age.begin(), after.age.end());
  ASSERT_GE(oldest, 20.0f);
  const float bornBy16 = oldest + 1.0f - 16.0f;  // the age at step D of an organ born at step 16
  std::vector<std::pair<float, float>> then, now;
  for (size_t i = 0; i < before.nodeCount(); ++i) then.emplace_back(before.length[i], before.radius[i]);
  for (size_t i = 0; i < after.nodeCount(); ++i)
    if (after.age[i] >= bornBy16) now.emplace_back(after.length[i], after.radius[i]);
  std::sort(then.begin(), then.end());
  std::sort(now.begin(), now.end());
  ASSERT_GT(then.size(), 50u);
  EXPECT_EQ(now, then);
  // Leaves (their node is not their age): every leaf size of step 16 is among those at step D.
  std::vector<float> leavesThen(before.leafSize.begin(), before.leafSize.end());
  std::vector<float> leavesNow(after.leafSize.begin(), after.leafSize.end());
  std::sort(leavesThen.begin(), leavesThen.end());
  std::sort(leavesNow.begin(), leavesNow.end());
  ASSERT_GT(leavesThen.size(), 5u);
  EXPECT_TRUE(std::includes(leavesNow.begin(), leavesNow.end(), leavesThen.begin(), leavesThen.end()));
}

TEST(GrowthFlowLSystem, WindBelowMinChangesNothingAndStrongWindTearsLeavesOff) {
  const uint64_t calm = plant::contentHash(growLSystem(R"({"velocity": [0, 0, 0]})"));
  EXPECT_EQ(plant::contentHash(growLSystem(R"({"velocity": [3.5, 0, 1]})")), calm);  // 3.6 m/s < w_min
  EXPECT_NE(plant::contentHash(growLSystem(R"({"velocity": [8, 0, 0]})")), calm);
  // Leaves whose life saw a wind above c_p t_p = 20 m/s are gone (Algorithm 2); the species'
  // strengths are plant keys.
  EXPECT_GT(growLSystem(R"({"velocity": [19, 0, 0]})").leafCount(), 10u);
  EXPECT_EQ(growLSystem(R"({"velocity": [25, 0, 0]})").leafCount(), 0u);
  EXPECT_GT(growLSystem(R"({"velocity": [25, 0, 0]})", R"(, "growth_flow": {"petiole_strength": 2, "blade_strength": 2})")
                .leafCount(),
            10u);
}

}  // namespace
}  // namespace tendril
