// Climbers on swaying hosts in the looping wind clip (plants as supports): a climber node that
// clings to a host node is skinned to the host's joint for it, so it keeps its rest offset from
// that node while the host sways; without that the climber stays put and the host moves off it.
#include "tendril/core/error.h"
#include "tendril/io/export_model.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/plant_sway.h"
#include "tendril/wind/gltf_animation.h"
#include "tendril/wind/motion.h"

#include "session/session_test_util.h"
#include "support/determinism.h"
#include "support/gltf_read.h"
#include "support/gltf_validator.h"
#include "support/synthetic_plants.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>

namespace tendril::wind {
namespace {

// Reads `count` × `width` floats (or, for the joints, unsigned shorts) an accessor holds.
template <class T>
std::vector<T> readAccessor(const tinygltf::Model& m, int accessor, int width) {
  const tinygltf::Accessor& a = m.accessors[size_t(accessor)];
  const tinygltf::BufferView& v = m.bufferViews[size_t(a.bufferView)];
  std::vector<T> out(a.count * size_t(width));
  std::memcpy(out.data(), m.buffers[size_t(v.buffer)].data.data() + v.byteOffset + a.byteOffset, out.size() * sizeof(T));
  return out;
}

// The clip's nodes posed at keyframe k: each node's world matrix (the channels' keyframe k
// values, else the node's own translation, rotation and scale), composed from the scene's roots.
std::vector<Mat4> poseAt(const tinygltf::Model& m, int k) {
  std::vector<Vec3> t(m.nodes.size(), Vec3::Zero()), sc(m.nodes.size(), Vec3::Ones());
  std::vector<Quat> r(m.nodes.size(), Quat::Identity());
  for (size_t i = 0; i < m.nodes.size(); ++i) {
    const auto& n = m.nodes[i];
    if (n.translation.size() == 3) t[i] = Vec3(float(n.translation[0]), float(n.translation[1]), float(n.translation[2]));
    if (n.rotation.size() == 4)
      r[i] = Quat(float(n.rotation[3]), float(n.rotation[0]), float(n.rotation[1]), float(n.rotation[2]));
    if (n.scale.size() == 3) sc[i] = Vec3(float(n.scale[0]), float(n.scale[1]), float(n.scale[2]));
  }
  for (const tinygltf::Animation& a : m.animations)
    for (const tinygltf::AnimationChannel& c : a.channels) {
      const int out = a.samplers[size_t(c.sampler)].output;
      if (c.target_path == "translation") {
        const std::vector<float> v = readAccessor<float>(m, out, 3);
        t[size_t(c.target_node)] = Vec3(v[size_t(3 * k)], v[size_t(3 * k + 1)], v[size_t(3 * k + 2)]);
      } else if (c.target_path == "rotation") {
        const std::vector<float> v = readAccessor<float>(m, out, 4);
        r[size_t(c.target_node)] = Quat(v[size_t(4 * k + 3)], v[size_t(4 * k)], v[size_t(4 * k + 1)], v[size_t(4 * k + 2)]);
      } else if (c.target_path == "scale") {
        const std::vector<float> v = readAccessor<float>(m, out, 3);
        sc[size_t(c.target_node)] = Vec3(v[size_t(3 * k)], v[size_t(3 * k + 1)], v[size_t(3 * k + 2)]);
      }
    }
  std::vector<Mat4> world(m.nodes.size(), Mat4::Identity());
  std::function<void(int, const Mat4&)> visit = [&](int node, const Mat4& parent) {
    Mat4 local = Mat4::Identity();
    local.block<3, 3>(0, 0) = r[size_t(node)].normalized().toRotationMatrix() * sc[size_t(node)].asDiagonal();
    local.block<3, 1>(0, 3) = t[size_t(node)];
    world[size_t(node)] = parent * local;
    for (int child : m.nodes[size_t(node)].children) visit(child, world[size_t(node)]);
  };
  for (int root : m.scenes[0].nodes) visit(root, Mat4::Identity());
  return world;
}

// The glTF node index of the mesh node named `name`.
int meshNode(const tinygltf::Model& m, const std::string& name) {
  for (size_t i = 0; i < m.nodes.size(); ++i)
    if (m.nodes[i].mesh >= 0 && m.nodes[i].name == name) return int(i);
  return -1;
}

// Per node of `plant` (meshed as the clip meshes it, its bark the mesh's first primitive): the
// glTF node of the joint its bark vertices follow in the clip, -1 for a node without bark.
// Every vertex of a node follows one joint (checked).
std::vector<int> jointNodeOfNodes(const tinygltf::Model& m, const std::string& name, const plant::PlantModel& plant,
                                  const WindAnimationOptions& o) {
  io::ExportScene scene;
  scene.plants = {plant};
  scene.plants[0].keepLeaves({});
  io::ExportOptions eo;
  eo.mesh = o.mesh;
  const io::ExportModel model = io::buildExportModel(scene, eo);
  const TriangleMesh& bark = *model.objects.at(0).parts.at(0).mesh;
  const int node = meshNode(m, name);
  EXPECT_GE(node, 0);
  if (node < 0) return {};
  const tinygltf::Node& n = m.nodes[size_t(node)];
  const tinygltf::Primitive& prim = m.meshes[size_t(n.mesh)].primitives.at(0);
  const std::vector<uint16_t> joints = readAccessor<uint16_t>(m, prim.attributes.at("JOINTS_0"), 4);
  EXPECT_EQ(joints.size(), bark.positions.size() * 4) << "the clip's bark is the bark meshed here";
  std::vector<int> out(plant.nodeCount(), -1);
  for (size_t v = 0; v < bark.positions.size() && 4 * v < joints.size(); ++v) {
    const int j = m.skins[size_t(n.skin)].joints.at(joints[4 * v]);
    int& o = out[bark.nodeIds[v]];
    EXPECT_TRUE(o < 0 || o == j) << "node " << bark.nodeIds[v] << " has vertices on two joints";
    o = j;
  }
  return out;
}

// The inverse bind matrix the skin of mesh node `name` gives glTF node `joint`.
Mat4 inverseBind(const tinygltf::Model& m, const std::string& name, int joint) {
  const tinygltf::Skin& skin = m.skins[size_t(m.nodes[size_t(meshNode(m, name))].skin)];
  const std::vector<float> all = readAccessor<float>(m, skin.inverseBindMatrices, 16);
  const size_t at = size_t(std::find(skin.joints.begin(), skin.joints.end(), joint) - skin.joints.begin());
  return Eigen::Map<const Mat4>(all.data() + 16 * at);
}

Vec3 apply(const Mat4& m, const Vec3& p) { return (m * p.homogeneous()).head<3>(); }

// How far the clinging nodes' distance to their host nodes strays from its rest value over
// the clip, and how far the host nodes themselves move (the worst over nodes and keyframes).
// The host nodes are posed by the host's Growth-Flow motion, or with `hostName` as the clip
// draws them (a node's rest position carried by the joint its bark follows: with fewer joints
// than nodes, a joint carries the nodes below it rigidly).
struct Follow {
  double stray = 0.0;
  double hostMoves = 0.0;
  size_t clinging = 0;
};

Follow followOf(const tinygltf::Model& m, const std::vector<AnimatedPlant>& plants, size_t climber,
                const std::string& climberName, const env::WindField& wind, const WindAnimationOptions& o,
                int frames, const std::string& hostName = "") {
  const plant::PlantModel& c = *plants[climber].plant;
  const std::vector<int> jointOf = jointNodeOfNodes(m, climberName, c, o);
  const size_t host0 = size_t(plants[climber].hostPlant.empty() ? 0 : std::max(plants[climber].hostPlant[0], 0));
  const std::vector<int> hostJointOf =
      hostName.empty() ? std::vector<int>{} : jointNodeOfNodes(m, hostName, *plants[host0].plant, o);
  std::vector<std::unique_ptr<WindMotion>> motions(plants.size());
  std::vector<plant::PlantModel> posed(plants.size());
  for (size_t i = 0; i < plants.size(); ++i) {
    MotionSettings ms;
    ms.loopSeconds = o.seconds;
    ms.seed = o.seed + i;
    motions[i] = std::make_unique<WindMotion>(*plants[i].plant, plants[i].species, ms);
  }
  Follow f;
  const float dt = o.seconds / float(frames - 1);
  for (int k = 0; k < frames; ++k) {
    const std::vector<Mat4> world = poseAt(m, k);
    for (size_t i = 0; i < plants.size(); ++i) motions[i]->step(dt * float(k), dt, wind, posed[i]);
    for (size_t i = 0; i < c.nodeCount(); ++i) {
      if (plants[climber].hostPlant[i] < 0 || jointOf[i] < 0) continue;
      if (k == 0) ++f.clinging;
      const size_t hp = size_t(plants[climber].hostPlant[i]), hn = size_t(plants[climber].hostNode[i]);
      const Vec3 node = apply(world[size_t(jointOf[i])] * inverseBind(m, climberName, jointOf[i]), c.position[i]);
      Vec3 host = posed[hp].position[hn];
      if (!hostName.empty()) {
        EXPECT_EQ(hp, host0) << "one host";
        if (hostJointOf[hn] < 0) continue;
        host = apply(world[size_t(hostJointOf[hn])] * inverseBind(m, hostName, hostJointOf[hn]),
                     plants[hp].plant->position[hn]);
      }
      const Vec3 hostRest = plants[hp].plant->position[hn];
      f.stray = std::max(f.stray, std::abs(double((node - host).norm()) - double((c.position[i] - hostRest).norm())));
      f.hostMoves = std::max(f.hostMoves, double((host - hostRest).norm()));
    }
  }
  return f;
}

plant::GrowthFlowSpecies softSpecies() {
  plant::GrowthFlowSpecies soft;
  soft.youngModulus = 2e6f;
  return soft;
}

env::WindField gustyWind() {
  env::WindSettings g;
  g.mode = env::WindMode::Gusty;
  g.velocity = Vec3(8, 0, 0);
  return env::WindField(g);
}

// A 2 m pole (the host) and a climber beside it: its root on the ground, nodes 1-11 clinging
// up the pole (each to the pole node beside it), then a free shoot of two nodes out from it.
struct PoleAndClimber {
  plant::PlantModel pole = meshtest::straightChain(8, 0.25f, 0.06f, 0.02f);
  plant::PlantModel climber;
  std::vector<AnimatedPlant> plants;

  PoleAndClimber() {
    pole.name = "pole";
    climber.name = "climber";
    int32_t prev = -1;
    std::vector<int32_t> hostNode;
    for (int i = 0; i < 14; ++i) {
      plant::PlantModel::NodeDef d;
      const bool shoot = i >= 12;
      d.position = shoot ? Vec3(0.09f + 0.125f * float(i - 12), 1.5f, 0.0f) : Vec3(0.09f, 0.125f * float(i), 0.0f);
      d.orientation = frameFromYZ(shoot ? Vec3::UnitX() : Vec3::UnitY(), Vec3::UnitZ());
      d.length = 0.125f;
      d.radius = 0.008f;
      d.parent = prev;
      d.flags = i >= 1 && i <= 11 ? plant::kNodeClimbing : 0u;
      prev = climber.addNode(d);
      hostNode.push_back(i >= 1 && i <= 11 ? std::min(i / 2, 7) : -1);
    }
    plants.resize(2);
    plants[0].plant = &pole;
    plants[1].plant = &climber;
    plants[0].species = plants[1].species = softSpecies();
    plants[1].hostNode = hostNode;
    for (int32_t h : hostNode) plants[1].hostPlant.push_back(h >= 0 ? 0 : -1);
  }
};

WindAnimationOptions clipOptions() {
  WindAnimationOptions o;
  o.seconds = 10.0f;
  o.fps = 6;
  o.maxJoints = 128;
  return o;
}

TEST(ClimberOnHost, ClingingNodesKeepTheirOffsetFromTheSwayingHostOverATenSecondClip) {
  PoleAndClimber s;
  const WindAnimationOptions o = clipOptions();
  const std::filesystem::path file = meshtest::exportTestDir() / "pole.glb";
  const WindAnimationStats stats = writeWindAnimationGlb(s.plants, gustyWind(), o, file);
  const meshtest::GltfValidation v = meshtest::validateGltf(file);
  EXPECT_EQ(v.exitCode, 0) << v.output;
  EXPECT_EQ(v.errors, 0) << v.output;
  EXPECT_EQ(v.warnings, 0) << v.output;

  const tinygltf::Model m = test::loadGlb(file);
  const Follow f = followOf(m, s.plants, 1, "climber", gustyWind(), o, int(stats.keyframes));
  std::printf("climber on a pole, 10 s: %zu clinging nodes; their host nodes move up to %.3f m, the distance to them "
              "strays up to %.5f m from its rest value\n",
              f.clinging, f.hostMoves, f.stray);
  EXPECT_EQ(f.clinging, 11u);
  EXPECT_GT(f.hostMoves, 0.05) << "the host sways: a climber left in place would drift off it";
  // Every host node is a joint here (128 joints), so the offset is kept to float rounding.
  EXPECT_LT(f.stray, 0.002);

  // The climber's skin lists the pole's joints, which the clip moves.
  const tinygltf::Skin& skin = m.skins[size_t(m.nodes[size_t(meshNode(m, "climber"))].skin)];
  size_t moving = 0;
  for (int joint : skin.joints)
    if (m.nodes[size_t(joint)].name.rfind("pole-joint-", 0) == 0)
      for (const tinygltf::AnimationChannel& c : m.animations.at(0).channels)
        moving += c.target_node == joint && c.target_path == "rotation";
  EXPECT_GE(moving, 5u);

  // The free shoot (nodes 12, 13) hangs under the pole's joints: its joints' chain of parents
  // reaches a pole joint.
  std::vector<int> parent(m.nodes.size(), -1);
  for (size_t i = 0; i < m.nodes.size(); ++i)
    for (int c : m.nodes[i].children) parent[size_t(c)] = int(i);
  const std::vector<int> jointOf = jointNodeOfNodes(m, "climber", s.climber, o);
  for (size_t node : {size_t(12), size_t(13)}) {
    bool underPole = false;
    for (int at = jointOf[node]; at >= 0 && !underPole; at = parent[size_t(at)])
      underPole = m.nodes[size_t(at)].name.rfind("pole-joint-", 0) == 0;
    EXPECT_TRUE(underPole) << "climber node " << node;
  }
}

TEST(ClimberOnHost, WithoutHostsTheClimberStaysWhileTheHostSwaysAway) {
  // The mechanism removed: the same plants with no hosts given; the climber's clinging nodes are
  // held where they grew, so the pole moves off them.
  PoleAndClimber s;
  const std::vector<int32_t> hostPlant = s.plants[1].hostPlant, hostNode = s.plants[1].hostNode;
  s.plants[1].hostPlant.clear();
  s.plants[1].hostNode.clear();
  const WindAnimationOptions o = clipOptions();
  const std::filesystem::path file = meshtest::exportTestDir() / "pole.glb";
  const WindAnimationStats stats = writeWindAnimationGlb(s.plants, gustyWind(), o, file);
  const tinygltf::Model m = test::loadGlb(file);
  s.plants[1].hostPlant = hostPlant;  // measured against the same host nodes
  s.plants[1].hostNode = hostNode;
  const Follow f = followOf(m, s.plants, 1, "climber", gustyWind(), o, int(stats.keyframes));
  EXPECT_GT(f.stray, 0.02);
}

TEST(ClimberOnHost, TheClipIsTheSameAtEveryThreadCount) {
  PoleAndClimber s;
  WindAnimationOptions o = clipOptions();
  o.seconds = 2.0f;
  const std::filesystem::path file = meshtest::exportTestDir() / "pole.glb";
  test::sameAtEveryThreadCount([&] {
    writeWindAnimationGlb(s.plants, gustyWind(), o, file);
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  });
}

TEST(ClimberOnHost, TheFrameSequenceCarriesTheClimberWithItsHost) {
  PoleAndClimber s;
  WindAnimationOptions o = clipOptions();
  o.fps = 3;
  auto measure = [&](const std::vector<AnimatedPlant>& plants) {
    Follow f;
    forEachWindFrame(plants, gustyWind(), o, "frames", [&](int, const std::vector<plant::PlantModel>& posed) {
      for (size_t i = 0; i < s.climber.nodeCount(); ++i) {
        const int32_t hn = s.plants[1].hostNode[i];
        if (hn < 0) continue;
        const double rest = (s.climber.position[i] - s.pole.position[size_t(hn)]).norm();
        const double now = (posed[1].position[i] - posed[0].position[size_t(hn)]).norm();
        f.stray = std::max(f.stray, std::abs(now - rest));
        f.hostMoves = std::max(f.hostMoves, double((posed[0].position[size_t(hn)] - s.pole.position[size_t(hn)]).norm()));
      }
      // The free shoot stays by its clinging node 11 (its own sway, at most 25 cm long, aside).
      EXPECT_LT((posed[1].position[13] - posed[1].position[11]).norm(), 0.26f);
    });
    return f;
  };
  test::sameAtEveryThreadCount([&] {
    std::vector<float> xyz;  // the climber's posed nodes, frame after frame
    forEachWindFrame(s.plants, gustyWind(), o, "frames", [&](int, const std::vector<plant::PlantModel>& posed) {
      for (const Vec3& p : posed[1].position) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
    });
    return xyz;
  });
  const Follow f = measure(s.plants);
  EXPECT_GT(f.hostMoves, 0.05);
  EXPECT_LT(f.stray, 0.002);
  std::vector<AnimatedPlant> alone = s.plants;  // without the hosts, the pole moves off the climber
  alone[1].hostPlant.clear();
  alone[1].hostNode.clear();
  EXPECT_GT(measure(alone).stray, 0.02);
}

// The growth clip: the climber grows in (its joints scale in from 0 as its nodes are born, on
// the clock its host shares) while its clinging nodes follow the swaying host's joints, as in the
// loop. Without the hosts the climber sways on its own and the pole moves off it.
TEST(ClimberOnHost, InTheGrowthClipTheClimberGrowsInOnItsSwayingHost) {
  PoleAndClimber s;
  s.pole.age.assign(s.pole.nodeCount(), 20.0f);  // the pole was there first
  for (size_t i = 0; i < s.climber.nodeCount(); ++i) s.climber.age[i] = 10.0f - 0.5f * float(i);  // born at 10 … 16.5 s
  WindAnimationOptions o = clipOptions();
  o.growth = true;
  auto measure = [&](const std::vector<AnimatedPlant>& plants, bool check) {
    const std::filesystem::path file = meshtest::exportTestDir() / "pole-growth.glb";
    const WindAnimationStats stats = writeWindAnimationGlb(plants, gustyWind(), o, file);
    if (check) {
      const meshtest::GltfValidation v = meshtest::validateGltf(file);
      EXPECT_EQ(v.exitCode, 0) << v.output;
      EXPECT_EQ(v.errors, 0) << v.output;
      EXPECT_EQ(v.warnings, 0) << v.output;
    }
    const tinygltf::Model m = test::loadGlb(file);
    const std::vector<int> jointOf = jointNodeOfNodes(m, "climber", s.climber, o);
    const std::vector<int> poleJointOf = jointNodeOfNodes(m, "pole", s.pole, o);
    Follow f;
    size_t unborn = 0, growing = 0, grown = 0;
    const int frames = int(stats.keyframes);
    for (int k = 0; k < frames; ++k) {
      const float t = o.seconds * float(k) / float(frames - 1);
      const float clock = std::min(20.0f, t / (kGrowthShare * o.seconds) * 20.0f);  // the growth time shown
      const std::vector<Mat4> world = poseAt(m, k);
      for (size_t i = 1; i <= 11; ++i) {  // the clinging nodes
        const Mat4 skin = world[size_t(jointOf[i])] * inverseBind(m, "climber", jointOf[i]);
        const float scale = std::cbrt(skin.block<3, 3>(0, 0).determinant());
        const float born = 20.0f - s.climber.age[i];
        if (clock < 10.0f) {
          EXPECT_NEAR(scale, 0.0f, 1e-6f) << "node " << i << " at " << t << " s, before the climber was born";
          ++unborn;
        } else if (clock > born && clock < 16.5f && scale > 0.01f && scale < 0.99f) {
          ++growing;
        }
        if (t < kGrowthShare * o.seconds) continue;
        // Grown: the node at its rest offset from the host node it clings to, as the clip draws the host.
        EXPECT_NEAR(scale, 1.0f, 1e-4f) << "node " << i << " at " << t << " s";
        ++grown;
        const size_t hn = size_t(s.plants[1].hostNode[i]);
        const Vec3 node = apply(skin, s.climber.position[i]);
        const Vec3 host = apply(world[size_t(poleJointOf[hn])] * inverseBind(m, "pole", poleJointOf[hn]), s.pole.position[hn]);
        const double rest = (s.climber.position[i] - s.pole.position[hn]).norm();
        f.stray = std::max(f.stray, std::abs(double((node - host).norm()) - rest));
        f.hostMoves = std::max(f.hostMoves, double((host - s.pole.position[hn]).norm()));
      }
    }
    if (check) {
      std::printf("climber growing on a pole, %d keyframes: clinging nodes unborn %zu, growing %zu, grown %zu times; "
                  "grown, the host nodes move up to %.3f m and the distance to them strays up to %.5f m\n",
                  frames, unborn, growing, grown, f.hostMoves, f.stray);
      EXPECT_GT(unborn, 0u);
      EXPECT_GT(growing, 3u) << "the clinging nodes scale in";
      EXPECT_GT(grown, 0u);
    }
    return f;
  };
  const Follow f = measure(s.plants, true);
  EXPECT_GT(f.hostMoves, 0.05);
  EXPECT_LT(f.stray, 0.002);
  std::vector<AnimatedPlant> alone = s.plants;
  alone[1].hostPlant.clear();
  alone[1].hostNode.clear();
  EXPECT_GT(measure(alone, false).stray, 0.02);
}

TEST(ClimberOnHost, BadHostsAreAnError) {
  PoleAndClimber s;
  const WindAnimationOptions o = clipOptions();
  const std::filesystem::path file = meshtest::exportTestDir() / "bad.glb";
  auto fails = [&](std::vector<AnimatedPlant> plants, const std::string& words) {
    try {
      writeWindAnimationGlb(plants, gustyWind(), o, file);
      ADD_FAILURE() << "no error for " << words;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.glb"), std::string::npos) << e.what();
    }
  };
  std::vector<AnimatedPlant> p = s.plants;
  p[1].hostNode.pop_back();
  fails(p, "14 nodes but 14 host plants and 13 host nodes");
  p = s.plants;
  p[1].hostPlant[3] = 1;
  fails(p, "node 3: host plant 1 is not another plant");
  p = s.plants;
  p[1].hostNode[3] = 8;
  fails(p, "node 3: host plant 0 has no node 8");
  p = s.plants;
  p[0].hostPlant.assign(s.pole.nodeCount(), 1);
  p[0].hostNode.assign(s.pole.nodeCount(), 0);
  fails(p, "clings to a plant itself");
  EXPECT_FALSE(std::filesystem::exists(file));
}

// Through the session: ivy grown on a graph chestnut (a support plant) clings to it, and the
// scene's wind clip keeps the clinging ivy on the swaying tree.
TEST(ClimberOnHost, IvyGrownOnAChestnutMovesWithItInTheSessionsClip) {
  auto session = test::makeSession(R"({"tendril": 1, "seed": 3, "steps": 60,
    "environment": {"obstacles": [{"name": "ground", "type": "plane", "size": [14, 14]}],
                    "lights": [{"type": "directional", "direction": [-0.3, -1, -0.4]}],
                    "wind": {"mode": "gusty", "velocity": [12, 0, 0], "gust_strength": 0.4, "gust_period": 3, "seed": 5}},
    "plants": [{"name": "chestnut", "model": "graph", "graph": "examples/graphs/chestnut.json",
                "position": [0, 0, 0], "support": true},
               {"name": "ivy", "species": "japanese-ivy", "position": [0.38, 0, 0], "seed": 1}]})");
  session->run(60);
  const io::ExportScene exported = session::exportScene(*session, "scene");
  const auto start = std::chrono::steady_clock::now();
  const std::vector<AnimatedPlant> plants = session::animatedPlants(*session, exported);
  std::printf("the attachments of %zu nodes looked up in %.1f ms\n", exported.plants[1].nodeCount(),
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  ASSERT_EQ(plants.size(), 2u);
  EXPECT_TRUE(plants[0].hostPlant.empty()) << "a support clings to nothing";
  ASSERT_EQ(plants[1].hostPlant.size(), exported.plants[1].nodeCount());
  size_t clinging = 0;
  for (size_t i = 0; i < plants[1].hostPlant.size(); ++i)
    if (plants[1].hostPlant[i] >= 0) {
      EXPECT_EQ(plants[1].hostPlant[i], 0);
      ++clinging;
    }
  EXPECT_GT(clinging, 50u);
  test::sameAtEveryThreadCount([&] { return session::animatedPlants(*session, exported)[1].hostNode; });

  // With every chestnut node a joint, against the chestnut's motion; with 128 joints, against the
  // chestnut as the clip draws it.
  for (int joints : {int(exported.plants[0].nodeCount()), 128}) {
    WindAnimationOptions o = session::windClipOptions(*session, 10.0f);
    o.fps = 4;
    o.maxJoints = joints;
    const std::filesystem::path file = meshtest::exportTestDir() / "ivy-on-chestnut.glb";
    const WindAnimationStats stats = writeWindAnimationGlb(plants, session->environment().windField(), o, file);
    const meshtest::GltfValidation v = meshtest::validateGltf(file);
    EXPECT_EQ(v.exitCode, 0) << v.output;
    EXPECT_EQ(v.errors, 0) << v.output;
    const tinygltf::Model m = test::loadGlb(file);
    const Follow f = followOf(m, plants, 1, "ivy", session->environment().windField(), o, int(stats.keyframes),
                              joints == 128 ? "chestnut" : "");
    std::printf("ivy on a chestnut of %zu nodes, %d joints, 10 s: %zu clinging nodes; their host nodes move up to %.3f "
                "m, the distance to them strays up to %.5f m from its rest value\n",
                exported.plants[0].nodeCount(), joints, f.clinging, f.hostMoves, f.stray);
    EXPECT_GT(f.hostMoves, 0.02);
    EXPECT_LT(f.stray, 0.02);
  }

  // The studio's sway (PlantSway) carries the clinging ivy with the chestnut too, frame by frame.
  session::PlantSway sway;
  const std::vector<plant::PlantModel> rest = session->plants();
  double stray = 0.0, hostMoves = 0.0;
  for (int k = 0; k < 48; ++k) {
    std::vector<plant::PlantModel> posed = session->plants();
    sway.pose(*session, posed, float(k) / 24.0f, 1.0f / 24.0f);
    for (size_t i = 0; i < rest[1].nodeCount(); ++i) {
      if (plants[1].hostPlant[i] < 0) continue;
      const size_t hn = size_t(plants[1].hostNode[i]);
      const double d0 = (rest[1].position[i] - rest[0].position[hn]).norm();
      stray = std::max(stray, std::abs(double((posed[1].position[i] - posed[0].position[hn]).norm()) - d0));
      hostMoves = std::max(hostMoves, double((posed[0].position[hn] - rest[0].position[hn]).norm()));
    }
  }
  std::printf("ivy on a chestnut in the studio's sway, 2 s: host nodes move up to %.3f m, the distance to them strays "
              "up to %.5f m\n", hostMoves, stray);
  EXPECT_GT(hostMoves, 0.02);
  EXPECT_LT(stray, 0.002);
}

}  // namespace
}  // namespace tendril::wind
