#include "tendril/wind/gltf_animation.h"

#include "tendril/core/error.h"
#include "tendril/core/parallel.h"
#include "tendril/io/atomic_file.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/mesh/leaf_mesh.h"
#include "tendril/wind/motion.h"

#include <fmt/format.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <array>
#include <map>
#include <memory>
#include <unordered_map>

namespace tendril::wind {

// The clip is written with the export module's meshes, materials and atomic files.
using namespace io;

std::vector<int32_t> chooseJoints(const plant::PlantModel& plant, int maxJoints) {
  const size_t n = plant.nodeCount();
  std::vector<uint32_t> subtree(n, 1);
  for (size_t i = n; i-- > 0;)
    if (plant.parent[i] >= 0) subtree[size_t(plant.parent[i])] += subtree[i];
  std::vector<uint32_t> depth(n, 0);  // nodes since the last branch start
  for (size_t i = 0; i < n; ++i) {
    int32_t p = plant.parent[i];
    bool start = p < 0 || (plant.flags[i] & plant::kNodeBranchStart);
    depth[i] = start ? 0 : depth[size_t(p)] + 1;
  }
  std::vector<int32_t> joints;
  for (uint32_t k = 1;; k *= 2) {
    joints.clear();
    for (size_t i = 0; i < n; ++i) {
      bool root = plant.parent[i] < 0;
      if (root || (subtree[i] >= k && depth[i] % k == 0)) joints.push_back(int32_t(i));
    }
    size_t roots = size_t(std::count(plant.parent.begin(), plant.parent.end(), -1));
    if (joints.size() <= size_t(std::max(maxJoints, 1)) || joints.size() == roots || k > n) break;
  }
  return joints;
}

namespace {

size_t align4(size_t n) { return (n + 3) & ~size_t(3); }

// The binary buffer and its views.
struct Bin {
  tinygltf::Model& gltf;
  std::vector<uint8_t>& data;

  int view(const void* bytes, size_t size, int target) {
    size_t at = data.size();
    data.resize(align4(at + size));
    if (size) std::memcpy(data.data() + at, bytes, size);
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = at;
    v.byteLength = size;
    v.target = target;
    gltf.bufferViews.push_back(v);
    return int(gltf.bufferViews.size() - 1);
  }
  int accessor(int view, int component, int type, size_t count) {
    tinygltf::Accessor a;
    a.bufferView = view;
    a.componentType = component;
    a.type = type;
    a.count = count;
    gltf.accessors.push_back(a);
    return int(gltf.accessors.size() - 1);
  }
};

// A linearly interpolated channel of glTF node `node`'s `path` over the clip's keyframes, its
// values in `output`.
void addChannel(tinygltf::Animation& animation, int timeAccessor, int output, int node, const char* path) {
  tinygltf::AnimationSampler sampler;
  sampler.input = timeAccessor;
  sampler.output = output;
  sampler.interpolation = "LINEAR";
  animation.samplers.push_back(sampler);
  tinygltf::AnimationChannel channel;
  channel.sampler = int(animation.samplers.size() - 1);
  channel.target_node = node;
  channel.target_path = path;
  animation.channels.push_back(channel);
}

// A uniform scale channel for glTF node `node` from one scale per keyframe; none (false) when
// every scale is 1.
bool addScaleChannel(Bin& bin, tinygltf::Animation& animation, int timeAccessor, int node,
                     const std::vector<float>& scale) {
  if (std::all_of(scale.begin(), scale.end(), [](float s) { return s == 1.0f; })) return false;
  std::vector<float> xyz(3 * scale.size());
  for (size_t k = 0; k < scale.size(); ++k) std::fill_n(&xyz[3 * k], 3, scale[k]);
  addChannel(animation, timeAccessor,
             bin.accessor(bin.view(xyz.data(), xyz.size() * sizeof(float), 0), TINYGLTF_COMPONENT_TYPE_FLOAT,
                          TINYGLTF_TYPE_VEC3, scale.size()),
             node, "scale");
  return true;
}

// The plant the clip is meshed from: the rest plant without the leaves the loop tears off.
// `kept` gets the rest plant's index of each leaf left.
plant::PlantModel withoutTornLeaves(const plant::PlantModel& rest, const LeafLoop& loop, std::vector<uint32_t>& kept) {
  plant::PlantModel out = rest;
  kept.clear();
  for (size_t j = 0; j < rest.leafCount(); ++j)
    if (!loop.leaves[j].torn) kept.push_back(uint32_t(j));
  out.keepLeaves(kept);
  return out;
}

// The leaves' loop as morph targets. Per leaf shape (the leaf mesh of that shape, its leaves in
// index order) and motion k: each vertex's displacement when its leaf makes motion k at its full
// amplitude, taken as half the difference between the leaf posed at +amplitude and at
// −amplitude (the tangent of the motion, with the error of the small angles only).
std::vector<std::array<std::vector<Vec3>, 3>> leafDisplacements(const plant::PlantModel& clipRest,
                                                                const std::vector<uint32_t>& kept,
                                                                const LeafLoop& loop, const mesh::MeshOptions& options) {
  std::vector<std::array<std::vector<Vec3>, 3>> out(mesh::leafShapeCount(clipRest));
  for (int k = 0; k < 3; ++k) {
    std::vector<TriangleMesh> side[2];
    for (int sign = 0; sign < 2; ++sign) {
      plant::PlantModel posed = clipRest;
      posed.leafMotion.assign(posed.leafCount(), Vec3::Zero());
      for (size_t o = 0; o < kept.size(); ++o) {
        const LeafLoop::Leaf& f = loop.leaves[kept[o]];
        plant::LeafMotionState L;
        const float a = sign == 0 ? f.amplitude[k] : -f.amplitude[k];
        if (k == 0) (loop.bendsBlade ? L.bladeBend : L.petioleBend) = a;
        else if (k == 1) L.twist = a;
        else L.vibrate = a;
        poseLeaf(clipRest.leafRotation[o].normalized(), L, posed.leafRotation[o], posed.leafMotion[o]);
      }
      side[sign] = mesh::buildLeafQuads(posed, options);
    }
    for (size_t s = 0; s < out.size() && s < side[0].size(); ++s) {
      const std::vector<Vec3>& plus = side[0][s].positions;
      const std::vector<Vec3>& minus = side[1][s].positions;
      std::vector<Vec3>& d = out[s][size_t(k)];
      d.resize(plus.size());
      for (size_t v = 0; v < plus.size(); ++v) d[v] = 0.5f * (plus[v] - minus[v]);
    }
  }
  return out;
}

// Checks the plants' hosts (AnimatedPlant::hostPlant / hostNode) and says whether any node clings.
bool checkHosts(const std::vector<AnimatedPlant>& plants, const std::filesystem::path& source) {
  const std::string path = source.string();
  bool any = false;
  for (size_t pi = 0; pi < plants.size(); ++pi) {
    const AnimatedPlant& a = plants[pi];
    if (a.hostPlant.empty() && a.hostNode.empty()) continue;
    const size_t n = a.plant->nodeCount();
    if (a.hostPlant.size() != n || a.hostNode.size() != n)
      throw Error(path, "", fmt::format("plant {} has {} nodes but {} host plants and {} host nodes", pi, n,
                                        a.hostPlant.size(), a.hostNode.size()));
    for (size_t i = 0; i < n; ++i) {
      const int32_t h = a.hostPlant[i];
      if (h < 0) continue;
      if (size_t(h) >= plants.size() || size_t(h) == pi)
        throw Error(path, "", fmt::format("plant {} node {}: host plant {} is not another plant of the clip", pi, i, h));
      const AnimatedPlant& host = plants[size_t(h)];
      if (a.hostNode[i] < 0 || size_t(a.hostNode[i]) >= host.plant->nodeCount())
        throw Error(path, "", fmt::format("plant {} node {}: host plant {} has no node {}", pi, i, h, a.hostNode[i]));
      if (std::any_of(host.hostPlant.begin(), host.hostPlant.end(), [](int32_t x) { return x >= 0; }))
        throw Error(path, "", fmt::format("plant {} node {}: host plant {} clings to a plant itself", pi, i, h));
      any = true;
    }
  }
  return any;
}

// A plant's reduced hierarchy in the clip.
struct Skeleton {
  std::vector<int32_t> joints;       // the node of each joint, parents first
  std::vector<int32_t> jointOf;      // per node: the nearest joint at or above it
  std::vector<int32_t> parentJoint;  // per joint; -1 for a root
  int firstNode = 0;                 // the glTF node of joint 0
};

Skeleton skeletonOf(const plant::PlantModel& rest, int maxJoints) {
  Skeleton s;
  const size_t n = rest.nodeCount();
  s.joints = chooseJoints(rest, maxJoints);
  std::vector<int32_t> jointOfJointNode(n, -1);
  for (size_t j = 0; j < s.joints.size(); ++j) jointOfJointNode[size_t(s.joints[j])] = int32_t(j);
  s.jointOf.assign(n, -1);
  for (size_t i = 0; i < n; ++i)
    s.jointOf[i] = jointOfJointNode[i] >= 0 ? jointOfJointNode[i] : s.jointOf[size_t(rest.parent[i])];
  s.parentJoint.assign(s.joints.size(), -1);
  for (size_t j = 0; j < s.joints.size(); ++j) {
    int32_t p = rest.parent[size_t(s.joints[j])];
    s.parentJoint[j] = p < 0 ? -1 : s.jointOf[size_t(p)];
  }
  return s;
}

// Growth clips: every joint's scale at every keyframe. All plants share one clock (a node's
// age is the time since it was born, counted back from the same present): the growth time
// runs from the oldest node's birth to the present over the first kGrowthShare of the clip. A
// joint scales in from 0 when its node is born to 1 once the last node it carries is; a plant
// whose nodes are all of age 0 (a component graph) is whole from the start. No joint is larger
// than the joint it hangs from: its parent, or for a climber's joint on a clinging node, its
// host's joint.
struct GrowthScales {
  // Per plant, per joint, per keyframe: the scale in the scene and relative to the glTF parent.
  std::vector<std::vector<std::vector<float>>> global, local;

  float hostScale(size_t plant, int32_t joint, size_t k) const { return global[plant][size_t(joint)][k]; }
};

GrowthScales growthScales(const std::vector<plant::PlantModel>& rest, const std::vector<AnimatedPlant>& plants,
                          const std::vector<Skeleton>& skeletons, bool attached, const std::vector<float>& times,
                          float seconds) {
  GrowthScales out;
  out.global.resize(rest.size());
  out.local.resize(rest.size());
  float clock = 0.0f;
  for (const plant::PlantModel& p : rest)
    for (float a : p.age) clock = std::max(clock, a);
  auto clings = [&](size_t pi, size_t node) {
    return attached && !plants[pi].hostPlant.empty() && plants[pi].hostPlant[node] >= 0;
  };
  // Hosts before their climbers (a host clings to nothing).
  for (int pass = 0; pass < 2; ++pass)
    for (size_t pi = 0; pi < rest.size(); ++pi) {
      const bool climber = attached && std::any_of(plants[pi].hostPlant.begin(), plants[pi].hostPlant.end(),
                                                   [](int32_t h) { return h >= 0; });
      if (climber != (pass == 1)) continue;
      const plant::PlantModel& p = rest[pi];
      const Skeleton& sk = skeletons[pi];
      const size_t joints = sk.joints.size(), frames = times.size();
      float own = 0.0f;
      for (float a : p.age) own = std::max(own, a);
      std::vector<float> start(joints), end(joints);
      for (size_t j = 0; j < joints; ++j) start[j] = end[j] = clock - p.age[size_t(sk.joints[j])];
      for (size_t i = 0; i < p.nodeCount(); ++i) {
        const size_t j = size_t(sk.jointOf[i]);
        end[j] = std::max(end[j], clock - p.age[i]);
      }
      const float shortest = clock / 64.0f;  // a joint whose nodes were born at once still grows in visibly
      auto& global = out.global[pi];
      auto& local = out.local[pi];
      global.assign(joints, std::vector<float>(frames, 1.0f));
      local.assign(joints, std::vector<float>(frames, 1.0f));
      for (size_t k = 0; k < frames; ++k) {
        const float g = std::min(clock, times[k] / (kGrowthShare * seconds) * clock);
        for (size_t j = 0; j < joints; ++j) {  // parents first
          const size_t node = size_t(sk.joints[j]);
          float scale = own > 0.0f ? std::clamp((g - start[j]) / std::max(end[j] - start[j], shortest), 0.0f, 1.0f) : 1.0f;
          float parent = 1.0f;
          if (clings(pi, node)) {
            const size_t h = size_t(plants[pi].hostPlant[node]);
            parent = out.hostScale(h, skeletons[h].jointOf[size_t(plants[pi].hostNode[node])], k);
          } else if (sk.parentJoint[j] >= 0) {
            parent = global[size_t(sk.parentJoint[j])][k];
          }
          scale = std::min(scale, parent);
          global[j][k] = scale;
          local[j][k] = parent > 0.0f ? scale / parent : 0.0f;
        }
      }
    }
  return out;
}

// In a growth clip a climber's clinging nodes follow their host's joint, as in the loop, and
// scale in with the climber's own joint: for each pair of host joint and climber joint, a joint
// hanging from the host's joint at the climber joint's rest position, scaled as the climber
// joint is (relative to the host's joint).
struct ClingJoint {
  int hostNode = -1;                         // the host joint's glTF node
  size_t plant = 0, hostPlant = 0;
  int32_t joint = -1, hostJoint = -1;        // the climber's and the host's joint
  Vec3 offset = Vec3::Zero();                // from the host joint's rest position
};

}  // namespace

WindAnimationStats writeWindAnimationGlb(const std::vector<AnimatedPlant>& plants, const env::WindField& wind,
                                         const WindAnimationOptions& options, const std::filesystem::path& path) {
  if (!(options.seconds > 0.0f) || options.fps < 1 || options.maxJoints < 1)
    throw Error(path.string(), "", "wind animation needs seconds > 0, fps >= 1 and joints >= 1");
  checkOutputPath(path);
  // Growth-Flow motion of each plant, sway periods and leaf waves dividing the clip. The clip is
  // meshed without the leaves the wind tears off.
  std::vector<std::unique_ptr<wind::WindMotion>> motions;
  std::vector<std::vector<uint32_t>> keptLeaves(plants.size());
  ExportScene scene;
  for (size_t pi = 0; pi < plants.size(); ++pi) {
    if (!plants[pi].plant) throw Error(path.string(), "", fmt::format("plant {} is missing", pi));
  }
  // Climbers follow their hosts' joints.
  const bool attached = checkHosts(plants, path);
  for (size_t pi = 0; pi < plants.size(); ++pi) {
    wind::MotionSettings ms;
    ms.loopSeconds = options.seconds;
    ms.seed = options.seed + pi;
    motions.push_back(std::make_unique<wind::WindMotion>(*plants[pi].plant, plants[pi].species, ms));
    scene.plants.push_back(withoutTornLeaves(*plants[pi].plant, motions.back()->prepareLeafLoop(wind), keptLeaves[pi]));
  }
  ExportOptions exportOptions;
  exportOptions.mesh = options.mesh;
  ExportModel model = buildExportModel(scene, exportOptions);

  tinygltf::Model gltf;
  gltf.asset.version = "2.0";
  gltf.asset.generator = "Tendril " TENDRIL_VERSION;
  std::vector<uint8_t> data;
  Bin bin{gltf, data};
  tinygltf::Scene gscene;
  gscene.name = "Tendril wind";
  tinygltf::Animation animation;
  animation.name = "wind";

  const int frames = std::max(2, int(std::lround(options.seconds * float(options.fps)))) + 1;
  std::vector<float> times(static_cast<size_t>(frames));
  for (int k = 0; k < frames; ++k) times[size_t(k)] = options.seconds * float(k) / float(frames - 1);
  int timeAccessor = bin.accessor(bin.view(times.data(), times.size() * sizeof(float), 0),
                                  TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, times.size());
  gltf.accessors[size_t(timeAccessor)].minValues = {0.0};
  gltf.accessors[size_t(timeAccessor)].maxValues = {double(options.seconds)};

  // Every plant's reduced hierarchy first, since a climber's skin lists its hosts' joints. The
  // nodes: the shared root when climbers cling, then per plant its joints and its mesh node.
  std::vector<Skeleton> skeletons(plants.size());
  int rootNode = -1;
  if (attached) {
    tinygltf::Node root;
    root.name = "plants";
    gltf.nodes.push_back(std::move(root));
    rootNode = 0;
    gscene.nodes.push_back(rootNode);
  }
  size_t plantNodes = gltf.nodes.size();
  for (size_t pi = 0; pi < plants.size(); ++pi) {
    skeletons[pi] = skeletonOf(scene.plants[pi], options.maxJoints);
    skeletons[pi].firstNode = int(plantNodes);
    plantNodes += skeletons[pi].joints.size() + (model.objects[pi].parts.empty() ? 0 : 1);
  }
  std::vector<std::pair<int, int>> hostChildren;  // (host joint, climber joint), linked once all nodes exist
  const GrowthScales growth =
      options.growth ? growthScales(scene.plants, plants, skeletons, attached, times, options.seconds) : GrowthScales{};
  // Growth clips: the joints that carry a climber's clinging nodes at its host's joints (see
  // ClingJoint), after every plant's nodes.
  std::vector<ClingJoint> clingJoints;

  WindAnimationStats stats;
  stats.keyframes = size_t(frames);
  for (size_t pi = 0; pi < plants.size(); ++pi) {
    const plant::PlantModel& rest = scene.plants[pi];
    const ExportObject& object = model.objects[pi];
    const mesh::PlantMesh& pm = model.plantMeshes[pi];
    const size_t n = rest.nodeCount();

    // The reduced hierarchy and each node's joint (nearest joint at or above it).
    const Skeleton& skeleton = skeletons[pi];
    const std::vector<int32_t>& joints = skeleton.joints;
    const std::vector<int32_t>& jointOf = skeleton.jointOf;
    const std::vector<int32_t>& parentJoint = skeleton.parentJoint;
    // A clinging node's host: its plant and the glTF node and rest position of the host's joint.
    const std::vector<int32_t>* hostPlant = attached && !plants[pi].hostPlant.empty() ? &plants[pi].hostPlant : nullptr;
    auto clings = [&](size_t i) { return hostPlant && (*hostPlant)[i] >= 0; };
    auto hostJointNode = [&](size_t i) {
      const Skeleton& host = skeletons[size_t((*hostPlant)[i])];
      return host.firstNode + host.jointOf[size_t(plants[pi].hostNode[i])];
    };
    auto hostJointRest = [&](size_t i) {
      const size_t h = size_t((*hostPlant)[i]);
      const Skeleton& host = skeletons[h];
      return scene.plants[h].position[size_t(host.joints[size_t(host.jointOf[size_t(plants[pi].hostNode[i])])])];
    };

    // Joint nodes: rest pose = translation to the node's position, relative to the parent joint
    // (for a joint on a clinging node, relative to the host's joint).
    const int firstNode = int(gltf.nodes.size());
    if (firstNode != skeleton.firstNode) throw Error(path.string(), "", "wind animation: joint nodes out of place");
    for (size_t j = 0; j < joints.size(); ++j) {
      tinygltf::Node node;
      node.name = fmt::format("{}-joint-{}", object.name, j);
      const size_t at = size_t(joints[j]);
      Vec3 p = rest.position[at];
      if (clings(at)) p -= hostJointRest(at);
      else if (parentJoint[j] >= 0) p -= rest.position[size_t(joints[size_t(parentJoint[j])])];
      node.translation = {p.x(), p.y(), p.z()};
      gltf.nodes.push_back(std::move(node));
    }
    for (size_t j = 0; j < joints.size(); ++j) {
      const size_t at = size_t(joints[j]);
      if (clings(at))
        hostChildren.push_back({hostJointNode(at), firstNode + int(j)});
      else if (parentJoint[j] >= 0)
        gltf.nodes[size_t(firstNode + parentJoint[j])].children.push_back(firstNode + int(j));
      else if (rootNode >= 0)
        gltf.nodes[size_t(rootNode)].children.push_back(firstNode + int(j));
      else
        gscene.nodes.push_back(firstNode + int(j));
    }

    tinygltf::Skin skin;
    skin.name = object.name;
    std::vector<float> inverseBind;
    auto bindAt = [&](const Vec3& p) {
      float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -p.x(), -p.y(), -p.z(), 1};  // column-major
      inverseBind.insert(inverseBind.end(), m, m + 16);
    };
    for (size_t j = 0; j < joints.size(); ++j) {
      skin.joints.push_back(firstNode + int(j));
      bindAt(rest.position[size_t(joints[j])]);
    }
    // Each node's joint in the skin: its own plant's, or for a clinging node its host's joint,
    // added to the skin in the order the nodes first use them.
    std::vector<int32_t> skinJointOf = jointOf;
    if (hostPlant) {
      // glTF node → index in the skin; in growth clips (host joint's node, climber joint) → index
      std::map<std::pair<int, int32_t>, int32_t> hostJoints;
      for (size_t i = 0; i < n; ++i) {
        if (!clings(i)) continue;
        const int node = hostJointNode(i);
        const int32_t own = options.growth ? jointOf[i] : -1;
        auto found = hostJoints.find({node, own});
        if (found == hostJoints.end()) {
          found = hostJoints.emplace(std::pair{node, own}, int32_t(skin.joints.size())).first;
          if (options.growth) {
            const size_t h = size_t((*hostPlant)[i]);
            const Vec3 at = rest.position[size_t(joints[size_t(own)])];
            clingJoints.push_back({node, pi, h, own, skeletons[h].jointOf[size_t(plants[pi].hostNode[i])],
                                   Vec3(at - hostJointRest(i))});
            skin.joints.push_back(int(plantNodes + clingJoints.size() - 1));
            bindAt(at);
          } else {
            skin.joints.push_back(node);
            bindAt(hostJointRest(i));
          }
        }
        skinJointOf[i] = found->second;
      }
      if (skin.joints.size() > 65535)
        throw Error(path.string(), "", fmt::format("plant {}: its skin would have {} joints, more than 65535", pi,
                                                   skin.joints.size()));
    }
    skin.inverseBindMatrices = bin.accessor(bin.view(inverseBind.data(), inverseBind.size() * sizeof(float), 0),
                                            TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_MAT4, skin.joints.size());
    gltf.skins.push_back(skin);
    const int skinIndex = int(gltf.skins.size() - 1);

    // The leaves' own motion: morph targets (k, g) for motion k in phase group g, if any leaf moves.
    wind::WindMotion& motion = *motions[pi];
    const LeafLoop& leafLoop = motion.leafLoop();
    bool leavesMove = false;
    for (uint32_t j : keptLeaves[pi])
      for (float a : leafLoop.leaves[j].amplitude) leavesMove = leavesMove || a > 0.0f;
    std::vector<std::array<std::vector<Vec3>, 3>> displacement;
    if (leavesMove) displacement = leafDisplacements(rest, keptLeaves[pi], leafLoop, options.mesh);
    constexpr int kTargets = 3 * LeafLoop::kPhases;

    // The skinned mesh: every part with JOINTS_0 / WEIGHTS_0.
    tinygltf::Mesh gmesh;
    gmesh.name = object.name;
    const size_t nvLeaf = mesh::leafVertexCount(options.mesh);
    for (const ExportPart& part : object.parts) {
      const TriangleMesh& m = *part.mesh;
      const size_t nv = m.positions.size();
      int leafShape = -1;
      for (size_t s = 0; s < pm.leaves.size(); ++s)
        if (part.mesh == &pm.leaves[s]) leafShape = int(s);
      // Each vertex follows the joint of the node it was built from (mesh/plant_mesh.h).
      std::vector<uint16_t> jointIds(nv * 4, 0);
      std::vector<float> weights(nv * 4, 0.0f);
      for (size_t v = 0; v < nv; ++v) {
        jointIds[4 * v] = m.nodeIds.empty() ? 0 : uint16_t(skinJointOf[m.nodeIds[v]]);
        weights[4 * v] = 1.0f;
      }
      std::vector<Vec2> uvs(m.uvs.size());
      for (size_t v = 0; v < m.uvs.size(); ++v) uvs[v] = Vec2(m.uvs[v].x(), 1.0f - m.uvs[v].y());

      tinygltf::Primitive prim;
      prim.mode = TINYGLTF_MODE_TRIANGLES;
      prim.material = part.material;
      int pa = bin.accessor(bin.view(m.positions.data(), nv * sizeof(Vec3), TINYGLTF_TARGET_ARRAY_BUFFER),
                            TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, nv);
      Bounds3 b;
      for (const Vec3& p : m.positions) b.extend(p);
      gltf.accessors[size_t(pa)].minValues = {b.min.x(), b.min.y(), b.min.z()};
      gltf.accessors[size_t(pa)].maxValues = {b.max.x(), b.max.y(), b.max.z()};
      prim.attributes["POSITION"] = pa;
      if (!m.normals.empty())
        prim.attributes["NORMAL"] =
            bin.accessor(bin.view(m.normals.data(), nv * sizeof(Vec3), TINYGLTF_TARGET_ARRAY_BUFFER),
                         TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, nv);
      if (!uvs.empty())
        prim.attributes["TEXCOORD_0"] = bin.accessor(bin.view(uvs.data(), nv * sizeof(Vec2), TINYGLTF_TARGET_ARRAY_BUFFER),
                                                     TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, nv);
      prim.attributes["JOINTS_0"] =
          bin.accessor(bin.view(jointIds.data(), jointIds.size() * sizeof(uint16_t), TINYGLTF_TARGET_ARRAY_BUFFER),
                       TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_VEC4, nv);
      prim.attributes["WEIGHTS_0"] =
          bin.accessor(bin.view(weights.data(), weights.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER),
                       TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, nv);
      prim.indices = bin.accessor(bin.view(m.indices.data(), m.indices.size() * sizeof(uint32_t),
                                           TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
                                  TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, m.indices.size());
      if (leavesMove) {
        // Every primitive of a mesh has the same targets: parts without leaves all zeros, the
        // leaf parts sparse (target (k, g) holds only the vertices of the leaves in phase g of k).
        std::vector<uint32_t> leafOfSlot;  // the clip plant's leaf of each leaf in this part
        if (leafShape >= 0)
          for (size_t l = 0; l < rest.leafCount(); ++l)
            if (rest.leafShape[l] == leafShape) leafOfSlot.push_back(uint32_t(l));
        int zeroTarget = -1;  // this part's all-zero target, shared by its targets that move nothing
        for (int target = 0; target < kTargets; ++target) {
          const int k = target / LeafLoop::kPhases, g = target % LeafLoop::kPhases;
          std::vector<uint32_t> at;
          std::vector<Vec3> by;
          if (leafShape >= 0 && size_t(leafShape) < displacement.size()) {
            const std::vector<Vec3>& d = displacement[size_t(leafShape)][size_t(k)];
            for (size_t slot = 0; slot < leafOfSlot.size(); ++slot) {
              const LeafLoop::Leaf& f = leafLoop.leaves[keptLeaves[pi][leafOfSlot[slot]]];
              if (f.phase[k] != g || !(f.amplitude[k] > 0.0f)) continue;
              for (size_t v = slot * nvLeaf; v < (slot + 1) * nvLeaf && v < d.size(); ++v) {
                at.push_back(uint32_t(v));
                by.push_back(d[v]);
              }
            }
          }
          int accessor = -1;
          if (at.empty()) {
            // No leaf of this part moves so: all zeros, which an accessor without a buffer is.
            if (zeroTarget < 0) {
              zeroTarget = bin.accessor(-1, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, nv);
              gltf.accessors[size_t(zeroTarget)].minValues = {0.0, 0.0, 0.0};
              gltf.accessors[size_t(zeroTarget)].maxValues = {0.0, 0.0, 0.0};
            }
            accessor = zeroTarget;
          } else {
            accessor = bin.accessor(-1, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, nv);
            tinygltf::Accessor& a = gltf.accessors[size_t(accessor)];
            a.sparse.isSparse = true;
            a.sparse.count = int(at.size());
            a.sparse.indices.bufferView = bin.view(at.data(), at.size() * sizeof(uint32_t), 0);
            a.sparse.indices.byteOffset = 0;
            a.sparse.indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
            a.sparse.values.bufferView = bin.view(by.data(), by.size() * sizeof(Vec3), 0);
            a.sparse.values.byteOffset = 0;
            Bounds3 tb;
            if (at.size() < nv) tb.extend(Vec3::Zero());
            for (const Vec3& p : by) tb.extend(p);
            gltf.accessors[size_t(accessor)].minValues = {tb.min.x(), tb.min.y(), tb.min.z()};
            gltf.accessors[size_t(accessor)].maxValues = {tb.max.x(), tb.max.y(), tb.max.z()};
          }
          prim.targets.push_back({{"POSITION", accessor}});
        }
      }
      gmesh.primitives.push_back(std::move(prim));
    }
    if (leavesMove && !gmesh.primitives.empty()) {
      gmesh.weights.assign(size_t(kTargets), 0.0);
      // Target names (the convention Blender's importer reads for its shape keys).
      tinygltf::Value::Array names;
      const char* motionNames[3] = {"bend", "twist", "vibrate"};
      for (int target = 0; target < kTargets; ++target)
        names.emplace_back(fmt::format("leaf-{}-{}", motionNames[target / LeafLoop::kPhases], target % LeafLoop::kPhases));
      tinygltf::Value::Object extras;
      extras["targetNames"] = tinygltf::Value(std::move(names));
      gmesh.extras = tinygltf::Value(std::move(extras));
    }
    int meshNodeIndex = -1;
    const bool hasMesh = !gmesh.primitives.empty();
    if (hasMesh) {
      gltf.meshes.push_back(std::move(gmesh));
      tinygltf::Node meshNode;
      meshNode.name = object.name;
      meshNode.mesh = int(gltf.meshes.size() - 1);
      meshNode.skin = skinIndex;
      meshNodeIndex = int(gltf.nodes.size());
      gltf.nodes.push_back(std::move(meshNode));
      gscene.nodes.push_back(int(gltf.nodes.size() - 1));
    }

    // Keyframes: Growth-Flow sway with a period that divides the clip.
    plant::PlantModel posed;
    std::vector<std::vector<float>> rot(joints.size(), std::vector<float>(size_t(frames) * 4));
    std::vector<std::vector<float>> trans(joints.size(), std::vector<float>(size_t(frames) * 3));
    const float dt = options.seconds / float(frames - 1);
    for (int k = 0; k < frames; ++k) {
      motion.step(times[size_t(k)], dt, wind, posed);
      for (size_t j = 0; j < joints.size(); ++j) {
        size_t node = size_t(joints[j]);
        Quat q = motion.nodeRotation(node);
        Vec3 p = posed.position[node];
        if (parentJoint[j] >= 0) {
          size_t pn = size_t(joints[size_t(parentJoint[j])]);
          Quat qp = motion.nodeRotation(pn);
          q = (qp.conjugate() * q).normalized();
          p = qp.conjugate() * (p - posed.position[pn]);
        }
        if (q.w() < 0.0f) q.coeffs() = -q.coeffs();  // one hemisphere: no spurious flips
        float* r = &rot[j][size_t(k) * 4];
        r[0] = q.x(), r[1] = q.y(), r[2] = q.z(), r[3] = q.w();
        float* t = &trans[j][size_t(k) * 3];
        t[0] = p.x(), t[1] = p.y(), t[2] = p.z();
      }
    }
    for (size_t j = 0; j < joints.size(); ++j) {
      if (clings(size_t(joints[j]))) continue;  // held at its offset in the host joint's frame
      bool moves = false;
      for (int k = 0; k < frames && !moves; ++k) moves = rot[j][size_t(k) * 4 + 3] < 1.0f - 1e-7f;
      if (!moves) continue;
      int ra = bin.accessor(bin.view(rot[j].data(), rot[j].size() * sizeof(float), 0), TINYGLTF_COMPONENT_TYPE_FLOAT,
                            TINYGLTF_TYPE_VEC4, size_t(frames));
      int ta = bin.accessor(bin.view(trans[j].data(), trans[j].size() * sizeof(float), 0),
                            TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, size_t(frames));
      addChannel(animation, timeAccessor, ra, firstNode + int(j), "rotation");
      addChannel(animation, timeAccessor, ta, firstNode + int(j), "translation");
    }
    stats.joints += joints.size();

    // Growth: each joint scales in over the growth time of the nodes it carries.
    if (options.growth)
      for (size_t j = 0; j < joints.size(); ++j)
        if (addScaleChannel(bin, animation, timeAccessor, firstNode + int(j), growth.local[pi][j])) ++stats.growingJoints;

    // The leaves' waves, one weight per target and keyframe.
    if (leavesMove && hasMesh) {
      std::vector<float> weights(size_t(frames) * kTargets);
      for (int k = 0; k < frames; ++k)
        for (int target = 0; target < kTargets; ++target)
          weights[size_t(k) * kTargets + size_t(target)] =
              leafLoop.wave(target / LeafLoop::kPhases, target % LeafLoop::kPhases, times[size_t(k)], options.seconds);
      addChannel(animation, timeAccessor,
                 bin.accessor(bin.view(weights.data(), weights.size() * sizeof(float), 0),
                              TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, weights.size()),
                 meshNodeIndex, "weights");
      stats.morphTargets += size_t(kTargets);
    }
  }
  if (gltf.nodes.size() != plantNodes) throw Error(path.string(), "", "wind animation: cling joints out of place");
  for (size_t c = 0; c < clingJoints.size(); ++c) {
    const ClingJoint& cj = clingJoints[c];
    tinygltf::Node node;
    node.name = fmt::format("{}-cling-{}", model.objects[cj.plant].name, c);
    node.translation = {cj.offset.x(), cj.offset.y(), cj.offset.z()};
    const int index = int(gltf.nodes.size());
    gltf.nodes.push_back(std::move(node));
    hostChildren.push_back({cj.hostNode, index});
    std::vector<float> scale(times.size());
    for (size_t k = 0; k < times.size(); ++k) {
      const float host = growth.hostScale(cj.hostPlant, cj.hostJoint, k);
      scale[k] = host > 0.0f ? growth.global[cj.plant][size_t(cj.joint)][k] / host : 0.0f;
    }
    if (addScaleChannel(bin, animation, timeAccessor, index, scale)) ++stats.growingJoints;
  }
  stats.joints += clingJoints.size();
  for (const auto& [host, climber] : hostChildren) gltf.nodes[size_t(host)].children.push_back(climber);
  gltf.scenes.push_back(std::move(gscene));
  gltf.defaultScene = 0;
  if (!animation.channels.empty()) gltf.animations.push_back(std::move(animation));

  // Materials, samplers, textures and images as the static writer makes them.
  appendMaterialsAndTextures(model, gltf);
  for (const ExportImage& img : model.images) {
    tinygltf::Image image;
    image.name = std::filesystem::path(img.spec).filename().string();
    image.mimeType = img.image.mimeType;
    image.bufferView = bin.view(img.image.bytes.data(), img.image.bytes.size(), 0);
    gltf.images.push_back(std::move(image));
  }
  tinygltf::Buffer buffer;
  buffer.data = std::move(data);
  gltf.buffers.push_back(std::move(buffer));
  std::ostringstream out;
  tinygltf::TinyGLTF tiny;
  if (!tiny.WriteGltfSceneToStream(&gltf, out, false, true))
    throw Error(path.string(), "", "cannot write .glb: tinygltf could not serialise the animation");
  std::string bytes = out.str();
  AtomicFileWriter file(path);
  file.write(bytes);
  file.commit();
  stats.bytes = bytes.size();
  return stats;
}

void forEachWindFrame(const std::vector<AnimatedPlant>& plants, const env::WindField& wind,
                      const WindAnimationOptions& options, const std::string& source,
                      const std::function<void(int, const std::vector<plant::PlantModel>&)>& frame) {
  if (!(options.seconds > 0.0f) || options.fps < 1)
    throw Error(source, "", "wind frames need seconds > 0 and fps >= 1");
  const int frames = std::max(1, int(std::lround(options.seconds * float(options.fps))));
  const float dt = options.seconds / float(frames);
  // The same motion as the clip (same loop and seeds), one posed plant per plant kept across
  // frames so WindMotion writes only what moves.
  std::vector<wind::WindMotion> motions;
  motions.reserve(plants.size());
  for (size_t pi = 0; pi < plants.size(); ++pi) {
    if (!plants[pi].plant) throw Error(source, "", fmt::format("plant {} is missing", pi));
    wind::MotionSettings ms;
    ms.loopSeconds = options.seconds;
    ms.seed = options.seed + pi;
    motions.emplace_back(*plants[pi].plant, plants[pi].species, ms);
  }
  // Climbers follow their hosts, as in the clip (carryWithHosts), posed into copies: WindMotion
  // rewrites only what moves in `posed`.
  const bool attached = checkHosts(plants, source);
  std::vector<std::vector<int32_t>> carriers(plants.size());
  for (size_t pi = 0; attached && pi < plants.size(); ++pi)
    if (!plants[pi].hostPlant.empty()) carriers[pi] = clingingCarriers(*plants[pi].plant, plants[pi].hostPlant);
  std::vector<plant::PlantModel> posed(plants.size()), shown;
  for (int k = 0; k < frames; ++k) {
    for (size_t pi = 0; pi < plants.size(); ++pi) motions[pi].step(float(k) * dt, dt, wind, posed[pi]);
    if (!attached) {
      frame(k, posed);
      continue;
    }
    shown = posed;
    for (size_t pi = 0; pi < plants.size(); ++pi)
      if (!carriers[pi].empty())
        carryWithHosts(shown[pi], motions[pi], carriers[pi], plants[pi].hostPlant, plants[pi].hostNode,
                       [&](size_t h) { return HostPose{&motions[h], &posed[h]}; });
    frame(k, shown);
  }
}

std::vector<std::filesystem::path> writeWindFrames(const std::vector<AnimatedPlant>& plants,
                                                   const env::WindField& wind, const WindAnimationOptions& options,
                                                   const std::filesystem::path& dir, const std::string& stem) {
  ExportOptions exportOptions;
  exportOptions.mesh = options.mesh;
  std::vector<std::filesystem::path> written;
  forEachWindFrame(plants, wind, options, dir.string(), [&](int k, const std::vector<plant::PlantModel>& posed) {
    ExportScene scene;
    scene.plants = posed;
    std::filesystem::path file = dir / fmt::format("{}_{:04d}.glb", stem, k);
    writeGlb(scene, file, exportOptions);
    written.push_back(std::move(file));
  });
  return written;
}

}  // namespace tendril::wind
