// Wind motion as a looping glTF animation (.glb) that standard viewers play.
//
// Each plant is meshed once in its rest pose and skinned to a reduced branch hierarchy of at
// most `maxJoints` joints: the roots, then branch starts and every K-th node along a branch
// whose subtree holds at least K nodes, K doubling until the count fits. Every vertex follows
// one joint (weight 1): the joint of the skeleton node it was built from (TriangleMesh::nodeIds:
// leaves, their node; bark, the segment it was swept from; primitives, their node). The joints'
// rotations and translations are
// sampled from Growth-Flow motion (wind/motion.h) with loopSeconds set, so the last keyframe
// equals the first and the clip repeats seamlessly. Leaves follow their branches, and their
// own bending, twisting and vibrating is the loop's periodic leaf motion (motion.h, LeafLoop)
// as 3 × LeafLoop::kPhases morph targets on each plant's mesh: target (k, g), named
// leaf-<bend|twist|vibrate>-<g>, moves the leaves whose motion k is in phase group g by their
// displacement at full amplitude (half the difference of the leaf posed at ±amplitude; sparse,
// the other parts all zeros), and its weight is that group's triangle wave, so a vertex is
// displaced by Σ amplitude · wave — the loop's leaf angles to small-angle accuracy. Morph
// targets apply before skinning: leaves flutter on their swaying branches, and clinging ivy,
// whose nodes its support holds, flutters in place. Leaves the wind tears off are left out.
//
// Climbers on hosts. A plant may cling to other plants (AnimatedPlant::hostPlant / hostNode:
// plants as supports). A clinging node's vertices are skinned to the host's joint for its host
// node (the joint chooseJoints gave that node or its nearest ancestor that is one), listed in the
// climber's skin, so they keep their rest offset in that joint's frame as the host sways. A
// climber joint on a clinging node is a child of that host joint (at its rest offset, with no
// channels of its own), so the free shoots beyond it sway on a base that moves with the host.
// The plants' root joints then hang under one root node ("plants") that every skin shares.
// Growth clips leave climbers on their own skeletons.
//
// With `growth` the clip shows the plants growing as they move (joints scale in, see
// WindAnimationOptions::growth); it is not meant to loop.
//
// The file passes the Khronos validator with no errors (tested). It is written atomically.
#pragma once

#include "tendril/env/wind_field.h"
#include "tendril/mesh/mesh_options.h"
#include "tendril/plant/plant_model.h"
#include "tendril/plant/growth_flow.h"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace tendril::wind {

struct WindAnimationOptions {
  float seconds = 4.0f;  // clip length
  int fps = 24;          // keyframes per second
  int maxJoints = 128;   // per plant
  uint64_t seed = 1;
  mesh::MeshOptions mesh;
  // A growth clip: the plants grow while they move. Over the first kGrowthShare of the clip
  // every joint scales in from 0 at the growth time its node was born (the plant's age minus
  // the node's, mapped onto the clip) to 1 once the last node it carries was born; the rest of
  // the clip holds the grown plants moving. Scales are set relative to the parent joint, so a
  // joint's geometry is at its own scale whatever its parent's. Plants whose nodes are all of
  // one age (component graphs) are there from the start.
  bool growth = false;
};
inline constexpr float kGrowthShare = 0.8f;

struct AnimatedPlant {
  const plant::PlantModel* plant = nullptr;
  plant::GrowthFlowSpecies species;
  // Empty, or per node: the plant (index in the clip's list) and node this node clings to, -1
  // for a free node. A host must not cling to anything itself.
  std::vector<int32_t> hostPlant = {}, hostNode = {};
};

struct WindAnimationStats {
  size_t joints = 0;     // over all plants
  size_t keyframes = 0;  // per channel
  size_t morphTargets = 0;  // the leaves' motion, over all plants
  size_t growingJoints = 0;  // joints with a scale channel (growth clips)
  uint64_t bytes = 0;
};

// Chooses the joints of a plant's reduced hierarchy (node indices, parents before children).
std::vector<int32_t> chooseJoints(const plant::PlantModel& plant, int maxJoints);

WindAnimationStats writeWindAnimationGlb(const std::vector<AnimatedPlant>& plants, const env::WindField& wind,
                                         const WindAnimationOptions& options, const std::filesystem::path& path);

// The clip's frames one after the other: calls frame(k, posed) for k = 0 … seconds × fps − 1 with
// every plant posed at time k / fps (the same sway and leaf motion as the looping clip; frame
// `frames` would equal frame 0). The posed plants are reused from frame to frame. A climber's
// clinging nodes, and the free shoots beyond them, are carried by their host nodes' posed
// motion, as in the clip.
void forEachWindFrame(const std::vector<AnimatedPlant>& plants, const env::WindField& wind,
                      const WindAnimationOptions& options, const std::string& source,
                      const std::function<void(int, const std::vector<plant::PlantModel>&)>& frame);
// The per-step sequence: every frame of the same clip (seconds × fps frames, the same sway and
// leaf motion as the looping clip) as a static .glb of the posed plants, for tools that play
// neither skins nor morph targets; the leaves are posed exactly rather than to small-angle
// accuracy.
// Writes <dir>/<stem>_0000.glb, <stem>_0001.glb, … atomically and returns their paths.
std::vector<std::filesystem::path> writeWindFrames(const std::vector<AnimatedPlant>& plants,
                                                   const env::WindField& wind, const WindAnimationOptions& options,
                                                   const std::filesystem::path& dir, const std::string& stem);

}  // namespace tendril::wind
