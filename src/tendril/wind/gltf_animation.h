// Wind motion as a looping glTF animation (.glb) that standard viewers play.
//
// Each plant is meshed once in its rest pose and skinned to a reduced branch hierarchy of at
// most `maxJoints` joints: the roots, then branch starts and every K-th node along a branch
// whose subtree holds at least K nodes, K doubling until the count fits. Every vertex follows
// one joint (weight 1): the joint of the skeleton node it was built from (leaves: their node;
// bark: the segment whose surface is nearest). The joints' rotations and translations are
// sampled from Growth-Flow motion (wind/motion.h) with loopSeconds set, so the last keyframe
// equals the first and the clip repeats seamlessly. Leaves follow their branches; the leaves'
// own bending, twisting and vibrating (Algorithm 2 picks a random motion each frame, so it does
// not loop) are in the per-step sequence export instead.
//
// The file passes the Khronos validator with no errors (tested). It is written atomically.
#pragma once

#include "tendril/env/wind_field.h"
#include "tendril/mesh/mesh_options.h"
#include "tendril/plant/plant_model.h"
#include "tendril/plant/growth_flow.h"

#include <cstdint>
#include <filesystem>
#include <vector>

namespace tendril::wind {

struct WindAnimationOptions {
  float seconds = 4.0f;  // clip length
  int fps = 24;          // keyframes per second
  int maxJoints = 128;   // per plant
  uint64_t seed = 1;
  mesh::MeshOptions mesh;
};

struct AnimatedPlant {
  const plant::PlantModel* plant = nullptr;
  plant::GrowthFlowSpecies species;
};

struct WindAnimationStats {
  size_t joints = 0;     // over all plants
  size_t keyframes = 0;  // per channel
  uint64_t bytes = 0;
};

// Chooses the joints of a plant's reduced hierarchy (node indices, parents before children).
std::vector<int32_t> chooseJoints(const plant::PlantModel& plant, int maxJoints);

WindAnimationStats writeWindAnimationGlb(const std::vector<AnimatedPlant>& plants, const env::WindField& wind,
                                         const WindAnimationOptions& options, const std::filesystem::path& path);

// The per-step sequence: every frame of the same clip (seconds × fps frames, the same sway as
// the looping clip) as a static .glb of the posed plants, with what skinning cannot carry —
// leaves bending, twisting and vibrating (eq. 10–15) and leaves torn off (Algorithm 2).
// Writes <dir>/<stem>_0000.glb, <stem>_0001.glb, … atomically and returns their paths.
std::vector<std::filesystem::path> writeWindFrames(const std::vector<AnimatedPlant>& plants,
                                                   const env::WindField& wind, const WindAnimationOptions& options,
                                                   const std::filesystem::path& dir, const std::string& stem);

}  // namespace tendril::wind
