// Growth-Flow growth in the growth models: a plant grown in a wind above w_max against the same
// seed in still air (seed 001 §3.1.2, §3.2.2), and a wind below w_min changing nothing.
#include "support/test_paths.h"
#include "tendril/scene/scene.h"
#include "tendril/session/session.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

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

}  // namespace
}  // namespace tendril
